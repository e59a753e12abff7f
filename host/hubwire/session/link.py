"""The link layer of a session (PROTOCOL.md §4): transport, framing, hello handshake, heartbeats,
loss detection and re-opening a port that went away.

Everything here runs on the session's event loop and is driven by the transport's callbacks and
by loop timers: a hello every 100 ms while unlinked, a heartbeat a little more often than every
``heartbeat_ms`` while linked, a loss check due 4 device heartbeat intervals after the last frame
heard, and re-opening a vanished port with backoff (0.1 s doubling to 2 s). No timer runs for
nothing: while linked there is no hello timer, while unlinked no heartbeat or loss timer.

Loss detection on a noisy line (docs/RELIABILITY.md, "Heavy noise"). A heartbeat sent exactly
every interval lands on the peer's deadline (4 intervals of silence) with its fourth beat, so only
three of them count; the hub therefore sends its own on a fixed grid at 15/16 of the interval it
announced, and all four fall inside the device's window. The device's heartbeats keep their
interval, so the hub makes up for its fourth: once the device has been silent for 2 intervals the
hub probes with a hello every half interval (a linked device answers a hello at once, and a hello
is no transaction: duplicate detection is untouched). A dead link answers nothing, so it is still
declared lost 4 intervals after the last frame; a healthy link never probes.
"""
from __future__ import annotations

import asyncio
import enum
import logging
import os
import time
from typing import Any, List, Optional

from ..transport import Transport
from ..wire import messages as m
from ..wire.frame import Frame, FrameDecoder, encode_frame
from .sketch_hints import LoopWatch, PrintedText
from .fragments import Reassembler, accepted, encode_message
from .pacer import Pacer
from .records import Stats

__all__ = ["Link", "HelloOutcome", "HELLO_INTERVAL", "HUB_MAX_PAYLOAD"]

log = logging.getLogger("hubwire")

HELLO_INTERVAL = 0.1
HUB_MAX_PAYLOAD = 255
REOPEN_FIRST = 0.1
REOPEN_MAX = 2.0
#: the link is lost after this many of the device's heartbeat intervals without a frame
LOSS_HEARTBEATS = 4
#: a device silent this long (seconds) after the port opened, then saying hello, has just started
START_SILENCE = 0.5
#: the hub's heartbeats go out at this fraction of its announced interval (see the module docstring)
HEARTBEAT_LEAD = 15 / 16
#: after this many silent device intervals the hub probes with a hello ...
PROBE_AFTER = 2
#: ... and again every this many intervals until the link is lost or heard again
PROBE_EVERY = 0.5
#: an announcement this many hub intervals after the hub answered the last one left before the
#: answer reached the device: the same loss (a new one takes LOSS_HEARTBEATS silent intervals)
ANNOUNCE_REPEAT = 2


def new_nonce() -> int:
    """A hub session nonce: random per connection, never 0 (os.urandom: distinct across forks)."""
    return int.from_bytes(os.urandom(4), "little") or 1


class HelloOutcome(enum.Enum):
    """What a device hello meant for the link."""

    FIRST = "first"          # the first hello of this session
    REBOOT = "reboot"        # a new device session (nonce or descriptor changed)
    RESTORED = "restored"    # the same device session, after the link was lost
    ANNOUNCE = "announce"    # an unsolicited hello while linked: the device dropped the link
    SAME = "same"            # nothing new (a reply to our hello)
    VERSION = "version"      # a protocol version this hub does not speak


