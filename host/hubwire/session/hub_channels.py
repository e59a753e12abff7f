"""The hub's own channels in one session (PROTOCOL.md §10): answering the device's ``R``/``C``/``J``,
the bind report (``C`` id 0) and the queue of hub events (``!``) to the device.

- Device transactions: :mod:`.hub_answers` (answers, duplicate device controls, handlers).
- The bind report goes out every time the session becomes ready and whenever the hub's channel set
  changes; it is a ``C`` so it never overlaps an application's ``C`` (the device's duplicate
  detection for controls stays exact: :meth:`Transactions.claim_control`).
- Hub events: one queue per device session object, one event unacked at a time, the head retried
  every retry interval while linked, without limit, with the same seq; the queue survives link
  loss and device reboots.
- Seqs come from the session's transactions (:meth:`Transactions.hold`): a new event never carries
  the seq of the last one the device acknowledged or of the one before it, a new bind report none
  the device may remember for a control (PROTOCOL.md 4.1), and neither shares a (seq, id) with
  anything else in flight. Sent only once the device acked the bind report in this pairing of
  device and hub sessions, and only for names it listed with access ``e``.
- Persistence (optional): a ``keeper`` with ``add(name, payload) -> token`` (called as notify()
  queues an event; it may refuse by raising), ``sent(token, seq, id)`` (the event's seq and id,
  before it first goes out; if it raises, the event waits and is tried again), ``done(token, acked)`` (the device answered it: ``acked`` its seq on
  ACK, else None) and ``nonce(n)`` (the link drew a new hub nonce). Events a keeper kept from an
  earlier session go back in the queue with :meth:`HubSide.restore`; the one in flight when that
  session ended goes out with its seq and id again when the session is resumed (:mod:`.resume`).
"""
from __future__ import annotations

import asyncio
import logging
import threading
from collections import deque
from typing import Any, Deque, List, Optional, Tuple

from ..descriptor import Channel, Descriptor
from ..errors import HubChannelError, HubwireError
from ..hub import HubChannel, HubChannels, bind_status
from ..text import clip
from ..wire import messages as m
from ..wire.frame import Frame
from ..wire.messages import NakCode
from .hub_answers import HubAnswers
from .resume import HubSession

__all__ = ["HubSide", "HUB_EVENT_QUEUE_LIMIT", "BIND_REPORT_VERSION"]

log = logging.getLogger("hubwire")

#: hub events waiting for one device; notify() raises beyond it
HUB_EVENT_QUEUE_LIMIT = 4096
#: first byte of the bind report's payload
BIND_REPORT_VERSION = 1
#: seconds before a bind report nobody answered is sent again (meanwhile application writes may go)
BIND_PAUSE = 0.5


class _Queued:
    __slots__ = ("name", "payload", "seq", "id", "token")

    def __init__(self, name: str, payload: bytes, token: Any = None) -> None:
        self.name = name
        self.payload = payload
        self.seq: Optional[int] = None  # drawn at the first send, kept for every retry
        self.id = 0
        self.token = token  # the keeper's handle, if any


