"""Descriptor parsing: the Rover example parses; every kind of defect gives a clear DescriptorError."""
from __future__ import annotations

import json
from typing import Any

import pytest

from hubwire.descriptor import parse_descriptor
from hubwire.errors import DescriptorError, InvalidValue
from hubwire.wire.messages import NakCode, fnv1a32

EXAMPLE = (b'{"p":1,"n":"rover","fw":"1.0.0","ch":['
           b'{"id":1,"n":"left","a":"rws","t":"f32","u":"m/s","min":-1,"max":1,"fs":0,"d":"left motor"},'
           b'{"id":2,"n":"imu","a":"rs","t":"struct","f":[{"n":"ax","t":"f32"},{"n":"gyro","t":"i16","c":3}]},'
           b'{"id":3,"n":"bumper","a":"e","t":"bool"},'
           b'{"id":4,"n":"beep","a":"c","t":"u16","rt":"bool"},'
           b'{"id":5,"n":"label","a":"rw","t":"str","c":16}]}')


def test_example_from_protocol_parses() -> None:
    d = parse_descriptor(EXAMPLE)
    assert d.name == "rover" and d.firmware == "1.0.0" and d.protocol == 1
    assert d.hash == fnv1a32(EXAMPLE)
    left = d.by_name("left")
    assert left is not None and left.id == 1 and left.readable and left.writable and left.streamable
    assert left.unit == "m/s" and left.min == -1 and left.max == 1 and left.failsafe == 0.0
    assert left.description == "left motor"
    imu = d.by_id(2)
    assert imu is not None and imu.type_name == "struct{ax: f32, gyro: i16[3]}"
    v = imu.codec.decode(imu.codec.encode({"ax": 1.5, "gyro": (1, 2, 3)}))
    assert v.ax == 1.5 and v.gyro == (1, 2, 3)
    beep = d.by_name("beep")
    assert beep is not None and beep.callable and beep.type_name == "(u16) -> bool"
    assert d.by_name("label").codec.name == "str[16]"  # type: ignore[union-attr]
    assert d.by_name("bumper").is_event  # type: ignore[union-attr]


def test_channel_range_check() -> None:
    left = parse_descriptor(EXAMPLE).by_name("left")
    assert left is not None
    assert left.check(0.5) == 0.5
    with pytest.raises(InvalidValue) as e:
        left.check(1.5)
    assert e.value.code == NakCode.OUT_OF_RANGE and "-1..1" in str(e.value)
    with pytest.raises(InvalidValue) as e:
        left.check(float("nan"))  # NaN compares false with everything: never inside a range
    assert e.value.code == NakCode.OUT_OF_RANGE


def doc(**chan: Any) -> bytes:
    ch = {"id": 1, "n": "x", "a": "rw", "t": "u8"}
    ch.update(chan)
    ch = {k: v for k, v in ch.items() if v is not None}
    return json.dumps({"p": 1, "n": "d", "ch": [ch]}).encode()


BAD = [
    (b"", "not valid JSON"),
    (b"{", "not valid JSON"),
    (b"\xff\xfe", "UTF-8"),
    (b"[]", "must be a JSON object"),
    (b'{"p":1,"n":"d","ch":[]}' + b" " * 16384, "exceeds"),
    (b'{"p":1,"n":"d","ch":[{"id":1,"n":"x","a":"r","t":"u8","fs":[[[[1]]]]}]}', "nests"),
    (b"[" * 5000, "nests"),
    (b'{"p":2,"n":"d","ch":[]}', "protocol version"),
    (b'{"p":1,"n":"d","ch":[],"zz":1}', "unknown top-level key"),
    (b'{"p":1,"n":"d","n":"e","ch":[]}', "duplicate key"),
    (b'{"p":1,"n":5,"ch":[]}', "device name"),
    (b'{"p":1,"n":"d","ch":{}}', "must be a list"),
    (b'{"p":1,"n":"d","ch":[{"id":1,"n":"x","a":"r","t":"f32","min":NaN}]}', "not valid JSON"),
    (json.dumps({"p": 1, "n": "d", "ch": [{"id": 1, "n": "a", "a": "r", "t": "u8"},
                                          {"id": 1, "n": "b", "a": "r", "t": "u8"}]}).encode(), "duplicate channel id 1"),
    (json.dumps({"p": 1, "n": "d", "ch": [{"id": 1, "n": "a", "a": "r", "t": "u8"},
                                          {"id": 2, "n": "a", "a": "r", "t": "u8"}]}).encode(), "duplicate channel name"),
    (doc(t="u7"), "unknown type 'u7'"),
    (doc(a="rx"), "unknown access letter"),
    (doc(a="s"), "requires readable"),
    (doc(a="wc"), "exclude each other"),
    (doc(a="re"), "stands alone"),
    (doc(a="rr"), "repeated access letter"),
    (doc(a=""), "access"),
    (doc(id=0), "'id' must be an integer 1..255"),
    (doc(id=256), "'id' must be an integer 1..255"),
    (doc(id="1"), "'id' must be an integer"),
    (doc(n="1abc"), "must match"),
    (doc(n="a" * 33), "longer than 32"),
    (doc(n=None), "no name"),
    (doc(t=None), "no type"),
    (doc(zz=1), "unknown key"),
    (doc(t="str"), "needs a capacity"),
    (doc(t="str", c=255), "string capacity"),
    (doc(c=0), "array count"),
    (doc(t="u32", c=16384), "more than the largest value, 65535"),
    (doc(t="u8", c=65536), "array count"),
    (doc(vc=0), "variable-length array capacity"),
    (doc(vc=256), "variable-length array capacity"),
    (doc(vc=4, c=4), "exclude each other"),
    (doc(t="str", vc=4), "needs a scalar type"),
    (doc(t="struct", f=[{"n": "a", "t": "u8"}], vc=2), "no count"),
    (doc(t="struct", f=[{"n": "a", "t": "u8", "vc": 2}]), "unknown key"),
    (doc(rvc=2), "only for callable"),
    (doc(a="c", rvc=2), "without a return type"),
    (doc(a="c", rt="str", rvc=2), "needs a scalar type"),
    (doc(a="c", rt="u8", rc=2, rvc=2), "exclude each other"),
    (doc(vc=2, min=-1), "outside the u8 range"),
    (doc(t="struct"), "needs its fields"),
    (doc(t="struct", f=[]), "non-empty list"),
    (doc(t="struct", f=[{"n": "a", "t": "u8"}, {"n": "a", "t": "u8"}]), "duplicate field name"),
    (doc(t="struct", f=[{"n": "a", "t": "str", "c": 3}]), "not allowed here"),
    (doc(t="struct", f=[{"n": "a", "t": "u8", "q": 1}]), "unknown key"),
    (doc(t="struct", f=[{"n": "a"}]), "no type"),
    (doc(t="struct", f=[{"n": "a", "t": "u8"}], c=2), "no count"),
    (doc(f=[{"n": "a", "t": "u8"}]), "only for type 'struct'"),
    (doc(t="void"), "not allowed here"),
    (doc(rt="u8"), "only for callable"),
    (doc(a="c", rc=2), "without a return type"),
    (doc(a="c", rt="struct"), "not allowed here"),
    (doc(a="c", rt="str"), "needs a capacity 'rc'"),
    (doc(min=5, max=1), "greater than"),
    (doc(min=-1), "outside the u8 range"),
    (doc(min="0"), "must be a number"),
    (doc(t="bool", min=0), "only for numeric"),
    (doc(fs=300), "failsafe"),
    (doc(a="c", fs=1), "failsafe"),
    (doc(u=5), "unit"),
    (doc(d=5), "description"),
    (doc(t="bool", a="rw", fs="yes"), "failsafe"),
]


