"""The MQTT bridge against a real mosquitto and emulated Rovers: retained descriptor, link state and
channel states; commands with replies (MQTT 5 and the 3.1.1 envelope); malformed payloads."""
from __future__ import annotations

import asyncio
import json
from typing import Any

from .conftest import Broker
from .helpers import StandInFleet, running_bridge, watcher

READABLE = ("left", "right", "imu", "range", "battery", "led", "name", "failsafes", "applied")


def run(coro: Any, timeout: float = 60) -> Any:
    return asyncio.run(asyncio.wait_for(coro, timeout))


def test_descriptor_status_and_every_readable_state_are_retained(broker: Broker, emulators, cache_dir: str) -> None:  # type: ignore[no-untyped-def]
    emus = emulators(2)

    async def main() -> None:
        fleet = StandInFleet(cache_dir)
        await fleet.plug("rover-a", emus[0].link)
        await fleet.plug("rover-b", emus[1].link)
        async with running_bridge(fleet, broker.port):
            # a client that arrives later gets everything from the broker's retained store
            want = [f"hubwire/{k}/state/{c}" for k in ("rover-a", "rover-b") for c in READABLE]
            async with watcher(broker.port, "hubwire/#") as w:
                await w.wait_for(lambda: all(t in w.last for t in want), 15, "every state topic")
            async with watcher(broker.port, "hubwire/#") as late:
                await late.wait_for(lambda: all(t in late.last for t in want), 10, "retained states")
                assert all(late.retained[t] for t in want)
                assert late.last["hubwire/_service/test/status"] == b"online"
                for k in ("rover-a", "rover-b"):
                    assert late.last[f"hubwire/{k}/status"] == b"online"
                    d = late.json(f"hubwire/{k}/descriptor")
                    assert (d["key"], d["name"], d["state"], d["service"]) == (k, "rover", "ready", "test")
                    assert [c["n"] for c in d["descriptor"]["ch"]][:3] == ["left", "right", "imu"]
                    assert late.json(f"hubwire/{k}/state/battery") == 7400
                    assert late.json(f"hubwire/{k}/state/name") == "rover"
                    assert set(late.json(f"hubwire/{k}/state/imu")) == {"ax", "ay", "az", "gyro"}
                assert not any(t.startswith("hubwire/rover-a/state/") and t.endswith(("bumper", "beep"))
                               for t in late.last)  # events and actions have no state
        await fleet.close()
    run(main())


def test_write_read_call_with_replies(broker: Broker, emulators, cache_dir: str) -> None:  # type: ignore[no-untyped-def]
    emu, = emulators(1)

    async def main() -> None:
        fleet = StandInFleet(cache_dir)
        await fleet.plug("rover", emu.link)
        async with running_bridge(fleet, broker.port):
            async with watcher(broker.port, "hubwire/rover/state/+") as w:
                assert await w.request("hubwire/rover/set/left", "0.5") == {"ok": True}
                await w.wait_for(lambda: w.last.get("hubwire/rover/state/left") == b"0.5", 5, "left 0.5")
                assert await w.request("hubwire/rover/set/led", "true") == {"ok": True}
                await w.wait_for(lambda: w.last.get("hubwire/rover/state/led") == b"true", 5, "led on")
                assert await w.request("hubwire/rover/set/name", '"robbie"') == {"ok": True}
                assert await w.request("hubwire/rover/read/name", "") == {"ok": True, "value": "robbie"}
                assert await w.request("hubwire/rover/call/beep", "200") == {"ok": True, "value": True}
                assert await w.request("hubwire/rover/call/beep", "2001") == {"ok": True, "value": False}
                # each write applied exactly once (the sketch counts its writes from the hub)
                assert await w.request("hubwire/rover/read/applied", "") == {"ok": True, "value": 3}
            # an MQTT 3.1.1 client: the rpc envelope names the reply topic and an id
            async with watcher(broker.port, "hubwire/v311/replies", v311=True) as old:
                await old.client.publish("hubwire/rover/rpc", json.dumps(
                    {"op": "set", "channel": "right", "value": -0.25, "id": 7, "reply_to": "hubwire/v311/replies"}), qos=1)
                await old.client.publish("hubwire/rover/rpc", json.dumps(
                    {"op": "read", "channel": "right", "id": "r2", "reply_to": "hubwire/v311/replies"}), qos=1)
                await old.wait_for(lambda: len(old.on("hubwire/v311/replies")) == 2, 10, "two rpc replies")
                assert sorted(old.on("hubwire/v311/replies"), key=lambda r: str(r["id"])) == [
                    {"id": 7, "ok": True}, {"id": "r2", "ok": True, "value": -0.25}]
        await fleet.close()
    run(main())


