"""examples/Missions on the simulated Uno (real AVR firmware in simavr) through `hubwire serve`: a
drive started once, its progress in order, its result; a second start while it runs is BUSY; a
cancel from the command line ends it as cancelled; and the service's one open reset the Uno once."""
from __future__ import annotations

from typing import Callable, List

import pytest

import hubwire
from hubwire import MissionCancelled, NakError
from hubwire.wire.messages import NakCode
from simuno.conftest import Simuno

from .conftest import Serve

#: generous: the simulated Uno runs slower than real time on a busy machine
DEADLINE = 90.0


@pytest.fixture
def uno(served_uno: Callable[..., Simuno]) -> Simuno:
    return served_uno("Missions")


def test_missions_example_on_the_uno_through_the_service(serve: Serve, uno: Simuno) -> None:
    serve.wait_state("missions", "ready", uno.link)
    with hubwire.connect("missions") as dev:
        dev.speed = 2.0
        job = dev.start("drive", 1.0)
        assert (job.run, job.status) == (1, "running")
        progress: List[float] = list(job.feedback(timeout=DEADLINE))
        assert job.result(timeout=DEADLINE) == pytest.approx(1.0)
        assert progress and progress == sorted(set(progress)) and all(0 < p < 1.0 for p in progress), progress
        dev.speed = 0.1
        job = dev.start("drive", 10.0)
        with pytest.raises(NakError) as e:
            dev.start("drive", 1.0)
        assert e.value.code == NakCode.BUSY
        assert next(iter(job.feedback(timeout=DEADLINE))) > 0
        # another connection follows it by its run id and cancels it
        with hubwire.connect("missions") as other:
            assert other.session.follow(job.run_id).cancel() is True
        with pytest.raises(MissionCancelled):
            job.result(timeout=DEADLINE)
        assert job.status == "cancelled"
    assert uno.resets() == 1  # only the service's open reset the Uno
