"""A scripted device on a pty that follows PROTOCOL.md 12 as the reference device does: it accepts
32-byte payloads, reassembles the hub's large `C` into one buffer sized to its largest writable or
argument value (NAK BAD_LENGTH for a total over it), answers large reads and calls in fragments of
its own and window requests (12.8) in one frame, and checks values (lists included) with the hub's
codecs in the device's order. Test helper only: it counts what it applied so tests can prove
exactly once."""
from __future__ import annotations

import json
import os
import struct
import time
from typing import Any, Callable, Dict, List, Optional, Tuple

from hubwire.descriptor import Channel, parse_descriptor
from hubwire.errors import InvalidValue
from hubwire.session.fragments import encode_message
from hubwire.testing.ptypeer import PtyPeer
from hubwire.wire import messages as m
from hubwire.wire.frame import Frame

NakCode = m.NakCode
STRUCT_1K = {"t": "struct", "f": [{"n": "seq", "t": "u32"}, {"n": "data", "t": "u8", "c": 1016},
                                  {"n": "check", "t": "u32"}]}
STRUCT_200 = {"t": "struct", "f": [{"n": "seq", "t": "u16"}, {"n": "samples", "t": "i16", "c": 99}]}
CHANNELS: List[Dict[str, Any]] = [
    {"id": 1, "n": "big", "a": "rws", **STRUCT_1K},
    {"id": 2, "n": "mid", "a": "rw", **STRUCT_200},
    {"id": 3, "n": "path", "a": "rw", "t": "i16", "vc": 8, "min": -1000, "max": 1000},
    {"id": 4, "n": "flags", "a": "rw", "t": "bool", "vc": 4},
    {"id": 5, "n": "digest", "a": "c", **STRUCT_200, "rt": "u32"},
    {"id": 6, "n": "echo", "a": "c", "t": "u8", "c": 300, "rt": "u8", "rc": 300},
    {"id": 7, "n": "pick", "a": "c", "t": "u8", "vc": 6, "rt": "u16", "rvc": 3},
]


def descriptor(channels: Optional[List[Dict[str, Any]]] = None) -> bytes:
    return json.dumps({"p": 1, "n": "large", "ch": channels or CHANNELS}, separators=(",", ":")).encode()


