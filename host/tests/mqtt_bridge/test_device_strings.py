"""Device-supplied strings (board names, board ids, channel names) are data, never topic syntax: every
key and topic level is free of MQTT wildcards, separators and NULs, ids derived from them are unique
by construction, and a board's key depends only on what identifies it (never on discovery order)."""
from __future__ import annotations

import json
from typing import Dict, List, Optional, Tuple

from hubwire.descriptor import parse_descriptor
from hubwire.bridge import ha
from hubwire.daemon.fleet import Fleet
from hubwire.bridge.topics import Topics

from . import ha_documented as doc

#: names that break topics or reduce to the same safe id
NASTY = ["+", "#", "a/b", "a_b", "a-b", "x\x00y", "$SYS", "rover", "rover-2", "a b", "été", "a--b",
         "", "_", "a_b-x00000000", "/", "++"]


def desc(name: str, channels: List[str]) -> bytes:
    return json.dumps({"p": 1, "n": name, "ch": [
        {"id": i + 1, "n": c, "a": "rs", "t": "f32", "u": "m/s"} for i, c in enumerate(channels)]}).encode()


def keys_of(boards: List[Tuple[str, Optional[str]]]) -> Dict[Tuple[str, Optional[str]], str]:
    fleet = Fleet(usb=False, udev=False)
    return {(n, i): fleet._match(n, i, f"/dev/tty{j}").key for j, (n, i) in enumerate(boards)}


def assert_clean_level(level: str) -> None:
    assert level, "empty topic level"
    assert not set(level) & set("+#/\x00"), repr(level)
    assert not level.startswith("$"), repr(level)


def test_board_keys_never_carry_topic_syntax_and_stay_distinct() -> None:
    keys = keys_of([(n, None) for n in NASTY])
    assert len(set(keys.values())) == len(NASTY)
    t = Topics()
    for key in keys.values():
        levels = t.status(key).split("/")
        assert len(levels) == 3, t.status(key)
        assert_clean_level(levels[1])
        assert doc.TOPIC.match(ha.config_topic(t, "sensor", key, "speed"))


def test_home_assistant_ids_of_names_that_reduce_alike_differ() -> None:
    keys = keys_of([(n, None) for n in NASTY])
    d = parse_descriptor(desc("x", ["speed"]))
    t = Topics()
    uniques, nodes, devices = set(), set(), set()
    for key in keys.values():
        for topic, payload in ha.discovery_messages(t, "host1", key, d, None):
            m = doc.TOPIC.match(topic)
            assert m is not None, topic
            cfg = json.loads(payload)
            nodes.add(m["node"])
            uniques.add(cfg["unique_id"])
            devices.add(cfg["device"]["identifiers"][0])
    assert len(uniques) == len(nodes) == len(devices) == len(NASTY)


def test_channel_ids_are_distinct_across_boards_whose_key_and_channel_split_differently() -> None:
    """Channel names are identifiers (the descriptor parser checks that), but ``a_b`` + ``c`` and
    ``a`` + ``b_c`` must still give two entities."""
    keys = keys_of([("a_b", None), ("a", None)])
    t = Topics()
    uniques, topics = set(), set()
    for (name, _), chan in ((("a_b", None), "c"), (("a", None), "b_c")):
        d = parse_descriptor(desc(name, [chan]))
        for topic, payload in ha.discovery_messages(t, "host1", keys[(name, None)], d, None):
            topics.add(topic)
            uniques.add(json.loads(payload)["unique_id"])
    assert len(uniques) == len(topics) == 2
    for name, chan in (("a_b", "c"), ("a", "b_c")):
        d = parse_descriptor(desc(name, [chan]))
        parsed = t.parse_command(t.command(keys[(name, None)], "set", chan))
        assert parsed is not None and t.channel(d, parsed[2] or "") is d.by_name(chan)


def test_keys_depend_on_the_board_not_on_the_order_it_was_found() -> None:
    boards = [("rover", "bb02"), ("rover", "aa01"), ("rover", None), ("arm", "aa01")]
    first = keys_of(boards)
    again = keys_of(list(reversed(boards)))
    assert first == again
    assert len(set(first.values())) == len(boards)


def test_board_ids_are_escaped_like_names() -> None:
    keys = keys_of([("rover", "+"), ("rover", "#"), ("rover", "a/b"), ("rover", "a_b")])
    assert len(set(keys.values())) == 4
    for key in keys.values():
        assert_clean_level(Topics().status(key).split("/")[1])
        assert doc.TOPIC.match(ha.config_topic(Topics(), "sensor", key, "speed"))


def test_topics_of_a_key_the_board_no_longer_has_are_cleared(broker, emulators, cache_dir: str) -> None:  # type: ignore[no-untyped-def]
    """A board that had the key ``rover-aa01`` (before keys were derived from identity alone) is
    served as ``rover--aa01``: what the broker retains under the old key (descriptor, link state,
    channel states, Home Assistant configs) is cleared, so Home Assistant drops the ghost device;
    a key of a board that is merely unplugged is left alone."""
    import asyncio

    import aiomqtt

    from .helpers import StandInFleet, running_bridge, watcher

    emus = emulators(1)
    old = "rover-aa01"
    rover = json.loads(desc("rover", ["speed"]))
    old_topics = {f"hubwire/{old}/descriptor": json.dumps({"key": old, "name": "rover", "board_id": "aa01",
                                                           "service": "test", "descriptor": rover}),
                  f"hubwire/{old}/status": "online", f"hubwire/{old}/state/speed": "0.5",
                  f"homeassistant/sensor/{old}/speed/config": "{}"}
    # another board of this service, unplugged now, keeps its topics
    kept = {"hubwire/arm/descriptor": json.dumps({"key": "arm", "name": "arm", "board_id": None,
                                                  "service": "test", "descriptor": rover}),
            "hubwire/arm/state/speed": "0.25"}

    async def main() -> None:
        async with aiomqtt.Client("127.0.0.1", broker.port) as c:
            for t, p in {**old_topics, **kept}.items():
                await c.publish(t, p, qos=1, retain=True)
        fleet = StandInFleet(cache_dir)
        b = await fleet.plug("rover--aa01", emus[0].link)
        b.board_id = "aa01"
        async with running_bridge(fleet, broker.port):
            async with watcher(broker.port, "hubwire/rover--aa01/descriptor") as w:
                await w.wait_for(lambda: "hubwire/rover--aa01/descriptor" in w.last, 15, "the new key")
            await asyncio.sleep(1.0)
            async with watcher(broker.port, "hubwire/#", "homeassistant/#") as w:
                await w.wait_for(lambda: all(t in w.last for t in kept), 10, "the retained store")
                await asyncio.sleep(1.0)
                left = {t for t in old_topics if w.last.get(t)}
                assert not left, left
                assert {t: w.last[t].decode() for t in kept} == kept
        await fleet.close()
    asyncio.run(asyncio.wait_for(main(), 60))
