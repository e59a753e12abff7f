"""Transactions (PROTOCOL.md §4.4): pending requests matched to answers by ``(seq, id)``, retries
with the same seq, NOT_LINKED handling and the stop-and-wait rule for controls.

Many ``R``/``J``/``S`` may be in flight at once, but a ``C`` (write or call) runs alone: while it is
unanswered nothing else is sent, so the device's duplicate detection (last seq per channel) is
exact and a retried write is never applied twice.
"""
from __future__ import annotations

import asyncio
import random
import time
from contextlib import asynccontextmanager
from typing import Any, AsyncIterator, Dict, Optional, Tuple

from ..errors import NakError, Timeout
from ..wire import messages as m
from ..wire.frame import Frame, encode_frame
from ..wire.messages import NakCode

__all__ = ["Pending", "Gate", "Transactions"]


class Pending:
    """One transaction waiting for its answer (a future re-armed when a NOT_LINKED NAK is retried)."""

    __slots__ = ("type", "seq", "id", "wire", "fut", "sent_at", "tries")

    def __init__(self, loop: asyncio.AbstractEventLoop, type: int, seq: int, id: int, wire: bytes) -> None:
        self.type = type
        self.seq = seq
        self.id = id
        self.wire = wire
        self.fut: "asyncio.Future[Frame]" = loop.create_future()
        self.sent_at = 0.0
        self.tries = 0

    def rearm(self) -> None:
        self.fut = self.fut.get_loop().create_future()

    async def wait(self, timeout: float) -> Optional[Frame]:
        """The answer within ``timeout`` s, or None; raises the error the transaction failed with."""
        fut = self.fut
        if not fut.done():
            await asyncio.wait((fut,), timeout=max(0.0, timeout))
            if not fut.done():
                return None
        return fut.result()


class Gate:
    """Shared/exclusive gate: many R/J/S in flight, or one C alone (stop and wait); a waiting C
    goes before new shared users."""

    def __init__(self) -> None:
        self._cond = asyncio.Condition()
        self._shared = 0
        self._excl = False
        self._excl_waiting = 0

    @asynccontextmanager
    async def shared(self) -> AsyncIterator[None]:
        if self._excl or self._excl_waiting:
            async with self._cond:
                await self._cond.wait_for(lambda: not self._excl and not self._excl_waiting)
        self._shared += 1
        try:
            yield
        finally:
            self._shared -= 1
            if self._excl_waiting and not self._shared:
                await self._notify()

    @asynccontextmanager
    async def exclusive(self) -> AsyncIterator[None]:
        if self._excl or self._shared:
            self._excl_waiting += 1
            try:
                async with self._cond:
                    await self._cond.wait_for(lambda: not self._excl and not self._shared)
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


class Transactions:
    """Pending transactions of one session. ``core`` provides ``link``, ``stats``, ``url``,
    ``retry_timeout``, ``tries``, ``connect_timeout`` and ``check_ready(timeout)``."""

    def __init__(self, core: Any) -> None:
        self.core = core
        self.loop: asyncio.AbstractEventLoop = core.loop
        self.pending: Dict[Tuple[int, int], Pending] = {}
        self.gate = Gate()
        self._seq = random.randrange(256)

    def next_seq(self) -> int:
        self._seq = (self._seq + 1) & 0xFF
        return self._seq

    def register(self, type: int, id: int, payload: bytes) -> Pending:
        seq = self.next_seq()
        while (seq, id) in self.pending:
            seq = self.next_seq()
        p = Pending(self.loop, type, seq, id, encode_frame(type, seq, id, payload))
        self.pending[(seq, id)] = p
        return p

    def unregister(self, p: Pending) -> None:
        if self.pending.get((p.seq, p.id)) is p:
            del self.pending[(p.seq, p.id)]

    def transmit(self, p: Pending) -> None:
        p.tries += 1
        p.sent_at = time.monotonic()
        self.core.link.send(p.wire)

    def on_answer(self, f: Frame) -> bool:
        """Route an ACK/NAK/r/J to its transaction; False if nobody waits for it."""
        p = self.pending.get((f.seq, f.id))
        if p is None or p.fut.done():
            self.core.stats.unmatched_answers += 1
            return False
        p.fut.set_result(f)
        return True

    def fail_all(self, exc: BaseException) -> None:
        for p in self.pending.values():
            if not p.fut.done():
                p.fut.set_exception(exc)
                p.fut.exception()  # retrieved by its waiter; keeps asyncio from logging it

    async def transact(self, type: int, id: int, payload: bytes = b"", *, timeout: Optional[float] = None,
                       what: str = "") -> Frame:
        """Send one transaction and return its answer (ACK, ``r``, ``J``); raise NakError on NAK.

        Retries with the same seq every ``retry_timeout`` up to ``tries`` times (Timeout after).
        Controls (``C``) are stop-and-wait: they run alone.
        """
        core = self.core
        retry = core.retry_timeout if timeout is None else timeout / core.tries
        gate = self.gate.exclusive() if type == m.CONTROL else self.gate.shared()
        async with gate:
            await core.check_ready(max(core.connect_timeout, retry * core.tries))
            p = self.register(type, id, payload)
            try:
                self.transmit(p)
                return await self._answer(p, retry, what)
            finally:
                self.unregister(p)

    async def _answer(self, p: Pending, retry: float, what: str) -> Frame:
        core = self.core
        while True:
            a = await p.wait(p.sent_at + retry - time.monotonic())
            if a is None:
                if p.tries >= core.tries:
                    raise Timeout(f"no answer from the device on {core.url}"
                                  f"{' for ' + what if what else ''} after {p.tries} tries")
                core.stats.retries += 1
                self.transmit(p)
                continue
            if a.type != m.NAK:
                return a
            code = a.payload[0] if a.payload else 0
            if code != NakCode.NOT_LINKED or p.tries >= core.tries:
                raise NakError(code, what or None)
            # the device re-links on our hello; ask again (it was not applied)
            hello = core.link.next_hello()
            p.rearm()
            await asyncio.wait((hello, p.fut), timeout=retry, return_when=asyncio.FIRST_COMPLETED)
            hello.cancel()
            if p.fut.done():
                p.fut.result()  # the link was lost meanwhile: raise
            core.stats.retries += 1
            self.transmit(p)
