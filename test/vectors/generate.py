#!/usr/bin/env python3
"""Regenerate the golden vectors in this directory from the Python codec (host/hubwire).

Deterministic: running it twice gives byte-identical files. Published reference values (the CRC
check value, the Wikipedia COBS examples) are hard-coded here and asserted against the codec, and
every stream vector is cross-checked against an independent byte-at-a-time reference receiver
written below, so a codec bug cannot silently become a "golden" vector.

    python3 test/vectors/generate.py          # rewrite the files
    python3 test/vectors/generate.py --check  # exit 1 if a file would change
"""
from __future__ import annotations

import hashlib
import json
import importlib.util
import os
import random
import struct
import sys
from typing import Any, Dict, List, Optional, Tuple

HERE = os.path.dirname(os.path.abspath(__file__))

from cobs import cobs

from hubwire.wire.frame import FrameDecoder, crc16, encode_frame
from hubwire.wire import messages as m
from hubwire.wire.values import codec_for


def _sibling(name: str) -> Any:
    """A module of this folder, also when this file is itself loaded by path (test_properties)."""
    spec = importlib.util.spec_from_file_location(name, os.path.join(HERE, name + ".py"))
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


session_rules = _sibling("session_rules")  # the session rules of PROTOCOL.md section 8
both_frames = _sibling("both_frames")  # frames of both directions (PROTOCOL.md 10)
large_frames = _sibling("large_frames")  # large values in fragments, variable-length arrays (PROTOCOL.md 12)
missions_frames = _sibling("missions_frames")  # frames of missions (PROTOCOL.md 11)

# ---------------------------------------------------------------------------------------------- CRC


def gen_crc() -> Dict[str, Any]:
    vectors = []

    def add(name: str, data: bytes, expect: Optional[int] = None) -> None:
        c = crc16(data)
        if expect is not None:
            assert c == expect, (name, hex(c), hex(expect))
        vectors.append({"name": name, "data": data.hex(), "crc": c})

    add("check value 123456789", b"123456789", 0x29B1)  # the published CRC-16/CCITT-FALSE check
    add("empty (initial value)", b"", 0xFFFF)
    add("single zero byte", b"\x00", 0xE1F0)
    add("single 0xff", b"\xff", 0xFF00)
    add("ascii A", b"A", 0xB915)
    add("256 x 'A'", b"A" * 256)
    add("bytes 0..255", bytes(range(256)))
    add("hello frame header", bytes((m.HELLO, 0, 0)))
    add("four zeros", b"\x00\x00\x00\x00")
    return {"description": "CRC-16/CCITT-FALSE: poly 0x1021, init 0xFFFF, no reflection, no final xor. "
                           "crc is the integer value; on the wire it is sent little-endian.",
            "vectors": vectors}


# --------------------------------------------------------------------------------------------- COBS


def gen_cobs() -> Dict[str, Any]:
    vectors = []

    def add(name: str, decoded: bytes, encoded: Optional[bytes] = None) -> None:
        e = cobs.encode(decoded)
        if encoded is not None:
            assert e == encoded, (name, e.hex(), encoded.hex())
        assert cobs.decode(e) == decoded
        vectors.append({"name": name, "decoded": decoded.hex(), "encoded": e.hex()})

    r = bytes(range(1, 256))  # 01..ff
    # Wikipedia "Consistent Overhead Byte Stuffing" encoding examples 1-11
    add("empty", b"", b"\x01")
    add("wikipedia 1: 00", b"\x00", b"\x01\x01")
    add("wikipedia 2: 00 00", b"\x00\x00", b"\x01\x01\x01")
    add("wikipedia 3: 00 11 00", b"\x00\x11\x00", b"\x01\x02\x11\x01")
    add("wikipedia 4: 11 22 00 33", b"\x11\x22\x00\x33", b"\x03\x11\x22\x02\x33")
    add("wikipedia 5: 11 22 33 44", b"\x11\x22\x33\x44", b"\x05\x11\x22\x33\x44")
    add("wikipedia 6: 11 00 00 00", b"\x11\x00\x00\x00", b"\x02\x11\x01\x01\x01")
    add("wikipedia 7: 01..fe (254 bytes)", r[:254], b"\xff" + r[:254])
    add("wikipedia 8: 00 01..fe (255 bytes)", b"\x00" + r[:254], b"\x01\xff" + r[:254])
    add("wikipedia 9: 01..ff (255 bytes)", r, b"\xff" + r[:254] + b"\x02\xff")
    add("wikipedia 10: 02..ff 00 (255 bytes)", r[1:] + b"\x00", b"\xff" + r[1:] + b"\x01\x01")
    add("wikipedia 11: 03..ff 00 01 (255 bytes)", r[2:] + b"\x00\x01", b"\xfe" + r[2:] + b"\x02\x01")
    # runs around the 254-byte block length
    for n in (253, 254, 255, 256):
        add(f"{n} non-zero bytes", bytes((0x41,)) * n)
    for n in (253, 254, 255, 256):
        add(f"{n} bytes, zero at the end", bytes((0x42,)) * (n - 1) + b"\x00")
    add("256 bytes, zero in the middle", bytes((0x43,)) * 127 + b"\x00" + bytes((0x44,)) * 128)
    add("254 non-zero bytes then 00 then 01", bytes((0x45,)) * 254 + b"\x00\x01")
    add("260 zero bytes", b"\x00" * 260)
    add("single 0xff", b"\xff", b"\x02\xff")
    return {"description": "Standard COBS (no delimiter): blocks of at most 254 non-zero bytes, code = "
                           "block length + 1, code 0xff = 254 bytes and no zero follows. Includes the "
                           "Wikipedia reference examples.",
            "vectors": vectors}


