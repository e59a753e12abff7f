"""The bridge's promises through outages: events once across a client's reconnect and a broker
restart, availability following the link, a board replugged on a new path, states republished to a
broker that forgot them, streams at the rate asked for under the channel's ceiling."""
from __future__ import annotations

import asyncio
import time
from typing import Any, Dict, List

from .conftest import Broker
from .helpers import StandInFleet, Watcher, running_bridge, watcher

EVENTS = "hubwire/rover/event/bumper"


def run(coro: Any, timeout: float = 90) -> Any:
    return asyncio.run(asyncio.wait_for(coro, timeout))


def deduped(w: Watcher, topic: str = EVENTS) -> List[Dict[str, Any]]:
    """The events a client keeps: the first of each id (docs/MQTT.md, "Events")."""
    seen, out = set(), []
    for ev in w.on(topic):
        if ev["id"] not in seen:
            seen.add(ev["id"])
            out.append(ev)
    return out


async def bump(emu, bridge, n: int) -> None:  # type: ignore[no-untyped-def]
    """``n`` presses or releases of the bumper, each waited for at the bridge (the board's queue
    holds 4)."""
    bb = bridge.boards["rover"]
    for _ in range(n):
        before = bb.events
        emu.bump()
        deadline = time.monotonic() + 10
        while bb.events == before:
            assert time.monotonic() < deadline, "the bridge did not get the event"
            await asyncio.sleep(0.01)


def test_events_once_across_a_client_reconnect(broker: Broker, emulators, cache_dir: str) -> None:  # type: ignore[no-untyped-def]
    emu, = emulators(1)

    async def main() -> None:
        fleet = StandInFleet(cache_dir)
        await fleet.plug("rover", emu.link)
        async with running_bridge(fleet, broker.port) as bridge:
            async with watcher(broker.port, EVENTS, identifier="ev-client", persistent=True) as w:
                await bump(emu, bridge, 3)
                await w.wait_for(lambda: len(deduped(w)) == 3, 10, "3 events")
                first = deduped(w)
            await bump(emu, bridge, 4)  # while the client is away: the broker keeps them for it
            async with watcher(broker.port, identifier="ev-client", persistent=True) as w2:
                await w2.wait_for(lambda: len(deduped(w2)) >= 4, 10, "the 4 events missed")
                await asyncio.sleep(0.5)  # anything more would be a duplicate
                later = deduped(w2)
        evs = first + later
        assert len(evs) == 7
        assert [e["value"] for e in evs] == [True, False] * 3 + [True]  # press, release, ... in order
        assert len({e["id"] for e in evs}) == 7
        assert [int(e["id"].rsplit(":", 1)[1]) for e in evs] == list(range(1, 8))
        assert all(e["event_type"] == "bumper" and e["board"] == "rover" for e in evs)
        await fleet.close()
    run(main())


def test_link_loss_takes_the_board_offline_and_back(broker: Broker, emulators, cache_dir: str) -> None:  # type: ignore[no-untyped-def]
    emu, = emulators(1)

    async def main() -> None:
        fleet = StandInFleet(cache_dir)
        await fleet.plug("rover", emu.link)
        async with running_bridge(fleet, broker.port) as bridge:
            async with watcher(broker.port, "hubwire/rover/status", "hubwire/rover/descriptor", EVENTS) as w:
                await w.wait_for(lambda: w.last.get("hubwire/rover/status") == b"online", 5, "online")
                await bump(emu, bridge, 1)
                emu.pause()  # a silent board: the hub declares the link lost after 4 heartbeats
                await w.wait_for(lambda: w.last.get("hubwire/rover/status") == b"offline", 10, "offline")
                assert w.json("hubwire/rover/descriptor")["state"] == "lost"
                r = await w.request("hubwire/rover/set/left", "0.5")
                assert r["ok"] is False and r["error"] == "LinkLost" and "nothing was sent" in r["message"]
                emu.resume()
                await w.wait_for(lambda: w.last.get("hubwire/rover/status") == b"online", 10, "online again")
                assert await w.request("hubwire/rover/set/left", "0.25") == {"ok": True}
                await bump(emu, bridge, 1)  # events go on across the board's reconnect, once each
                await w.wait_for(lambda: len(deduped(w)) == 2, 5, "2 events")
                assert [(e["value"], e["id"].rsplit(":", 1)[1]) for e in deduped(w)] == [(True, "1"), (False, "2")]
                assert len(w.on(EVENTS)) == 2
                statuses = [p for t, p, _ in w.all if t == "hubwire/rover/status"]
                assert statuses == [b"online", b"offline", b"online"]
        await fleet.close()
    run(main())


