"""The behaviour suite on asyncio: :class:`hubwire.aio.AsyncDevice` (direct) and the routed
``AsyncRemoteDevice`` (through ``hubwire serve``) on the same emulated boards, one test per road;
errors compared between the roads. Hub channels a client declares and missions are left out until
the service routes them (test_not_routed.py)."""
from __future__ import annotations

import asyncio
from typing import Any, Callable, List

import pytest

import hubwire
from hubwire.board import AsyncBoardAPI

from .conftest import ROADS, Roads, aconnect, run


async def _until(pred: Callable[[], Any], timeout: float = 10.0) -> Any:
    end = asyncio.get_running_loop().time() + timeout
    while not pred() and asyncio.get_running_loop().time() < end:
        await asyncio.sleep(0.05)
    return pred()


def test_declares_the_board_interface(roads: Roads, road: str) -> None:
    async def main() -> None:
        async with aconnect(roads, road, "rover") as dev:
            assert isinstance(dev, AsyncBoardAPI)
            assert (dev.name, dev.state, dev.url.startswith("service:")) == ("rover", "ready", road == "routed")
            assert dev.channel("imu").streamable
        assert dev.state == "closed" and (await dev.fetch_health()).state == "closed"
    run(main())


def test_reads_writes_and_calls(roads: Roads, road: str) -> None:
    async def main() -> None:
        async with aconnect(roads, road, "rover") as dev, aconnect(roads, road, "actions") as act:
            applied = await dev.read("applied")
            await dev.write("left", -0.25)
            await dev.write("name", "a" * 16)
            assert (await dev.read("left"), await dev.read("name")) == (-0.25, "a" * 16)
            assert await dev.read("applied") == applied + 2
            assert await dev.call("beep", 100) is True and await dev.call("beep", 2001) is False
            with pytest.raises(hubwire.InvalidValue):
                await dev.write("right", -2.0)
            with pytest.raises(hubwire.NakError) as e:
                await act.write("blink", 11)
            assert e.value.error == "REJECTED"
            assert await act.call("read_pin", 200) == -1
            assert await dev.read("applied") == applied + 2
    run(main())


def test_events_exactly_once_in_order(roads: Roads, road: str) -> None:
    async def main() -> None:
        async with aconnect(roads, road, "rover") as dev:
            heard: List[Any] = []
            remove = dev.on("bumper", heard.append)
            async with dev.events("bumper", timeout=10) as events:
                await asyncio.sleep(0.5)  # the service's subscriptions are in place
                assert await dev.call("selftest", 4) == 4
                got: List[Any] = []
                async for ev in events:
                    got.append(ev)
                    if len(got) == 4:
                        break
                assert [e.value for e in got] == [True, False] * 2 and len({e.seq for e in got}) == 4
                assert await _until(lambda: len(heard) >= 4)
                await asyncio.sleep(1.0)  # a duplicate would have come by now
                assert heard == [True, False] * 2
                assert await events.get(0.5) is None
            remove()
    run(main())


def test_stream(roads: Roads, road: str) -> None:
    async def main() -> None:
        async with aconnect(roads, road, "rover") as dev:
            got: List[Any] = []
            async with dev.stream("range", hz=20, meta=True, timeout=10) as samples:
                async for s in samples:
                    got.append(s)
                    if len(got) == 5:
                        break
                assert samples.granted_ms > 0
            assert all(len(s.value) == 4 for s in got) and [s.seq for s in got] == sorted({s.seq for s in got})
    run(main())


def test_large_values_and_lists(roads: Roads, road: str) -> None:
    async def main() -> None:
        async with aconnect(roads, road, "large") as dev:
            table = [i * 3 for i in range(-20, 20)]
            await dev.write("profile", {"gain": [0.5] * 20, "table": table, "name": [7] * 40})
            assert (await dev.read("profile")).table == tuple(table)
            await dev.write("path", [1, 2, 3])
            assert await dev.read("path") == [1, 2, 3]
            assert await dev.call("sum", [255] * 16) == 255 * 16
    run(main())


