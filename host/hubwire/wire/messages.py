"""Message types, NAK codes and the fixed payloads of PROTOCOL.md §2-§5."""
from __future__ import annotations

import enum
import struct
from dataclasses import dataclass
from typing import Any, Dict, Optional

from .frame import Frame

__all__ = [
    "PROTOCOL_VERSION", "HELLO", "HEARTBEAT", "CHUNK", "REQUEST", "RESPONSE", "CONTROL", "ACK", "NAK",
    "EVENT", "SUBSCRIBE", "SAMPLE", "TYPE_NAMES", "FLAG_DEVICE", "FLAG_REPLY", "FLAG_F64", "FLAG_SEQ_RULES",
    "NakCode", "nak_name", "fnv1a32", "Hello", "Heartbeat", "ChunkRequest", "Chunk", "Subscribe",
    "SubscribeAck", "Sample", "Nak", "BindReport", "describe", "FRAGMENT", "Fragment", "MISSION",
]

PROTOCOL_VERSION = 1

HELLO = 0x2A  # '*'
HEARTBEAT = 0x48  # 'H'
CHUNK = 0x4A  # 'J'
REQUEST = 0x52  # 'R'
RESPONSE = 0x72  # 'r'
CONTROL = 0x43  # 'C'
ACK = 0x07
NAK = 0x15
EVENT = 0x21  # '!'
SUBSCRIBE = 0x53  # 'S'
SAMPLE = 0x44  # 'D'
FRAGMENT = 0x46  # 'F': one piece of a message too long for one frame (PROTOCOL.md 12)
MISSION = 0x4D  # 'M': mission update, device to hub (PROTOCOL.md 11)

TYPE_NAMES: Dict[int, str] = {
    HELLO: "hello", HEARTBEAT: "heartbeat", CHUNK: "chunk", REQUEST: "request", RESPONSE: "response",
    CONTROL: "control", ACK: "ack", NAK: "nak", EVENT: "event", SUBSCRIBE: "subscribe", SAMPLE: "sample",
    FRAGMENT: "fragment",
    MISSION: "mission_update",
}

FLAG_DEVICE = 0x01
FLAG_REPLY = 0x02
FLAG_F64 = 0x04
#: the sender numbers its messages by the rules of PROTOCOL.md 4.1 (sequence numbers never make a
#: new message look like a retry, whatever the traffic mix)
FLAG_SEQ_RULES = 0x08


class NakCode(enum.IntEnum):
    """NAK error codes (PROTOCOL.md §5)."""

    UNKNOWN_TYPE = 1
    UNKNOWN_CHANNEL = 2
    BAD_LENGTH = 3
    OUT_OF_RANGE = 4
    NOT_WRITABLE = 5
    NOT_READABLE = 6
    NOT_STREAMABLE = 7
    BUSY = 8
    BAD_OFFSET = 9
    NOT_LINKED = 10
    BAD_VALUE = 11
    REJECTED = 12
    UNSUPPORTED_VERSION = 13


def nak_name(code: int) -> str:
    """Name of a NAK code, ``"UNKNOWN_<n>"`` for a code this hub does not know."""
    try:
        return NakCode(code).name
    except ValueError:
        return f"UNKNOWN_{code}"


def fnv1a32(data: bytes) -> int:
    """FNV-1a 32-bit hash (descriptor hash)."""
    h = 0x811C9DC5
    for b in data:
        h = ((h ^ b) * 0x01000193) & 0xFFFFFFFF
    return h


class PayloadError(ValueError):
    """A fixed message payload has the wrong length."""


def _need(payload: bytes, size: int, what: str, exact: bool = True) -> None:
    if len(payload) < size or (exact and len(payload) != size):
        raise PayloadError(f"{what} payload must be {'' if exact else 'at least '}{size} bytes, got {len(payload)}")


_HELLO = struct.Struct("<BBIHHIH")
_HEARTBEAT = struct.Struct("<HHHHH")
_CHUNK_REQ = struct.Struct("<HB")
_CHUNK_HDR = struct.Struct("<HH")
_U16 = struct.Struct("<H")
_FRAGMENT = struct.Struct("<BHH")


