"""A scripted device with missions on a pty (PROTOCOL.md 11), for hub tests: start and cancel with
the device's duplicate-control memory, R [run, state], and mission updates M sent stop-and-wait
with retries (latest progress wins, a final replaces an unsent progress). The test plays the
sketch: ``progress``, ``finish``, ``fail``. Test helper only."""
from __future__ import annotations

import struct
import threading
import time
from dataclasses import dataclass, field
from typing import Callable, Dict, List, Optional, Tuple

from hubwire.descriptor.cache import descriptor_digest
from hubwire.descriptor import parse_descriptor
from hubwire.errors import InvalidValue
from hubwire.testing.ptypeer import PtyPeer
from hubwire.wire import messages as m
from hubwire.wire.frame import Frame
from hubwire.wire.missions import MissionKind, MissionState, MissionUpdate

from hubdevice import wait_for  # noqa: F401  (the tests take it from here too)

DESCRIPTOR = (b'{"p":1,"n":"rover","ch":[{"id":1,"n":"beep","a":"c","t":"u16","rt":"bool"},'
              b'{"id":2,"n":"x","a":"rw","t":"u16"},'
              b'{"id":7,"n":"drive","a":"m","t":"f32","rt":"f32","pt":"f32","u":"m","min":0,"max":10,"pmax":2,'
              b'"d":"drive straight"},{"id":8,"n":"home","a":"m","t":"void"}]}')
DRIVE, HOME = 7, 8
RETRY_S = 0.1  # HUBWIRE_EVENT_RETRY_MS


def f32(x: float) -> bytes:
    return struct.pack("<f", x)


@dataclass
class Mission:
    run: int = 0
    running: bool = False
    progress: Optional[bytes] = None  # pending, not yet sent (latest wins)
    final: Optional[Tuple[int, bytes]] = None  # (kind, data), not yet sent
    starts: List[bytes] = field(default_factory=list)  # goals the sketch started with
    cancels: int = 0


