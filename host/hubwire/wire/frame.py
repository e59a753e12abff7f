"""Frames: ``type seq id payload crc16``, COBS encoded, terminated by one ``0x00`` (PROTOCOL.md §1)."""
from __future__ import annotations

import re
from binascii import crc_hqx
from collections import deque
from typing import Deque, Dict, List, NamedTuple, Optional

from cobs.cobs import DecodeError as _CobsError
from cobs.cobs import decode as _cobs_decode
from cobs.cobs import encode as _cobs_encode

__all__ = [
    "Frame",
    "FrameDecoder",
    "crc16",
    "encode_frame",
    "decode_frame",
    "decoded_length",
    "max_encoded_length",
    "PROTOCOL_MAX_PAYLOAD",
    "HEADER_CRC_SIZE",
    "NOISE_SAMPLE_SIZE",
]

PROTOCOL_MAX_PAYLOAD = 255
HEADER_CRC_SIZE = 5
#: bytes of the first discarded input a FrameDecoder keeps, to tell what a port said instead of frames
NOISE_SAMPLE_SIZE = 64
#: lines of text (a sketch's Serial.println) kept from among the discarded bytes, newest last;
#: older ones are forgotten (:attr:`FrameDecoder.text_lines` counts them all)
TEXT_LINES = 8
#: a kept line is cut to this many characters
TEXT_CHARS = 80
# printable ASCII ended by a newline: what print()/println() on the hub's line looks like
_TEXT_LINE = re.compile(rb"([\x20-\x7e\t]{2,})\r?\n")


class Frame(NamedTuple):
    """One raw frame: message ``type``, ``seq``, channel ``id`` and ``payload`` bytes."""

    type: int
    seq: int
    id: int
    payload: bytes


_tuple_new = tuple.__new__


def crc16(data: bytes) -> int:
    """CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF) of ``data``."""
    return crc_hqx(data, 0xFFFF)


def encode_frame(type: int, seq: int, id: int, payload: bytes = b"") -> bytes:
    """Return the wire bytes of a frame: COBS(raw frame + CRC) followed by the ``0x00`` delimiter.

    Raises ValueError if a header byte is out of 0..255 or the payload is longer than 255 bytes.
    """
    if len(payload) > PROTOCOL_MAX_PAYLOAD:
        raise ValueError(f"payload of {len(payload)} bytes exceeds the protocol maximum of 255")
    raw = bytes((type, seq, id)) + bytes(payload)
    crc = crc_hqx(raw, 0xFFFF)
    encoded: bytes = _cobs_encode(raw + bytes((crc & 0xFF, crc >> 8)))
    return encoded + b"\x00"


def max_encoded_length(raw_length: int) -> int:
    """Largest COBS encoding (without delimiter) of a raw frame of ``raw_length`` bytes."""
    if raw_length <= 0:
        return 1
    return raw_length + 1 + (raw_length - 1) // 254


def decoded_length(encoded: bytes) -> int:
    """Number of raw bytes a streaming COBS decoder produces from ``encoded`` (no ``0x00`` inside).

    The implicit zero ending a block (code < 0xFF) is counted only when another block follows it,
    and a block cut short by the end of ``encoded`` counts the bytes present. This is the length the
    overflow rule compares with ``5 + max_payload`` (see test/vectors/README.md).
    """
    n = len(encoded)
    i = 0
    count = 0
    prev = 0xFF  # no zero before the first block
    while i < n:
        code = encoded[i]
        if prev != 0xFF:
            count += 1
        take = code - 1
        avail = n - i - 1
        count += take if take < avail else avail
        i += code
        prev = code
    return count


def decode_frame(encoded: bytes, max_payload: int = PROTOCOL_MAX_PAYLOAD) -> Optional[Frame]:
    """Decode one encoded frame (without delimiter); None if it would be dropped."""
    d = FrameDecoder(max_payload)
    frames = d.feed(bytes(encoded) + b"\x00")
    return frames[0] if frames else None


