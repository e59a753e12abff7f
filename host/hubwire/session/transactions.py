"""Transactions (PROTOCOL.md §4.4): pending requests matched to answers by ``(seq, id)``, retries,
NOT_LINKED handling and the stop-and-wait rule for controls.

Many ``R``/``J``/``S`` may be in flight at once (at most ``max_in_flight``, the rest wait their
turn: :mod:`.slots`), but a ``C`` (write or call) runs alone: while it is unanswered nothing else is
sent, so the device's duplicate detection (the last control) is exact and a retried write is never
applied twice. A retried ``C`` keeps its seq; a retried ``R``/``J``/``S`` (idempotent) takes a new
one, so a late answer to an earlier try, or the fragments of one, never completes the new try. New
seqs skip what the device may still remember (:mod:`.seqs`).

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
from typing import Any, Dict, Optional, Tuple

from ..errors import HubwireError, NakError, Timeout
from ..wire import messages as m
from ..wire.frame import Frame
from ..wire.messages import NakCode
from .pending import Gate, GateCounts, Pending
from .seqs import SeqRules
from .slots import DEFAULT_MAX_IN_FLIGHT, Slots, Waiter

__all__ = ["Pending", "GateCounts", "Gate", "Transactions"]

#: the line speed assumed for a transport that names none (a pty, a socket)
DEFAULT_BAUD = 115200
_NOT_LINKED = bytes((NakCode.NOT_LINKED,))


def no_seq(type: int, what: str, url: str) -> Timeout:
    """No seq free for a new message even after the board-id read (session/seqs.py)."""
    of = f" of {what}" if what else ""
    if type == m.CONTROL:
        return Timeout(f"no sequence number free for a control{of} on {url}")
    return Timeout(f"no sequence number free{of} on {url}: the device has not answered any of the last "
                   f"256 messages to this channel, nor anything sent after them (a blocked loop()?)")


class Transactions:
    """Pending transactions of one session. ``core`` provides ``link``, ``stats``, ``url``,
    ``retry_timeout``, ``tries``, ``connect_timeout``, ``max_in_flight`` and ``check_ready(timeout)``."""

    def __init__(self, core: Any) -> None:
        self.core = core
        self.loop: asyncio.AbstractEventLoop = core.loop
        self.pending: Dict[Tuple[int, int], Pending] = {}
        self.lock = threading.Lock()
        self.gate = Gate()
        self.rules = SeqRules(random.randrange(256))
        #: (seq, id) of the hub's own frames in flight: its bind report and its head event
        self.held: Dict[Tuple[int, int], int] = {}
        self.slots = Slots(getattr(core, "max_in_flight", DEFAULT_MAX_IN_FLIGHT))
        #: who has a C outstanding: "user" (the application) or "hub" (the bind report), see claim_control
        self.control_owner: Optional[str] = None
        #: when the first hub hello not yet answered went out (SeqRules.unanswered's clock)
        self._hello_at: Optional[int] = None

    # -------------------------------------------------------------------------------- seqs

    def _busy(self, seq: int, id: int) -> bool:
        return (seq, id) in self.pending or (seq, id) in self.held

    def next_seq(self, type: int, id: int) -> int:
        """A seq for a message nobody waits an answer for (a subscription cancelled at close)."""
        with self.lock:
            seq = self.rules.draw(type, id, self._busy)
            if seq is not None:
                self.rules.unanswered.ended((seq, id))  # sent once, now
        return self.rules.seq if seq is None else seq

    def hold(self, type: int, id: int) -> Optional[int]:
        """A seq for the hub's own bind report or event to ``id``, held until :meth:`let_go`;
        None when none is free (sent later)."""
        with self.lock:
            seq = self.rules.draw(type, id, self._busy)
            if seq is not None:
                self.held[(seq, id)] = type
        return seq

    def let_go(self, seq: int, id: int, answer: Optional[Frame]) -> None:
        """The hub's own message ``(seq, id)`` is over: ``answer`` is its ACK/NAK, None if it ended unanswered."""
        with self.lock:
            type = self.held.pop((seq, id), None)
            acked = answer is not None and answer.type == m.ACK
            self.rules.unanswered.ended((seq, id))
            if answer is not None:
                self.rules.unanswered.answered((seq, id))
            if type == m.CONTROL:
                self.rules.control_answered(seq) if acked else self.rules.control_ended(seq)
            elif type == m.EVENT and answer is not None:
                self.rules.event_ended(seq, acked)

    def device_rebooted(self) -> None:
        with self.lock:
            self.rules.device_rebooted()

    def resume(self, acked: Optional[int], head: Optional[Tuple[int, int]]) -> None:
        """Go on from an earlier run of the hub (:mod:`.resume`): its seq rules, and the (seq, id)
        of its event in flight held for it (:meth:`let_go` it if that event is not sent again)."""
        with self.lock:
            self.rules.resumed(acked, None if head is None else head[0])
            if head is not None:
                self.held[head] = m.EVENT
                self.rules.unanswered.add(head)

    def hello_sent(self) -> None:
        """A hub hello asking for the device's went out (:meth:`hello_answered`)."""
        with self.lock:
            if self._hello_at is None:
                self._hello_at = self.rules.unanswered.now()

    def hello_answered(self) -> None:
        """The device's hello answered one of ours: it answers in order, so every answer to what was
        sent before our first unanswered hello has come (or never will)."""
        with self.lock:
            if self._hello_at is not None:
                self.rules.unanswered.answered_through(self._hello_at)
                self._hello_at = None

    # ----------------------------------------------------------------------- control right

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
            self.core.wake()  # the loop's own requests wait for a thread's control to end (transact)
        elif owner == "hub":
            self.core.wake()

    # ------------------------------------------------------------------------ the table

    def register(self, type: int, id: int, payload: bytes, *, threaded: bool = False) -> Pending:
        """A new pending transaction outside the slots (discovery's window, a probe); see :meth:`try_register`."""
        p = self.try_register(type, id, payload, threaded=threaded)
        if p is None:
            raise HubwireError(f"no sequence number free for channel id {id}")
        return p

    def try_register(self, type: int, id: int, payload: bytes, *, threaded: bool = False,
                     slot: bool = False, granted: bool = False) -> Optional[Pending]:
        """A new pending transaction with a free seq (:mod:`.seqs`); ``threaded``: waited for by a thread.
        ``slot``: it takes one of the session's slots (``granted``: it has one already); None when no
        slot is free, or no seq (a ``C``: the device may remember every one), the slot given back."""
        with self.lock:
            if slot and not granted and not self.slots.take():
                return None
            seq = self.rules.draw(type, id, self._busy)
            if seq is None:
                w = self.slots.give_back() if slot else None
            else:
                # a large payload goes out as fragments, and so does every retry (PROTOCOL.md 12)
                p = Pending(type, seq, id, self.core.link.encode(type, seq, id, payload),
                            loop=None if threaded else self.loop)
                p.payload, p.drawn, p.slot = payload, self.rules.draws, slot
                self.pending[(seq, id)] = p
                return p
        if w is not None:
            w.wake()
        return None

    def unregister(self, p: Pending) -> None:
        w = None
        with self.lock:
            if self.pending.get((p.seq, p.id)) is p:
                del self.pending[(p.seq, p.id)]
                self.rules.unanswered.ended((p.seq, p.id))
                if p.type == m.CONTROL and not p.acked:
                    self.rules.control_ended(p.seq)
                if p.slot:
                    p.slot = False
                    w = self.slots.give_back()
        if w is not None:
            w.wake()
        if not p.done():
            self.core.link.reassembler.abandon(p.seq, p.id)

    def _renew(self, p: Pending) -> None:
        """A retried R/J/S takes a new seq: what comes for the old one now finds nobody."""
        with self.lock:
            seq = self.rules.draw(p.type, p.id, self._busy)
            if seq is None or self.pending.get((p.seq, p.id)) is not p:
                if seq is not None:
                    self.rules.unanswered.ended((seq, p.id))  # drawn, never sent
                return
            old = p.seq
            del self.pending[(old, p.id)]
            self.rules.unanswered.ended((old, p.id))
            p.seq, p.drawn = seq, self.rules.draws
            p.wire = self.core.link.encode(p.type, seq, p.id, p.payload)
            self.pending[(seq, p.id)] = p
        self.core.link.reassembler.abandon(old, p.id)

    # ---------------------------------------------------------------------- waiting turns

    def _enqueue(self, threaded: bool) -> Waiter:
        w = Waiter(None if threaded else self.loop)
        with self.lock:
            if self.slots.take():
                w.granted = True
            else:
                self.slots.waiting.append(w)
        return w

    def _leave(self, w: Waiter) -> None:
        with self.lock:
            nxt = self.slots.leave(w)
        if nxt is not None:
            nxt.wake()

    def wait_turn_thread(self) -> None:
        """(Threads) wait asleep until a slot is this caller's; raises what failed the session meanwhile."""
        w = self._enqueue(True)
        assert w.event is not None
        try:
            while not w.granted and w.error is None:
                w.event.wait(1.0)
                if self.core.closed and not w.granted:
                    raise HubwireError("session closed")
        except BaseException:
            self._leave(w)
            raise
        if w.error is not None:
            raise w.error

    async def wait_turn(self) -> None:
        """(Coroutines) as :meth:`wait_turn_thread`."""
        w = self._enqueue(False)
        try:
            if not w.granted:
                await w.fut  # type: ignore[misc]
        except BaseException:
            self._leave(w)
            raise
        if w.error is not None:
            raise w.error

    # --------------------------------------------------------------------------- sending

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
        """Send again: a ``C`` with its seq (the device's duplicate memory), anything else with a new one."""
        with self.lock:
            self.core.stats.retries += 1
        if p.type != m.CONTROL:
            self._renew(p)
        self.transmit(p)

    def silence(self, p: Pending, what: str) -> None:
        """No answer within the retry timeout: send again, or Timeout after ``tries``.
        A large answer still coming in (a fragment since the last send) is waited for instead."""
        if self.core.link.reassembler.receiving(p.seq, p.id, p.sent_at):
            p.sent_at = time.monotonic()
            return
        if p.tries >= self.tries_for(p):
            raise Timeout(f"no answer from the device on {self.core.url}{' for ' + what if what else ''} "
                          f"after {p.tries} tries{self.core.link.blocked_hint()}")
        self.retry(p)

    def tries_for(self, p: Pending) -> int:
        """``tries``, and for a control in fragments one more per fragment: the device keeps what each
        try brought (PROTOCOL.md 12.4), so a long value needs tries in proportion to its length."""
        if p.max_tries:
            return p.max_tries
        frames = p.wire.count(0)
        return int(self.core.tries) + (frames if p.type == m.CONTROL and frames > 1 else 0)

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
            self.rules.unanswered.answered((f.seq, f.id))
            if p is None or p.done():
                self.core.stats.unmatched_answers += 1
                return False
            if f.type != m.NAK:
                if p.type == m.CONTROL:
                    p.acked = True
                    self.rules.control_answered(p.seq)
                else:
                    self.rules.other_answered(p.drawn)
            elif p.type != m.CONTROL and f.payload[:1] != _NOT_LINKED:
                self.rules.other_answered(p.drawn)  # refused after the device took it in (4.4)
            p.resolve(f)
        return True

    def fail_all(self, exc: BaseException) -> None:
        with self.lock:
            for p in self.pending.values():
                if not p.done():
                    p.fail(exc)
            waiters = self.slots.fail_all(exc)
        for w in waiters:
            w.wake()

    async def transact(self, type: int, id: int, payload: bytes = b"", *, timeout: Optional[float] = None,
                       what: str = "", tries: Optional[int] = None) -> Frame:
        """Send one transaction and return its answer (ACK, ``r``, ``J``); raise NakError on NAK.

        Retries every ``retry_timeout`` up to ``tries`` times (Timeout after; ``tries`` given: that
        many, each ``timeout`` / the session's tries long). Controls (``C``) are stop-and-wait: they
        run alone. Beyond ``max_in_flight`` transactions it waits its turn.
        """
        core = self.core
        retry = core.retry_timeout if timeout is None else timeout / core.tries
        gate = self.gate.exclusive() if type == m.CONTROL else self.gate.shared()
        async with gate:
            await core.check_ready(max(core.connect_timeout, retry * core.tries))
            while type == m.CONTROL and not self.claim_control("user"):
                await core.changes(retry)  # the hub's bind report is out: a round trip at most
            # A thread's control (the synchronous API has a gate of its own) runs alone too: an R,
            # J or S between its tries would end the device's memory of it (PROTOCOL.md 4.1).
            while type != m.CONTROL and self.control_owner == "user":
                await core.changes(retry)
            try:
                p = self.try_register(type, id, payload, slot=True)
                if p is None:
                    p = await self._register_later(type, id, payload, retry, what)
                p.max_tries = tries or 0
                try:
                    self.transmit(p)
                    return await self._answer(p, retry, what)
                finally:
                    self.unregister(p)
            finally:
                if type == m.CONTROL:
                    self.release_control()

    async def _register_later(self, type: int, id: int, payload: bytes, retry: float, what: str) -> Pending:
        await self.wait_turn()
        p = self.try_register(type, id, payload, slot=True, granted=True)
        if p is None:  # a C with every seq possibly remembered: a read shows the device moved on
            await self.transact_probe(retry, what)
            await self.wait_turn()
            p = self.try_register(type, id, payload, slot=True, granted=True)
            if p is None:
                raise no_seq(type, what, self.core.url)
        return p

    async def transact_probe(self, retry: float, what: str) -> None:
        """Read the board id (``R`` id 0): its answer ends the device's memory of every control."""
        p = self.register(m.REQUEST, 0, b"")
        try:
            self.transmit(p)
            try:
                await self._answer(p, retry, what)
            except NakError:
                pass  # a board without an id: refused after it was taken in, as good
        finally:
            self.unregister(p)

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
