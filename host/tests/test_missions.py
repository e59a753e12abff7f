"""Missions against a scripted device (PROTOCOL.md 11): start exactly once (also on a lossy link),
progress in order, result, failure code, cancel, a reboot mid-run, a link loss ridden through, and
the hub's duplicate and unknown-run rules for mission updates."""
from __future__ import annotations

import asyncio
import types
from typing import Any, List

import pytest

import hubwire
import hubwire.aio
from hubwire import MissionCancelled, MissionFailed, MissionLost, NakError
from hubwire.descriptor import parse_descriptor
from hubwire.errors import HubwireError, InvalidValue
from hubwire.testing.faultlink import Faults, FaultyTransport
from hubwire.transport import SerialTransport
from hubwire.wire.messages import NakCode

from missiondevice import DESCRIPTOR, DRIVE, HOME, Mission, MissionDevice, f32, wait_for


def connect(dev: MissionDevice, **kw: Any) -> hubwire.Device:
    return hubwire.connect(dev.path, timeout=5, cache_dir=False, **kw)


def report(dev: MissionDevice, cid: int, *values: float) -> None:
    """The sketch reports each value and waits until the hub acked it (so none is replaced)."""
    for v in values:
        assert dev.progress(cid, f32(v))
        assert wait_for(dev.idle)


def test_start_feedback_in_order_and_result() -> None:
    with MissionDevice() as dev, connect(dev) as d:
        job = d.start("drive", 2.0)
        assert (job.mission, job.run, job.status, job.done()) == ("drive", 1, "running", False)
        assert dev.missions[DRIVE].starts == [f32(2.0)]
        report(dev, DRIVE, 0.5, 1.0, 1.5)
        assert dev.finish(DRIVE, f32(2.0))
        assert list(job.feedback(timeout=5)) == [0.5, 1.0, 1.5]
        assert job.result(timeout=5) == 2.0
        assert (job.status, job.done()) == ("succeeded", True)
        assert list(job.feedback(timeout=5)) == [0.5, 1.0, 1.5]  # a second reader sees them too
        job2 = d.start("drive", 1.0)
        assert job2.run == 2  # +1 per accepted start


def test_a_mission_without_goal_with_void_progress_and_result() -> None:
    with MissionDevice() as dev, connect(dev) as d:
        job = d.start("home")
        assert dev.missions[HOME].starts == [b""]
        assert dev.progress(HOME) and wait_for(dev.idle)
        dev.finish(HOME)
        assert list(job.feedback(timeout=5)) == [None]
        assert job.result(timeout=5) is None and job.status == "succeeded"


def test_failure_code() -> None:
    with MissionDevice() as dev, connect(dev) as d:
        job = d.start("drive", 3.0)
        dev.fail(DRIVE, 7)
        with pytest.raises(MissionFailed) as e:
            job.result(timeout=5)
        assert (e.value.code, e.value.mission, e.value.run, job.status) == (7, "drive", 1, "failed")
        assert list(job.feedback(timeout=5)) == []


def test_cancel() -> None:
    with MissionDevice() as dev, connect(dev) as d:
        job = d.start("drive", 2.0)
        statuses: List[str] = []
        job.on_status(statuses.append)
        assert job.cancel() is True
        assert dev.missions[DRIVE].cancels == 1
        with pytest.raises(MissionCancelled):
            job.result(timeout=5)
        assert job.status == "cancelled"
        assert job.cancel() is False  # over: nothing sent
        assert wait_for(lambda: statuses == ["cancelled"])


def test_cancel_of_a_run_that_already_ended_on_the_board() -> None:
    with MissionDevice() as dev, connect(dev) as d:
        job = d.start("drive", 2.0)
        dev.mute = True  # the final waits on the board: the hub still thinks it runs
        dev.finish(DRIVE, f32(2.0))
        dev.mute = False
        controls = dev.controls
        assert job.cancel() is False  # the board: not running
        assert dev.controls == controls + 1 and dev.missions[DRIVE].cancels == 0
        assert job.result(timeout=5) == 2.0