class FrameDecoder:
    """Streaming frame receiver.

    Feed it whatever bytes arrive (:meth:`feed`); it returns the valid frames completed by them and
    counts every dropped frame in :attr:`crc`, :attr:`overflow` or :attr:`dropped` exactly as
    PROTOCOL.md §1 says (an empty frame, ``00 00``, is ignored and not counted). It resynchronises
    at every ``0x00``.

    ``max_payload`` is the largest payload this receiver accepts (1..255); a frame whose raw length
    exceeds ``5 + max_payload`` is counted as ``overflow``.

    The first :data:`NOISE_SAMPLE_SIZE` bytes it discards are kept in :attr:`sample` (with their
    ``0x00`` delimiters), so that a port that sends something other than frames can be described.
    """

    __slots__ = ("max_payload", "crc", "overflow", "dropped", "frames", "_pending", "_raw_limit",
                 "_fast_limit", "_spill", "_skipping", "sample", "text", "text_lines")

    def __init__(self, max_payload: int = PROTOCOL_MAX_PAYLOAD) -> None:
        if not 0 <= max_payload <= PROTOCOL_MAX_PAYLOAD:
            raise ValueError("max_payload must be within 0..255")
        self.max_payload = max_payload
        #: frames dropped because the CRC did not match
        self.crc = 0
        #: frames dropped because they were longer than the receiver accepts
        self.overflow = 0
        #: frames dropped for any other reason (bad COBS, too short, ...); the session adds
        #: well-formed frames of unknown type here too
        self.dropped = 0
        #: valid frames received
        self.frames = 0
        self._pending = b""
        self._raw_limit = HEADER_CRC_SIZE + max_payload
        # an encoded frame this short cannot decode to more than _raw_limit bytes
        self._fast_limit = self._raw_limit + 1
        # pending bytes beyond this length are certainly an overflow
        self._spill = 2 * self._raw_limit + 4
        self._skipping = False
        #: the first bytes discarded (at most NOISE_SAMPLE_SIZE); kept across reset()
        self.sample = b""
        #: the latest lines of text found among the discarded bytes (TEXT_LINES, each TEXT_CHARS at most)
        self.text: Deque[str] = deque(maxlen=TEXT_LINES)
        #: every line of text found so far
        self.text_lines = 0

    def _keep(self, data: bytes) -> None:
        # called for discarded bytes only, never on a valid frame's path
        if len(self.sample) < NOISE_SAMPLE_SIZE:
            self.sample = (self.sample + data)[:NOISE_SAMPLE_SIZE]
        if b"\n" in data:
            for line in _TEXT_LINE.findall(data):
                self.text.append(line[:TEXT_CHARS].decode("ascii").strip())
                self.text_lines += 1

    def noise(self) -> bytes:
        """:attr:`sample`, then the start of the bytes still waiting for a delimiter (bounded).

        Text without ``0x00`` is never discarded, only held back: this shows it as well.
        """
        return (self.sample + self._pending)[:NOISE_SAMPLE_SIZE]

    def counters(self) -> Dict[str, int]:
        """The three drop counters as a dict ``{"crc", "overflow", "dropped"}``."""
        return {"crc": self.crc, "overflow": self.overflow, "dropped": self.dropped}

    def reset(self) -> None:
        """Forget a partially received frame (counters are kept)."""
        self._pending = b""
        self._skipping = False

    def feed(self, data: bytes) -> List[Frame]:
        """Consume ``data``; return the valid frames it completes, in order."""
        if self._pending:
            data = self._pending + data
        parts = data.split(b"\x00")
        tail = parts.pop()
        out: List[Frame] = []
        if parts:
            if self._skipping:
                # the first part continues a frame already known to overflow
                self._skipping = False
                self.overflow += 1
                self._keep(parts[0] + b"\x00")
                del parts[0]
            fast = self._fast_limit
            limit = self._raw_limit
            append = out.append
            decode = _cobs_decode
            crc = crc_hqx
            new = _tuple_new
            frame_cls = Frame
            for enc in parts:
                if not enc:
                    continue  # an empty frame (00 00) is ignored, not counted: a sender's flush
                if len(enc) > fast and decoded_length(enc) > limit:
                    self.overflow += 1
                    self._keep(enc + b"\x00")
                    continue
                try:
                    raw = decode(enc)
                except _CobsError:
                    raw = b""
                if len(raw) < 5:
                    self.dropped += 1
                    self._keep(enc + b"\x00")
                    continue
                if crc(raw[:-2], 0xFFFF) != raw[-2] | (raw[-1] << 8):
                    self.crc += 1
                    self._keep(enc + b"\x00")
                    continue
                append(new(frame_cls, (raw[0], raw[1], raw[2], raw[3:-2])))
            self.frames += len(out)
        if len(tail) > self._spill and not self._skipping:
            # no delimiter for a long time: the frame is an overflow whatever follows; stop buffering
            self._skipping = True
            self._keep(tail)
            tail = b""
        elif self._skipping:
            tail = b""
        self._pending = tail
        return out