def test_health_and_board_id(roads: Roads, road: str) -> None:
    async def main() -> None:
        async with aconnect(roads, road, "rover") as dev:
            assert dev.health().state == "ready"
            end = asyncio.get_running_loop().time() + 10
            while (await dev.fetch_health()).device_heartbeats == 0 and asyncio.get_running_loop().time() < end:
                await asyncio.sleep(0.05)
            h = await dev.fetch_health()
            assert h.device_heartbeats > 0 and h.device_heartbeat_ms == 250
            bid = await dev.board_id()
            assert bid is None or isinstance(bid, str)
    run(main())


def test_hub_events(roads: Roads, road: str) -> None:
    async def main() -> None:
        async with aconnect(roads, road, "soak", hub_later=True) as dev:
            ticks, last = await dev.read("ticks"), await dev.read("tick_last")
            twice, gaps = await dev.read("tick_twice"), await dev.read("tick_gaps")
            for i in range(1, 4):
                dev.notify("tick", last + i)
            await dev.wait_notified(10)
            assert dev.notifications_pending == 0
            end = asyncio.get_running_loop().time() + 10
            while await dev.read("ticks") < ticks + 3 and asyncio.get_running_loop().time() < end:
                await asyncio.sleep(0.05)
            assert (await dev.read("ticks"), await dev.read("tick_last")) == (ticks + 3, last + 3)
            assert (await dev.read("tick_twice"), await dev.read("tick_gaps")) == (twice, gaps)
            with pytest.raises(hubwire.InvalidValue):
                dev.notify("tick", -1)
    run(main())


async def _outcome(aw: Any) -> Any:
    try:
        return ("value", await aw if asyncio.iscoroutine(aw) else aw)
    except Exception as e:  # noqa: BLE001 - the outcome compared between roads
        return (type(e), str(e))


def test_errors_are_the_same_on_both_roads(roads: Roads) -> None:
    cases: List[Callable[[Any], Any]] = [
        lambda d: d.read("nothing"),
        lambda d: d.write("battery", 1),
        lambda d: d.write("left", 7.0),
        lambda d: d.write("name", "x" * 17),
        lambda d: d.call("beep", -1),
        lambda d: d.call("left", 1),
        lambda d: d.start("beep", 1),
        lambda d: d.read("bumper"),
    ]
    sync_cases: List[Callable[[Any], Any]] = [
        lambda d: d.on("nothing", print),
        lambda d: d.stream("led"),
        lambda d: d.events("nothing"),
        lambda d: d.notify("tick", 1),
        lambda d: d.channel("nothing"),
    ]

    async def main() -> None:
        async with aconnect(roads, "direct", "rover") as direct, aconnect(roads, "routed", "rover") as routed:
            devs = dict(zip(ROADS, (direct, routed)))
            for i, case in enumerate(cases):
                a, b = [await _outcome(case(devs[r])) for r in ROADS]
                assert a == b, f"case {i}: direct {a!r}, routed {b!r}"
            for i, case in enumerate(sync_cases):
                a, b = [await _outcome(_call(case, devs[r])) for r in ROADS]
                assert a == b, f"sync case {i}: direct {a!r}, routed {b!r}"
    run(main())


async def _call(case: Callable[[Any], Any], dev: Any) -> Any:
    return case(dev)


def test_events_before_the_first_listener_are_kept_for_it(roads: Roads, road: str) -> None:
    async def main() -> None:
        async with aconnect(roads, road, "rover") as dev:
            assert await dev.call("selftest", 2) == 2  # nobody listens yet
            await asyncio.sleep(1.0)
            async with dev.events("bumper", timeout=5) as first:
                got = [await first.get(5), await first.get(5)]
                assert [e.value for e in got if e is not None] == [True, False]
                async with dev.events(timeout=1) as second:
                    assert await second.get(1) is None
    run(main())
