"""The behaviour suite: one board, two roads. Every test runs on a direct connection (the program
opens the port) and on a routed one (``hubwire.connect("name")`` through ``hubwire serve``), on the C++
emulators, and asserts what the API promises; errors must have the same type and text on both roads.

Hub channels a client provides and missions included: nothing may be missing on one road.
"""
from __future__ import annotations

import time
from typing import Any, Callable, Dict, List

import pytest

import hubwire
from hubwire.board import BoardAPI
from hubwire.wire.messages import NakCode

from .conftest import Roads

Open = Callable[..., hubwire.Device]


def test_declares_the_board_interface(board: Open) -> None:
    dev = board("rover")
    assert isinstance(dev, BoardAPI)
    assert (dev.name, dev.firmware, dev.state) == ("rover", "1.0.0", "ready")
    assert "left" in dev and "nothing" not in dev
    assert dev.channel("left").writable and "battery" in dev.table()


def test_write_accepted_applied_once_and_read_back(board: Open) -> None:
    dev = board("rover")
    applied = dev.applied
    dev.left = 0.25
    dev["right"] = -0.5
    dev.write("name", "robbie")
    assert (dev.left, dev.read("right"), dev["name"]) == (0.25, -0.5, "robbie")
    assert dev.applied == applied + 3  # each write applied exactly once
    imu = dev.imu  # a struct, decoded the same on both roads
    assert imu.az > 9 and len(imu.gyro) == 3


def test_write_refused_with_reason(board: Open) -> None:
    dev = board("rover")
    applied = dev.applied
    with pytest.raises(hubwire.InvalidValue, match="range"):
        dev.left = 1.5  # checked before anything is sent
    act = board("actions")
    with pytest.raises(hubwire.NakError) as e:
        act.blink = 11  # the sketch refuses it
    assert (e.value.error, e.value.code, e.value.channel) == ("REJECTED", NakCode.REJECTED, "blink")
    with pytest.raises(hubwire.InvalidValue) as bad:
        act.blink = 256
    assert bad.value.code == NakCode.OUT_OF_RANGE  # as the board would answer
    assert dev.applied == applied


def test_actions_with_arguments_and_results(board: Open) -> None:
    dev = board("rover")
    assert dev.beep(200) is True and dev.call("beep", 2001) is False
    assert dev["selftest"](0) == 0
    act = board("actions")
    calls = act.calls
    assert act.read_pin(200) == -1
    first = act.uptime_ms()
    assert isinstance(first, int) and act.uptime_ms() >= first
    act.blink = 2
    assert act.calls == calls + 2


def test_events_exactly_once_in_order(board: Open) -> None:
    dev = board("rover")
    heard: List[Any] = []
    remove = dev.on("bumper", heard.append)
    with dev.events("bumper", timeout=10) as events:
        time.sleep(0.5)  # the service's subscription is in place before the first event
        assert dev.selftest(4) == 4  # the Rover's event queue holds 4
        it = iter(events)
        got = [next(it) for _ in range(4)]
        assert [e.value for e in got] == [True, False] * 2
        assert all(e.name == "bumper" for e in got)
        seqs = [e.seq for e in got]
        assert len(set(seqs)) == 4  # four events, none twice
        deadline = time.monotonic() + 10
        while len(heard) < 4 and time.monotonic() < deadline:
            time.sleep(0.05)
        time.sleep(1.0)  # the device retries an unacked event every 100 ms: a duplicate would show
        assert heard == [True, False] * 2
        assert events.get(timeout=0.5) is None  # nothing more
    remove()


def test_stream_samples_in_order(board: Open) -> None:
    dev = board("rover")
    with dev.stream("battery", hz=20, meta=True, timeout=10) as samples:
        got = [next(samples) for _ in range(5)]
        assert samples.granted_ms > 0
    assert all(s.value == got[0].value and isinstance(s.value, int) for s in got)
    seqs = [s.seq for s in got]
    assert seqs == sorted(seqs) and len(set(seqs)) == 5
    assert all(s.gap == 0 for s in got)


def test_large_values_and_lists(board: Open) -> None:
    dev = board("large")
    writes = dev.profile_writes
    name = tuple(range(40))
    dev.profile = {"gain": [i / 4 for i in range(20)], "table": list(range(-20, 20)), "name": name}
    got = dev.profile
    assert got.gain == tuple(i / 4 for i in range(20)) and got.table == tuple(range(-20, 20)) and got.name == name
    assert dev.profile_writes == writes + 1
    dev.path = [5, -7, 1000]
    assert dev.path == [5, -7, 1000]
    dev.path = []
    assert dev.path == []
    assert dev.sum(list(range(16))) == sum(range(16))
    with pytest.raises(hubwire.InvalidValue):
        dev.path = list(range(13))  # more than the List holds


def test_health(board: Open) -> None:
    dev = board("rover")
    deadline = time.monotonic() + 10  # a fresh direct session has heard no heartbeat yet
    while dev.health().device_heartbeats == 0 and time.monotonic() < deadline:
        time.sleep(0.05)
    h = dev.health()
    assert h.state == "ready"
    assert h.device_heartbeats > 0 and h.device_heartbeat_ms == 250
    assert h.heartbeat_age is not None and h.heartbeat_age < 5


