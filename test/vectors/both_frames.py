"""Frames of both directions (issue 18, docs/PROTOCOL.md 10): test/vectors/both/frames.json.

Written by generate.py (which imports this module). Every frame the device originates toward the
hub (R, C, J with the device's transaction counter) and every new frame the hub originates toward
the device (hub events `!`, the bind report `C` id 0, its chunk answer to a device `J`, a hello that
carries the hub's descriptor hash and length), with the answers each side gives. A folder of its
own: the wire suites load test/vectors/*.json, and these frames carry a `direction` besides the
fields of frames.json (`"device"`: the device sends it; `"hub"`: the hub sends it).

`message` kinds are those of frames.json plus `bind_report` (`version`, `status`: one code per hub
id, 0 bound). `id` of a frame about a hub channel is the hub id (1..N in the order of the device's
"hub" list).
"""
from __future__ import annotations

import hashlib
import struct
from typing import Any, Dict, List, Optional

from hubwire.wire.frame import FrameDecoder, encode_frame
from hubwire.wire import messages as m

# The hub descriptor the chunk vectors read (same schema as a device descriptor).
HUB_DESCRIPTOR = (b'{"p":1,"n":"hub","ch":[{"id":1,"n":"setpoint","a":"r","t":"f32","u":"C"},'
                  b'{"id":2,"n":"report","a":"w","t":"u16"},{"id":3,"n":"dock","a":"c","t":"f32","rt":"bool"},'
                  b'{"id":4,"n":"mode","a":"e","t":"u8"}]}')
BIND_VERSION = 1


def fnv1a(data: bytes) -> int:
    h = 0x811C9DC5
    for b in data:
        h = ((h ^ b) * 0x01000193) & 0xFFFFFFFF
    return h