class HubSide:
    """The hub channels of one :class:`SessionCore`: ``core`` provides ``loop``, ``link``, ``tx``,
    ``stats``, ``dispatch``, ``decodable()``, ``is_ready()`` and ``retry_timeout``."""

    def __init__(self, core: Any, channels: HubChannels) -> None:
        self.core = core
        self.loop: asyncio.AbstractEventLoop = core.loop
        self.channels = channels
        self.queue: Deque[_Queued] = deque()
        self._lock = threading.Lock()
        #: (device nonce, hub nonce) the device acked a bind report for
        self.bound_key: Optional[Tuple[int, int]] = None
        #: the statuses of the last bind report sent (hub id k at index k-1)
        self.statuses: Tuple[int, ...] = ()
        self._bind: Optional[Tuple[int, bytes]] = None  # (seq, payload) outstanding
        self._bind_sends = 0
        self._bind_later: Optional[asyncio.TimerHandle] = None
        self._bind_wanted = False
        self._head_out = False  # the head event is sent and unanswered
        self._timer: Optional[asyncio.TimerHandle] = None
        #: optional persistence of the queue (see the module docs)
        self.keeper: Any = None
        self._probe: Optional["asyncio.Task[None]"] = None  # a read that lets controls be numbered again
        #: (token, seq, id) of the event a resumed session had in flight (session/resume.py)
        self.resumed_head: Optional[Tuple[Any, int, int]] = None
        #: answers the device's own R / C / J
        self.answers = HubAnswers(core, channels)
        self._noted = ""  # the unbound hub channels last logged (each set once)
        channels.add_listener(self)

    # ----------------------------------------------------------------------- declarations

    def hub_changed(self, hc: HubChannel, removed: bool) -> None:
        """A declaration changed (any thread): refuse one the connected device expects otherwise,
        then report the new binding."""
        desc = self.core.descriptor
        if not removed and desc is not None:
            for exp in desc.hub:
                if exp.name == hc.name:
                    code = bind_status(exp, hc)
                    if code:
                        raise HubChannelError(mismatch(exp, hc, code, desc.name))
        self.loop.call_soon_threadsafe(self.rebind)

    def expected(self, name: str) -> Optional[Channel]:
        """The hub channel ``name`` as the connected device declares it (None: unknown yet, or none)."""
        desc = self.core.descriptor
        return None if desc is None else next((c for c in desc.hub if c.name == name), None)

    def check_all(self, desc: Descriptor) -> None:
        """Raise HubChannelError naming every hub channel the device uses that the hub lacks or
        declares otherwise (connect() with channels declared beforehand; those typed by a Python
        ``int`` take the device's integer type first)."""
        for exp in desc.hub:
            self.channels.fit(exp)
        bad = [mismatch(exp, self.channels.get(exp.name), code, desc.name)
               for exp in desc.hub for code in (bind_status(exp, self.channels.get(exp.name)),) if code]
        if bad:
            raise HubChannelError("; ".join(bad) + HOW_TO_PROVIDE)

    def rebind(self) -> None:
        self._bind_wanted = True
        self.kick()

    def close(self) -> None:
        self.channels.remove_listener(self)
        if self._bind_later is not None:
            self._bind_later.cancel()
        if self._probe is not None:
            self._probe.cancel()
        self.link_down()

    # ------------------------------------------------------------------------- the pump

    def on_ready(self) -> None:
        """The session became ready (discovered, or the link is back): report the binding again."""
        self.rebind()

    def link_down(self) -> None:
        """Nothing is answered while the link is down: stop retrying (the head keeps its seq)."""
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
        if self._bind is not None:
            self.core.tx.let_go(self._bind[0], 0, None)
            self._bind = None
            self._bind_wanted = True
            self.core.tx.release_control()
        self._head_out = False

    def _key(self) -> Optional[Tuple[int, int]]:
        h = self.core.link.device_hello
        return None if h is None else (h.nonce, self.core.link.nonce)

    def kick(self) -> None:
        """Send what is due: the bind report first, then the head event."""
        core = self.core
        desc = core.decodable()
        if desc is None or not core.is_ready() or not core.link.linked or not desc.hub:
            return
        if self._bind_wanted and self._bind is None:
            if not core.tx.claim_control("hub"):
                return  # an application's C is in flight: kicked again when it ends
            self._bind_wanted = False
            self.statuses = tuple(bind_status(exp, self.channels.get(exp.name)) for exp in desc.hub)
            payload = m.BindReport(BIND_REPORT_VERSION, self.statuses).pack()
            h = core.link.device_hello
            if len(payload) > h.max_payload:
                core.tx.release_control()
                log.error("hubwire: %d hub channels do not fit the bind report %s accepts", len(desc.hub), desc.name)
                return
            seq = core.tx.hold(m.CONTROL, 0)
            if seq is None:  # the device may remember every seq for a control: a read ends that
                self._bind_wanted = True
                core.tx.release_control()
                if self._probe is None:
                    self._probe = self.loop.create_task(self._read_board_id())
                return
            self._bind, self._bind_sends = (seq, payload), 0
            core.stats.binds_sent += 1
            self._note_unbound(desc)
            self._send_bind()
        if self.bound_key == self._key() and not self._head_out:
            self._send_head(desc)
        self._arm()

    def _note_unbound(self, desc: Descriptor) -> None:
        """Say once which hub channels the device uses that this program does not offer as it
        expects: a warning when it offers some (a mistake), at info level when it offers none (a
        command that only reads or writes the board's own channels)."""
        failed = [f"{exp.name}: {m.nak_name(s)}" for exp, s in zip(desc.hub, self.statuses) if s]
        text = clip(", ".join(failed), 200)
        if not failed or text == self._noted:
            return
        self._noted = text
        (log.warning if len(self.channels) else log.info)(
            "hubwire: %s uses hub channels the hub does not offer as it expects: %s", desc.name, text)

    async def _read_board_id(self) -> None:
        try:
            await self.core.tx.transact_probe(self.core.retry_timeout, "board id")
        except HubwireError:
            pass  # the link is down or the device deaf: kicked again when it is back
        finally:
            self._probe = None
        self.kick()

    def _send_bind(self) -> None:
        assert self._bind is not None
        seq, payload = self._bind
        self._bind_sends += 1
        self.core.link.send_frame(m.CONTROL, seq, 0, payload)

    def _bind_unanswered(self) -> None:
        """``tries`` sends without an answer: give the application's writes their turn and try again
        a little later (the device may be busy or deaf; the report never blocks the link for long)."""
        if self._bind is not None:
            self.core.tx.let_go(self._bind[0], 0, None)
        self._bind = None
        self.core.tx.release_control()
        if self._bind_later is None:
            self._bind_later = self.loop.call_later(BIND_PAUSE, self._bind_again)

    def _bind_again(self) -> None:
        self._bind_later = None
        self.rebind()

    def _send_head(self, desc: Descriptor) -> None:
        while self.queue:
            ev = self.queue[0]
            exp = next((c for c in desc.hub if c.name == ev.name), None)
            if exp is None or "e" not in exp.access:
                if ev.seq is not None:  # (its seq stays skipped: the device may remember it)
                    self.core.tx.let_go(ev.seq, ev.id, None)
                self._done(self.queue.popleft())
                self.core.stats.hub_events_skipped += 1
                log.warning("hubwire: %s takes no event %s: not sent", desc.name, clip(ev.name))
                continue
            if ev.seq is not None and ev.id != exp.id:  # renumbered by a new descriptor
                self.core.tx.let_go(ev.seq, ev.id, None)
                ev.seq = None
            if ev.seq is None:
                ev.seq = self.core.tx.hold(m.EVENT, exp.id)
                if ev.seq is None or not self._kept(ev, ev.seq, exp.id):
                    ev.seq = None
                    self._kick_in_a_while()  # no seq free: every one in use (bounded, so not for long)
                    return
            ev.id = exp.id
            self.core.link.send_frame(m.EVENT, ev.seq, ev.id, ev.payload)
            self._head_out = True
            return

    def _kept(self, ev: _Queued, seq: int, id: int) -> bool:
        """The keeper stores the seq before the event first goes out (session/resume.py); if it
        cannot, the event waits: a restarted hub must know every seq the device may remember."""
        if self.keeper is None or ev.token is None:
            return True
        try:
            self.keeper.sent(ev.token, seq, id)
            return True
        except Exception as e:  # noqa: BLE001 - a full disk: tried again a retry interval later
            self.core.tx.let_go(seq, id, None)
            log.error("hubwire: event %s not sent: its seq was not kept: %s", clip(ev.name), clip(str(e), 200))
            return False

    def _arm(self) -> None:
        if self._timer is None and (self._bind is not None or self._head_out):
            self._timer = self.loop.call_later(self.core.retry_timeout, self._retry)

    def _retry(self) -> None:
        self._timer = None
        if not self.core.link.linked:
            return
        if self._bind is not None:
            if self._bind_sends >= self.core.tries:
                self._bind_unanswered()
            else:
                self.core.stats.bind_retries += 1
                self._send_bind()
        if self._head_out and self.queue:
            self.core.stats.hub_event_retries += 1
            ev = self.queue[0]
            self.core.link.send_frame(m.EVENT, ev.seq or 0, ev.id, ev.payload)
        self._arm()

    def on_answer(self, f: Frame) -> bool:
        """An ACK/NAK of the bind report or of the head event; False if it answers neither."""
        code = f.payload[0] if f.type == m.NAK and f.payload else 0
        if self._bind is not None and f.id == 0 and f.seq == self._bind[0]:
            self.core.tx.let_go(f.seq, 0, f)
            self._bind = None
            self.core.tx.release_control()
            if f.type == m.ACK:
                self.bound_key = self._key()
            elif code == NakCode.NOT_LINKED:
                self._relink()
                self._bind_wanted = True  # sent again (a new seq) a retry interval later
                self._kick_in_a_while()
                return True
            else:
                log.warning("hubwire: device refused the bind report: %s", m.nak_name(code))
            self._kick_later()
            return True
        if self._head_out and self.queue and f.seq == self.queue[0].seq and f.id == self.queue[0].id:
            self._head_out = False
            if code == NakCode.NOT_LINKED:
                self._relink()  # not delivered: the head stays, sent again with its seq
                self._kick_in_a_while()
                return True
            ev = self.queue.popleft()
            self.core.tx.let_go(f.seq, f.id, f)
            self._done(ev, f.type == m.ACK)
            if not self.queue:
                self.core.wake()  # whoever waits for the queue to empty (wait_notified)
            if f.type == m.ACK:
                self.core.stats.hub_events_delivered += 1
            else:
                self.core.stats.hub_events_refused += 1
                log.warning("hubwire: device refused event %s: %s", clip(ev.name), m.nak_name(code))
            self._kick_later()
            return True
        return False

    def _relink(self) -> None:
        """The device lost the link on its side: say hello (its answer links it again)."""
        self.core.stats.not_linked += 1
        self.core.link.send_hello(reply=False)

    def _kick_in_a_while(self) -> None:
        if self._timer is not None:
            self._timer.cancel()
        self._timer = self.loop.call_later(self.core.retry_timeout, self._retry_kick)

    def _retry_kick(self) -> None:
        self._timer = None
        self.kick()

    def _kick_later(self) -> None:
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
        self.kick()

    # ----------------------------------------------------------------------------- events

    def notify(self, name: str, value: Any) -> None:
        """Queue event ``name`` for the device (any thread); raises at once for a name that is not a
        hub event, a value that does not fit, or a device that takes no such event."""
        if self.core.closed:
            raise HubwireError("the session is closed: no event can reach the device any more")
        hc = self.channels[name]
        if not hc.is_event:
            raise HubChannelError(f"hub channel {name!r} is not an event (declare it with hub.event())")
        desc = self.core.descriptor
        if desc is not None:
            exp = next((c for c in desc.hub if c.name == name), None)
            if exp is None or "e" not in exp.access:
                raise HubChannelError(f"{desc.name} takes no hub event {name!r}")
        payload = hc.channel.codec.encode(hc.channel.check(value))
        h = self.core.link.device_hello
        if h is not None and len(payload) > h.max_payload:
            raise HubChannelError(f"event {name!r} is {len(payload)} bytes, the device accepts {h.max_payload}")
        with self._lock:
            if len(self.queue) >= HUB_EVENT_QUEUE_LIMIT:
                raise HubwireError(f"{HUB_EVENT_QUEUE_LIMIT} hub events wait for the device already")
            token = None if self.keeper is None else self.keeper.add(name, payload)
            self.queue.append(_Queued(name, payload, token))
        self.loop.call_soon_threadsafe(self.kick)

    def resume(self, hs: Optional[HubSession]) -> None:
        """Go on from where an earlier run of the hub left this hub session, if ``hs`` says it did."""
        if hs is not None and hs.resumed:
            self.core.tx.resume(hs.acked, None if hs.head is None else hs.head[1:])
            self.resumed_head = hs.head

    def restore(self, kept: List[Tuple[Any, str, bytes]]) -> None:
        """Queue (token, name, payload) events a keeper kept from an earlier session, ahead of any
        new one (the keeper has them already). The first one keeps its seq and id if it is the
        event a resumed session had in flight (call on the loop)."""
        head, self.resumed_head = self.resumed_head, None
        with self._lock:
            items = [_Queued(n, p, t) for t, n, p in kept]
            if head is not None and items and items[0].token == head[0] and not self.queue:
                items[0].seq, items[0].id = head[1], head[2]
            elif head is not None:
                self.core.tx.let_go(head[1], head[2], None)  # gone meanwhile: its seq stays skipped
            self.queue.extendleft(reversed(items))
        self.loop.call_soon_threadsafe(self.kick)

    def nonce_changed(self) -> None:
        """The link drew a new hub nonce: the keeper keeps it before the hello goes out."""
        if self.keeper is not None:
            self.keeper.nonce(self.core.link.nonce)

    def _done(self, ev: _Queued, acked: bool = False) -> None:
        if self.keeper is not None and ev.token is not None:
            self.keeper.done(ev.token, ev.seq if acked else None)