@pytest.mark.parametrize("data,message", BAD, ids=[m + f"#{i}" for i, (_, m) in enumerate(BAD)])
def test_bad_descriptors(data: bytes, message: str) -> None:
    with pytest.raises(DescriptorError) as e:
        parse_descriptor(data)
    assert message in str(e.value)


def test_failsafe_number_for_arrays_structs_and_bools() -> None:
    d = parse_descriptor(doc(t="f32", c=2, fs=0))
    assert d.by_name("x").failsafe == (0.0, 0.0)  # type: ignore[union-attr]
    d = parse_descriptor(doc(t="bool", fs=1))
    assert d.by_name("x").failsafe is True  # type: ignore[union-attr]
    d = parse_descriptor(doc(t="struct", f=[{"n": "a", "t": "u8"}, {"n": "b", "t": "i16", "c": 2}], fs=0))
    assert tuple(d.by_name("x").failsafe) == (0, (0, 0))  # type: ignore[union-attr, arg-type]
    d = parse_descriptor(doc(t="u8", c=2, fs=[1, 2]))
    assert d.by_name("x").failsafe == (1, 2)  # type: ignore[union-attr]


def test_keyword_and_underscore_field_names_work() -> None:
    d = parse_descriptor(doc(t="struct", f=[{"n": "from", "t": "u8"}, {"n": "_x", "t": "bool", "c": 2}], a="rw"))
    c = d.by_name("x")
    assert c is not None
    v = c.codec.decode(b"\x07\x01\x00")
    assert getattr(v, "from") == 7 and v._x == (True, False) and v["from"] == 7
    assert "from=7" in repr(v)


def test_bools_are_not_numbers_for_numeric_channels() -> None:
    """`left = True` must be refused like `beep(True)` is: a bool is not a speed."""
    from hubwire.errors import InvalidValue
    from hubwire.wire.values import codec_for

    for t in ("f32", "f64", "u8", "i16"):
        with pytest.raises(InvalidValue):
            codec_for({"t": t}).check(True)
    assert codec_for({"t": "bool"}).check(True) is True


def test_variable_length_arrays_and_large_values() -> None:
    d = parse_descriptor(json.dumps({"p": 1, "n": "d", "ch": [
        {"id": 1, "n": "path", "a": "rw", "t": "i16", "vc": 8, "min": -100, "max": 100},
        {"id": 2, "n": "blob", "a": "rws", "t": "u8", "c": 1024},
        {"id": 3, "n": "pick", "a": "c", "t": "u8", "vc": 3, "rt": "bool", "rvc": 2},
        {"id": 4, "n": "flags", "a": "rw", "t": "bool", "vc": 2, "fs": [True]}]}))
    path, blob, pick, flags = d.channels
    assert (path.codec.kind, path.codec.max_size, path.type_name) == ("list", 17, "i16[<=8]")
    assert path.type == {"t": "i16", "vc": 8}
    assert (blob.codec.size, blob.type_name) == (1024, "u8[1024]")
    assert pick.type_name == "(u8[<=3]) -> bool[<=2]"
    assert pick.returns is not None and pick.returns.max_size == 3
    assert flags.failsafe == [True]