def gen() -> Dict[str, Any]:
    vectors: List[Dict[str, Any]] = []

    def add(name: str, direction: str, t: int, seq: int, cid: int, payload: bytes, message: Dict[str, Any],
            kind: Optional[str] = None) -> None:
        wire = encode_frame(t, seq, cid, payload)
        frames = FrameDecoder(255).feed(wire)
        assert len(frames) == 1 and frames[0] == (t, seq, cid, payload), name
        if message["kind"] == "bind_report":
            assert t == m.CONTROL and cid == 0 and payload[0] == BIND_VERSION
            assert message == {"kind": "bind_report", "version": payload[0], "status": list(payload[1:])}
        else:
            got = m.describe(frames[0], kind or message.get("kind"))
            assert got == message, (name, got, message)
        vectors.append({"name": name, "direction": direction, "type": t, "seq": seq, "id": cid,
                        "payload": payload.hex(), "wire": wire.hex(), "message": message})

    # The hub's hello names its own descriptor (bytes 10..15); 0 and 0 when it declares nothing.
    h = fnv1a(HUB_DESCRIPTOR)
    add("hub hello with its descriptor hash and length", "hub", m.HELLO, 0, 0,
        m.Hello(1, 0, 0x0BADCAFE, 255, 250, h, len(HUB_DESCRIPTOR)).pack(),
        {"kind": "hello", "version": 1, "flags": 0, "nonce": 0x0BADCAFE, "max_payload": 255,
         "heartbeat_ms": 250, "descriptor_hash": h, "descriptor_length": len(HUB_DESCRIPTOR)})
    add("hub heartbeat (the device keeps since_ms and the counters)", "hub", m.HEARTBEAT, 7, 0,
        m.Heartbeat(7, 251, 3, 1, 2).pack(),
        {"kind": "heartbeat", "counter": 7, "since_ms": 251, "crc": 3, "overflow": 1, "dropped": 2})

    # Bind report: hub C id 0, payload [version, status of hub id 1..N].
    add("bind report, all bound", "hub", m.CONTROL, 0x21, 0, bytes([1, 0, 0, 0, 0]),
        {"kind": "bind_report", "version": 1, "status": [0, 0, 0, 0]})
    add("bind report, hub id 2 unknown, hub id 3 type differs", "hub", m.CONTROL, 0x22, 0,
        bytes([1, 0, 2, 3, 0]), {"kind": "bind_report", "version": 1, "status": [0, 2, 3, 0]})
    add("bind report, one hub channel not writable", "hub", m.CONTROL, 0x23, 0, bytes([1, 5]),
        {"kind": "bind_report", "version": 1, "status": [5]})
    add("bind report acknowledged", "device", m.ACK, 0x21, 0, b"", {"kind": "ack"})
    add("bind report refused by a device without hub channels", "device", m.NAK, 0x21, 0,
        bytes([m.NakCode.UNKNOWN_CHANNEL]), {"kind": "nak", "code": 2, "error": "UNKNOWN_CHANNEL"})

    # Device R of hub id 1 (f32 setpoint): empty payload; the hub answers r with the value.
    add("device reads hub id 1", "device", m.REQUEST, 0x05, 1, b"", {"kind": "request", "value": ""})
    v = struct.pack("<f", 21.5)
    add("hub answers the read: f32 21.5", "hub", m.RESPONSE, 0x05, 1, v, {"kind": "response", "value": v.hex()})
    add("hub refuses a read of a value the device may not read", "hub", m.NAK, 0x06, 2,
        bytes([m.NakCode.NOT_READABLE]), {"kind": "nak", "code": 6, "error": "NOT_READABLE"})
    add("hub refuses an unknown hub id", "hub", m.NAK, 0x07, 9,
        bytes([m.NakCode.UNKNOWN_CHANNEL]), {"kind": "nak", "code": 2, "error": "UNKNOWN_CHANNEL"})

    # Device C of hub id 2 (a u16 the device writes): ACK, or NAK with the hub's reason.
    w = struct.pack("<H", 1234)
    add("device writes hub id 2: u16 1234", "device", m.CONTROL, 0x08, 2, w, {"kind": "control", "value": w.hex()})
    add("hub acknowledges the write", "hub", m.ACK, 0x08, 2, b"", {"kind": "ack"})
    add("hub refuses the write: out of range", "hub", m.NAK, 0x09, 2,
        bytes([m.NakCode.OUT_OF_RANGE]), {"kind": "nak", "code": 4, "error": "OUT_OF_RANGE"})
    add("hub refuses the write: its handler refused", "hub", m.NAK, 0x0A, 2,
        bytes([m.NakCode.REJECTED]), {"kind": "nak", "code": 12, "error": "REJECTED"})
    add("hub refuses a write of a value the device may not write", "hub", m.NAK, 0x0B, 1,
        bytes([m.NakCode.NOT_WRITABLE]), {"kind": "nak", "code": 5, "error": "NOT_WRITABLE"})
    add("hub refuses the write: wrong length", "hub", m.NAK, 0x0C, 2,
        bytes([m.NakCode.BAD_LENGTH]), {"kind": "nak", "code": 3, "error": "BAD_LENGTH"})

    # Device C of hub id 3 (an action taking f32, returning bool): r with the return value.
    a = struct.pack("<f", 0.25)
    add("device calls hub id 3 with f32 0.25", "device", m.CONTROL, 0x0D, 3, a, {"kind": "control", "value": a.hex()})
    add("hub returns the action's value: bool true", "hub", m.RESPONSE, 0x0D, 3, b"\x01",
        {"kind": "response", "value": "01"})
    add("hub acknowledges a call of an action without a return value", "hub", m.ACK, 0x0E, 3, b"", {"kind": "ack"})

    # Device J: the hub's own descriptor, chunked as the device's is.
    add("device asks for the hub descriptor from 0, up to 28 bytes", "device", m.CHUNK, 0x0F, 0,
        m.ChunkRequest(0, 28).pack(), {"kind": "chunk_request", "offset": 0, "want": 28})
    part = HUB_DESCRIPTOR[:28]
    add("hub answers the first chunk of its descriptor", "hub", m.CHUNK, 0x0F, 0,
        m.Chunk(0, len(HUB_DESCRIPTOR), part).pack(),
        {"kind": "chunk", "offset": 0, "total": len(HUB_DESCRIPTOR), "data": part.hex()})
    tail_at = len(HUB_DESCRIPTOR) - 10
    add("hub answers the last chunk of its descriptor", "hub", m.CHUNK, 0x10, 0,
        m.Chunk(tail_at, len(HUB_DESCRIPTOR), HUB_DESCRIPTOR[tail_at:]).pack(),
        {"kind": "chunk", "offset": tail_at, "total": len(HUB_DESCRIPTOR), "data": HUB_DESCRIPTOR[tail_at:].hex()})
    add("hub refuses an offset past its descriptor", "hub", m.NAK, 0x11, 0,
        bytes([m.NakCode.BAD_OFFSET]), {"kind": "nak", "code": 9, "error": "BAD_OFFSET"})

    # Hub event `!` of hub id 4 (u8 mode), seq from the hub's transaction counter.
    add("hub event: hub id 4, u8 2", "hub", m.EVENT, 0x24, 4, b"\x02", {"kind": "event", "value": "02"})
    add("device acknowledges the hub event", "device", m.ACK, 0x24, 4, b"", {"kind": "ack"})
    add("device refuses an event for a hub id it takes no events on", "device", m.NAK, 0x25, 1,
        bytes([m.NakCode.UNKNOWN_CHANNEL]), {"kind": "nak", "code": 2, "error": "UNKNOWN_CHANNEL"})
    add("device refuses an event of the wrong length", "device", m.NAK, 0x26, 4,
        bytes([m.NakCode.BAD_LENGTH]), {"kind": "nak", "code": 3, "error": "BAD_LENGTH"})
    add("device refuses an event with an invalid value", "device", m.NAK, 0x27, 5,
        bytes([m.NakCode.BAD_VALUE]), {"kind": "nak", "code": 11, "error": "BAD_VALUE"})
    assert hashlib.sha256(HUB_DESCRIPTOR).digest()  # the descriptor is bytes, as sent
    return {"description": "Frames of both directions (docs/PROTOCOL.md 10): device R/C/J to the hub, "
                           "hub events, the bind report, the hub descriptor's chunks; `direction` is "
                           "who sends the frame.",
            "hub_descriptor": HUB_DESCRIPTOR.decode(),
            "vectors": vectors}
