"""Property tests: round trips, and arbitrary input never raises anything but our own errors."""
from __future__ import annotations

import importlib.util
import json
import math
import os
import struct
from typing import Any, Dict

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from hubwire.descriptor import parse_descriptor
from hubwire.errors import DescriptorError, InvalidValue
from hubwire.wire.frame import Frame, FrameDecoder, encode_frame
from hubwire.wire.messages import NakCode
from hubwire.wire.values import SCALARS, codec_for

_spec = importlib.util.spec_from_file_location(
    "vector_generator", os.path.join(os.path.dirname(__file__), "..", "..", "test", "vectors", "generate.py"))
assert _spec and _spec.loader
generate = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(generate)  # type: ignore[union-attr]

byte = st.integers(0, 255)
frames = st.builds(Frame, byte, byte, byte, st.binary(max_size=255))


@given(st.lists(frames, max_size=20), st.lists(st.integers(1, 300), min_size=1, max_size=10))
def test_frames_round_trip_with_any_chunking(fs: Any, cuts: Any) -> None:
    data = b"".join(encode_frame(*f) for f in fs)
    d = FrameDecoder(255)
    got = []
    pos = i = 0
    while pos < len(data):
        n = cuts[i % len(cuts)]
        got.extend(d.feed(data[pos:pos + n]))
        pos += n
        i += 1
    assert got == fs
    assert d.counters() == {"crc": 0, "overflow": 0, "dropped": 0}


@settings(max_examples=300)
@given(st.binary(max_size=800), st.integers(0, 255))
def test_decoder_arbitrary_bytes_matches_reference_receiver(data: bytes, max_payload: int) -> None:
    d = FrameDecoder(max_payload)
    got = d.feed(data)
    ref = generate.ReferenceReceiver(max_payload)
    for b in data:
        ref.byte(b)
    assert [tuple(f) for f in got] == ref.frames
    assert d.counters() == ref.counters
    assert all(len(f.payload) <= max_payload for f in got)


@settings(max_examples=200)
@given(st.lists(st.one_of(frames.map(lambda f: encode_frame(*f)), st.binary(max_size=50)), max_size=15),
       st.integers(0, 255))
def test_decoder_mixed_input_matches_reference(parts: Any, max_payload: int) -> None:
    data = b"".join(parts)
    d = FrameDecoder(max_payload)
    got = []
    for i in range(0, len(data), 7):
        got.extend(d.feed(data[i:i + 7]))
    ref = generate.ReferenceReceiver(max_payload)
    for b in data:
        ref.byte(b)
    assert [tuple(f) for f in got] == ref.frames
    assert d.counters() == ref.counters


# ---------------------------------------------------------------------------------------- values

scalar_names = st.sampled_from(sorted(SCALARS))
names = st.from_regex(r"[A-Za-z_][A-Za-z0-9_]{0,8}", fullmatch=True)


def scalar_type(with_count: bool = True) -> Any:
    base = scalar_names.map(lambda t: {"t": t})
    if not with_count:
        return base
    return st.one_of(base, st.tuples(scalar_names, st.integers(1, 6)).map(lambda x: {"t": x[0], "c": x[1]}))


struct_type = st.lists(st.tuples(names, scalar_type()), min_size=1, max_size=5, unique_by=lambda x: x[0]).map(
    lambda fs: {"t": "struct", "f": [{"n": n, **t} for n, t in fs]})
str_type = st.integers(1, 40).map(lambda c: {"t": "str", "c": c})
type_objs = st.one_of(scalar_type(), struct_type, str_type, st.just({"t": "void"}))


def scalar_value(t: str) -> Any:
    if t == "bool":
        return st.booleans()
    if t in ("f32",):
        return st.floats(width=32, allow_nan=False)
    if t == "f64":
        return st.floats(allow_nan=False)
    _, _, lo, hi = SCALARS[t]
    return st.integers(lo, hi)


def value_for(t: Dict[str, Any]) -> Any:
    if t["t"] == "void":
        return st.none()
    if t["t"] == "str":
        return st.text(max_size=t["c"]).filter(lambda s: len(s.encode()) <= t["c"])
    if t["t"] == "struct":
        return st.tuples(*[value_for(f) for f in t["f"]])
    if "c" in t:
        return st.tuples(*[scalar_value(t["t"])] * t["c"])
    return scalar_value(t["t"])