def test_malformed_payloads_get_clear_errors_and_nothing_is_applied(broker: Broker, emulators, cache_dir: str) -> None:  # type: ignore[no-untyped-def]
    emu, = emulators(1)
    cases = [
        ("hubwire/rover/set/left", "fast", "InvalidValue", "not JSON"),
        ("hubwire/rover/set/left", '"fast"', "InvalidValue", "left"),
        ("hubwire/rover/set/left", "1.5", "InvalidValue", "range"),
        ("hubwire/rover/set/left", "", "InvalidValue", "empty"),
        ("hubwire/rover/set/left", "NaN", "InvalidValue", "not JSON"),
        ("hubwire/rover/set/led", "2", "InvalidValue", "led"),
        ("hubwire/rover/set/name", '"' + "x" * 40 + '"', "InvalidValue", "name"),
        ("hubwire/rover/set/imu", '{"ax": 1}', "NotWritable", "imu"),
        ("hubwire/rover/set/battery", "1", "NotWritable", "battery"),
        ("hubwire/rover/set/wheels", "1", "UnknownChannel", "wheels"),
        ("hubwire/rover/call/beep", "", "InvalidValue", "argument"),
        ("hubwire/rover/call/beep", "-3", "InvalidValue", "beep"),
        ("hubwire/rover/read/bumper", "", "NotReadable", "bumper"),
        ("hubwire/rover/subscribe/led", '{"hz": 5}', "NotStreamable", "led"),
        ("hubwire/rover/subscribe/imu", '{"hz": "fast"}', "InvalidValue", "hz"),
        ("hubwire/rover/rpc", "[1, 2]", "InvalidValue", "rpc"),
        ("hubwire/rover/rpc", '{"op": "explode", "channel": "left"}', "InvalidValue", "op"),
        ("hubwire/rover/set/left", b"\xff\xfe", "InvalidValue", "UTF-8"),
        ("hubwire/nobody/set/left", "0.5", "UnknownBoard", "rover"),
    ]

    async def main() -> None:
        fleet = StandInFleet(cache_dir)
        await fleet.plug("rover", emu.link)
        async with running_bridge(fleet, broker.port):
            async with watcher(broker.port, "hubwire/rover/error") as w:
                for topic, payload, kind, word in cases:
                    r = await w.request(topic, payload)
                    assert r["ok"] is False and r["error"] == kind, (topic, payload, r)
                    assert word.lower() in r["message"].lower(), (topic, payload, r)
                # without a response topic an error still shows, on the board's error topic
                await w.client.publish("hubwire/rover/set/left", "2.0", qos=1)
                await w.wait_for(lambda: w.on("hubwire/rover/error"), 5, "an error message")
                assert w.on("hubwire/rover/error")[0]["error"] == "InvalidValue"
                assert await w.request("hubwire/rover/read/applied", "") == {"ok": True, "value": 0}
                assert await w.request("hubwire/rover/read/left", "") == {"ok": True, "value": 0.0}
                assert await w.request("hubwire/rover/read/led", "") == {"ok": True, "value": False}
        await fleet.close()
    run(main())


def test_two_services_on_one_broker_one_client_commands_both(broker: Broker, emulators, cache_dir: str) -> None:  # type: ignore[no-untyped-def]
    emus = emulators(2)

    async def main() -> None:
        kitchen, garage = StandInFleet(cache_dir), StandInFleet(cache_dir)
        await kitchen.plug("rover-k", emus[0].link)
        await garage.plug("rover-g", emus[1].link)
        async with running_bridge(kitchen, broker.port, service_id="kitchen"), \
                running_bridge(garage, broker.port, service_id="garage"):
            async with watcher(broker.port, "hubwire/+/descriptor", "hubwire/_service/+/status", "hubwire/+/error") as w:
                await w.wait_for(lambda: {"hubwire/rover-k/descriptor", "hubwire/rover-g/descriptor"} <= set(w.last),
                                 10, "both descriptors")
                assert w.json("hubwire/rover-k/descriptor")["service"] == "kitchen"
                assert w.json("hubwire/rover-g/descriptor")["service"] == "garage"
                assert w.last["hubwire/_service/kitchen/status"] == w.last["hubwire/_service/garage/status"] == b"online"
                for key in ("rover-k", "rover-g"):
                    # answered once, by the service that has the board; the other stays silent
                    assert await w.request(f"hubwire/{key}/set/left", "0.5") == {"ok": True}
                    assert await w.request(f"hubwire/{key}/read/applied", "") == {"ok": True, "value": 1}
                await asyncio.sleep(0.3)
                assert not w.on("hubwire/rover-k/error") and not w.on("hubwire/rover-g/error")
                assert [r["ok"] for r in w.on(w.reply_topic)] == [True] * 4  # one reply per request
        await kitchen.close()
        await garage.close()
    run(main())
