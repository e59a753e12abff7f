"""A scripted device on a pty that uses hub channels (descriptor key "hub"): it acks the hub's bind
report and events (deduplicated by seq and id, as PROTOCOL.md asks of a device) and lets a test
send device-side R / C / J with the device's retry rule (same seq every 100 ms). Test helper only."""
from __future__ import annotations

import os
import threading
import struct
import time
from typing import Any, Callable, Dict, List, Optional, Tuple

import hubwire
from hubwire import HubChannels

from hubwire.descriptor.cache import descriptor_digest
from hubwire.wire import messages as m
from hubwire.testing.ptypeer import PtyPeer
from hubwire.wire.frame import Frame, encode_frame

HUB_LIST = (b'[{"id":1,"n":"setpoint","a":"r","t":"f32"},'
            b'{"id":2,"n":"report","a":"w","t":"struct","f":[{"n":"temp","t":"f32"},{"n":"heater","t":"bool"}]},'
            b'{"id":3,"n":"dock","a":"c","t":"f32","rt":"bool"},'
            b'{"id":4,"n":"mode","a":"e","t":"u8"},'
            b'{"id":5,"n":"target","a":"w","t":"i16"}]')
DESCRIPTOR = (b'{"p":1,"n":"thermo","ch":[{"id":1,"n":"temp","a":"r","t":"f32"},{"id":2,"n":"level","a":"rw","t":"u8"}],'
              b'"hub":' + HUB_LIST + b'}')