# ------------------------------------------------------------------------------------------- frames


def pattern(n: int, start: int = 1) -> bytes:
    """n non-zero bytes (1..255 cycling)."""
    return bytes(((start + i - 1) % 255) + 1 for i in range(n))


def seq_without_zero_crc(t: int, i: int, p: bytes) -> int:
    for s in range(1, 256):
        c = crc16(bytes((t, s, i)) + p)
        if c & 0xFF and c >> 8:
            return s
    raise AssertionError("no seq gives a zero-free CRC")


def gen_frames() -> Dict[str, Any]:
    vectors = []

    def add(name: str, t: int, seq: int, cid: int, payload: bytes, message: Dict[str, Any],
            kind: Optional[str] = None) -> None:
        wire = encode_frame(t, seq, cid, payload)
        d = FrameDecoder(255)
        frames = d.feed(wire)
        assert len(frames) == 1 and frames[0] == (t, seq, cid, payload), name
        got = m.describe(frames[0], kind or message.get("kind"))
        assert got == message, (name, got, message)
        vectors.append({"name": name, "type": t, "seq": seq, "id": cid, "payload": payload.hex(),
                        "wire": wire.hex(), "message": message})

    hub_hello = m.Hello(1, 0, 0x1234ABCD, 255, 250, 0, 0)
    add("hello from hub", m.HELLO, 0, 0, hub_hello.pack(),
        {"kind": "hello", "version": 1, "flags": 0, "nonce": 0x1234ABCD, "max_payload": 255,
         "heartbeat_ms": 250, "descriptor_hash": 0, "descriptor_length": 0})
    hub_reply = m.Hello(1, m.FLAG_REPLY, 0x00000001, 255, 250, 0, 0)
    add("hello from hub, reply to a device announce", m.HELLO, 0, 0, hub_reply.pack(),
        {"kind": "hello", "version": 1, "flags": 2, "nonce": 1, "max_payload": 255,
         "heartbeat_ms": 250, "descriptor_hash": 0, "descriptor_length": 0})
    dev_hello = m.Hello(1, m.FLAG_DEVICE | m.FLAG_REPLY, 0xDEADBEEF, 32, 250, 0x4C0B6B8D, 517)
    add("hello from device (reply)", m.HELLO, 0, 0, dev_hello.pack(),
        {"kind": "hello", "version": 1, "flags": 3, "nonce": 0xDEADBEEF, "max_payload": 32,
         "heartbeat_ms": 250, "descriptor_hash": 0x4C0B6B8D, "descriptor_length": 517})
    dev_ann = m.Hello(1, m.FLAG_DEVICE | m.FLAG_F64, 0x00C0FFEE, 64, 100, 0xFFFFFFFF, 16384)
    add("hello from device (announce, f64)", m.HELLO, 0, 0, dev_ann.pack(),
        {"kind": "hello", "version": 1, "flags": 5, "nonce": 0x00C0FFEE, "max_payload": 64,
         "heartbeat_ms": 100, "descriptor_hash": 0xFFFFFFFF, "descriptor_length": 16384})
    # Devices that send the descriptor digest (PROTOCOL.md 3.1): bytes 16..31 are the first 16 bytes
    # of the descriptor's SHA-256; the hash and length are those of the same descriptor.
    digested = b'{"p":1,"n":"probe","ch":[{"id":1,"n":"duty","a":"rw","t":"i16","fs":0}]}'
    digest = hashlib.sha256(digested).digest()[:16]
    assert digest.hex() == "acc899d0357080500194e9d519b66f14"  # test/test_session/test_failsafe_digest.cpp
    dev_digest = m.Hello(1, m.FLAG_DEVICE | m.FLAG_REPLY, 0x0BADCAFE, 32, 250, m.fnv1a32(digested), len(digested),
                         digest)
    add("hello from device (reply, with digest)", m.HELLO, 0, 0, dev_digest.pack(),
        {"kind": "hello", "version": 1, "flags": 3, "nonce": 0x0BADCAFE, "max_payload": 32,
         "heartbeat_ms": 250, "descriptor_hash": m.fnv1a32(digested), "descriptor_length": len(digested),
         "descriptor_digest": digest.hex()})
    later = m.Hello(1, m.FLAG_DEVICE | m.FLAG_F64, 0x00C0FFEE, 255, 100, m.fnv1a32(digested), len(digested), digest)
    add("hello from device (announce, with digest and 2 later bytes)", m.HELLO, 0, 0, later.pack() + b"\xa5\x5a",
        {"kind": "hello", "version": 1, "flags": 5, "nonce": 0x00C0FFEE, "max_payload": 255,
         "heartbeat_ms": 100, "descriptor_hash": m.fnv1a32(digested), "descriptor_length": len(digested),
         "descriptor_digest": digest.hex()})
    add("hello from device, 24 bytes (no digest: it needs all 16)", m.HELLO, 0, 0, dev_hello.pack() + bytes(8),
        {"kind": "hello", "version": 1, "flags": 3, "nonce": 0xDEADBEEF, "max_payload": 32,
         "heartbeat_ms": 250, "descriptor_hash": 0x4C0B6B8D, "descriptor_length": 517})
    add("heartbeat, first", m.HEARTBEAT, 0, 0, m.Heartbeat(0, 0, 0, 0, 0).pack(),
        {"kind": "heartbeat", "counter": 0, "since_ms": 0, "crc": 0, "overflow": 0, "dropped": 0})
    add("heartbeat with counters", m.HEARTBEAT, 0x34, 0, m.Heartbeat(0x1234, 251, 3, 1, 65535).pack(),
        {"kind": "heartbeat", "counter": 0x1234, "since_ms": 251, "crc": 3, "overflow": 1, "dropped": 65535})
    add("chunk request", m.CHUNK, 7, 0, m.ChunkRequest(64, 28).pack(),
        {"kind": "chunk_request", "offset": 64, "want": 28})
    desc = b'{"p":1,"n":"rover","fw":"1.0.0","ch":['
    add("chunk", m.CHUNK, 7, 0, m.Chunk(0, 517, desc[:28]).pack(),
        {"kind": "chunk", "offset": 0, "total": 517, "data": desc[:28].hex()})
    add("chunk, empty (offset == total)", m.CHUNK, 9, 0, m.Chunk(517, 517, b"").pack(),
        {"kind": "chunk", "offset": 517, "total": 517, "data": ""})
    add("request (empty payload)", m.REQUEST, 1, 5, b"", {"kind": "request", "value": ""})
    add("response u16", m.RESPONSE, 1, 5, struct.pack("<H", 7400), {"kind": "response", "value": "e81c"})
    add("control f32 0.5", m.CONTROL, 2, 1, struct.pack("<f", 0.5), {"kind": "control", "value": "0000003f"})
    add("control call without argument", m.CONTROL, 3, 9, b"", {"kind": "control", "value": ""})
    add("ack (plain)", m.ACK, 2, 1, b"", {"kind": "ack"})
    add("ack to subscribe with granted_ms", m.ACK, 4, 3, m.SubscribeAck(20).pack(), {"kind": "ack", "granted_ms": 20})
    add("ack to cancel (granted 0)", m.ACK, 5, 3, m.SubscribeAck(0).pack(), {"kind": "ack", "granted_ms": 0})
    add("ack of an event (hub to device)", m.ACK, 17, 8, b"", {"kind": "ack"})
    add("nak OUT_OF_RANGE", m.NAK, 2, 1, m.Nak(m.NakCode.OUT_OF_RANGE).pack(), {"kind": "nak", "code": 4, "error": "OUT_OF_RANGE"})
    add("nak NOT_LINKED", m.NAK, 6, 0, m.Nak(m.NakCode.NOT_LINKED).pack(), {"kind": "nak", "code": 10, "error": "NOT_LINKED"})
    add("nak UNSUPPORTED_VERSION", m.NAK, 0, 0, bytes((13,)), {"kind": "nak", "code": 13, "error": "UNSUPPORTED_VERSION"})
    add("event bool true", m.EVENT, 17, 8, b"\x01", {"kind": "event", "value": "01"})
    add("subscribe 20 ms", m.SUBSCRIBE, 4, 3, m.Subscribe(20).pack(), {"kind": "subscribe", "interval_ms": 20})
    add("subscribe cancel", m.SUBSCRIBE, 5, 3, m.Subscribe(0).pack(), {"kind": "subscribe", "interval_ms": 0})
    imu = struct.pack("<fffhhh", 0.5, -1.0, 9.8125, 1, -2, 300)
    add("sample (imu struct)", m.SAMPLE, 200, 3, m.Sample(21, imu).pack(),
        {"kind": "sample", "since_ms": 21, "value": imu.hex()})
    add("sample, first (since 0)", m.SAMPLE, 0, 4, m.Sample(0, b"\x10\x00").pack(),
        {"kind": "sample", "since_ms": 0, "value": "1000"})
    # edge cases
    add("payload of 8 zero bytes", m.CONTROL, 1, 1, b"\x00" * 8, {"kind": "control", "value": "00" * 8})
    add("header of zeros: seq 0 id 0 empty ack", m.ACK, 0, 0, b"", {"kind": "ack"})
    for n in (249, 250, 253, 254, 255):
        p = pattern(n)
        s = seq_without_zero_crc(m.RESPONSE, 0x7F, p)
        add(f"payload {n} non-zero bytes (raw {n + 5})", m.RESPONSE, s, 0x7F, p, {"kind": "response", "value": p.hex()})
    for n in (249, 254, 255):
        p = b"\x00" * n
        add(f"payload {n} zero bytes", m.RESPONSE, 1, 0x7F, p, {"kind": "response", "value": p.hex()})
    p = pattern(255)[:100] + b"\x00" + pattern(154)
    add("maximum payload 255 with one zero", m.CONTROL, 9, 200, p, {"kind": "control", "value": p.hex()})
    return {"description": "One frame per vector: building (type, seq, id, payload) gives wire (COBS + "
                           "00); feeding wire to a receiver (max_payload 255) gives exactly this frame; "
                           "message is the payload decoded per PROTOCOL.md section 3.",
            "vectors": vectors}


