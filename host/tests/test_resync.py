"""Resynchronisation: valid frames survive any amount of interleaved garbage and corruption."""
from __future__ import annotations

import random

from hubwire.wire.frame import Frame, FrameDecoder, encode_frame


def _random_frame(rng: random.Random, max_payload: int) -> Frame:
    n = rng.choice((0, 1, 2, 10, rng.randrange(0, max_payload + 1)))
    alphabet = rng.choice((b"\x00", b"\x00\x01\xff", bytes(range(256))))
    payload = bytes(rng.choice(alphabet) for _ in range(n))
    return Frame(rng.randrange(256), rng.randrange(256), rng.randrange(256), payload)


def test_10000_frames_interleaved_with_garbage_and_corruption() -> None:
    rng = random.Random(0xC0B5)
    max_payload = 64
    stream = bytearray()
    expected = []
    corrupted = 0
    garbage_runs = 0
    for _ in range(10000):
        f = _random_frame(rng, max_payload)
        wire = encode_frame(*f)
        r = rng.random()
        if r < 0.15:
            # garbage ended by a delimiter
            stream += bytes(rng.randrange(256) for _ in range(rng.randrange(0, 40))) + b"\x00"
            garbage_runs += 1
        if r > 0.9:
            # corrupt this frame: flip bits of one byte (never the delimiter) -> must not be accepted
            w = bytearray(wire)
            i = rng.randrange(len(w) - 1)
            w[i] ^= rng.randrange(1, 256)
            if w[i] == 0:
                # we created a delimiter: the frame splits in two; neither half may be accepted
                pass
            wire = bytes(w)
            corrupted += 1
        else:
            expected.append(f)
        stream += wire
    d = FrameDecoder(max_payload)
    got = []
    pos = 0
    while pos < len(stream):
        n = rng.randrange(1, 700)
        got.extend(d.feed(bytes(stream[pos:pos + n])))
        pos += n
    # a corrupted frame may only disappear; it is never delivered as something else
    assert got == expected
    assert corrupted > 500 and garbage_runs > 1000
    # every corruption and every garbage run was counted somewhere
    total_bad = d.crc + d.overflow + d.dropped
    assert total_bad >= corrupted + garbage_runs - 50  # corruption making a 00 may add a drop, never lose many
    assert d.frames == len(expected)


def test_flood_without_delimiter_does_not_grow_memory() -> None:
    d = FrameDecoder(32)
    for _ in range(1000):
        assert d.feed(b"\x41" * 1000) == []
    assert len(d._pending) < 200  # bounded buffering
    f = Frame(0x52, 1, 2, b"ok")
    assert d.feed(b"\x00" + encode_frame(*f)) == [f]
    assert d.overflow == 1 and d.dropped == 0 and d.crc == 0
