"""The MQTT bridge's inbound commands: a bounded queue behind a rate limit (docs/MQTT.md "Limits").

Anyone who may publish on the broker can send commands; a flood of them must not grow the
service's memory nor starve the boards' heartbeats. A command is taken when the token bucket has
a token and the queue has room, else dropped and counted (no reply: the sender may ask again); a
warning says how many were dropped, at most once per ``log_interval`` seconds.
"""
from __future__ import annotations

import asyncio
import logging
import time
from collections import deque
from typing import Any, Callable, Deque, Generic, Optional, TypeVar

__all__ = ["Inbound"]

T = TypeVar("T")


class Inbound(Generic[T]):
    def __init__(self, size: int, rate_hz: float, burst: int, log_interval: float, log: logging.Logger,
                 clock: Callable[[], float] = time.monotonic) -> None:
        self.size, self.rate_hz, self.burst = size, rate_hz, burst
        self.log_interval = log_interval
        self._log = log
        self._clock = clock
        self._q: Deque[T] = deque()
        self._ready = asyncio.Event()
        self._tokens = float(burst)
        self._refilled = clock()
        self._logged_at: Optional[float] = None
        self._dropped_logged = 0
        #: commands seen, taken, dropped; the longest the queue has been
        self.received = self.accepted = self.dropped = self.peak = 0

    def __len__(self) -> int:
        return len(self._q)

    def offer(self, item: T) -> bool:
        """Queue ``item``; False (dropped, counted) over the rate or with the queue full."""
        self.received += 1
        now = self._clock()
        self._tokens = min(float(self.burst), self._tokens + (now - self._refilled) * self.rate_hz)
        self._refilled = now
        if self._tokens < 1.0 or len(self._q) >= self.size:
            self.dropped += 1
            self._note_drop(now)
            return False
        self._tokens -= 1.0
        self._q.append(item)
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
        return self._q.popleft()

    def stats(self) -> Any:
        return {"received": self.received, "accepted": self.accepted, "dropped": self.dropped, "peak": self.peak}
