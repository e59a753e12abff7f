"""The MQTT bridge's inbound commands: a bounded queue behind a rate limit (docs/MQTT.md "Limits").

Anyone who may publish on the broker can send commands; a flood of them must not grow the
service's memory nor starve the boards' heartbeats. A command costs one token per started
``bytes_per_token`` of its payload (parsing a large one takes the loop longer); it is taken when
the token bucket has that many and the queue has room (``size`` commands, ``max_bytes`` of
payload), else dropped and counted (no reply: the sender may ask again); a warning says how many
were dropped, at most once per ``log_interval`` seconds. :meth:`charge` spends tokens on other
work the same senders cause (the bridge's parsing of descriptors).
"""
from __future__ import annotations

import asyncio
import logging
import time
from collections import deque
from typing import Any, Callable, Deque, Generic, Optional, Tuple, TypeVar

__all__ = ["Inbound"]

T = TypeVar("T")


class Inbound(Generic[T]):
    def __init__(self, size: int, rate_hz: float, burst: int, log_interval: float, log: logging.Logger,
                 clock: Callable[[], float] = time.monotonic, bytes_per_token: int = 1 << 30,
                 max_bytes: int = 1 << 62) -> None:
        self.size, self.rate_hz, self.burst = size, rate_hz, burst
        self.bytes_per_token, self.max_bytes = bytes_per_token, max_bytes
        #: payload bytes of the commands queued
        self.bytes = 0
        self.log_interval = log_interval
        self._log = log
        self._clock = clock
        self._q: Deque[Tuple[T, int]] = deque()
        self._ready = asyncio.Event()
        self._tokens = float(burst)
        self._refilled = clock()
        self._logged_at: Optional[float] = None
        self._dropped_logged = 0
        #: commands seen, taken, dropped; the longest the queue has been
        self.received = self.accepted = self.dropped = self.peak = 0

    def __len__(self) -> int:
        return len(self._q)

    def _spend(self, nbytes: int) -> Optional[float]:
        """Take the tokens ``nbytes`` cost; None when there are not enough (else the time now)."""
        now = self._clock()
        self._tokens = min(float(self.burst), self._tokens + (now - self._refilled) * self.rate_hz)
        self._refilled = now
        cost = 1.0 + nbytes // self.bytes_per_token
        if self._tokens < cost:
            return None
        self._tokens -= cost
        return now

    def charge(self, nbytes: int) -> bool:
        """Spend the tokens ``nbytes`` of other work cost; False (nothing spent): skip that work."""
        return self._spend(nbytes) is not None

    def offer(self, item: T, nbytes: int = 0) -> bool:
        """Queue ``item`` (``nbytes`` of payload); False (dropped, counted) over the rate or with the
        queue full."""
        self.received += 1
        if len(self._q) >= self.size or self.bytes + nbytes > self.max_bytes or self._spend(nbytes) is None:
            self.dropped += 1
            self._note_drop(self._clock())
            return False
        self._q.append((item, nbytes))
        self.bytes += nbytes
        self.accepted += 1
        self.peak = max(self.peak, len(self._q))
        self._ready.set()
        return True

    def _note_drop(self, now: float) -> None:
        if self._logged_at is not None and now - self._logged_at < self.log_interval:
            return
        self._logged_at = now
        self._log.warning("hubwire serve: MQTT: commands arrive faster than %g a second (or %d wait): %d "
                          "dropped so far, unanswered; this is logged at most every %g s",
                          self.rate_hz, self.size, self.dropped, self.log_interval)

    async def get(self) -> T:
        while not self._q:
            self._ready.clear()
            await self._ready.wait()
        item, nbytes = self._q.popleft()
        self.bytes -= nbytes
        return item

    def stats(self) -> Any:
        return {"received": self.received, "accepted": self.accepted, "dropped": self.dropped, "peak": self.peak}
