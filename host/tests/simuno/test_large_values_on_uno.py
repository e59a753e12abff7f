"""End to end on the simulated Uno: examples/LargeValues, a 200-byte struct that does not fit the
Uno's 32-byte frame, read and written whole in fragments (PROTOCOL.md 12), and a list channel
(hubwire::List<int16_t, 12>) and an action taking a list, checked on both sides."""
from __future__ import annotations

import struct
from typing import Any, Dict

import pytest

from hubwire.errors import InvalidValue, NakError
from hubwire.wire import messages as m

from .conftest import Examples


def as_json(value: Any) -> Dict[str, Any]:
    return {k: (list(v) if isinstance(v, tuple) else v) for k, v in value._asdict().items()}


def profile(n: int) -> Dict[str, Any]:
    return {"gain": [(i - 10) * 0.125 * n for i in range(20)],
            "table": [(i * 977 * n) % 60000 - 30000 for i in range(40)],
            "name": [(n + i * 3) % 256 for i in range(40)]}


def test_a_200_byte_struct_and_a_list_on_the_uno(examples: Examples) -> None:
    dev = examples.start("LargeValues")
    core = dev.session.core
    prof = dev.descriptor.by_name("profile")
    assert prof.codec.size == 200 and dev.session.device_hello.max_payload == 32
    assert [(c.name, c.access, c.type_name, c.unit, c.min, c.max) for c in dev.descriptor.channels] == [
        ("profile", "rw", "struct{gain: f32[20], table: i16[40], name: u8[40]}", None, None, None),
        ("path", "rw", "i16[<=12]", "cm", -1000, 1000),
        ("sum", "c", "(u8[<=16]) -> u16", None, None, None),
        ("profile_writes", "r", "u16", None, None, None),
        ("path_writes", "r", "u16", None, None, None)]

    first = as_json(dev.profile)  # the sketch's setup() values, read in fragments
    assert first == {"gain": [i * 0.5 for i in range(20)], "table": [i * 100 - 2000 for i in range(40)],
                     "name": [ord("a") + i % 26 for i in range(40)]}
    assert core.link.reassembler.completed >= 1

    for n in (1, 2, 3):
        dev.profile = profile(n)  # 8 fragments of at most 27 bytes of value each
        assert dev.profile_writes == n  # applied exactly once each
        assert as_json(dev.profile) == profile(n)  # never torn

    dev.path = [10, -20, 30]
    assert dev.path == [10, -20, 30]
    dev.path = []
    assert dev.path == []
    dev.path = list(range(-1000, 1001, 182))[:12]
    assert dev.path == list(range(-1000, 1001, 182))[:12]
    assert dev.path_writes == 3
    assert dev.call("sum", [1, 2, 3, 250]) == 256
    assert dev.call("sum", []) == 0

    # the hub refuses what the board would, before sending
    for bad, code in (([0] * 13, m.NakCode.BAD_VALUE), ([1001], m.NakCode.OUT_OF_RANGE)):
        with pytest.raises(InvalidValue) as e:
            dev.path = bad
        assert e.value.code == code
    assert dev.path_writes == 3

    # and the board itself judges a list in the same order (count, length, elements)
    path_id = dev.descriptor.by_name("path").id
    for payload, code in ((bytes((13,)) + bytes(26), m.NakCode.BAD_VALUE),
                          (bytes((13,)) + bytes(2), m.NakCode.BAD_VALUE),
                          (bytes((2,)) + bytes(2), m.NakCode.BAD_LENGTH),
                          (bytes((1,)) + struct.pack("<h", 1001), m.NakCode.OUT_OF_RANGE)):
        with pytest.raises(NakError) as nak:
            dev.session.transact(m.CONTROL, path_id, payload)
        assert nak.value.code == code
    assert dev.path == list(range(-1000, 1001, 182))[:12] and dev.path_writes == 3
    assert dev.profile_writes == 3