@settings(suppress_health_check=[HealthCheck.too_slow])
@given(st.data())
def test_values_round_trip(data: Any) -> None:
    t = data.draw(type_objs)
    c = codec_for(t)
    v = data.draw(value_for(t))
    enc = c.encode(v)
    if c.size is not None:
        assert len(enc) == c.size
    dec = c.decode(enc)
    assert dec == v
    assert c.encode(dec) == enc
    # the JSON form survives a trip through json as well
    assert c.from_json(json.loads(json.dumps(c.to_json(dec)))) == dec


@given(type_objs, st.binary(max_size=80))
def test_value_decode_arbitrary_bytes_raises_only_invalid_value(t: Dict[str, Any], data: bytes) -> None:
    c = codec_for(t)
    try:
        v = c.decode(data)
    except InvalidValue as e:
        assert e.code in (NakCode.BAD_LENGTH, NakCode.BAD_VALUE)
    else:
        assert c.encode(v) == data or t["t"] == "str"  # invalid UTF-8 is replaced, not an error


@given(type_objs, st.one_of(st.none(), st.booleans(), st.integers(), st.floats(), st.text(max_size=5),
                            st.lists(st.integers(), max_size=4), st.dictionaries(names, st.integers(), max_size=3)))
def test_value_encode_arbitrary_python_raises_only_invalid_value(t: Dict[str, Any], v: Any) -> None:
    c = codec_for(t)
    try:
        enc = c.encode(v)
    except InvalidValue as e:
        assert e.code in (NakCode.BAD_LENGTH, NakCode.BAD_VALUE, NakCode.OUT_OF_RANGE)
        assert str(e)
    else:
        c.decode(enc)


def test_integer_limits_are_enforced() -> None:
    for t, (_, _, lo, hi) in SCALARS.items():
        if t in ("f32", "f64", "bool"):
            continue
        c = codec_for({"t": t})
        c.encode(lo)
        c.encode(hi)
        for bad in (lo - 1, hi + 1):
            try:
                c.encode(bad)
            except InvalidValue as e:
                assert e.code == NakCode.OUT_OF_RANGE
            else:
                raise AssertionError(f"{t} accepted {bad}")
    f32 = codec_for({"t": "f32"})
    try:
        f32.encode(1e39)
    except InvalidValue as e:
        assert e.code == NakCode.OUT_OF_RANGE
    else:
        raise AssertionError("f32 accepted 1e39")
    assert math.isinf(struct.unpack("<f", f32.encode(float("inf")))[0])


# ------------------------------------------------------------------------------------ descriptor

@given(st.binary(max_size=300))
def test_descriptor_arbitrary_bytes_raise_only_descriptor_error(data: bytes) -> None:
    try:
        parse_descriptor(data)
    except DescriptorError:
        pass


json_values = st.recursive(
    st.one_of(st.none(), st.booleans(), st.integers(-300, 300), st.floats(allow_nan=False, allow_infinity=False),
              st.sampled_from(["r", "rw", "rws", "e", "c", "f32", "u8", "str", "struct", "void", "x", ""])),
    lambda inner: st.one_of(st.lists(inner, max_size=4),
                            st.dictionaries(st.sampled_from(["p", "n", "ch", "id", "a", "t", "c", "f", "rt", "rc",
                                                             "u", "min", "max", "fs", "d", "fw", "zz"]),
                                            inner, max_size=6)),
    max_leaves=25)


@settings(max_examples=300)
@given(json_values)
def test_descriptor_arbitrary_json_raises_only_descriptor_error(doc: Any) -> None:
    for candidate in (doc, {"p": 1, "n": "x", "ch": doc}, {"p": 1, "n": "x", "ch": [doc]}):
        try:
            parse_descriptor(json.dumps(candidate).encode())
        except DescriptorError as e:
            assert str(e).startswith("descriptor")


channel_strategy = st.one_of(
    st.tuples(st.sampled_from(["r", "rw", "rws", "rs", "w"]), type_objs.filter(lambda t: t["t"] != "void")),
    st.tuples(st.just("e"), scalar_type()),
    st.tuples(st.just("c"), st.one_of(scalar_type(), st.just({"t": "void"}))),
)


@given(st.lists(st.tuples(names, channel_strategy), max_size=12, unique_by=lambda x: x[0]))
def test_generated_valid_descriptors_parse(chs: Any) -> None:
    doc = {"p": 1, "n": "dev", "ch": []}
    for i, (n, (a, t)) in enumerate(chs):
        doc["ch"].append({"id": i + 1, "n": n, "a": a, **t})
    d = parse_descriptor(json.dumps(doc, separators=(",", ":")).encode())
    assert [c.name for c in d] == [n for n, _ in chs]
    assert [c.id for c in d] == list(range(1, len(chs) + 1))