#: what a connect() missing hub channels says to do
HOW_TO_PROVIDE = (". Declare them on a hubwire.HubChannels given to connect(..., hub=hub) (hub.provide, hub.accept, "
                  "hub.action, hub.event), or pass connect(..., hub_later=True) and declare them on the device "
                  "once connected (dev.provide, dev.accept, dev.action, dev.event)")


def mismatch(exp: Channel, hc: Optional[HubChannel], code: int, device: str) -> str:
    """Why hub channel ``exp`` of ``device`` is not bound, in words."""
    want = {"r": "reads", "w": "writes", "c": "calls", "e": "receives events of"}
    verbs = " and ".join(want[a] for a in exp.access if a in want)
    if hc is None:
        return f"{device} {verbs} hub channel {exp.name!r} ({exp.type_name}), which the hub does not declare"
    if code == NakCode.BAD_LENGTH:
        return (f"{device} {verbs} hub channel {exp.name!r} as {exp.type_name}, the hub declares it "
                f"{hc.channel.type_name}")
    return f"{device} {verbs} hub channel {exp.name!r}, the hub declares it {_access_words(hc)}"


def _access_words(hc: HubChannel) -> str:
    words: List[str] = []
    for flag, word in ((hc.readable, "readable"), (hc.writable, "writable"), (hc.callable, "callable"),
                       (hc.is_event, "an event")):
        if flag:
            words.append(word)
    return " and ".join(words)
