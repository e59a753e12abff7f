"""Hostile and broken input against the hub (docs/RELIABILITY.md, "Hard caps").

Descriptors that are oversized, malformed, too deep, ambiguous or of the wrong shape; frames of
impossible lengths; a device that never answers; a device that floods garbage or valid frames;
values out of range. The hub must refuse with a clear error, stay bounded and leak nothing.
"""
from __future__ import annotations

import json
import random
import time
import tracemalloc
from typing import Any, Iterator, List

import pytest

import hubwire
from hubwire import parse_descriptor
from hubwire.descriptor import MAX_DEPTH, MAX_DESCRIPTOR_SIZE
from hubwire.errors import DescriptorError, InvalidValue
from hubwire.testing import tap_of, tapped
from hubwire.wire import messages as m
from hubwire.wire.frame import FrameDecoder, encode_frame
from hubwire.wire.messages import NakCode

from .conftest import HostileDevice, fd_count, hubwire_thread_ids, hubwire_threads, settle

#: tracemalloc peak allowed while a device floods the hub for FLOOD_SECONDS (documented cap)
FLOOD_MEMORY_CAP = 4 * 1024 * 1024
FLOOD_SECONDS = 2.0
#: a flood goes on past FLOOD_SECONDS until this much was written (or FLOOD_MAX_SECONDS passed)
FLOOD_MIN_BYTES = 150_000
FLOOD_MAX_SECONDS = 30.0


def ch(**kw: Any) -> dict:
    base = {"id": 1, "n": "x", "a": "rw", "t": "u16"}
    base.update(kw)
    return {k: v for k, v in base.items() if v is not None}


def desc(*channels: Any, **top: Any) -> str:
    d = {"p": 1, "n": "dev", "ch": list(channels)}
    d.update(top)
    return json.dumps(d)


# ------------------------------------------------------------------------------- descriptors

BAD_DESCRIPTORS = [
    # (case, descriptor, words the message must contain)
    ("oversized", desc(ch(d="x" * (MAX_DESCRIPTOR_SIZE + 1))).encode(), ["exceeds", "16384"]),
    ("oversized text", desc(ch(d="x" * (MAX_DESCRIPTOR_SIZE + 1))), ["exceeds"]),
    ("empty", b"", ["not valid JSON"]),
    ("truncated", desc(ch())[:-3].encode(), ["not valid JSON"]),
    ("not utf-8", b'{"p":1,"n":"\xff\xfe","ch":[]}', ["UTF-8"]),
    ("NaN constant", '{"p":1,"n":"d","ch":[{"id":1,"n":"x","a":"rw","t":"f32","min":NaN}]}', ["NaN"]),
    ("top-level list", "[1,2,3]", ["JSON object"]),
    ("deeply nested arrays", "[" * 8000 + "]" * 8000, ["nests", str(MAX_DEPTH)]),
    ("nested past the size cap", "[" * 100000 + "]" * 100000, ["exceeds"]),
    ("deeply nested objects", '{"a":' * 2500 + "1" + "}" * 2500, ["nests"]),
    ("nested inside a channel", desc(ch(d={"x": {"y": [[1]]}})), ["nests"]),
    ("duplicate ids", desc(ch(), ch(n="y")), ["duplicate channel id 1"]),
    ("duplicate names", desc(ch(), ch(id=2)), ["duplicate channel name 'x'"]),
    ("duplicate key", '{"p":1,"n":"d","n":"e","ch":[]}', ["duplicate key 'n'"]),
    ("duplicate field names", desc(ch(a="r", t="struct", f=[{"n": "a", "t": "u8"}, {"n": "a", "t": "u8"}])),
     ["duplicate field name 'a'"]),
    ("unknown type", desc(ch(t="u64")), ["unknown type 'u64'"]),
    ("unknown field type", desc(ch(a="r", t="struct", f=[{"n": "a", "t": "i17"}])), ["f[0]", "unknown type 'i17'"]),
    ("struct in a struct", desc(ch(a="r", t="struct", f=[{"n": "a", "t": "struct"}])), ["not allowed"]),
    ("unknown access", desc(ch(a="rwz")), ["access letter", "z"]),
    ("event with others", desc(ch(a="er")), ["stands alone"]),
    ("w and c", desc(ch(a="wc")), ["exclude"]),
    ("s without r", desc(ch(a="s")), ["requires readable"]),
    ("id 0", desc(ch(id=0)), ["'id' must be an integer 1..255"]),
    ("id 256", desc(ch(id=256)), ["1..255"]),
    ("id as string", desc(ch(id="1")), ["'id'"]),
    ("bool id", desc(ch(id=True)), ["'id'"]),
    ("name too long", desc(ch(n="a" * 33)), ["longer than 32"]),
    ("bad name", desc(ch(n="1abc")), ["must match"]),
    ("channel not an object", desc([1, 2]), ["must be an object"]),
    ("channels not a list", desc(), None),
    ("fields not a list", desc(ch(a="r", t="struct", f={"n": "a"})), ["non-empty list"]),
    ("field missing type", desc(ch(a="r", t="struct", f=[{"n": "a"}])), ["no type"]),
    ("field extra key", desc(ch(a="r", t="struct", f=[{"n": "a", "t": "u8", "zz": 1}])), ["unknown key"]),
    ("str without capacity", desc(ch(t="str")), ["capacity"]),
    ("str too long", desc(ch(t="str", c=255)), ["1..254"]),
    ("array too big", desc(ch(t="u32", c=16384)), ["more than the largest value, 65535"]),
    ("struct too big", desc(ch(a="r", t="struct", f=[{"n": "a", "t": "u8", "c": 65535}, {"n": "b", "t": "u8"}])),
     ["struct is 65536 bytes, more than the largest value"]),
    ("min > max", desc(ch(min=10, max=1)), ["greater than"]),
    ("min outside type", desc(ch(min=-1)), ["outside the u16 range"]),
    ("range on a string", desc(ch(t="str", c=4, min=0)), ["only for numeric"]),
    ("failsafe wrong type", desc(ch(fs="zero")), ["failsafe"]),
    ("unknown top key", desc(ch(), extra=1), ["unknown top-level key"]),
    ("wrong protocol", desc(ch(), p=2), ["protocol version"]),
    ("channel extra key", desc(ch(zz=1)), ["unknown key"]),
    ("rt on a variable", desc(ch(rt="u8")), ["only for callable"]),
]