def test_board_id(board: Open) -> None:
    dev = board("rover")
    bid = dev.board_id()
    assert bid is None or isinstance(bid, str)
    assert dev.board_id() == bid


def test_hub_events_reach_the_board_once_in_order(board: Open) -> None:
    dev = board("soak", hub_later=True)
    before = (dev.ticks, dev.tick_twice, dev.tick_gaps)
    last = dev.tick_last
    for i in range(1, 6):
        dev.notify("tick", last + i)  # the board counts a repeated or skipped tick
    dev.wait_notified(timeout=10)
    deadline = time.monotonic() + 10
    while dev.ticks < before[0] + 5 and time.monotonic() < deadline:
        time.sleep(0.05)
    assert (dev.ticks, dev.tick_twice, dev.tick_gaps) == (before[0] + 5, before[1], before[2])
    assert dev.tick_last == last + 5
    with pytest.raises(hubwire.HubChannelError, match="takes no hub event 'bump'"):
        dev.notify("bump", 1)


def _outcome(fn: Callable[[], Any]) -> Any:
    try:
        return ("value", fn())
    except Exception as e:  # noqa: BLE001 - the outcome compared between roads
        return (type(e), str(e))


def test_errors_are_the_same_on_both_roads(both: Callable[..., Dict[str, hubwire.Device]]) -> None:
    cases: List[Callable[[hubwire.Device], Any]] = [
        lambda d: d.read("nothing"),
        lambda d: d.write("nothing", 1),
        lambda d: d.write("battery", 1),
        lambda d: d.read("bumper"),
        lambda d: d.write("left", 7.0),
        lambda d: d.write("left", "fast"),
        lambda d: d.write("name", "x" * 17),
        lambda d: d.call("beep", -1),
        lambda d: d.call("left", 1),
        lambda d: d.on("nothing", print),
        lambda d: d.stream("led"),
        lambda d: d.events("nothing"),
        lambda d: d.nothing,
        lambda d: d.bumper,
        lambda d: d.start("beep", 1),
        lambda d: d.notify("tick", 1),
        lambda d: d.board_id(timeout=5),
    ]
    devs = both("rover")
    for i, case in enumerate(cases):
        direct, routed = (_outcome(lambda: case(devs[road])) for road in ("direct", "routed"))
        assert direct == routed, f"case {i}: direct {direct!r}, routed {routed!r}"
    act = both("actions")
    direct, routed = (_outcome(lambda: act[road].write("blink", 11)) for road in ("direct", "routed"))
    assert direct == routed


def test_repr_and_table_agree(both: Callable[..., Dict[str, hubwire.Device]], roads: Roads) -> None:
    devs = both("rover")
    assert devs["direct"].table() == devs["routed"].table()
    direct, routed = (devs[road].descriptor for road in ("direct", "routed"))
    assert (direct.name, direct.firmware, direct.hub) == (routed.name, routed.firmware, routed.hub)
    assert [(c.id, c.name, c.access, c.type_name, c.unit, c.min, c.max) for c in direct.channels] == \
        [(c.id, c.name, c.access, c.type_name, c.unit, c.min, c.max) for c in routed.channels]
    assert sorted(dir(devs["direct"])) == sorted(dir(devs["routed"]))


def test_events_before_the_first_listener_are_kept_for_it(board: Open) -> None:
    dev = board("rover")
    assert dev.selftest(2) == 2  # nobody listens yet
    time.sleep(1.0)
    heard: List[Any] = []
    dev.on("bumper", heard.append)  # the first listener gets them
    deadline = time.monotonic() + 10
    while len(heard) < 2 and time.monotonic() < deadline:
        time.sleep(0.05)
    with dev.events("bumper") as later:  # a second listener does not
        time.sleep(0.5)
        assert later.get(timeout=0.5) is None
    assert heard == [True, False]


def test_a_closed_board_says_so_the_same_on_both_roads(both: Callable[..., Dict[str, hubwire.Device]]) -> None:
    devs = both("rover")
    for dev in devs.values():
        dev.close()
        assert dev.state == "closed"
    cases: List[Callable[[hubwire.Device], Any]] = [
        lambda d: d.read("left"), lambda d: d.write("left", 0.0), lambda d: d.call("beep", 1),
        lambda d: d.stream("imu"), lambda d: d.events("bumper"), lambda d: d.health().state,
    ]
    for i, case in enumerate(cases):
        direct, routed = (_outcome(lambda: case(devs[road])) for road in ("direct", "routed"))
        assert direct == routed, f"case {i}: direct {direct!r}, routed {routed!r}"