class HubDevice(PtyPeer):
    """Answers hellos, heartbeats (``since_ms`` = ``beat_ms``), chunk requests, the bind report and
    hub events; ``ask()`` runs one device transaction."""

    def __init__(self, descriptor: bytes = DESCRIPTOR, *, beat_ms: int = 240, max_payload: int = 32,
                 ack_event: Optional[Callable[[int, int], bool]] = None) -> None:
        super().__init__(max_payload, beat_ms)
        self.descriptor = descriptor
        #: ack_event(seq, nth) False: the device "loses" its ACK of that event (the hub retries)
        self.ack_event = ack_event or (lambda seq, nth: True)
        self.binds: List[bytes] = []
        #: (seq, id) of every hub C, the bind report (id 0) included, in arrival order
        self.controls: List[Tuple[int, int]] = []
        #: answer the hub's writes of "level" (False: silence, the hub retries and times out)
        self.answer_controls = True
        #: acknowledge the bind report (False: a deaf device, the hub retries and gives way)
        self.answer_binds = True
        #: answer this many bind reports and events with NAK NOT_LINKED first (the device dropped
        #: the link on its side), then link again on the hub's hello
        self.not_linked = 0
        self.hellos = 0
        #: (hub id, payload) of every event delivered to the sketch, in order
        self.events: List[Tuple[int, bytes]] = []
        self.event_frames = 0
        self._event_nth: Dict[int, int] = {}
        self._last_event: Optional[Tuple[int, int]] = None
        self.hub_hello: Optional[m.Hello] = None
        self._seq = 0x40
        self.nonce = 0x1234567
        self._waiting: Dict[Tuple[int, int], "threading.Event"] = {}
        self._answers: Dict[Tuple[int, int], Frame] = {}
        #: every answer the hub sent to the device's own transactions, in arrival order
        self.answers_seen: List[Frame] = []

    def _hello(self, reply: bool, times: int = 1) -> None:
        h = m.Hello(1, m.FLAG_DEVICE | m.FLAG_SEQ_RULES | (m.FLAG_REPLY if reply else 0), self.nonce, self.max_payload, 250,
                    m.fnv1a32(self.descriptor), len(self.descriptor), digest=descriptor_digest(self.descriptor))
        with self.lock:  # in one write: the hub reads them together
            os.write(self.master, encode_frame(m.HELLO, 0, 0, h.pack()) * times)

    def announce(self, times: int = 1) -> None:
        """Announce itself as a device that lost the link does, ``times`` hellos at once (a backlog
        held up on the line while it waited for the hub's answer)."""
        self._hello(False, times)

    def reboot(self) -> None:
        """A new boot: a new nonce, duplicate detection forgotten, announced with a hello."""
        self.nonce += 1
        self._last_event = None
        self._hello(False)

    def ask(self, t: int, hub_id: int, payload: bytes = b"", *, tries: int = 20, retry: float = 0.1,
            lose: int = 0, seq: Optional[int] = None) -> Optional[Frame]:
        """One device transaction: the same frame every ``retry`` s until answered (None after
        ``tries``); the first ``lose`` answers are ignored, as if lost on the line."""
        if seq is None:
            self._seq = (self._seq + 1) & 0xFF
            seq = self._seq
        key = (seq, hub_id)
        for _ in range(tries):
            ev = threading.Event()
            self._waiting[key] = ev
            self.send(t, seq, hub_id, payload)
            if ev.wait(retry):
                if lose:
                    lose -= 1
                    continue
                return self._answers.pop(key)
        self._waiting.pop(key, None)
        return None

    def handle(self, f: Frame) -> None:
        if self.not_linked and f.type in (m.CONTROL, m.EVENT):
            self.not_linked -= 1
            self.send(m.NAK, f.seq, f.id, bytes((m.NakCode.NOT_LINKED,)))
            return
        if f.type == m.HELLO:
            self.hellos += 1
            h = m.Hello.unpack(f.payload)
            if self.hub_hello is None or h.nonce != self.hub_hello.nonce:
                self._last_event = None  # a new hub session: forget duplicate detection
            self.hub_hello = h
            if not h.is_reply:
                self._hello(True)
        elif f.type == m.CHUNK and len(f.payload) == 3:
            req = m.ChunkRequest.unpack(f.payload)
            k = min(req.want, self.max_payload - 4, len(self.descriptor) - req.offset)
            data = self.descriptor[req.offset:req.offset + k]
            self.send(m.CHUNK, f.seq, 0, m.Chunk(req.offset, len(self.descriptor), data).pack())
        elif f.type == m.CONTROL:
            self.controls.append((f.seq, f.id))
            if f.id == 0:
                self.binds.append(bytes(f.payload))
                if self.answer_binds:
                    self.send(m.ACK, f.seq, 0)
            elif self.answer_controls:
                self.send(m.ACK, f.seq, f.id)
        elif f.type == m.EVENT:
            self.event_frames += 1
            nth = self._event_nth.get(f.seq, 0)
            self._event_nth[f.seq] = nth + 1
            if self._last_event != (f.seq, f.id):
                self._last_event = (f.seq, f.id)
                self.events.append((f.id, bytes(f.payload)))
            if self.ack_event(f.seq, nth):
                self.send(m.ACK, f.seq, f.id)
        elif f.type in (m.ACK, m.NAK, m.RESPONSE, m.CHUNK):
            key = (f.seq, f.id)
            self.answers_seen.append(f)
            ev = self._waiting.pop(key, None)
            if ev is not None:
                self._answers[key] = f
                ev.set()


def wait_for(pred: Callable[[], bool], timeout: float = 5.0) -> bool:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if pred():
            return True
        time.sleep(0.01)
    return pred()


def full_hub(log: List[Any]) -> HubChannels:
    hub = HubChannels("home")
    hub.provide("setpoint", 21.5, unit="C")

    @hub.accept("report", type="struct", fields={"temp": "f32", "heater": "bool"})
    def report(v: Any) -> None:
        log.append(("report", v.temp, v.heater))

    @hub.action("dock")
    def dock(speed: float) -> bool:
        log.append(("dock", speed))
        return speed > 0

    hub.event("mode", type="u8")
    hub.accept("target", type="i16", min=-100, max=100)
    return hub


def f32(x: float) -> bytes:
    return struct.pack("<f", x)


def connect(dev: HubDevice, **kw: Any) -> hubwire.Device:
    """The device; without ``hub=`` its hub channels are declared by the test once connected."""
    kw.setdefault("hub_later", "hub" not in kw)
    return hubwire.connect(dev.path, timeout=5, cache_dir=False, **kw)