def test_board_replugged_on_a_new_path(broker: Broker, emulators, cache_dir: str) -> None:  # type: ignore[no-untyped-def]
    emu, = emulators(1)

    async def main() -> None:
        fleet = StandInFleet(cache_dir)
        await fleet.plug("rover", emu.link)
        async with running_bridge(fleet, broker.port) as bridge:
            async with watcher(broker.port, "hubwire/rover/#") as w:
                await w.wait_for(lambda: "hubwire/rover/state/applied" in w.last, 10, "states")
                emu.stop()
                await fleet.unplug("rover")
                await w.wait_for(lambda: w.last.get("hubwire/rover/status") == b"offline", 10, "offline")
                assert w.json("hubwire/rover/descriptor")["state"] == "unplugged"
                assert w.json("hubwire/rover/state/applied") == 0  # the last value stays cached
                emu2, = emulators(1, tag="moved")
                await fleet.plug("rover", emu2.link)
                await w.wait_for(lambda: w.last.get("hubwire/rover/status") == b"online", 10, "online")
                assert w.json("hubwire/rover/descriptor")["port"] == emu2.link
                assert await w.request("hubwire/rover/set/led", "true") == {"ok": True}
                await w.wait_for(lambda: w.last.get("hubwire/rover/state/led") == b"true", 5, "led state")
                await bump(emu2, bridge, 1)
                await w.wait_for(lambda: len(deduped(w, "hubwire/rover/event/bumper")) == 1, 5, "event")
        await fleet.close()
    run(main())


def test_a_broker_that_lost_everything_gets_the_states_again(broker: Broker, emulators, cache_dir: str) -> None:  # type: ignore[no-untyped-def]
    emu, = emulators(1)
    readable = ("left", "right", "imu", "range", "battery", "led", "name", "failsafes", "applied")

    async def main() -> None:
        fleet = StandInFleet(cache_dir)
        await fleet.plug("rover", emu.link)
        async with running_bridge(fleet, broker.port) as bridge:
            async with watcher(broker.port, "hubwire/#") as w:
                assert await w.request("hubwire/rover/set/left", "0.75") == {"ok": True}
                await w.wait_for(lambda: all(f"hubwire/rover/state/{c}" in w.last for c in readable), 10, "states")
            broker.kill()  # no persistence, no clean stop: every retained message is gone
            await asyncio.sleep(0.5)
            assert not bridge.connected.is_set()
            broker.start()
            await asyncio.wait_for(bridge.connected.wait(), 10)
            async with watcher(broker.port, "hubwire/#", "homeassistant/#") as fresh:
                want = [f"hubwire/rover/state/{c}" for c in readable] + [
                    "hubwire/rover/status", "hubwire/rover/descriptor", "hubwire/_service/test/status",
                    "homeassistant/number/rover/left/config"]
                await fresh.wait_for(lambda: all(t in fresh.last for t in want), 10, "everything republished")
            async with watcher(broker.port, "hubwire/#", "homeassistant/#") as fresh:
                await fresh.wait_for(lambda: all(t in fresh.last for t in want), 10, "everything retained")
                assert all(fresh.retained[t] for t in want)
                assert fresh.json("hubwire/rover/state/left") == 0.75
                assert fresh.last["hubwire/_service/test/status"] == b"online"
        await fleet.close()
    run(main())


def test_events_during_a_broker_restart_arrive_once(persistent_broker: Broker, emulators, cache_dir: str) -> None:  # type: ignore[no-untyped-def]
    emu, = emulators(1)
    broker = persistent_broker

    async def main() -> None:
        fleet = StandInFleet(cache_dir)
        await fleet.plug("rover", emu.link)
        async with running_bridge(fleet, broker.port) as bridge:
            async with watcher(broker.port, EVENTS, identifier="ev-client", persistent=True) as w:
                await bump(emu, bridge, 2)
                await w.wait_for(lambda: len(deduped(w)) == 2, 10, "2 events")
                before = deduped(w)
            broker.stop()  # a clean stop: mosquitto saves sessions and queued messages
            await bump(emu, bridge, 3)  # held by the bridge until the broker is back
            assert len(bridge.outbox.events) == 3
            broker.start()
            await asyncio.wait_for(bridge.connected.wait(), 10)
            async with watcher(broker.port, identifier="ev-client", persistent=True) as w2:
                await w2.wait_for(lambda: len(deduped(w2)) >= 3, 10, "the 3 events of the outage")
                await asyncio.sleep(0.5)
                after = deduped(w2)
            assert not bridge.outbox.events
        evs = before + after
        assert [e["value"] for e in evs] == [True, False, True, False, True]
        assert [int(e["id"].rsplit(":", 1)[1]) for e in evs] == [1, 2, 3, 4, 5]
        await fleet.close()
    run(main())