def test_refusals() -> None:
    with MissionDevice(refuse=lambda goal: goal == f32(3.0)) as dev, connect(dev) as d:
        job = d.start("drive", 2.0)
        with pytest.raises(NakError) as e:
            d.start("drive", 1.0)
        assert e.value.code == NakCode.BUSY
        dev.finish(DRIVE, f32(2.0))
        job.result(timeout=5)
        with pytest.raises(NakError) as e:
            d.start("drive", 3.0)
        assert e.value.code == NakCode.REJECTED
        with pytest.raises(InvalidValue) as ei:  # checked by the hub, never sent
            d.start("drive", 20.0)
        assert ei.value.code == NakCode.OUT_OF_RANGE
        assert dev.missions[DRIVE].starts == [f32(2.0)]


def test_clear_errors_for_the_wrong_use() -> None:
    with MissionDevice() as dev, connect(dev) as d:
        with pytest.raises(HubwireError, match="'beep' is not a mission .*call.*dev.call"):
            d.start("beep", 1)
        with pytest.raises(HubwireError, match="'x' is not a mission .*read, write"):
            d.start("x", 1)
        with pytest.raises(AttributeError, match=r"'drive' is a mission, not an action: start it with dev.start\('drive', goal\)"):
            d.drive(2.0)
        with pytest.raises(HubwireError, match="is a mission"):
            d.call("drive", 2.0)
        with pytest.raises(HubwireError, match=r"dev.start\('home'\)"):
            d["home"]
        with pytest.raises(HubwireError, match="needs an argument"):
            d.start("drive")
        with pytest.raises(HubwireError, match="takes no argument"):
            d.start("home", 1)
        assert dev.controls == 0


def test_reboot_mid_mission_is_mission_lost() -> None:
    with MissionDevice() as dev, connect(dev) as d:
        job = d.start("drive", 2.0)
        statuses: List[str] = []
        job.on_status(statuses.append)
        report(dev, DRIVE, 0.5)
        dev.reboot()
        with pytest.raises(MissionLost, match="rebooted"):
            job.result(timeout=5)
        assert job.status == "lost"
        assert list(job.feedback(timeout=5)) == [0.5]
        assert wait_for(lambda: statuses == ["lost"])
        assert wait_for(lambda: d.state == "ready")
        job2 = d.start("drive", 1.0)  # the rebooted board counts from 1 again
        assert job2.run == 1 and job2.status == "running"


def test_link_loss_then_completion_once_the_link_returns() -> None:
    with MissionDevice() as dev, connect(dev) as d:
        job = d.start("drive", 2.0)
        statuses: List[str] = []
        job.on_status(statuses.append)
        report(dev, DRIVE, 0.5)
        dev.mute = True  # the line is cut: the hub declares the link lost after 4 heartbeats
        assert wait_for(lambda: job.status == "link lost")
        assert d.state == "lost"
        dev.progress(DRIVE, f32(1.0))  # queued on the board meanwhile
        assert wait_for(lambda: dev.inflight is not None)
        dev.finish(DRIVE, f32(2.0))
        dev.mute = False
        assert job.result(timeout=10) == 2.0
        assert list(job.feedback(timeout=5)) == [0.5, 1.0]
        assert wait_for(lambda: statuses[-1:] == ["succeeded"])  # callbacks run on the dispatcher thread
        assert statuses[0] == "link lost"
        assert set(statuses) <= {"link lost", "running", "succeeded"}


def test_a_repeated_update_is_acked_and_delivered_once() -> None:
    # the device loses the hub's first ACK of every update, so it sends each one again
    with MissionDevice(ack_update=lambda seq, nth: nth > 0) as dev, connect(dev) as d:
        job = d.start("drive", 2.0)
        report(dev, DRIVE, 0.5, 1.0)
        dev.finish(DRIVE, f32(2.0))
        assert job.result(timeout=5) == 2.0
        assert list(job.feedback(timeout=5)) == [0.5, 1.0]
        assert wait_for(dev.idle)  # the final's repeat was acked too
        stats = d.session.stats
        assert stats.duplicate_mission_updates >= 3 and stats.mission_updates == 3
        assert dev.update_frames >= 6