class LargeDevice(PtyPeer):
    """``values`` holds each readable/writable channel's payload; ``applied`` counts writes applied
    per channel name; ``calls`` the arguments actions were called with; ``functions`` maps an
    action's name to the Python function it runs (decoded argument in, value out)."""

    def __init__(self, channels: Optional[List[Dict[str, Any]]] = None, max_payload: int = 32) -> None:
        # A heartbeat a second (loss after 4 s): these tests are about values, not the link, and a
        # scripted device shares the test's process, which a loaded machine may stall for a second.
        super().__init__(max_payload, beat_ms=1000)
        self.descriptor = descriptor(channels)
        self.desc = parse_descriptor(self.descriptor)
        self.values: Dict[int, bytes] = {}
        for c in self.desc.channels:
            if not c.callable:
                zero = c.codec.encode(c.codec.check([] if c.codec.kind == "list" else _zero(c)))
                self.values[c.id] = zero
        self.applied: Dict[str, int] = {c.name: 0 for c in self.desc.channels}
        self.calls: List[Tuple[str, Any]] = []
        self.functions: Dict[str, Callable[[Any], Any]] = {
            "digest": lambda v: sum(v.samples) & 0xFFFFFFFF,
            "echo": lambda v: v,
            "pick": lambda v: [x * 2 for x in v[:3]],
        }
        # the one reassembly buffer: the largest value written or passed that does not fit a frame
        self.capacity = max([c.codec.max_size for c in self.desc.channels if c.writable or c.callable] + [0])
        self._asm: Optional[Tuple[int, int, int, int]] = None
        self._buf = bytearray()
        self._last_c: Optional[Tuple[int, int, bytes]] = None  # seq, id, wire of the answer
        self.dropped = 0
        #: lose the answers to this many applied controls (the hub retries); duplicates answered again
        self.lose_answers = 0
        self.duplicates = 0
        #: seconds between two fragments of the device's answers (0: back to back)
        self.fragment_gap = 0.0
        self.subscribes: List[Tuple[int, int]] = []
        self.refused_totals = 0
        self.fragments_in = 0
        self.largest_frame_in = 0

    # ------------------------------------------------------------------------------ sending

    def reply(self, t: int, seq: int, cid: int, payload: bytes = b"") -> bytes:
        """Send a message, in fragments of the device's own frame size when it is large."""
        wire = encode_message(t, seq, cid, payload, self.max_payload)
        if self.mute:
            return wire
        if self.fragment_gap and len(payload) > self.max_payload:  # a slow line: one frame at a time
            for frame in wire.split(b"\x00")[:-1]:
                with self.lock:
                    os.write(self.master, frame + b"\x00")
                time.sleep(self.fragment_gap)
            return wire
        with self.lock:
            os.write(self.master, wire)
        return wire

    def sample(self, cid: int, seq: int) -> None:
        """Stream one sample of a channel's value now (dt 0)."""
        self.reply(m.SAMPLE, seq & 0xFF, cid, struct.pack("<H", 0) + self.values[cid])

    # ----------------------------------------------------------------------------- receiving

    def handle(self, f: Frame) -> None:
        self.largest_frame_in = max(self.largest_frame_in, len(f.payload))
        if f.type == m.FRAGMENT:
            self.fragments_in += 1
            whole = self._fragment(f)
            if whole is None:
                return
            f = whole
        if f.type == m.HELLO:
            if not m.Hello.unpack(f.payload).is_reply:
                h = m.Hello(1, m.FLAG_DEVICE | m.FLAG_SEQ_RULES | m.FLAG_REPLY, 0x2468ACE, self.max_payload, self.beat_ms,
                            m.fnv1a32(self.descriptor), len(self.descriptor))
                self.send(m.HELLO, 0, 0, h.pack())
        elif f.type == m.CHUNK:
            req = m.ChunkRequest.unpack(f.payload)
            k = min(req.want, self.max_payload - 4, len(self.descriptor) - req.offset)
            data = self.descriptor[req.offset:req.offset + k]
            self.send(m.CHUNK, f.seq, 0, m.Chunk(req.offset, len(self.descriptor), data).pack())
        elif f.type == m.REQUEST:
            self._last_c = None
            c = self.desc.by_id(f.id)
            if c is None or not c.readable:
                self.send(m.NAK, f.seq, f.id, bytes((NakCode.UNKNOWN_CHANNEL if c is None else NakCode.NOT_READABLE,)))
            elif len(f.payload) == 4:
                self.window(f, self.values[f.id])
            elif f.payload:
                self.send(m.NAK, f.seq, f.id, bytes((NakCode.BAD_LENGTH,)))
            else:
                self.reply(m.RESPONSE, f.seq, f.id, self.values[f.id])
        elif f.type == m.SUBSCRIBE:
            self._last_c = None
            self.subscribes.append((f.id, m.Subscribe.unpack(f.payload).interval_ms))
            self.send(m.ACK, f.seq, f.id, f.payload)
        elif f.type == m.CONTROL:
            self._control(f)

    def window(self, f: Frame, value: bytes, hash: Optional[int] = None) -> None:
        """Answer a window request (PROTOCOL.md 12.8) with a window of ``value`` (``hash``: claim another)."""
        offset, count = struct.unpack("<HH", f.payload)
        if offset > len(value):
            self.send(m.NAK, f.seq, f.id, bytes((NakCode.BAD_OFFSET,)))
            return
        n = min(count, self.max_payload - 8, len(value) - offset)
        h = m.fnv1a32(value) if hash is None else hash
        self.send(m.RESPONSE, f.seq, f.id, struct.pack("<HHI", offset, len(value), h) + value[offset:offset + n])

    def _fragment(self, f: Frame) -> Optional[Frame]:
        try:
            fr = m.Fragment.unpack(f.payload)
        except m.PayloadError:
            fr = None
        if fr is not None and fr.offset == 0:
            if fr.total > self.capacity:
                self.refused_totals += 1
                self._asm = None
                self.send(m.NAK, f.seq, f.id, bytes((NakCode.BAD_LENGTH,)))
                return None
            self._asm, self._buf = (fr.type, f.seq, f.id, fr.total), bytearray()
        elif fr is None or self._asm != (fr.type, f.seq, f.id, fr.total) or fr.offset != len(self._buf):
            self.dropped += 1
            self._asm = None
            return None
        self._buf += fr.data
        if len(self._buf) < fr.total:
            return None
        self._asm = None
        return Frame(fr.type, f.seq, f.id, bytes(self._buf))

    def _control(self, f: Frame) -> None:
        if self._last_c is not None and self._last_c[:2] == (f.seq, f.id):
            self.duplicates += 1
            with self.lock:  # a duplicate: the remembered answer, nothing applied
                os.write(self.master, self._last_c[2])
            return
        c = self.desc.by_id(f.id)
        if c is None:
            wire = self.reply(m.NAK, f.seq, f.id, bytes((NakCode.UNKNOWN_CHANNEL,)))
        elif not (c.writable or c.callable):
            wire = self.reply(m.NAK, f.seq, f.id, bytes((NakCode.NOT_WRITABLE,)))
        else:
            try:
                value = c.check(c.codec.decode(f.payload))
            except InvalidValue as e:
                wire = self.reply(m.NAK, f.seq, f.id, bytes((e.code,)))
            else:
                lose, self.mute = self.lose_answers > 0, self.lose_answers > 0  # the answer is lost on the line
                self.lose_answers -= lose
                try:
                    wire = self._apply(c, f, value)
                finally:
                    self.mute = False
        self._last_c = (f.seq, f.id, wire)

    def _apply(self, c: Channel, f: Frame, value: Any) -> bytes:
        if c.writable:
            self.values[c.id] = f.payload
            self.applied[c.name] += 1
            return self.reply(m.ACK, f.seq, f.id)
        self.calls.append((c.name, value))
        self.applied[c.name] += 1
        assert c.returns is not None
        result = self.functions[c.name](value)
        return self.reply(m.RESPONSE, f.seq, f.id, c.returns.encode(c.returns.check(result)))


def _zero(c: Channel) -> Any:
    if c.codec.kind == "struct":
        return {f["n"]: ([0] * f["c"] if "c" in f else 0) for f in c.type["f"]}
    if c.codec.kind == "array":
        return [0] * c.codec.count  # type: ignore[attr-defined]
    return 0
