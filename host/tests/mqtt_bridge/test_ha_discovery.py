"""Home Assistant discovery: one device per board, one entity per channel of the kind its descriptor
implies, every key one Home Assistant documents (ha_documented.py), availability tied to the link."""
from __future__ import annotations

import asyncio
import json
from typing import Any, Dict, Tuple

from hubwire.descriptor import parse_descriptor
from hubwire.bridge import ha
from hubwire.bridge.topics import Topics

from . import ha_documented as doc
from .conftest import Broker
from hubwire.testing import emulator_binary

from .helpers import StandInFleet, running_bridge, watcher

DESC = parse_descriptor(json.dumps({"p": 1, "n": "lab", "fw": "2.1", "ch": [
    {"id": 1, "n": "temp", "a": "rs", "t": "f32", "u": "°C"},
    {"id": 2, "n": "speed", "a": "rws", "t": "f32", "u": "m/s", "min": -1, "max": 1},
    {"id": 3, "n": "lamp", "a": "rw", "t": "bool"},
    {"id": 4, "n": "reset", "a": "c", "t": "void"},
    {"id": 5, "n": "door", "a": "e", "t": "bool"},
    {"id": 6, "n": "level", "a": "rw", "t": "u8"},
    {"id": 7, "n": "beep", "a": "c", "t": "u16", "rt": "bool"},
    {"id": 8, "n": "gain", "a": "w", "t": "f32"},
    {"id": 9, "n": "label", "a": "rw", "t": "str", "c": 8},
]}).encode())


def configs(key: str = "lab-1", board_id: Any = "a1b2") -> Dict[str, Tuple[str, Dict[str, Any]]]:
    out = {}
    for topic, payload in ha.discovery_messages(Topics(), "host1", key, DESC, board_id):
        m = doc.TOPIC.match(topic)
        assert m is not None, topic
        if payload:  # "": the config of an earlier version on another platform, cleared
            cfg = json.loads(payload)
            out[m["obj"] + ("--result" if cfg["unique_id"].endswith("--result") else "")] = (m["component"], cfg)
    return out


def check_documented(kind: str, cfg: Dict[str, Any]) -> None:
    assert set(cfg) <= doc.KEYS[kind], set(cfg) - doc.KEYS[kind]
    assert doc.REQUIRED[kind] <= set(cfg), doc.REQUIRED[kind] - set(cfg)
    assert set(cfg["device"]) <= doc.DEVICE_KEYS and cfg["device"]["identifiers"]
    assert set(cfg["origin"]) <= doc.ORIGIN_KEYS and cfg["origin"]["name"]
    assert cfg["availability_mode"] in doc.AVAILABILITY_MODES
    for a in cfg["availability"]:
        assert set(a) <= doc.AVAILABILITY_KEYS and "topic" in a
    assert "availability_topic" not in cfg  # documented: not together with availability


def test_each_channel_becomes_the_entity_its_descriptor_implies() -> None:
    got = configs()
    kinds = {name: kind for name, (kind, _) in got.items()}
    # beep takes an argument (set the number: a call; its result a sensor), gain is write-only f32
    # without a range: commands only, no entity
    assert kinds == {"temp": "sensor", "speed": "number", "lamp": "switch", "reset": "button",
                     "door": "event", "level": "number", "label": "text", "beep": "number",
                     "beep--result": "binary_sensor"}
    for kind, cfg in got.values():
        check_documented(kind, cfg)
    temp, speed, lamp = got["temp"][1], got["speed"][1], got["lamp"][1]
    assert (temp["unit_of_measurement"], temp["state_class"], temp["state_topic"]) == ("°C", "measurement", "hubwire/lab-1/state/temp")
    assert (speed["min"], speed["max"], speed["unit_of_measurement"]) == (-1, 1, "m/s")
    assert speed["command_topic"] == "hubwire/lab-1/set/speed" and speed["state_topic"] == "hubwire/lab-1/state/speed"
    assert got["label"][1]["value_template"] == "{{ value_json }}" and got["label"][1]["max"] == 8
    assert got["level"][1]["min"] == 0 and got["level"][1]["max"] == 255 and got["level"][1]["step"] == 1
    assert (lamp["payload_on"], lamp["payload_off"], lamp["state_on"], lamp["state_off"]) == ("true", "false", "true", "false")
    assert got["reset"][1]["command_topic"] == "hubwire/lab-1/call/reset" and got["reset"][1]["payload_press"] == "null"
    door = got["door"][1]
    assert (door["state_topic"], door["event_types"], door["qos"]) == ("hubwire/lab-1/event/door", ["door"], 1)
    # one device per board, the same in every entity; availability = service and board link
    devices = {json.dumps(cfg["device"], sort_keys=True) for _, cfg in got.values()}
    assert len(devices) == 1
    dev = temp["device"]
    assert (dev["identifiers"], dev["model"], dev["sw_version"], dev["serial_number"]) == (["hubwire_lab-1"], "lab", "2.1", "a1b2")
    assert dev["name"] == "Lab-1"
    assert [a["topic"] for a in temp["availability"]] == ["hubwire/_service/host1/status", "hubwire/lab-1/status"]
    assert temp["availability_mode"] == "all"
    assert len({cfg["unique_id"] for _, cfg in got.values()}) == len(got)
    assert temp["name"] == "Temp" and temp["device_class"] == "temperature"


