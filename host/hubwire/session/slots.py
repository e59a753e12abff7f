"""The bound on a session's transactions in flight: at most ``limit`` at once; the next ones wait
their turn in arrival order, asleep (threads on an event, coroutines on a future), and a transaction
that ends hands its slot straight to the first waiter. None ever polls.

Not locked itself: :class:`.transactions.Transactions` calls it under its lock, and wakes the waiter
it is handed after letting go of the lock.
"""
from __future__ import annotations

import asyncio
import threading
from collections import deque
from typing import Deque, Optional

__all__ = ["DEFAULT_MAX_IN_FLIGHT", "MAX_IN_FLIGHT", "Waiter", "Slots"]

#: transactions a session has in flight at most, unless told otherwise (``max_in_flight``)
DEFAULT_MAX_IN_FLIGHT = 64
#: the largest ``max_in_flight``: below the 256 seqs one channel id can have, with room for the hub's
#: own bind report and event (PROTOCOL.md 4.1), so a new request always finds a free seq
MAX_IN_FLIGHT = 200


class Waiter:
    """One transaction waiting for a slot: ``granted`` once it has one, ``error`` if the session
    failed meanwhile (lost, closed)."""

    __slots__ = ("event", "fut", "granted", "error")

    def __init__(self, loop: Optional[asyncio.AbstractEventLoop]) -> None:
        self.fut: Optional["asyncio.Future[None]"] = loop.create_future() if loop is not None else None
        self.event: Optional[threading.Event] = None if loop is not None else threading.Event()
        self.granted = False
        self.error: Optional[BaseException] = None

    def wake(self) -> None:
        """Wake it (any thread; call without the transactions' lock)."""
        if self.event is not None:
            self.event.set()
            return
        fut = self.fut
        assert fut is not None
        loop = fut.get_loop()
        if loop.is_closed():
            return
        try:
            running = asyncio.get_running_loop()
        except RuntimeError:
            running = None
        if running is loop:
            _settle(fut)
        else:
            loop.call_soon_threadsafe(_settle, fut)


def _settle(fut: "asyncio.Future[None]") -> None:
    if not fut.done():
        fut.set_result(None)


class Slots:
    """``limit`` slots and the queue of those waiting for one (FIFO, unbounded: each waiter is a
    caller blocked in its own call, so the callers bound it)."""

    def __init__(self, limit: int) -> None:
        if not 1 <= limit <= MAX_IN_FLIGHT:
            raise ValueError(f"max_in_flight must be 1..{MAX_IN_FLIGHT}, not {limit}")
        self.limit = limit
        self.used = 0
        self.waiting: Deque[Waiter] = deque()

    def take(self) -> bool:
        """A slot now if one is free and nobody waits before us."""
        if self.used < self.limit and not self.waiting:
            self.used += 1
            return True
        return False

    def give_back(self) -> Optional[Waiter]:
        """A transaction ended: its slot goes to the first waiter (returned: wake it), else is free."""
        if self.waiting:
            w = self.waiting.popleft()
            w.granted = True
            return w
        self.used -= 1
        return None

    def leave(self, w: Waiter) -> Optional[Waiter]:
        """``w`` stops waiting (cancelled, timed out): passes on a slot it was granted meanwhile."""
        if w.granted:
            w.granted = False
            return self.give_back()
        try:
            self.waiting.remove(w)
        except ValueError:
            pass
        return None

    def fail_all(self, exc: BaseException) -> "list[Waiter]":
        """Every waiter fails with ``exc`` (the link is lost, the session closed); returns them to wake."""
        out = list(self.waiting)
        self.waiting.clear()
        for w in out:
            w.error = exc
        return out