@dataclass(frozen=True)
class Hello:
    """Hello payload (§3.1).

    ``digest`` is the device's descriptor digest (the first 16 bytes of the descriptor's SHA-256,
    hello bytes 16..31), or None: a hub's hello, or a device that sends the 16-byte hello.
    """

    version: int
    flags: int
    nonce: int
    max_payload: int
    heartbeat_ms: int
    descriptor_hash: int = 0
    descriptor_length: int = 0
    digest: Optional[bytes] = None

    SIZE = 16
    DIGEST_SIZE = 16
    SIZE_WITH_DIGEST = SIZE + DIGEST_SIZE

    def __post_init__(self) -> None:
        if self.digest is not None:
            if not isinstance(self.digest, (bytes, bytearray)) or len(self.digest) != self.DIGEST_SIZE:
                raise ValueError(f"hello digest must be {self.DIGEST_SIZE} bytes, got {self.digest!r}")
            object.__setattr__(self, "digest", bytes(self.digest))

    def pack(self) -> bytes:
        """16 bytes, or 32 with the digest."""
        head = _HELLO.pack(self.version, self.flags, self.nonce, self.max_payload, self.heartbeat_ms,
                           self.descriptor_hash, self.descriptor_length)
        return head if self.digest is None else head + self.digest

    @classmethod
    def unpack(cls, payload: bytes) -> "Hello":
        """Decode a hello: the digest when the payload has 32 bytes or more, None when it has 16..31;
        bytes after the digest (later additions) are ignored."""
        _need(payload, cls.SIZE, "hello", exact=False)
        digest = bytes(payload[cls.SIZE:cls.SIZE_WITH_DIGEST]) if len(payload) >= cls.SIZE_WITH_DIGEST else None
        version, flags, nonce, max_payload, heartbeat_ms, dhash, dlen = _HELLO.unpack_from(payload)
        return cls(version, flags, nonce, max_payload, heartbeat_ms, dhash, dlen, digest)

    @property
    def is_device(self) -> bool:
        return bool(self.flags & FLAG_DEVICE)

    @property
    def is_reply(self) -> bool:
        return bool(self.flags & FLAG_REPLY)

    @property
    def has_f64(self) -> bool:
        return bool(self.flags & FLAG_F64)


@dataclass(frozen=True)
class Heartbeat:
    """Heartbeat payload (§3.2); the counters are those of the sender's receiver."""

    counter: int
    since_ms: int
    crc: int
    overflow: int
    dropped: int

    SIZE = 10

    def pack(self) -> bytes:
        return _HEARTBEAT.pack(self.counter & 0xFFFF, min(self.since_ms, 0xFFFF), self.crc & 0xFFFF,
                               self.overflow & 0xFFFF, self.dropped & 0xFFFF)

    @classmethod
    def unpack(cls, payload: bytes) -> "Heartbeat":
        _need(payload, 10, "heartbeat", exact=False)
        return cls(*_HEARTBEAT.unpack_from(payload))


@dataclass(frozen=True)
class ChunkRequest:
    """Descriptor chunk request (§3.3, hub to device)."""

    offset: int
    want: int

    def pack(self) -> bytes:
        return _CHUNK_REQ.pack(self.offset, self.want)

    @classmethod
    def unpack(cls, payload: bytes) -> "ChunkRequest":
        _need(payload, 3, "chunk request")
        return cls(*_CHUNK_REQ.unpack(payload))


@dataclass(frozen=True)
class Chunk:
    """Descriptor chunk (§3.3, device to hub)."""

    offset: int
    total: int
    data: bytes

    def pack(self) -> bytes:
        return _CHUNK_HDR.pack(self.offset, self.total) + self.data

    @classmethod
    def unpack(cls, payload: bytes) -> "Chunk":
        _need(payload, 4, "chunk", exact=False)
        offset, total = _CHUNK_HDR.unpack_from(payload)
        return cls(offset, total, bytes(payload[4:]))


@dataclass(frozen=True)
class Subscribe:
    """Subscribe payload (§3.7): interval in ms, 0 cancels."""

    interval_ms: int

    def pack(self) -> bytes:
        return _U16.pack(self.interval_ms)

    @classmethod
    def unpack(cls, payload: bytes) -> "Subscribe":
        _need(payload, 2, "subscribe")
        return cls(*_U16.unpack(payload))


@dataclass(frozen=True)
class SubscribeAck:
    """ACK payload answering a subscribe: the granted interval (0 on cancel)."""

    granted_ms: int

    def pack(self) -> bytes:
        return _U16.pack(self.granted_ms)

    @classmethod
    def unpack(cls, payload: bytes) -> "SubscribeAck":
        _need(payload, 2, "subscribe ACK")
        return cls(*_U16.unpack(payload))


@dataclass(frozen=True)
class Sample:
    """Streamed sample payload (§3.7): ms since the previous sample, then the value bytes."""

    since_ms: int
    value: bytes

    def pack(self) -> bytes:
        return _U16.pack(self.since_ms) + self.value

    @classmethod
    def unpack(cls, payload: bytes) -> "Sample":
        _need(payload, 2, "sample", exact=False)
        return cls(_U16.unpack_from(payload)[0], bytes(payload[2:]))