class MissionDevice(PtyPeer):
    """``refuse(goal bytes)`` True: the sketch's start function returns False (NAK REJECTED).
    ``ack_update(seq, nth)`` False: the hub's nth ACK of that update is lost (the device retries)."""

    def __init__(self, descriptor: bytes = DESCRIPTOR, *, refuse: Optional[Callable[[bytes], bool]] = None,
                 ack_update: Optional[Callable[[int, int], bool]] = None, cancel_ends: bool = True,
                 report_at_start: Optional[bytes] = None) -> None:
        super().__init__(32, 240)
        self.descriptor = descriptor
        self.desc = parse_descriptor(descriptor)
        self.refuse = refuse or (lambda goal: False)
        self.ack_update = ack_update or (lambda seq, nth: True)
        #: the cancel function ends the run as cancelled (False: the sketch goes on and finishes it)
        self.cancel_ends = cancel_ends
        #: a progress value the start function reports at once: its M follows the start's answer
        self.report_at_start = report_at_start
        self.nonce = 0x2345678
        self.missions: Dict[int, Mission] = {c.id: Mission() for c in self.desc.channels if c.mission}
        self.lock2 = threading.RLock()
        self._seq = 0x10
        self._last_tx: Optional[Tuple[int, int, int]] = None  # (type, seq, id) of the last hub transaction
        self._answer: Optional[Frame] = None
        self.inflight: Optional[Tuple[int, int, bytes, float]] = None  # seq, id, payload, sent at
        self.update_frames = 0  # M frames sent, retries included
        self.acked: List[Tuple[int, bytes]] = []  # (id, payload) of every update the hub acked, in order
        self._ack_nth: Dict[int, int] = {}
        self.controls = 0  # hub C frames received, retries included
        self.received: List[Frame] = []  # every frame from the hub but hellos and heartbeats

    # ------------------------------------------------------------------------ the sketch

    def progress(self, cid: int, data: bytes = b"") -> bool:
        with self.lock2:
            ms = self.missions[cid]
            if not ms.running:
                return False
            ms.progress = data
            return True

    def _end(self, cid: int, kind: int, data: bytes) -> bool:
        with self.lock2:
            ms = self.missions[cid]
            if not ms.running:
                return False
            ms.running = False
            ms.progress = None  # a final replaces an unsent progress
            ms.final = (kind, data)
            return True

    def finish(self, cid: int, data: bytes = b"") -> bool:
        return self._end(cid, MissionKind.SUCCEEDED, data)

    def fail(self, cid: int, code: int) -> bool:
        return self._end(cid, MissionKind.FAILED, bytes((code,)))

    def idle(self) -> bool:
        """Nothing queued or in flight."""
        with self.lock2:
            return self.inflight is None and all(ms.progress is None and ms.final is None
                                                 for ms in self.missions.values())

    def reboot(self) -> None:
        """A new boot: new nonce, no runs, nothing queued, duplicate memory forgotten; announced."""
        with self.lock2:
            self.nonce += 1
            self.missions = {cid: Mission() for cid in self.missions}
            self.inflight = None
            self._last_tx = None
        self._hello(False)

    # --------------------------------------------------------------------------- frames

    def _hello(self, reply: bool) -> None:
        h = m.Hello(1, m.FLAG_DEVICE | m.FLAG_SEQ_RULES | (m.FLAG_REPLY if reply else 0), self.nonce, self.max_payload, 250,
                    m.fnv1a32(self.descriptor), len(self.descriptor), digest=descriptor_digest(self.descriptor))
        self.send(m.HELLO, 0, 0, h.pack())

    def handle(self, f: Frame) -> None:
        with self.lock2:
            if f.type not in (m.HELLO, m.HEARTBEAT):
                self.received.append(f)
            self._handle(f)

    def _handle(self, f: Frame) -> None:
        if f.type == m.HELLO:
            if not m.Hello.unpack(f.payload).is_reply:
                self._hello(True)
        elif f.type == m.CHUNK:
            req = m.ChunkRequest.unpack(f.payload)
            k = min(req.want, self.max_payload - 4, len(self.descriptor) - req.offset)
            self.send(m.CHUNK, f.seq, 0, m.Chunk(req.offset, len(self.descriptor), self.descriptor[req.offset:req.offset + k]).pack())
            self._last_tx = (f.type, f.seq, f.id)
        elif f.type == m.CONTROL:
            self.controls += 1
            if self._last_tx == (f.type, f.seq, f.id) and self._answer is not None:
                a = self._answer  # a retry: the remembered answer, nothing applied again
            else:
                a = self._control(f)
                self._answer = a
            self._last_tx = (f.type, f.seq, f.id)
            self.send(*a)
        elif f.type == m.REQUEST:
            self._last_tx = (f.type, f.seq, f.id)
            ms = self.missions.get(f.id)
            if ms is None:
                self.send(m.NAK, f.seq, f.id, bytes((m.NakCode.NOT_READABLE,)))
            else:
                self.send(m.RESPONSE, f.seq, f.id, MissionState(ms.run, ms.running).pack())
        elif f.type in (m.ACK, m.NAK) and self.inflight is not None and (f.seq, f.id) == self.inflight[:2]:
            nth = self._ack_nth.get(f.seq, 0)
            self._ack_nth[f.seq] = nth + 1
            if self.ack_update(f.seq, nth):
                self.acked.append((f.id, self.inflight[2]))
                self.inflight = None

    def _control(self, f: Frame) -> Tuple[int, int, int, bytes]:
        def nak(code: int) -> Tuple[int, int, int, bytes]:
            return (m.NAK, f.seq, f.id, bytes((code,)))
        ms = self.missions.get(f.id)
        if ms is None:
            return (m.ACK, f.seq, f.id, b"")  # beep / x: not what these tests look at
        p = f.payload
        if not p:
            return nak(m.NakCode.BAD_LENGTH)
        if p[0] == 2:
            if len(p) != 2:
                return nak(m.NakCode.BAD_LENGTH)
            if ms.running and p[1] == ms.run:
                ms.cancels += 1
                if self.cancel_ends:
                    self._end(f.id, MissionKind.CANCELLED, b"")
                return (m.RESPONSE, f.seq, f.id, b"\x01")
            return (m.RESPONSE, f.seq, f.id, b"\x00")
        if p[0] != 1:
            return nak(m.NakCode.BAD_VALUE)
        if ms.running:
            return nak(m.NakCode.BUSY)
        ch = self.desc.by_id(f.id)
        assert ch is not None
        try:
            ch.check(ch.codec.decode(p[1:]))
        except InvalidValue as e:
            return nak(e.code)
        if self.refuse(p[1:]):
            return nak(m.NakCode.REJECTED)
        ms.run = 1 if ms.run == 255 else ms.run + 1
        ms.running = True
        ms.final = None
        ms.starts.append(bytes(p[1:]))
        ms.progress = self.report_at_start
        return (m.RESPONSE, f.seq, f.id, bytes((ms.run,)))

    def tick(self) -> None:
        with self.lock2:
            now = time.monotonic()
            if self.inflight is not None:
                if now - self.inflight[3] >= RETRY_S and self.linked and not self.mute:
                    seq, cid, payload, _ = self.inflight
                    self.inflight = (seq, cid, payload, now)
                    self.update_frames += 1
                    self.send(m.MISSION, seq, cid, payload)
                return
            if not self.linked:
                return
            for cid, ms in self.missions.items():
                if ms.progress is not None:
                    payload = MissionUpdate(ms.run, MissionKind.PROGRESS, ms.progress).pack()
                    ms.progress = None
                elif ms.final is not None:
                    payload = MissionUpdate(ms.run, ms.final[0], ms.final[1]).pack()
                    ms.final = None
                else:
                    continue
                self._seq = (self._seq + 1) & 0xFF
                self.inflight = (self._seq, cid, payload, now)
                self.update_frames += 1
                self.send(m.MISSION, self._seq, cid, payload)
                return

