"""A transaction waiting for its answer (:class:`Pending`) and the stop-and-wait gate of the asyncio
API (:class:`Gate`; the threads' one is :class:`.blocking.ThreadGate`): many ``R``/``J``/``S`` in
flight, or one ``C`` alone."""
from __future__ import annotations

import asyncio
import threading
from contextlib import asynccontextmanager
from typing import AsyncIterator, Optional

from ..wire.frame import Frame

__all__ = ["Pending", "GateCounts", "Gate"]


class Pending:
    """One transaction waiting for its answer. A coroutine waits on ``fut`` (re-armed when a
    NOT_LINKED NAK is retried); a thread waits on ``event`` and reads ``answer`` / ``error``."""

    __slots__ = ("type", "seq", "id", "payload", "wire", "fut", "event", "answer", "error", "sent_at", "tries",
                 "drawn", "slot", "acked", "max_tries")

    def __init__(self, type: int, seq: int, id: int, wire: bytes, *, loop: Optional[asyncio.AbstractEventLoop] = None) -> None:
        self.type = type
        self.seq = seq
        self.id = id
        self.wire = wire
        self.fut: Optional["asyncio.Future[Frame]"] = loop.create_future() if loop is not None else None
        self.event: Optional[threading.Event] = None if loop is not None else threading.Event()
        self.answer: Optional[Frame] = None
        self.error: Optional[BaseException] = None
        self.sent_at = 0.0
        self.tries = 0
        self.payload = b""
        self.drawn = 0  # the seq's draw number (SeqRules.draws)
        self.slot = False  # holds one of the session's slots (released by unregister)
        self.acked = False  # a C answered ACK or r: the device remembers it
        self.max_tries = 0  # tries before Timeout; 0: the session's (Transactions.tries_for)

    def done(self) -> bool:
        if self.fut is not None:
            return self.fut.done()
        return self.answer is not None or self.error is not None

    def resolve(self, f: Frame) -> None:
        if self.fut is not None:
            self.fut.set_result(f)
        else:
            self.answer = f
            self.event.set()  # type: ignore[union-attr]

    def fail(self, exc: BaseException) -> None:
        if self.fut is not None:
            self.fut.set_exception(exc)
            self.fut.exception()  # retrieved by its waiter; keeps asyncio from logging it
        else:
            self.error = exc
            self.event.set()  # type: ignore[union-attr]

    def rearm(self) -> None:
        if self.fut is not None:
            self.fut = self.fut.get_loop().create_future()
        else:
            self.answer = None
            self.event.clear()  # type: ignore[union-attr]

    async def wait(self, timeout: float) -> Optional[Frame]:
        """(Coroutine waiters) the answer within ``timeout`` s, or None; raises the error."""
        fut = self.fut
        assert fut is not None
        if not fut.done():
            await asyncio.wait((fut,), timeout=max(0.0, timeout))
            if not fut.done():
                return None
        return fut.result()


class GateCounts:
    """The bookkeeping of a shared/exclusive gate: many R/S in flight, or one C alone (stop and
    wait); a waiting C goes before new shared users. Subclasses add the waiting."""

    def __init__(self) -> None:
        self._shared = 0
        self._excl = False
        self._excl_waiting = 0

    def _may_share(self) -> bool:
        return not self._excl and not self._excl_waiting

    def _may_own(self) -> bool:
        return not self._excl and not self._shared


class Gate(GateCounts):
    """The gate for coroutines (the asyncio API)."""

    def __init__(self) -> None:
        super().__init__()
        self._cond = asyncio.Condition()

    @asynccontextmanager
    async def shared(self) -> AsyncIterator[None]:
        if not self._may_share():
            async with self._cond:
                await self._cond.wait_for(self._may_share)
        self._shared += 1
        try:
            yield
        finally:
            self._shared -= 1
            if self._excl_waiting and not self._shared:
                await self._notify()

    @asynccontextmanager
    async def exclusive(self) -> AsyncIterator[None]:
        if not self._may_own():
            self._excl_waiting += 1
            try:
                async with self._cond:
                    await self._cond.wait_for(self._may_own)
            finally:
                self._excl_waiting -= 1
        self._excl = True
        try:
            yield
        finally:
            self._excl = False
            await self._notify()

    async def _notify(self) -> None:
        async with self._cond:
            self._cond.notify_all()