@dataclass(frozen=True)
class Nak:
    """NAK payload: one error code."""

    code: int

    def pack(self) -> bytes:
        return bytes((self.code,))

    @classmethod
    def unpack(cls, payload: bytes) -> "Nak":
        _need(payload, 1, "NAK")
        return cls(payload[0])

    @property
    def error(self) -> str:
        return nak_name(self.code)


@dataclass(frozen=True)
class BindReport:
    """Bind report payload (hub to device, ``C`` id 0): ``version`` (1), then one status per hub
    id of the device's "hub" list, 0 bound or the NAK code saying why not."""

    version: int
    status: "tuple[int, ...]"

    def pack(self) -> bytes:
        return bytes((self.version,) + tuple(self.status))

    @classmethod
    def unpack(cls, payload: bytes) -> "BindReport":
        _need(payload, 1, "bind report", exact=False)
        return cls(payload[0], tuple(payload[1:]))


@dataclass(frozen=True)
class Fragment:
    """Fragment payload (§12): the carried message's ``type``, where ``data`` sits in its payload
    (``offset``) and the payload's ``total`` length; the frame's seq and id are the carried message's."""

    type: int
    offset: int
    total: int
    data: bytes

    HEADER = 5

    def pack(self) -> bytes:
        return _FRAGMENT.pack(self.type, self.offset, self.total) + self.data

    @classmethod
    def unpack(cls, payload: bytes) -> "Fragment":
        """Raises PayloadError unless there are a header and at least one byte of data."""
        _need(payload, cls.HEADER + 1, "fragment", exact=False)
        t, offset, total = _FRAGMENT.unpack_from(payload)
        return cls(t, offset, total, bytes(payload[cls.HEADER:]))


def describe(frame: Frame, kind: Optional[str] = None) -> Dict[str, Any]:
    """Decode a frame's payload into a dict ``{"kind": ..., fields...}`` (format of frames.json).

    ``kind`` disambiguates ``J`` (``chunk_request`` / ``chunk``; by default a 3-byte ``J`` payload is
    a request), names a ``C`` with id 0 from the hub ``bind_report`` and the frames of missions
    (``mission_start``, ``mission_cancel``, ``mission_state``; ``M`` is ``mission_update``). Byte strings are given as lowercase hex. Raises PayloadError on a bad length.
    """
    t, p = frame.type, frame.payload
    if t == MISSION or (kind or "").startswith("mission_"):
        from .missions import describe_mission

        mission = describe_mission(frame, kind or "")
        if mission is not None:
            return mission
    if t == HELLO:
        h = Hello.unpack(p)
        hello = {"kind": "hello", "version": h.version, "flags": h.flags, "nonce": h.nonce,
                 "max_payload": h.max_payload, "heartbeat_ms": h.heartbeat_ms,
                 "descriptor_hash": h.descriptor_hash, "descriptor_length": h.descriptor_length}
        if h.digest is not None:
            hello["descriptor_digest"] = h.digest.hex()
        return hello
    if t == HEARTBEAT:
        hb = Heartbeat.unpack(p)
        return {"kind": "heartbeat", "counter": hb.counter, "since_ms": hb.since_ms, "crc": hb.crc,
                "overflow": hb.overflow, "dropped": hb.dropped}
    if t == CHUNK:
        if kind == "chunk_request" or (kind is None and len(p) == 3):
            r = ChunkRequest.unpack(p)
            return {"kind": "chunk_request", "offset": r.offset, "want": r.want}
        c = Chunk.unpack(p)
        return {"kind": "chunk", "offset": c.offset, "total": c.total, "data": c.data.hex()}
    if t == ACK:
        if p:
            return {"kind": "ack", "granted_ms": SubscribeAck.unpack(p).granted_ms}
        return {"kind": "ack"}
    if t == NAK:
        n = Nak.unpack(p)
        return {"kind": "nak", "code": n.code, "error": n.error}
    if t == SUBSCRIBE:
        return {"kind": "subscribe", "interval_ms": Subscribe.unpack(p).interval_ms}
    if t == SAMPLE:
        s = Sample.unpack(p)
        return {"kind": "sample", "since_ms": s.since_ms, "value": s.value.hex()}
    if t == FRAGMENT:
        fr = Fragment.unpack(p)
        return {"kind": "fragment", "carries": fr.type, "offset": fr.offset, "total": fr.total,
                "data": fr.data.hex()}
    if t == CONTROL and kind == "bind_report":
        b = BindReport.unpack(p)
        return {"kind": "bind_report", "version": b.version, "status": list(b.status)}
    if t in (REQUEST, RESPONSE, CONTROL, EVENT):
        return {"kind": TYPE_NAMES[t], "value": bytes(p).hex()}
    raise PayloadError(f"unknown message type 0x{t:02x}")