@pytest.mark.parametrize("case,text,words", BAD_DESCRIPTORS, ids=[c[0] for c in BAD_DESCRIPTORS])
def test_bad_descriptor_raises_a_clear_descriptor_error(case: str, text: Any, words: Any) -> None:
    if case == "channels not a list":
        text = json.dumps({"p": 1, "n": "d", "ch": {"id": 1}})
        words = ["'ch' must be a list"]
    t = time.monotonic()
    with pytest.raises(DescriptorError) as e:
        parse_descriptor(text)
    assert time.monotonic() - t < 2.0  # no pathological slowness either
    msg = str(e.value)
    assert msg.startswith("descriptor"), msg
    for w in words:
        assert w in msg, f"{case}: {w!r} not in {msg!r}"
    assert len(msg) < 400, "the message must stay readable"


def test_largest_valid_descriptor_is_accepted() -> None:
    chans = [ch(id=i, n=f"c{i}", u="m") for i in range(1, 256)]
    text = json.dumps({"p": 1, "n": "dev", "ch": chans}, separators=(",", ":"))
    assert len(text) <= MAX_DESCRIPTOR_SIZE
    d = parse_descriptor(text)
    assert len(d.channels) == 255


# ----------------------------------------------------------------------- over the wire: connect

def test_device_with_a_malformed_descriptor_fails_connect_clearly(tmp_path: Any) -> None:
    with HostileDevice(b'{"p":1,"n":"bad","ch":[{"id":1,"n":"x","a":"rw","t":"u99"}]}') as d:
        t = time.monotonic()
        with pytest.raises(DescriptorError) as e:
            hubwire.connect(d.path, cache_dir=False, timeout=3)
        assert time.monotonic() - t < 10
    assert "unknown type 'u99'" in str(e.value)


def test_device_announcing_a_descriptor_over_the_cap_is_refused_without_downloading_it() -> None:
    """A hello announcing 60000 bytes: over the hub's 16 KiB cap. The hub must refuse it from the
    hello alone instead of downloading 60 KB first."""
    big = b'{"p":1,"n":"big","ch":[],"x":"' + b"y" * 60000 + b'"}'
    with HostileDevice(big) as d:
        with pytest.raises(DescriptorError) as e:
            hubwire.connect(d.path, cache_dir=False, timeout=3)
        requests = d.chunk_requests
    assert "16384" in str(e.value)
    assert requests <= 8, f"the hub asked for {requests} chunks of a descriptor it must refuse"


def test_device_announcing_a_wrong_hash_is_refused(tmp_path: Any) -> None:
    with HostileDevice(announce_hash=0x12345678) as d:
        with pytest.raises(DescriptorError) as e:
            hubwire.connect(d.path, cache_dir=False, timeout=3)
    assert "hash mismatch" in str(e.value)