# ------------------------------------------------------------------------------------------ streams


class ReferenceReceiver:
    """Independent byte-at-a-time receiver (the behaviour streams.json pins), used as a cross-check.

    State: collecting decoded bytes with the COBS block counter; the zero that ends a block is
    appended only when another code byte follows. Decoded length > 5 + max_payload -> overflow, skip
    to the next 00. At 00: nothing collected -> ignored (empty frame); block not finished -> dropped
    (bad COBS); length < 5 -> dropped; bad CRC -> crc; else a frame.
    """

    def __init__(self, max_payload: int) -> None:
        self.limit = 5 + max_payload
        self.counters = {"crc": 0, "overflow": 0, "dropped": 0}
        self.frames: List[Tuple[int, int, int, bytes]] = []
        self._reset()

    def _reset(self) -> None:
        self.buf = bytearray()
        self.remaining = 0  # data bytes left in the current block
        self.code = 0  # 0: expecting the first code byte
        self.skipping = False

    def _push(self, b: int) -> None:
        if len(self.buf) >= self.limit:
            self.skipping = True
        else:
            self.buf.append(b)

    def byte(self, b: int) -> None:
        if b == 0:
            if self.skipping:
                self.counters["overflow"] += 1
            elif self.code == 0:
                pass  # empty frame: ignored, not counted
            elif self.remaining:
                self.counters["dropped"] += 1
            elif len(self.buf) < 5:
                self.counters["dropped"] += 1
            else:
                raw = bytes(self.buf)
                if crc16(raw[:-2]) != raw[-2] | raw[-1] << 8:
                    self.counters["crc"] += 1
                else:
                    self.frames.append((raw[0], raw[1], raw[2], raw[3:-2]))
            self._reset()
            return
        if self.skipping:
            return
        if self.remaining:
            self._push(b)
            self.remaining -= 1
            return
        # a code byte
        if self.code and self.code != 0xFF:
            self._push(0)
        self.code = b
        self.remaining = b - 1