def test_link_loss_is_told_and_the_stream_rides_through(board: Open, roads: Roads, road: str) -> None:
    dev = board("rover")
    told: List[str] = []
    dev.on("link_lost", lambda: told.append("lost"))
    dev.on("link_restored", lambda: told.append("restored"))
    emu = roads.emulator(road, "rover")
    with dev.stream("battery", hz=10, meta=True, timeout=30) as samples:
        it = iter(samples)
        next(it)
        emu.pause()  # silent for 4 heartbeat intervals (1 s): both sides call the link lost
        try:
            deadline = time.monotonic() + 15
            while "lost" not in told and time.monotonic() < deadline:
                time.sleep(0.05)
        finally:
            emu.resume()
        assert told[:1] == ["lost"]
        gaps = 0
        for _ in range(40):  # the first sample after the outage reports it
            gaps += next(it).gap
            if gaps:
                break
        assert gaps == 1 and samples.gaps == 1
    deadline = time.monotonic() + 10
    while told.count("restored") < 1 and time.monotonic() < deadline:
        time.sleep(0.05)
    assert told == ["lost", "restored"] and dev.state == "ready"


def test_a_reboot_is_told_as_reconnect_with_the_descriptor(board: Open, roads: Roads, road: str) -> None:
    dev = board("rover")
    told: List[Any] = []
    dev.on("link_lost", lambda: told.append("lost"))
    dev.on("link_restored", lambda: told.append("restored"))
    dev.on("reconnect", lambda desc: told.append(("reconnect", desc.name)))
    emu = roads.emulator(road, "rover")
    emu.stop()  # the board goes away and comes back on the same port: a new device session
    time.sleep(1.5)
    emu.start()
    deadline = time.monotonic() + 20
    while len(told) < 2 and time.monotonic() < deadline:
        time.sleep(0.05)
    time.sleep(1.0)  # nothing more comes
    assert told == ["lost", ("reconnect", "rover")]
    assert dev.state == "ready" and dev.left == 0.0  # the new boot's value


def test_closing_ends_streams_and_event_iterators_alike(both: Callable[..., Dict[str, hubwire.Device]]) -> None:
    devs = both("rover")
    seen = {}
    for road, dev in devs.items():
        events = dev.events("bumper")
        samples = iter(dev.stream("battery", hz=10))
        next(samples)
        dev.close()
        seen[road] = (events.get(timeout=5), list(iter(events)), _outcome(lambda: [next(samples) for _ in range(100)]))
    assert seen["direct"] == seen["routed"] == (None, [], (hubwire.LinkLost, "session closed"))


def test_a_mission_runs_the_same_on_both_roads(board: Open) -> None:
    """Start, progress in order, one result; a failure with its code; a refused goal (Soak's `count`:
    progress 1, 2, ... below n, newer values replacing unsent ones; result n * 1000 + its run)."""
    dev = board("soak", hub_later=True)
    job = dev.start("count", 6)
    progress = list(job.feedback(timeout=30))
    result = job.result(timeout=30)
    assert progress == sorted(set(progress)) and set(progress) <= set(range(1, 6)), progress
    assert result // 1000 == 6 and job.status == "succeeded"
    failing = dev.start("count", 999)
    with pytest.raises(hubwire.MissionFailed) as failed:
        failing.result(timeout=30)
    assert failed.value.code == 9
    with pytest.raises(hubwire.HubwireError) as refused:
        dev.start("count", 0).result(timeout=30)
    assert type(refused.value).__name__ in ("NakError", "MissionFailed"), refused.value


def test_hub_channels_a_program_provides_bind_and_answer(board: Open) -> None:
    """Soak writes `tally` (u32) and calls `bump` (u32 -> u32) on the hub: the same HubChannels bind
    on both roads, every tally the board saw acknowledged reached the handler once and in order,
    and every bump came back right."""
    tallies: List[int] = []
    hub = hubwire.HubChannels("behaviour")
    hub.accept("tally", tallies.append, type="u32")
    hub.action("bump", lambda n: n + 1, type="u32", returns="u32")
    hub.event("tick", type="u32")
    dev = board("soak", hub=hub)
    deadline = time.monotonic() + 60
    while dev.hub_binding() != {"tally": "ok", "bump": "ok", "tick": "ok"}:
        assert time.monotonic() < deadline, dev.hub_binding()
        time.sleep(0.05)
    dev.hub_load = True
    while not (dev.tally_acked >= 10 and dev.bump_ok >= 3):
        assert time.monotonic() < deadline, (dev.tally_acked, dev.bump_ok)
        time.sleep(0.05)
    dev.hub_load = False
    while dev.tally_acked + dev.tally_failed != dev.tally_token:
        assert time.monotonic() < deadline
        time.sleep(0.05)
    assert tallies == sorted(set(tallies)) and dev.tally_acked <= len(tallies)
    assert dev.bump_wrong == 0


def test_every_implementation_names_the_interface() -> None:
    from hubwire.aio import AsyncDevice
    from hubwire.board import BOARD_METHODS, AsyncBoardAPI, BoardAPI
    from hubwire.client.connection import AsyncRemoteDevice
    from hubwire.client.remote import RemoteDevice

    for cls, api in ((hubwire.Device, BoardAPI), (RemoteDevice, BoardAPI), (AsyncDevice, AsyncBoardAPI),
                     (AsyncRemoteDevice, AsyncBoardAPI)):
        assert api in cls.__mro__, cls  # so mypy checks its signatures against the interface
        missing = [m for m in BOARD_METHODS if not hasattr(cls, m)]
        assert not missing, (cls, missing)