class Link:
    """Transport + framing + handshake + heartbeats of one session; reports to ``owner``.

    ``owner`` provides ``handle(frame, now)`` (every valid frame but hellos and heartbeats),
    ``on_hello(outcome)``, ``link_down(why)``, ``port_down()`` and ``hub_nonce_changed()``.
    """

    def __init__(self, transport: Transport, loop: asyncio.AbstractEventLoop, stats: Stats,
                 heartbeat_ms: int, owner: Any, nonce: Optional[int] = None) -> None:
        self.transport = transport
        self.loop = loop
        #: every write goes through it: a large message's fragments are paced on a fast line
        self.pacer = Pacer(transport, loop)
        self.stats = stats
        self.heartbeat_ms = heartbeat_ms
        self.owner = owner
        #: drawn here unless given (a hub resuming its session after a restart: session/resume.py)
        self.nonce = new_nonce() if nonce is None else nonce
        self.decoder = FrameDecoder(HUB_MAX_PAYLOAD)
        #: large messages from the device come in fragments (PROTOCOL.md 12)
        self.reassembler = Reassembler(self.decoder)
        self.linked = False
        self.closed = False
        self.device_hello: Optional[m.Hello] = None
        self.peer_hb: Optional[m.Heartbeat] = None
        self.peer_hb_at: Optional[float] = None
        self.peer_hb_count = 0
        self.rejected_version = 0
        #: device hellos heard (threads waiting for a re-link watch it)
        self.hello_count = 0
        self.last_rx = 0.0
        self.printed = PrintedText(str(transport.url))
        self.opened_at = 0.0
        #: the device's first frame came long after the port opened and its first heartbeat counts from
        #: its boot: it started then (an Uno restarts when its port opens, and its bootloader waits),
        #: rather than answering at once as a running one does
        self.started_on_open = False
        self._silent_start = False
        self.loop_watch = LoopWatch()
        self._peer_hb_ms = 250
        self._hb_counter = 0
        self._last_hb_tx = 0.0
        #: ms between the hub's last two heartbeats, as it sent them (what its last heartbeat said)
        self.sent_since_ms = 0
        self._next_hb = 0.0
        self._beats_since_up = 0
        #: hellos sent to a silent device while linked (loss detection's probes)
        self.probes = 0
        self._reopen_delay = REOPEN_FIRST
        self._hello_waiters: List["asyncio.Future[None]"] = []
        #: a device announcement was answered by asking for its hello again (PROTOCOL.md 7.1): its
        #: answer stands for the announcement
        self._announce_pending = False
        self._answered_at: Optional[float] = None  # the hub's last answer to an announcement
        self._hello_timer: Optional[asyncio.TimerHandle] = None
        self._hb_timer: Optional[asyncio.TimerHandle] = None
        self._loss_timer: Optional[asyncio.TimerHandle] = None
        self._reopen_timer: Optional[asyncio.TimerHandle] = None

    # ---------------------------------------------------------------------------- transport

    def open(self) -> None:
        """Open the transport (OSError if it cannot be) and start saying hello."""
        self._open_transport()
        self.opened_at = time.monotonic()
        self._hello_tick()

    def _open_transport(self) -> None:
        self.transport.open(self.loop, self._on_data, self._on_port_lost)

    def close(self) -> None:
        self.closed = True
        self.linked = False
        for t in (self._hello_timer, self._hb_timer, self._loss_timer, self._reopen_timer):
            if t is not None:
                t.cancel()
        self.pacer.close()
        self.transport.close()

    def send(self, data: bytes) -> None:
        self.pacer.write(data)

    def send_frame(self, type: int, seq: int, id: int, payload: bytes = b"") -> None:
        """Send one message: one frame, or its fragments when the device cannot take it in one."""
        self.pacer.write(self.encode(type, seq, id, payload))

    def peer_limit(self) -> int:
        """The largest payload the device accepts in one frame (its hello's, within 16..255)."""
        h = self.device_hello
        return min(HUB_MAX_PAYLOAD, accepted(h.max_payload if h is not None else None))

    def encode(self, type: int, seq: int, id: int, payload: bytes = b"") -> bytes:
        """Wire bytes of a message for this device: one frame or all its fragments back to back."""
        return encode_message(type, seq, id, payload, self.peer_limit())

    def _on_data(self, data: bytes) -> None:
        frames = self.decoder.feed(data)
        if self.decoder.text_lines != self.printed.seen:  # a sketch printing on the line
            self.printed.check(self.decoder, self.linked, time.monotonic())
        if not frames:
            return
        now = time.monotonic()
        self.loop_watch.heard(now, self.last_rx, self._peer_hb_ms)
        if not self.last_rx:
            self._silent_start = now - self.opened_at >= START_SILENCE
        self.last_rx = now
        handle = self.owner.handle
        for f in frames:
            if f.type == m.FRAGMENT:
                whole = self.reassembler.feed(f)
                if whole is None:
                    continue
                f = whole  # handled as if it had come in one frame
            t = f.type
            try:
                if t == m.HEARTBEAT:
                    self._on_heartbeat(f, now)
                elif t == m.HELLO:
                    self._on_hello(f, now)
                else:
                    handle(f, now)
            except Exception:  # noqa: BLE001 - never let one frame stop the link
                log.exception("hubwire: error handling %r", f)

    def _on_port_lost(self, err: BaseException) -> None:
        log.info("hubwire: port %s failed: %s", self.transport.url, err)
        self.decoder.reset()
        self.reassembler.reset()
        self.owner.port_down()
        self._reopen_delay = REOPEN_FIRST
        self._schedule_reopen()

    def _schedule_reopen(self) -> None:
        if not self.closed:
            self._reopen_timer = self.loop.call_later(self._reopen_delay, self._try_reopen)

    def _try_reopen(self) -> None:
        self._reopen_timer = None
        if self.closed:
            return
        try:
            self._open_transport()
        except OSError:
            self._reopen_delay = min(self._reopen_delay * 2, REOPEN_MAX)
            self._schedule_reopen()
            return
        self.stats.port_reopens += 1
        # A re-opened port is a new connection: a new hub nonce (PROTOCOL.md 4.2). A board that lost
        # power mixes it into its own nonce, which is how its new boot is told from the old one.
        self.nonce = new_nonce()
        self.owner.hub_nonce_changed()  # (kept before the hello goes out)
        self.decoder.reset()
        self.reassembler.reset()
        self._hello_tick()

    # -------------------------------------------------------------------------------- timers

    def send_hello(self, reply: bool) -> None:
        dhash, dlen = self.owner.hub_descriptor_id()  # the hub's own channels (PROTOCOL.md 10.5)
        h = m.Hello(m.PROTOCOL_VERSION, m.FLAG_SEQ_RULES | (m.FLAG_REPLY if reply else 0), self.nonce, HUB_MAX_PAYLOAD, self.heartbeat_ms,
                    dhash, dlen)
        # a lone 00 first ends whatever noise the device may have collected (an empty frame is
        # ignored by the receiver, PROTOCOL.md 1), so this hello is not lost with it
        self.send(b"\x00" + encode_frame(m.HELLO, 0, 0, h.pack()))
        if not reply:
            self.owner.tx.hello_sent()  # its answer shows what the device has answered (session/seqs.py)

    def _hello_tick(self) -> None:
        """Say hello now and every HELLO_INTERVAL until linked (or the port is gone)."""
        if self._hello_timer is not None:
            self._hello_timer.cancel()
        self._hello_timer = None
        if self.linked or self.closed or not self.transport.is_open or self.owner.fatal is not None:
            return
        self.send_hello(reply=False)
        self._hello_timer = self.loop.call_later(HELLO_INTERVAL, self._hello_tick)

    def _up(self) -> None:
        """Linked: heartbeats from now on, and watch for silence."""
        self.linked = True
        self._beats_since_up = 0
        if self._hello_timer is not None:
            self._hello_timer.cancel()
            self._hello_timer = None
        self._next_hb = 0.0
        self._heartbeat_tick()
        if self._loss_timer is None:
            first = min(PROBE_AFTER * self._peer_hb_ms / 1000.0, self._loss_after() + 0.001)
            self._loss_timer = self.loop.call_later(first, self._loss_check)

    def down(self) -> None:
        """The link is lost: stop heartbeats, say hello again."""
        self.linked = False
        self._hb_counter = 0
        for t in (self._hb_timer, self._loss_timer):
            if t is not None:
                t.cancel()
        self._hb_timer = self._loss_timer = None
        self._hello_tick()

    def blocked_hint(self) -> str:
        """What shows a blocked loop() on the device (sketch_hints.LoopWatch), or empty."""
        return self.loop_watch.hint(self.peer_hb, self._peer_hb_ms)

    def blocked(self) -> bool:
        return self.loop_watch.gap_ms(self.peer_hb, self._peer_hb_ms) is not None

    def _loss_after(self) -> float:
        return LOSS_HEARTBEATS * self._peer_hb_ms / 1000.0

    def _loss_check(self) -> None:
        """Lost after LOSS_HEARTBEATS silent device intervals; probing from PROBE_AFTER on."""
        self._loss_timer = None
        if not self.linked or self.closed:
            return
        beat = self._peer_hb_ms / 1000.0
        silent = time.monotonic() - self.last_rx
        limit = self._loss_after()
        if silent > limit:
            self.owner.link_down(f"nothing heard for {silent * 1000:.0f} ms")
            return
        due = PROBE_AFTER * beat
        if silent >= due - 0.001:
            self.probes += 1
            self.send_hello(reply=False)
            due = silent + PROBE_EVERY * beat
        self._loss_timer = self.loop.call_later(min(due, limit + 0.001) - silent, self._loss_check)

    def _heartbeat_tick(self) -> None:
        if self._hb_timer is not None:
            self._hb_timer.cancel()
        self._hb_timer = None
        if not self.linked or self.closed:
            return
        now = time.monotonic()
        period = self.heartbeat_ms / 1000.0 * HEARTBEAT_LEAD
        # a fixed grid: a late tick does not push the next ones later (unless it is a whole period late)
        self._next_hb = self._next_hb + period if self._next_hb + period > now else now + period
        since = 0 if self._hb_counter == 0 else int((now - self._last_hb_tx) * 1000)
        self._hb_counter = (self._hb_counter + 1) & 0xFFFF
        d = self.decoder
        hb = m.Heartbeat(self._hb_counter, min(since, 0xFFFF), d.crc, d.overflow, d.dropped)
        self._last_hb_tx = now
        self.sent_since_ms = hb.since_ms
        self.send_frame(m.HEARTBEAT, self._hb_counter & 0xFF, 0, hb.pack())
        self._hb_timer = self.loop.call_later(self._next_hb - now, self._heartbeat_tick)

    # ------------------------------------------------------------------------------ frames in

    def _on_heartbeat(self, f: Frame, now: float) -> None:
        try:
            hb = m.Heartbeat.unpack(f.payload)
        except m.PayloadError:
            self.decoder.dropped += 1
            return
        prev, self.peer_hb = self.peer_hb, hb
        self.peer_hb_at = now
        self.peer_hb_count += 1
        if self.peer_hb_count == 1:  # a device's counter starts at 1 at boot (PROTOCOL.md 3.2)
            self.started_on_open = self._silent_start and hb.counter <= 2
        self._beats_since_up += 1
        fresh = prev is None or hb.counter != prev.counter  # not a duplicated frame
        if hb.since_ms == 0 and fresh and self._beats_since_up > 1 and self.linked:
            # the device's first heartbeat of a new link-up that we did not see: it dropped the
            # link and took one of our probes as the hello that brings it back
            self._up()
            self.owner.on_hello(HelloOutcome.ANNOUNCE)

    def _on_hello(self, f: Frame, now: float) -> None:
        outcome = self._hello_outcome(f)
        if outcome in (HelloOutcome.FIRST, HelloOutcome.REBOOT):
            self.loop_watch.started()
        if outcome is not None:
            self.owner.on_hello(outcome)

    def _hello_outcome(self, f: Frame) -> Optional[HelloOutcome]:
        try:
            h = m.Hello.unpack(f.payload)
        except m.PayloadError:
            self.decoder.dropped += 1
            return None
        if not h.is_device:
            self.decoder.dropped += 1  # our own hello echoed back (loopback) or another hub
            return None
        if h.version != m.PROTOCOL_VERSION:
            self.rejected_version = h.version
            return HelloOutcome.VERSION
        if not h.is_reply:
            if h.digest is None and h.max_payload >= m.Hello.SIZE_WITH_DIGEST:
                # It announced itself before it knew we take a hello with the descriptor digest
                # (after a reset it has not heard us yet): ask for its hello again instead of
                # answering, so discovery can trust its cache (PROTOCOL.md 7.1). A device that
                # predates the digest answers without one, and that answer is taken as it is.
                self.send_hello(reply=False)
                self._announce_pending = True
                return None
            now = time.monotonic()
            repeat = self._answered_at is not None and now - self._answered_at < ANNOUNCE_REPEAT * self.heartbeat_ms / 1000
            self._answered_at = now
            self.send_hello(reply=True)
        else:
            repeat = False
            self.owner.tx.hello_answered()
        announced, self._announce_pending = not h.is_reply or self._announce_pending, False
        prev, was_linked = self.device_hello, self.linked
        self.device_hello = h
        self._peer_hb_ms = h.heartbeat_ms or 250
        self.hello_count += 1
        for w in self._hello_waiters:
            if not w.done():
                w.set_result(None)
        self._hello_waiters.clear()
        if not h.flags & m.FLAG_SEQ_RULES and (prev is None or prev.nonce != h.nonce):
            log.warning("hubwire: the board on %s runs a Hubwire library older than its sequence rules "
                        "(PROTOCOL.md 4.1): in some traffic mixes an acknowledged message may be lost when "
                        "its 8-bit counter comes round; build the sketch again with this version of the "
                        "library", self.transport.url)
        if prev is None:
            self._up()
            return HelloOutcome.FIRST
        if prev.nonce != h.nonce or (prev.descriptor_hash, prev.descriptor_length) != (
                h.descriptor_hash, h.descriptor_length):
            # the device rebooted: new session on its side (a changed descriptor with an
            # unchanged nonce means the same: new firmware on a board without nonce entropy)
            log.info("hubwire: device on %s rebooted (nonce %08x -> %08x)", self.transport.url, prev.nonce, h.nonce)
            self._up()
            return HelloOutcome.REBOOT
        if not was_linked:
            self._up()
            return HelloOutcome.RESTORED
        if announced and not repeat:
            self._up()
            return HelloOutcome.ANNOUNCE
        return HelloOutcome.SAME

    def next_hello(self) -> "asyncio.Future[None]":
        """A future done at the next device hello."""
        fut = self.loop.create_future()
        self._hello_waiters.append(fut)
        return fut