def test_ids_in_topics_stay_in_the_documented_characters() -> None:
    got = ha.discovery_messages(Topics(), "host1", "rover.kitchen:2", DESC, None)
    for topic, payload in got:
        assert doc.TOPIC.match(topic), topic
        assert not payload or "serial_number" not in json.loads(payload)["device"]  # no board id: left out


def test_the_bridge_retains_discovery_and_sends_it_again_when_home_assistant_starts(broker: Broker, emulators, cache_dir: str) -> None:  # type: ignore[no-untyped-def]
    emu, = emulators(1)
    want = {"left": "number", "right": "number", "imu": "sensor", "range": "sensor", "battery": "sensor",
            "led": "switch", "name": "text", "bumper": "event", "failsafes": "sensor", "applied": "sensor",
            "beep": "number", "selftest": "number"}
    results = {"homeassistant/binary_sensor/rover/beep/config", "homeassistant/sensor/rover/selftest/config"}

    async def main() -> None:
        fleet = StandInFleet(cache_dir)
        await fleet.plug("rover", emu.link)
        # states read rarely: nothing else wakes the bridge while Home Assistant asks again
        async with running_bridge(fleet, broker.port, state_hz=0.05, poll_s=100):
            topics = {f"homeassistant/{k}/rover/{c}/config" for c, k in want.items()} | results
            cleared = {"homeassistant/sensor/rover/name/config"}  # a sensor before text entities
            async with watcher(broker.port, "homeassistant/+/rover/+/config") as first:
                await first.wait_for(lambda: topics <= set(first.last), 10, "discovery configs")
            async with watcher(broker.port, "homeassistant/+/rover/+/config") as w:
                await w.wait_for(lambda: topics <= set(w.last), 10, "retained discovery configs")
                assert set(w.last) == topics  # the cleared config of earlier versions is not retained
                assert all(w.retained[t] for t in topics)
                for t in topics:
                    check_documented(t.split("/")[1], w.json(t))
                assert w.json("homeassistant/sensor/rover/battery/config")["unit_of_measurement"] == "mV"
                n = len(w.all)
                await w.client.publish("homeassistant/status", "online", qos=1)  # HA's birth message
                await w.wait_for(lambda: len(w.all) >= n + len(topics | cleared), 10, "configs sent again")
                assert {t for t, _, _ in w.all[n:]} == topics | cleared
    asyncio.run(asyncio.wait_for(main(), 60))


def test_a_write_only_channel_shows_what_the_board_accepted_and_an_action_its_last_result(broker: Broker, tmp_path, cache_dir: str) -> None:  # type: ignore[no-untyped-def]
    """examples/Actions: ``blink`` (write-only, refuses more than 10) and ``read_pin`` (an action
    with an argument). Home Assistant's number shows its state topic, so a refused value must never
    appear there, and an accepted one must."""
    import os
    from conftest import Emulator
    emu = Emulator(os.path.join(os.path.dirname(emulator_binary()), "hubwire-actions-emulator"), str(tmp_path / "a"))
    emu.start()

    async def main() -> None:
        fleet = StandInFleet(cache_dir)
        await fleet.plug("actions", emu.link)
        async with running_bridge(fleet, broker.port, state_hz=0.05, poll_s=100):
            async with watcher(broker.port, "hubwire/actions/state/blink", "hubwire/actions/result/#") as w:
                assert (await w.request("hubwire/actions/set/blink", "3"))["ok"]
                await w.wait_for(lambda: "hubwire/actions/state/blink" in w.last, 10, "the accepted value")
                assert w.json("hubwire/actions/state/blink") == 3
                refused = await w.request("hubwire/actions/set/blink", "11")
                assert refused["ok"] is False and refused["error"] == "Nak"
                got = await w.request("hubwire/actions/call/read_pin", "200")
                assert got == {"ok": True, "value": -1}
                await w.wait_for(lambda: "hubwire/actions/result/read_pin" in w.last, 10, "the call's result")
                assert w.json("hubwire/actions/result/read_pin") == {"arg": 200, "value": -1}
                assert w.on("hubwire/actions/state/blink") == [3]  # 11 was refused: never shown
                assert (await w.request("hubwire/actions/call/uptime_ms", ""))["ok"]
                await w.wait_for(lambda: "hubwire/actions/result/uptime_ms" in w.last, 10, "the button's result")
                assert w.json("hubwire/actions/result/uptime_ms")["arg"] is None
        await fleet.close()
    try:
        asyncio.run(asyncio.wait_for(main(), 60))
    finally:
        emu.stop()