def test_device_that_never_answers_times_out_within_the_deadline_without_leaks() -> None:
    with HostileDevice(answer_hello=False) as d:
        hubwire.connect  # warm imports before counting
        threads0, fds0 = hubwire_thread_ids(), fd_count()
        for _ in range(3):
            t = time.monotonic()
            with pytest.raises(hubwire.Timeout) as e:
                hubwire.connect(d.path, cache_dir=False, timeout=1.0)
            took = time.monotonic() - t
            assert 0.9 <= took < 1.0 + 2.5, took  # the deadline, plus closing the port and threads
        assert "no Hubwire device answered" in str(e.value)
        assert settle(lambda: not hubwire_thread_ids() - threads0), hubwire_threads()
        assert fd_count() == fds0
        # the hub did try: hellos every 100 ms
        assert sum(1 for f in d.received if f.type == m.HELLO) >= 10


def test_device_that_never_serves_its_descriptor_fails_connect_without_leaks() -> None:
    with HostileDevice(answer_chunks=False) as d:
        threads0, fds0 = hubwire_thread_ids(), fd_count()
        t = time.monotonic()
        with pytest.raises(hubwire.HubwireError) as e:
            hubwire.connect(d.path, cache_dir=False, timeout=2.0)
        took = time.monotonic() - t
        assert isinstance(e.value, hubwire.Timeout), repr(e.value)
        assert took < 2.0 + 2.5, took
        assert settle(lambda: not hubwire_thread_ids() - threads0), hubwire_threads()
        assert fd_count() == fds0


def test_never_answering_device_honours_the_connect_deadline_even_with_discovery_stuck() -> None:
    """connect(timeout=T) must return within about T however discovery is going."""
    with HostileDevice(answer_chunks=False) as d:
        t = time.monotonic()
        with pytest.raises(hubwire.HubwireError):
            hubwire.connect(d.path, cache_dir=False, timeout=0.5, retry_timeout=0.5, tries=10)
        took = time.monotonic() - t
    assert took < 0.5 + 1.5, f"connect(timeout=0.5) took {took:.1f} s"


# ---------------------------------------------------------------------- impossible frames

def test_impossible_frames_are_dropped_and_counted_and_the_link_survives() -> None:
    def answers(f: Any) -> Any:
        if f.type == m.REQUEST and f.id == 1:
            return (b"\x01" * 300 + b"\x00"              # longer than any frame: overflow
                    + b"\x02\x52\x00"                    # raw length < 5: dropped
                    + b"\x03\x05\x05\x00"                # COBS code pointing past the delimiter
                    + bytes(b ^ (0x40 if i == 4 else 0) for i, b in enumerate(encode_frame(m.RESPONSE, f.seq, f.id, b"\x07\x00")))  # crc
                    + encode_frame(m.HELLO, 0, 0, b"\x01\x01")   # hello of 2 bytes: dropped
                    + encode_frame(m.HEARTBEAT, 0, 0, b"\x01")   # heartbeat of 1 byte: dropped
                    + encode_frame(m.SAMPLE, 0, 3, b"\x01")      # sample shorter than its header
                    + encode_frame(0x99, 0, 0, b"")              # unknown type
                    + encode_frame(m.RESPONSE, f.seq, f.id, b"\x07\x00"))  # finally the answer
        return None

    with HostileDevice(on_request=answers) as d:
        with hubwire.connect(d.path, cache_dir=False, timeout=3) as dev:
            assert dev.x == 7
            c = dev.health().hub_counters
            assert c["overflow"] >= 1 and c["crc"] >= 1 and c["dropped"] >= 5, c
            assert dev.session.stats.unknown_frames >= 1
            assert dev.state == "ready"
            dev.x = 5


def test_answers_of_the_wrong_length_raise_not_crash() -> None:
    def answers(f: Any) -> Any:
        if f.type == m.REQUEST:
            return encode_frame(m.RESPONSE, f.seq, f.id, b"\x01\x02\x03")  # u16 needs 2 bytes
        if f.type == m.CONTROL:
            return encode_frame(m.NAK, f.seq, f.id, b"")  # NAK without its code
        return None

    with HostileDevice(on_request=answers) as d:
        with hubwire.connect(d.path, cache_dir=False, timeout=3) as dev:
            with pytest.raises(hubwire.HubwireError):
                dev.x
            with pytest.raises(hubwire.HubwireError):
                dev.x = 3
            assert dev.state == "ready"


# -------------------------------------------------------------------------------- floods

def garbage(seed: int, zeros: bool) -> Iterator[bytes]:
    rng = random.Random(seed)
    while True:
        b = bytes(rng.getrandbits(8) for _ in range(4096))
        yield b if zeros else b.replace(b"\x00", b"\x01")