def gen_streams() -> Dict[str, Any]:
    vectors = []

    def f(t: int, seq: int, cid: int, p: bytes = b"") -> Tuple[bytes, Dict[str, Any]]:
        return encode_frame(t, seq, cid, p), {"type": t, "seq": seq, "id": cid, "payload": p.hex()}

    def add(name: str, max_payload: int, stream: bytes, frames: List[Dict[str, Any]],
            counters: Optional[Dict[str, int]]) -> None:
        """counters None: complex case, take the reference receiver's (both decoders must agree)."""
        d = FrameDecoder(max_payload)
        got = []
        for i in range(len(stream)):  # byte by byte, as the README says
            got.extend(d.feed(stream[i:i + 1]))
        whole = FrameDecoder(max_payload)
        got_whole = whole.feed(stream)
        ref = ReferenceReceiver(max_payload)
        for b in stream:
            ref.byte(b)
        if counters is None:
            counters = dict(ref.counters)
        exp = [(x["type"], x["seq"], x["id"], bytes.fromhex(x["payload"])) for x in frames]
        assert [tuple(g) for g in got] == exp, (name, got)
        assert [tuple(g) for g in got_whole] == exp, (name, "whole")
        assert ref.frames == exp, (name, "reference", ref.frames)
        assert d.counters() == counters == whole.counters() == ref.counters, (name, d.counters(), ref.counters, counters)
        vectors.append({"name": name, "max_payload": max_payload, "input": stream.hex(), "frames": frames,
                        "counters": counters})

    Z = {"crc": 0, "overflow": 0, "dropped": 0}

    def c(**kw: int) -> Dict[str, int]:
        return {**Z, **kw}

    a, fa = f(m.REQUEST, 1, 5)
    b, fb = f(m.RESPONSE, 1, 5, b"\xe8\x1c")
    e, fe = f(m.EVENT, 2, 8, b"\x01")
    z, fz = f(m.CONTROL, 3, 6, b"\x00\x00\x00\x00")
    add("one frame", 32, a, [fa], Z)
    add("three frames back to back", 32, a + b + e, [fa, fb, fe], Z)
    add("empty input", 32, b"", [], Z)
    add("garbage between frames (ended by 00)", 32, a + b"\x11\x22\x33\x00" + b, [fa, fb], c(dropped=1))
    add("boot noise before the first frame", 32, b"\r\nbootloader 1.6\r\n\x00" + a, [fa], c(dropped=1))
    add("garbage glued to the front of a frame costs that frame", 32, a + b"\x05\x41\x42" + b + e, [fa, fe], None)
    add("garbage 0xff run glued to a frame", 32, b"\xff" * 7 + a + e, [fe], None)
    # bad CRC: flip a payload bit, keep the COBS structure valid
    raw = bytes((m.RESPONSE, 1, 5, 0xE8, 0x1C))
    crc = crc16(raw) ^ 0x0100
    badcrc = cobs.encode(raw + bytes((crc & 0xFF, crc >> 8))) + b"\x00"
    add("bad CRC", 32, a + badcrc + e, [fa, fe], c(crc=1))
    flipped = bytearray(b)
    flipped[3] ^= 0x40  # a data byte inside the frame, not a code byte, never becomes 0
    add("one flipped payload bit -> crc", 32, bytes(flipped) + e, [fe], c(crc=1))
    add("truncated frame (tail lost, COBS block unfinished)", 32, b[:3] + b"\x00" + e, [fe], c(dropped=1))
    add("truncated frame (3 bytes decoded, too short)", 32, cobs.encode(b"\x52\x01\x05") + b"\x00" + a, [fa], c(dropped=1))
    add("lost delimiter merges two frames -> crc", 32, b[:-1] + e + a, [fa], c(crc=1))
    add("missing delimiter at end (frame pending, nothing counted)", 32, a + e[:-1], [fa], Z)
    add("two 00 in a row: the empty frame is ignored, not counted", 32, a + b"\x00" + e, [fa, fe], Z)
    add("stream starting with 00 (a sender's flush) is not counted", 32, b"\x00" + a, [fa], Z)
    add("three 00 in a row", 32, a + b"\x00\x00" + e, [fa, fe], Z)
    add("lone 00 after garbage ends the garbage", 32, b"\x13\x37\x00\x00" + a, [fa], c(dropped=1))
    add("empty frames between frames and after an overflow", 32,
        b"\x41" * 100 + b"\x00\x00" + a + b"\x00" + e, [fa, fe], c(overflow=1))
    add("payload full of zeros", 32, z + a, [fz, fa], Z)
    add("bad COBS: code byte points past the delimiter", 32, b"\x09\x52\x01\x05\x00" + a, [fa], c(dropped=1))
    add("bad COBS: 0xff block cut short", 32, b"\xff" + b"\x01" * 20 + b"\x00" + a, [fa], c(dropped=1))
    add("extra empty block after a short block adds a zero -> crc", 32, b[:-1] + b"\x01\x00" + a, [fa], c(crc=1))
    p249 = pattern(249)
    s249 = seq_without_zero_crc(m.RESPONSE, 2, p249)
    w249, f249 = f(m.RESPONSE, s249, 2, p249)
    assert w249[0] == 0xFF and len(w249) == 256
    add("raw frame of exactly 254 bytes: canonical (no trailing block)", 255, w249, [f249], Z)
    add("raw frame of exactly 254 bytes: non-canonical trailing 01 block accepted", 255,
        w249[:-1] + b"\x01\x00", [f249], Z)
    p32, f32_ = f(m.RESPONSE, 4, 3, pattern(32))
    p33, _ = f(m.RESPONSE, 5, 3, pattern(33))
    add("payload of exactly max_payload (32) accepted", 32, p32, [f32_], Z)
    add("oversized frame (payload 33 > max_payload 32)", 32, p33 + a, [fa], c(overflow=1))
    p33z, _ = f(m.RESPONSE, 6, 3, b"\x00" * 33)
    add("oversized frame of zeros (payload 33 > 32)", 32, p33z + a, [fa], c(overflow=1))
    add("oversized frame with max_payload 0", 0, b + a, [fa], c(overflow=1))
    add("max_payload 0 accepts an empty payload", 0, a, [fa], Z)
    add("long garbage run without 00 (600 bytes) is one overflow", 32, b"\x41" * 600 + b"\x00" + a, [fa], c(overflow=1))
    add("oversized bad COBS counts as overflow", 32, b"\x30" + b"\x41" * 46 + b"\x00" + a, [fa], c(overflow=1))
    p255, f255 = f(m.RESPONSE, 7, 1, pattern(255))
    add("maximum payload 255 accepted", 255, p255 + a, [f255, fa], Z)
    add("payload 255 is overflow for max_payload 254", 254, p255 + a, [fa], c(overflow=1))
    unk, funk = f(0x99, 1, 1, b"\x01")
    add("unknown type is still a valid frame at this layer", 32, unk, [funk], Z)
    # a pseudo-random mix, deterministic
    rng = random.Random(20240521)
    stream = b""
    frames: List[Dict[str, Any]] = []
    for i in range(40):
        p = bytes(rng.choice((0, 1, 2, 0x55, 0xFF)) for _ in range(rng.randrange(0, 33)))
        w, fr0 = f(rng.choice((m.EVENT, m.RESPONSE, m.SAMPLE)), i, rng.randrange(256), p)
        fr: Optional[Dict[str, Any]] = fr0
        r = rng.random()
        if r < 0.2:
            stream += bytes(rng.randrange(1, 256) for _ in range(rng.randrange(1, 6))) + b"\x00"
        elif r < 0.3:
            w = w[:1] + bytes((w[1] ^ 0x10 or 1,)) + w[2:]  # corrupt one byte: this frame is lost
            fr = None
        stream += w
        if fr is not None:
            frames.append(fr)
    add("pseudo-random mix of frames, zero-terminated garbage and corrupted frames", 32, stream, frames, None)
    return {"description": "A receiver with the given max_payload, fed input byte by byte, yields exactly "
                           "frames and ends with exactly counters. Rules: bytes are collected until 00; "
                           "the raw length is the number of bytes COBS decoding yields (the zero ending a "
                           "block counts only when another block follows; a block cut short counts the "
                           "bytes present); raw length > 5 + max_payload -> overflow (takes precedence); "
                           "else COBS block unfinished at the 00 -> dropped; raw length < 5 -> dropped; "
                           "CRC mismatch -> crc. Garbage ending in 00 is one dropped frame; an empty frame "
                           "(00 00) is ignored and not counted; bytes after the last 00 are pending, not "
                           "counted.",
            "vectors": vectors}