def test_an_update_of_an_unknown_run_is_acked_and_ignored() -> None:
    with MissionDevice() as dev, connect(dev) as d:
        job = d.start("drive", 2.0)
        report(dev, DRIVE, 0.5)
        with dev.lock2:  # the board reports a run this hub never started (another hub's)
            dev.missions[DRIVE] = Mission(run=9, running=True)
        report(dev, DRIVE, 7.0)
        assert dev.acked[-1][0] == DRIVE and dev.acked[-1][1][:2] == bytes((9, 1))
        assert d.session.stats.unknown_mission_updates == 1
        with dev.lock2:
            dev.missions[DRIVE] = Mission(run=1, running=True)
        dev.finish(DRIVE, f32(2.0))
        assert job.result(timeout=5) == 2.0
        assert list(job.feedback(timeout=5)) == [0.5]


def test_an_update_right_behind_the_start_answer_reaches_the_run() -> None:
    # the board reports at once from its start function: the M follows the start's r on the wire
    # and may be handled before the caller has registered the run number
    with MissionDevice(report_at_start=f32(0.0)) as dev, connect(dev) as d:
        for i in range(5):
            job = d.start("drive", 1.0)
            # the report is acked before the board finishes: a final replaces a progress not yet sent
            assert wait_for(dev.idle, 15)
            dev.finish(DRIVE, f32(1.0))
            assert job.result(timeout=5) == 1.0
            assert list(job.feedback(timeout=5)) == [0.0]
        assert d.session.stats.unknown_mission_updates == 0


def test_starts_are_applied_exactly_once_on_a_lossy_link() -> None:
    runs = 12
    with MissionDevice() as dev:
        fl = FaultyTransport(SerialTransport(dev.path), seed=3, both=Faults(drop=0.01))  # per byte: about one frame in ten
        with hubwire.connect(transport=fl, timeout=10, cache_dir=False, tries=12) as d:
            for i in range(runs):
                job = d.start("drive", float(i % 10))
                if i % 3 == 0:
                    report(dev, DRIVE, 0.25)
                dev.finish(DRIVE, f32(i))
                assert job.result(timeout=20) == float(i)
                assert job.run == i + 1
                assert list(job.feedback(timeout=5)) == ([0.25] if i % 3 == 0 else [])
            assert d.session.stats.retries > 0  # the link did lose frames
        assert dev.missions[DRIVE].starts == [f32(float(i % 10)) for i in range(runs)]


def test_the_asyncio_face() -> None:
    async def main(dev: MissionDevice) -> None:
        async with hubwire.aio.connect(transport=SerialTransport(dev.path), cache_dir=False) as d:
            job = await d.start("drive", 2.0)
            assert (job.run, job.status) == (1, "running")
            await asyncio.get_running_loop().run_in_executor(None, report, dev, DRIVE, 0.5)
            dev.finish(DRIVE, f32(1.5))
            assert [x async for x in job.feedback(timeout=5)] == [0.5]
            assert await job.result(timeout=5) == 1.5
            job = await d.start("drive", 1.0)
            assert await job.cancel() is True
            with pytest.raises(MissionCancelled):
                await job.result(timeout=5)
            with pytest.raises(HubwireError, match="not a mission"):
                await d.start("beep", 1)
            job = await d.start("drive", 1.0)
            dev.reboot()
            with pytest.raises(MissionLost):
                await job.result(timeout=5)

    with MissionDevice() as dev:
        asyncio.run(main(dev))


def test_a_routed_session_starts_missions_through_the_service() -> None:
    started = []
    remote = types.SimpleNamespace(descriptor=parse_descriptor(DESCRIPTOR), remote=object(),
                                   start_mission=lambda *a: started.append(a) or "job")
    d = hubwire.Device(remote)  # type: ignore[arg-type]
    assert d.start("drive", 2.0) == "job" and started == [("drive", 2.0, None)]
    with pytest.raises(HubwireError, match="not a mission"):  # the name is checked first
        d.start("beep", 1)
    with pytest.raises(hubwire.InvalidValue):  # and the goal
        d.start("drive", 20.0)
    assert len(started) == 1


def test_a_run_without_end_times_out_and_is_lost_when_the_session_closes() -> None:
    with MissionDevice() as dev:
        d = connect(dev)
        job = d.start("drive", 2.0)
        with pytest.raises(hubwire.Timeout, match="did not end within"):
            job.result(timeout=0.2)
        with pytest.raises(hubwire.Timeout, match="no progress"):
            list(job.feedback(timeout=0.2))
        d.close()
        with pytest.raises(MissionLost, match="session was closed"):
            job.result(timeout=5)
        assert job.status == "lost"
