"""The topic layout, settings and the outbox on their own (no broker)."""
from __future__ import annotations

import asyncio
import json

import pytest

from hubwire.bridge.outbox import Outbox
from hubwire.bridge.topics import BadPayload, BridgeConfig, Topics, parse_value, safe_id


def test_command_topics_parse_and_others_do_not() -> None:
    t = Topics("hw")
    assert t.parse_command("hw/rover/set/left") == ("rover", "set", "left")
    assert t.parse_command("hw/rover/unsubscribe/imu") == ("rover", "unsubscribe", "imu")
    assert t.parse_command("hw/rover/rpc") == ("rover", "rpc", None)
    for other in ("hw/rover/state/left", "hw/rover/set", "hw/rover/set/left/x", "hubwire/rover/set/left",
                  "hw/rover/rpc/reply", "hw/rover/descriptor"):
        assert t.parse_command(other) is None, other
    assert set(t.command_filters()) == {"hw/+/set/+", "hw/+/call/+", "hw/+/read/+", "hw/+/subscribe/+",
                                        "hw/+/unsubscribe/+", "hw/+/rpc"}


def test_ceiling_by_board_and_channel_then_channel_then_default() -> None:
    c = BridgeConfig(max_rate_hz={"imu": 50, "rover/imu": 20}, default_max_rate_hz=80)
    assert (c.ceiling("rover", "imu"), c.ceiling("other", "imu"), c.ceiling("rover", "battery")) == (20, 50, 80)


def test_values_parse_as_json_only() -> None:
    assert parse_value(b"0.5") == 0.5 and parse_value(b'{"ax": 1}') == {"ax": 1}
    assert parse_value(b"", empty_is_none=True) is None
    for bad in (b"", b"fast", b"NaN", b"Infinity", b"\xff"):
        with pytest.raises(BadPayload):
            parse_value(bad)
    assert safe_id("rover.kitchen:2") == "rover_kitchen_2"


def test_outbox_keeps_last_values_and_events_in_order() -> None:
    async def main() -> None:
        box = Outbox(event_limit=3)
        box.put_latest("a", "1")
        box.put_latest("b", "x")
        box.put_latest("a", "2")  # the newest wins, in its first place
        assert [box.take_latest(), box.take_latest(), box.take_latest()] == [("a", "2"), ("b", "x"), None]
        box.put_latest("a", "2")  # unchanged: nothing to send
        assert box.take_latest() is None
        box.forget("b")  # cleared once on the broker, then never republished
        assert box.take_latest() == ("b", "")
        box.all_dirty()  # after a reconnect
        assert [box.take_latest(), box.take_latest()] == [("a", "2"), None]
        for i in range(5):
            box.put_event("e", str(i))
        assert [p for _, p in box.events] == ["2", "3", "4"] and box.events_dropped == 2
    asyncio.run(main())


def test_f32_values_are_published_in_their_shortest_form() -> None:
    """An f32 read back as a Python float prints all the digits of the double (0.10000000149011612);
    the state (what Home Assistant shows) carries the shortest decimal that is the same f32."""
    import struct as st

    from hubwire.descriptor import parse_descriptor
    from hubwire.bridge.topics import dumps, to_json
    desc = parse_descriptor(json.dumps({"p": 1, "n": "x", "ch": [
        {"id": 1, "n": "imu", "a": "r", "t": "struct", "f": [{"n": "ax", "t": "f32"}, {"n": "g", "t": "f32", "c": 2},
                                                             {"n": "n", "t": "i16"}]},
        {"id": 2, "n": "v", "a": "r", "t": "f32"}, {"id": 3, "n": "d", "a": "r", "t": "f64"},
        {"id": 4, "n": "l", "a": "r", "t": "f32", "vc": 4}]}).encode())

    def f32(x: float) -> float:
        return float(st.unpack("<f", st.pack("<f", x))[0])
    imu, v, d, lst = (desc.by_name(n) for n in ("imu", "v", "d", "l"))
    value = imu.codec.decode(imu.codec.encode({"ax": 0.1, "g": [9.81, -1e-7], "n": 3}))
    assert dumps(to_json(imu, value)) == '{"ax":0.1,"g":[9.81,-1e-07],"n":3}'
    assert dumps(to_json(v, f32(0.1))) == "0.1" and to_json(v, f32(1 / 3)) == 0.33333334
    assert to_json(d, 0.10000000149011612) == 0.10000000149011612  # an f64 keeps every digit
    assert to_json(lst, [f32(2.2), f32(float("nan"))]) == [2.2, None]
    for x in (f32(0.1), f32(123456.789), f32(3.4e38), f32(1.17e-38), 0.0, -0.0):
        assert f32(to_json(v, x)) == x  # the same f32
