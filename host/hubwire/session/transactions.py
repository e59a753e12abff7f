"""Transactions (PROTOCOL.md §4.4): pending requests matched to answers by ``(seq, id)``, retries
with the same seq, NOT_LINKED handling and the stop-and-wait rule for controls.

Many ``R``/``J``/``S`` may be in flight at once, but a ``C`` (write or call) runs alone: while it is
unanswered nothing else is sent, so the device's duplicate detection (last seq per channel) is
exact and a retried write is never applied twice.

Answers are matched on the event loop. A transaction is driven either by a coroutine on that loop
(:meth:`Transactions.transact`, the asyncio API and discovery) or by the calling thread itself
(:mod:`.blocking`, the synchronous API: it writes its frame and sleeps until the loop hands it the
answer, one thread hand-over per round trip). The table of pending transactions is shared, so it
is guarded by a lock.
"""
from __future__ import annotations

import asyncio
import random
import threading
import time
from contextlib import asynccontextmanager
from typing import Any, AsyncIterator, Dict, Optional, Tuple

from ..errors import NakError, Timeout
from ..wire import messages as m
from ..wire.frame import Frame
from ..wire.messages import NakCode

__all__ = ["Pending", "GateCounts", "Gate", "Transactions"]

#: the line speed assumed for a transport that names none (a pty, a socket)
DEFAULT_BAUD = 115200


class Pending:
    """One transaction waiting for its answer. A coroutine waits on ``fut`` (re-armed when a
    NOT_LINKED NAK is retried); a thread waits on ``event`` and reads ``answer`` / ``error``."""

    __slots__ = ("type", "seq", "id", "wire", "fut", "event", "answer", "error", "sent_at", "tries")

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


class Transactions:
    """Pending transactions of one session. ``core`` provides ``link``, ``stats``, ``url``,
    ``retry_timeout``, ``tries``, ``connect_timeout`` and ``check_ready(timeout)``."""

    def __init__(self, core: Any) -> None:
        self.core = core
        self.loop: asyncio.AbstractEventLoop = core.loop
        self.pending: Dict[Tuple[int, int], Pending] = {}
        self.lock = threading.Lock()
        self.gate = Gate()
        self._seq = random.randrange(256)
        #: who has a C outstanding: "user" (the application) or "hub" (the bind report), see claim_control
        self.control_owner: Optional[str] = None

    def next_seq(self) -> int:
        with self.lock:
            return self._next_seq()

    def _next_seq(self) -> int:
        self._seq = (self._seq + 1) & 0xFF
        return self._seq

    def claim_control(self, owner: str) -> bool:
        """Take the right to have a ``C`` outstanding: the application's controls and the hub's bind
        report never overlap, so the device's duplicate detection (last C) stays exact."""
        with self.lock:
            if self.control_owner is None:
                self.control_owner = owner
            return self.control_owner == owner

    def release_control(self) -> None:
        """Give the right back; wakes whoever waits for it (the hub's bind report, callers)."""
        with self.lock:
            owner, self.control_owner = self.control_owner, None
        if owner == "user" and not self.loop.is_closed():
            self.loop.call_soon_threadsafe(self.core.hub.kick)
        elif owner == "hub":
            self.core.wake()

    def register(self, type: int, id: int, payload: bytes, *, threaded: bool = False) -> Pending:
        """A new pending transaction with a seq not in use for ``id``; ``threaded``: waited for by a thread."""
        with self.lock:
            seq = self._next_seq()
            while (seq, id) in self.pending:
                seq = self._next_seq()
            # a large payload goes out as fragments, and so does every retry (PROTOCOL.md 12)
            p = Pending(type, seq, id, self.core.link.encode(type, seq, id, payload),
                        loop=None if threaded else self.loop)
            self.pending[(seq, id)] = p
        return p

    def unregister(self, p: Pending) -> None:
        with self.lock:
            if self.pending.get((p.seq, p.id)) is p:
                del self.pending[(p.seq, p.id)]

    def transmit(self, p: Pending) -> None:
        p.tries += 1
        p.sent_at = time.monotonic()
        if p.wire.count(0) > 1:  # fragments: the retry timeout runs from when the last one is out on the line
            p.sent_at += self._line_time(p.wire)
        self.core.link.send(p.wire)

    def _line_time(self, wire: bytes) -> float:
        """Seconds until the last byte of ``wire`` is out (paced on a fast line: session/pacer.py)."""
        return self.core.link.pacer.burst_time(wire) or len(wire) * 10.0 / DEFAULT_BAUD

    def retry(self, p: Pending) -> None:
        with self.lock:
            self.core.stats.retries += 1
        self.transmit(p)

    def silence(self, p: Pending, what: str) -> None:
        """No answer within the retry timeout: send again with the same seq, or Timeout after ``tries``.
        A large answer still coming in (a fragment since the last send) is waited for instead."""
        if self.core.link.reassembler.receiving(p.seq, p.id, p.sent_at):
            p.sent_at = time.monotonic()
            return
        if p.tries >= self.core.tries:
            raise Timeout(f"no answer from the device on {self.core.url}{' for ' + what if what else ''} "
                          f"after {p.tries} tries")
        self.retry(p)

    def verdict(self, p: Pending, a: Frame, what: str) -> Optional[Frame]:
        """The answer to return; None for a NOT_LINKED NAK to ask again; NakError for the others."""
        if a.type != m.NAK:
            return a
        code = a.payload[0] if a.payload else 0
        if code != NakCode.NOT_LINKED or p.tries >= self.core.tries:
            raise NakError(code, what or None)
        return None

    def on_answer(self, f: Frame) -> bool:
        """Route an ACK/NAK/r/J to its transaction; False if nobody waits for it."""
        with self.lock:
            p = self.pending.get((f.seq, f.id))
            if p is None or p.done():
                self.core.stats.unmatched_answers += 1
                return False
            p.resolve(f)
        return True

    def fail_all(self, exc: BaseException) -> None:
        with self.lock:
            for p in self.pending.values():
                if not p.done():
                    p.fail(exc)

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
            while type == m.CONTROL and not self.claim_control("user"):
                await core.changes(retry)  # the hub's bind report is out: a round trip at most
            try:
                p = self.register(type, id, payload)
                try:
                    self.transmit(p)
                    return await self._answer(p, retry, what)
                finally:
                    self.unregister(p)
            finally:
                if type == m.CONTROL:
                    self.release_control()

    async def _answer(self, p: Pending, retry: float, what: str) -> Frame:
        core = self.core
        while True:
            a = await p.wait(p.sent_at + retry - time.monotonic())
            if a is None:
                self.silence(p, what)
                continue
            if self.verdict(p, a, what) is not None:
                return a
            # the device re-links on our hello; ask again (it was not applied)
            hello = core.link.next_hello()
            p.rearm()
            await asyncio.wait((hello, p.fut), timeout=retry, return_when=asyncio.FIRST_COMPLETED)
            hello.cancel()
            if p.fut.done():  # type: ignore[union-attr]
                p.fut.result()  # type: ignore[union-attr]  # the link was lost meanwhile: raise
            self.retry(p)