def test_streams_at_the_rate_asked_under_the_ceiling(broker: Broker, emulators, cache_dir: str) -> None:  # type: ignore[no-untyped-def]
    emu, = emulators(1)
    ceiling = 20.0

    async def main() -> None:
        fleet = StandInFleet(cache_dir)
        await fleet.plug("rover", emu.link)
        async with running_bridge(fleet, broker.port, max_rate_hz={"imu": ceiling}):
            topic = "hubwire/rover/stream/imu"
            async with watcher(broker.port, topic) as w:
                r = await w.request("hubwire/rover/subscribe/imu", '{"hz": 50, "client": "t", "lease_s": 30}')
                assert r["ok"] and r["topic"] == topic and r["hz"] == ceiling and r["max_rate_hz"] == ceiling
                await w.wait_for(lambda: len(w.on(topic)) >= 3, 10, "samples")
                t0, n0 = time.monotonic(), len(w.on(topic))
                await asyncio.sleep(2.0)
                rate = (len(w.on(topic)) - n0) / (time.monotonic() - t0)
                # never above the ceiling (a sample may fall either side of the window's ends)
                assert rate <= ceiling * 1.25 + 1, rate
                samples = w.on(topic)
                assert set(samples[-1]["v"]) == {"ax", "ay", "az", "gyro"} and "t" in samples[-1]
                seqs = [s["seq"] for s in samples]
                assert seqs == sorted(seqs)
                assert await w.request("hubwire/rover/unsubscribe/imu", '{"client": "t"}') == {"ok": True, "hz": 0.0}
                # samples already on their way still come (a busy machine delays them); then none:
                # quiet for 10 periods of the stream, then nothing for 2 s more
                n1 = await w.wait_quiet(topic, 10 / ceiling)
                await asyncio.sleep(2.0)
                assert len(w.on(topic)) == n1  # stopped: nobody asks any more
                # a lease not renewed ends by itself
                lease = 1.0
                r = await w.request("hubwire/rover/subscribe/imu", f'{{"hz": 10, "lease_s": {lease}}}')
                assert r["ok"] and r["lease_s"] == lease and r["hz"] == 10
                await w.wait_for(lambda: len(w.on(topic)) > n1, 5, "samples again")
                await asyncio.sleep(lease)
                n2 = await w.wait_quiet(topic, 10 / 10)  # the lease ended: quiet for 10 periods
                await asyncio.sleep(2.0)
                assert len(w.on(topic)) == n2
        await fleet.close()
    run(main())


CHILD = """
import asyncio, sys
from mqtt_bridge.helpers import StandInFleet
from hubwire.bridge.mqtt import run_bridge

async def main():
    fleet = StandInFleet(sys.argv[3])
    await fleet.plug("rover", sys.argv[2])
    print("READY", flush=True)
    await run_bridge(fleet, "127.0.0.1", int(sys.argv[1]), service_id="child", keepalive=5)

asyncio.run(main())
"""


def test_the_last_will_marks_the_service_offline_when_it_dies(broker: Broker, emulators, cache_dir: str) -> None:  # type: ignore[no-untyped-def]
    import os
    import subprocess
    import sys

    emu, = emulators(1)
    tests_dir = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    status = "hubwire/_service/child/status"

    async def main() -> None:
        async with watcher(broker.port, status, "hubwire/rover/status") as w:
            # the tests' helpers importable in the child as they are here (the package is installed)
            path = os.pathsep.join(p for p in (tests_dir, os.environ.get("PYTHONPATH")) if p)
            child = subprocess.Popen([sys.executable, "-c", CHILD, str(broker.port), emu.link, cache_dir],
                                     stdout=subprocess.PIPE, env=dict(os.environ, PYTHONPATH=path))
            try:
                await w.wait_for(lambda: w.last.get(status) == b"online", 15, "the service online")
                await w.wait_for(lambda: w.last.get("hubwire/rover/status") == b"online", 10, "the board online")
                child.kill()  # no goodbye: only the broker's last will can tell
                child.wait(10)
                await w.wait_for(lambda: w.last.get(status) == b"offline", 10, "the last will")
            finally:
                if child.poll() is None:
                    child.kill()
                    child.wait(10)
            # the board's own topic keeps its last value; Home Assistant's "all" takes both
            assert w.last["hubwire/rover/status"] == b"online"
    run(main())


def test_a_clean_stop_says_offline_itself(broker: Broker, emulators, cache_dir: str) -> None:  # type: ignore[no-untyped-def]
    emu, = emulators(1)

    async def main() -> None:
        fleet = StandInFleet(cache_dir)
        await fleet.plug("rover", emu.link)
        async with watcher(broker.port, "hubwire/_service/test/status") as w:
            async with running_bridge(fleet, broker.port):
                await w.wait_for(lambda: w.last.get("hubwire/_service/test/status") == b"online", 10, "online")
            await w.wait_for(lambda: w.last.get("hubwire/_service/test/status") == b"offline", 10, "offline")
            assert [p for t, p, _ in w.all] == [b"online", b"offline"]
        await fleet.close()
    run(main())