# ------------------------------------------------------------------------------------------- values

IMU = {"t": "struct", "f": [{"n": "ax", "t": "f32"}, {"n": "ay", "t": "f32"}, {"n": "az", "t": "f32"},
                            {"n": "gyro", "t": "i16", "c": 3}]}
MIXED = {"t": "struct", "f": [{"n": "on", "t": "bool"}, {"n": "id", "t": "u8"}, {"n": "pos", "t": "i32", "c": 2},
                              {"n": "t", "t": "f64"}, {"n": "flags", "t": "bool", "c": 2}]}


def gen_values() -> Tuple[Dict[str, Any], Dict[str, Any]]:
    vectors = []

    def add(name: str, t: Dict[str, Any], value: Any, hexv: Optional[str] = None) -> None:
        c = codec_for(t)
        enc = c.encode(c.from_json(value))
        if hexv is not None:
            assert enc.hex() == hexv, (name, enc.hex(), hexv)
        dec = c.to_json(c.decode(enc))
        assert dec == value and json.dumps(dec) == json.dumps(value), (name, dec, value)
        vectors.append({"name": name, "type": t, "value": value, "hex": enc.hex()})

    add("bool false", {"t": "bool"}, False, "00")
    add("bool true", {"t": "bool"}, True, "01")
    add("u8 0", {"t": "u8"}, 0, "00")
    add("u8 max", {"t": "u8"}, 255, "ff")
    add("u16 max", {"t": "u16"}, 65535, "ffff")
    add("u16 little-endian", {"t": "u16"}, 0x1234, "3412")
    add("u32 max", {"t": "u32"}, 4294967295, "ffffffff")
    add("u32 little-endian", {"t": "u32"}, 0x12345678, "78563412")
    add("i8 min", {"t": "i8"}, -128, "80")
    add("i8 max", {"t": "i8"}, 127, "7f")
    add("i8 -1", {"t": "i8"}, -1, "ff")
    add("i16 min", {"t": "i16"}, -32768, "0080")
    add("i16 max", {"t": "i16"}, 32767, "ff7f")
    add("i32 min", {"t": "i32"}, -2147483648, "00000080")
    add("i32 max", {"t": "i32"}, 2147483647, "ffffff7f")
    add("i32 -2", {"t": "i32"}, -2, "feffffff")
    add("f32 0", {"t": "f32"}, 0.0, "00000000")
    add("f32 0.5", {"t": "f32"}, 0.5, "0000003f")
    add("f32 -1", {"t": "f32"}, -1.0, "000080bf")
    add("f32 0.1 (as stored in f32)", {"t": "f32"}, 0.10000000149011612, "cdcccc3d")
    add("f32 largest finite", {"t": "f32"}, 3.4028234663852886e38, "ffff7f7f")
    add("f32 smallest normal", {"t": "f32"}, 1.1754943508222875e-38, "00008000")
    add("f32 smallest subnormal", {"t": "f32"}, 1.401298464324817e-45, "01000000")
    add("f32 lowest", {"t": "f32"}, -3.4028234663852886e38, "ffff7fff")
    add("f64 0.1", {"t": "f64"}, 0.1, "9a9999999999b93f")
    add("f64 largest finite", {"t": "f64"}, 1.7976931348623157e308, "ffffffffffffef7f")
    add("f64 -2.5", {"t": "f64"}, -2.5, "00000000000004c0")
    add("u8[3]", {"t": "u8", "c": 3}, [1, 2, 255], "0102ff")
    add("u16[4] (range sensor)", {"t": "u16", "c": 4}, [0, 1, 400, 65535], "000001009001ffff")
    add("i16[3]", {"t": "i16", "c": 3}, [-1, 0, 32767], "ffff0000ff7f")
    add("f32[2]", {"t": "f32", "c": 2}, [1.5, -0.25], "0000c03f000080be")
    add("bool[4]", {"t": "bool", "c": 4}, [True, False, False, True], "01000001")
    add("array of one", {"t": "u32", "c": 1}, [7], "07000000")
    add("struct with array field (imu)", IMU, {"ax": 0.5, "ay": -1.0, "az": 9.8125, "gyro": [1, -2, 300]},
        "0000003f000080bf00001d410100feff2c01")
    add("struct with bool, f64 and arrays", MIXED,
        {"on": True, "id": 7, "pos": [-1, 100000], "t": 0.1, "flags": [False, True]})
    add("string empty", {"t": "str", "c": 8}, "", "00")
    add("string short", {"t": "str", "c": 8}, "hi", "026869")
    add("string full (capacity 8)", {"t": "str", "c": 8}, "abcdefgh", "086162636465666768")
    add("string utf-8 (bytes counted)", {"t": "str", "c": 8}, "h\u00e9llo", "0668c3a96c6c6f")
    add("string capacity 1", {"t": "str", "c": 1}, "x", "0178")
    add("void", {"t": "void"}, None, "")
    # variable-length arrays (appended: the vectors above stay byte for byte): count byte, then elements
    add("list empty (u8, capacity 4)", {"t": "u8", "vc": 4}, [], "00")
    add("list u8 [1, 2, 255]", {"t": "u8", "vc": 4}, [1, 2, 255], "030102ff")
    add("list i16 full (capacity 3)", {"t": "i16", "vc": 3}, [-1, 0, 32767], "03ffff0000ff7f")
    add("list f32 one element", {"t": "f32", "vc": 8}, [1.5], "010000c03f")
    add("list bool", {"t": "bool", "vc": 4}, [True, False], "020100")
    add("list u32 capacity 1", {"t": "u32", "vc": 1}, [7], "0107000000")
    add("list capacity 255", {"t": "u8", "vc": 255}, [9, 8, 7], "03090807")

    invalid = []

    def bad(name: str, t: Dict[str, Any], hexv: str, error: str) -> None:
        c = codec_for(t)
        try:
            c.decode(bytes.fromhex(hexv))
        except Exception as ex:  # noqa: BLE001 - checking the kind below
            assert getattr(ex, "code", None) == m.NakCode[error], (name, ex)
        else:
            raise AssertionError(f"{name}: decoded without error")
        invalid.append({"name": name, "type": t, "hex": hexv, "error": error})

    bad("bool 0x02", {"t": "bool"}, "02", "BAD_VALUE")
    bad("bool 0xff", {"t": "bool"}, "ff", "BAD_VALUE")
    bad("bool empty", {"t": "bool"}, "", "BAD_LENGTH")
    bad("bool two bytes", {"t": "bool"}, "0100", "BAD_LENGTH")
    bad("u8 empty", {"t": "u8"}, "", "BAD_LENGTH")
    bad("u16 one byte", {"t": "u16"}, "01", "BAD_LENGTH")
    bad("u16 three bytes", {"t": "u16"}, "010203", "BAD_LENGTH")
    bad("u32 three bytes", {"t": "u32"}, "010203", "BAD_LENGTH")
    bad("i32 five bytes", {"t": "i32"}, "0102030405", "BAD_LENGTH")
    bad("f32 two bytes", {"t": "f32"}, "0000", "BAD_LENGTH")
    bad("f64 four bytes", {"t": "f64"}, "00000000", "BAD_LENGTH")
    bad("u16[3] five bytes", {"t": "u16", "c": 3}, "0100020003", "BAD_LENGTH")
    bad("u16[3] seven bytes", {"t": "u16", "c": 3}, "01000200030004", "BAD_LENGTH")
    bad("bool[2] with 0x02", {"t": "bool", "c": 2}, "0102", "BAD_VALUE")
    bad("struct one byte short", IMU, "0000003f000080bf00001d410100feff2c", "BAD_LENGTH")
    bad("struct one byte long", IMU, "0000003f000080bf00001d410100feff2c0100", "BAD_LENGTH")
    bad("struct bool field 0x02", MIXED, "0207ffffffffa08601009a9999999999b93f0001", "BAD_VALUE")
    bad("struct bool array field 0x05", MIXED, "0107ffffffffa08601009a9999999999b93f0005", "BAD_VALUE")
    bad("string empty payload (no length byte)", {"t": "str", "c": 8}, "", "BAD_LENGTH")
    bad("string length > capacity", {"t": "str", "c": 8}, "09616263646566676869", "BAD_VALUE")
    bad("string length byte 255, capacity 8", {"t": "str", "c": 8}, "ff" + "61" * 255, "BAD_VALUE")
    bad("string length byte over capacity and payload short", {"t": "str", "c": 8}, "0961", "BAD_VALUE")
    bad("string shorter than its length byte", {"t": "str", "c": 8}, "036162", "BAD_LENGTH")
    bad("string longer than its length byte", {"t": "str", "c": 8}, "02616263", "BAD_LENGTH")
    bad("void with a byte", {"t": "void"}, "00", "BAD_LENGTH")
    # variable-length arrays: the count first (over the capacity BAD_VALUE, whatever the length),
    # then the length (1 + n * size, else BAD_LENGTH), then the elements in order
    bad("list empty payload (no count byte)", {"t": "u8", "vc": 4}, "", "BAD_LENGTH")
    bad("list count > capacity", {"t": "u8", "vc": 4}, "050102030405", "BAD_VALUE")
    bad("list count > capacity and payload short", {"t": "u8", "vc": 4}, "0501", "BAD_VALUE")
    bad("list count byte 255, capacity 4", {"t": "i16", "vc": 4}, "ff", "BAD_VALUE")
    bad("list shorter than its count", {"t": "i16", "vc": 4}, "02ffff00", "BAD_LENGTH")
    bad("list longer than its count", {"t": "i16", "vc": 4}, "01ffff0000", "BAD_LENGTH")
    bad("list with half an element", {"t": "i16", "vc": 4}, "01ff", "BAD_LENGTH")
    bad("list count 0 with a byte", {"t": "u8", "vc": 4}, "0001", "BAD_LENGTH")
    bad("list bool element 0x02", {"t": "bool", "vc": 4}, "020102", "BAD_VALUE")
    bad("list bool wrong length before bad element", {"t": "bool", "vc": 4}, "0202", "BAD_LENGTH")
    return ({"description": "encode(value) == hex and decode(hex) == value for a descriptor type object. "
                            "Arrays are JSON lists, structs JSON objects, strings JSON strings, void null.",
             "vectors": vectors},
            {"description": "decode(hex) as type fails with error (the NAK code name a device answers). "
                            "Strings: a length byte over the capacity is BAD_VALUE (checked before the "
                            "payload length); otherwise payload length != 1 + n is BAD_LENGTH. Lists "
                            "(vc): likewise with the count byte, then 1 + n * size, then the elements.",
             "vectors": invalid})


def main() -> int:
    check = "--check" in sys.argv[1:]
    values, invalid = gen_values()
    files = {
        "crc.json": gen_crc(),
        "cobs.json": gen_cobs(),
        "frames.json": gen_frames(),
        "streams.json": gen_streams(),
        "values.json": values,
        "values_invalid.json": invalid,
        "session/rules.json": session_rules.gen(),  # a folder of its own: the wire suites load *.json here
        "both/frames.json": both_frames.gen(),  # likewise: frames of both directions, with a direction
        "large/frames.json": large_frames.gen(),  # likewise: fragments and lists, with exchanges
        "missions/frames.json": missions_frames.gen(),  # likewise: frames of missions, with a direction
    }
    changed = []
    for name, doc in files.items():
        text = json.dumps(doc, indent=1, ensure_ascii=True) + "\n"
        path = os.path.join(HERE, name)
        old = open(path).read() if os.path.exists(path) else None
        if old != text:
            changed.append(name)
            if not check:
                with open(path, "w") as fh:
                    fh.write(text)
    if check:
        if changed:
            print("out of date:", ", ".join(changed))
            return 1
        print("vectors up to date")
    else:
        print("wrote", ", ".join(changed) if changed else "nothing (up to date)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
