"""End to end: examples/Missions built for the Uno and run in simavr, driven by the real hub: a
drive started once, its progress in order, its result, a start while it runs (BUSY), a refused
start (REJECTED), a failure code, a cancel, and a reset of the board mid-run (MissionLost)."""
from __future__ import annotations

from typing import Any, List

import pytest

from hubwire import InvalidValue, MissionCancelled, MissionFailed, MissionLost, NakError
from hubwire.wire.messages import NakCode

from .conftest import Examples, wait_until

#: generous: the simulated Uno runs slower than real time on a busy machine
DEADLINE = 60.0


def first_progress(job: Any) -> float:
    """Wait for the run's first progress value (the board is driving)."""
    return next(iter(job.feedback(timeout=DEADLINE)))  # type: ignore[no-any-return]


def test_drive_on_uno(examples: Examples) -> None:
    dev = examples.start("Missions")
    assert dev.descriptor.name == "missions"
    assert [(c.name, c.access, c.type_name, c.unit, c.min, c.max) for c in dev.descriptor.channels] == [
        ("drive", "m", "(f32) -> f32, progress f32", "m", 0.1, 10), ("speed", "rw", "f32", "m/s", 0.1, 2),
        ("odometer", "r", "f32", "m", None, None), ("blocked", "rw", "bool", None, None, None)]
    assert dev.channel("drive").progress_max == 10
    # start, progress in order, result
    dev.speed = 2.0
    odometer = dev.odometer
    job = dev.start("drive", 1.0)
    assert (job.run, job.status) == (1, "running")
    progress: List[float] = list(job.feedback(timeout=DEADLINE))
    assert job.result(timeout=DEADLINE) == pytest.approx(1.0)
    assert progress and progress == sorted(set(progress)) and all(0 < p < 1.0 for p in progress), progress
    assert dev.odometer == pytest.approx(odometer + 1.0)
    # a start while a run goes is BUSY; a cancel ends the run as cancelled
    dev.speed = 0.1
    job = dev.start("drive", 10.0)
    assert job.run == 2
    with pytest.raises(NakError) as e:
        dev.start("drive", 1.0)
    assert e.value.code == NakCode.BUSY
    assert first_progress(job) > 0
    assert job.cancel() is True
    with pytest.raises(MissionCancelled):
        job.result(timeout=DEADLINE)
    assert job.cancel() is False and job.status == "cancelled"
    # blocked while driving: the run fails with the sketch's code; blocked at the start: REJECTED
    job = dev.start("drive", 10.0)
    first_progress(job)
    dev.blocked = True
    with pytest.raises(MissionFailed) as f:
        job.result(timeout=DEADLINE)
    assert (f.value.code, job.status) == (1, "failed")
    with pytest.raises(NakError) as e:
        dev.start("drive", 1.0)
    assert e.value.code == NakCode.REJECTED
    dev.blocked = False
    # out of the declared range: refused by the hub before anything is sent
    with pytest.raises(InvalidValue, match="outside the declared range"):
        dev.start("drive", 20.0)
    assert dev.session.stats.unknown_mission_updates == 0


def test_a_reset_mid_run_is_mission_lost(examples: Examples) -> None:
    dev = examples.start("Missions")
    dev.speed = 0.1
    job = dev.start("drive", 10.0)
    statuses: List[str] = []
    job.on_status(statuses.append)
    first_progress(job)
    reboots = dev.session.stats.reboots
    examples.sim("Missions").reset()  # the MCU restarts under the hub's feet
    with pytest.raises(MissionLost, match="rebooted"):
        job.result(timeout=DEADLINE)
    assert job.status == "lost"
    wait_until(lambda: dev.session.stats.reboots > reboots and dev.state == "ready", DEADLINE, "the board back")
    wait_until(lambda: statuses[-1:] == ["lost"], DEADLINE, "the status callback")
    dev.speed = 2.0  # the reset set it back to its initial value
    job = dev.start("drive", 0.5)  # the rebooted board counts its runs from 1 again
    assert job.run == 1
    assert job.result(timeout=DEADLINE) == pytest.approx(0.5)