def valid_frames(kind: str) -> Iterator[bytes]:
    seq = 0
    while True:
        batch = []
        for _ in range(256):
            seq = (seq + 1) & 0xFF
            if kind == "events":
                batch.append(encode_frame(m.EVENT, seq, 2, bytes((seq,))))
            elif kind == "samples":
                batch.append(encode_frame(m.SAMPLE, seq, 3, b"\x0a\x00\x01\x00"))
            elif kind == "answers":
                batch.append(encode_frame(m.ACK, seq, 1))
            else:
                batch.append(encode_frame(m.HEARTBEAT, seq, 0, m.Heartbeat(seq, 1, 0, 0, 0).pack()))
        yield b"".join(batch)


def flood_peak(dev_factory: Any, chunks: Iterator[bytes], setup: Any = None) -> Any:
    with HostileDevice() as d:
        with hubwire.connect(d.path, cache_dir=False, timeout=3) as dev:
            keep = setup(dev) if setup else None
            tracemalloc.start()
            try:
                sent = d.flood(chunks, FLOOD_SECONDS, min_bytes=FLOOD_MIN_BYTES, max_seconds=FLOOD_MAX_SECONDS)
                time.sleep(0.3)  # let the reader catch up
                _, peak = tracemalloc.get_traced_memory()
            finally:
                tracemalloc.stop()
            alive = dev.state
            del keep
    return peak, sent, alive


@pytest.mark.parametrize("zeros", [True, False], ids=["garbage", "garbage-without-delimiters"])
def test_garbage_flood_keeps_memory_bounded(zeros: bool) -> None:
    peak, sent, state = flood_peak(None, garbage(1, zeros))
    assert sent > 100_000, f"flood too small to mean anything ({sent} bytes)"
    assert peak < FLOOD_MEMORY_CAP, f"peak {peak} bytes while flooded with {sent} bytes"


@pytest.mark.parametrize("kind", ["heartbeats", "samples", "answers", "events"])
def test_valid_frame_flood_keeps_memory_bounded(kind: str) -> None:
    peak, sent, state = flood_peak(None, valid_frames(kind))
    assert sent > 100_000, f"flood too small to mean anything ({sent} bytes)"
    assert peak < FLOOD_MEMORY_CAP, f"peak {peak} bytes while flooded with {sent} bytes of {kind}"
    assert state == "ready"


def test_event_flood_with_an_idle_listener_keeps_memory_bounded() -> None:
    def listen(dev: Any) -> Any:
        return dev.events("ev"), dev.on("ev", lambda v: time.sleep(0.01))

    peak, sent, state = flood_peak(None, valid_frames("events"), listen)
    assert sent > 100_000
    assert peak < FLOOD_MEMORY_CAP, f"peak {peak} bytes while flooded with {sent} bytes of events"


# ------------------------------------------------------------------ values refused before sending

OUT_OF_RANGE = [
    ("left", 1.5), ("left", -1.0000001), ("left", float("inf")), ("left", float("-inf")),
    ("left", 1e39), ("left", "0.5"), ("left", None), ("led", "yes"), ("led", 2), ("name", "x" * 17),
    ("name", "é" * 9), ("right", [0.1]),
]


def test_values_out_of_range_are_refused_before_sending(emu: Any) -> None:
    with hubwire.connect(transport=tapped(emu.link), cache_dir=False) as dev:
        sent: List[Any] = []
        tap_of(dev).tx_filter = lambda w: (sent.extend(f for f in FrameDecoder().feed(w) if f.type == m.CONTROL), True)[1]
        for name, value in OUT_OF_RANGE:
            with pytest.raises((InvalidValue, TypeError, ValueError)) as e:
                dev.write(name, value)
            assert name in str(e.value) or isinstance(e.value, InvalidValue), (name, value, e.value)
        for arg in (70000, -1, 1.5, "1"):
            with pytest.raises((InvalidValue, TypeError, ValueError)):
                dev.beep(arg)
        for arg in (256, -1):
            with pytest.raises((InvalidValue, TypeError, ValueError)):
                dev.selftest(arg)
        tap_of(dev).tx_filter = None
        assert sent == [], f"sent {sent}"
        assert dev.applied == 0


def test_nan_is_refused_for_a_ranged_channel(emu: Any) -> None:
    with hubwire.connect(emu.link, cache_dir=False) as dev:
        with pytest.raises(InvalidValue) as e:
            dev.left = float("nan")
        assert e.value.code == NakCode.OUT_OF_RANGE
