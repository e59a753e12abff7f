"""`hubwire serve` with a simulated Uno (real Rover firmware in simavr, reset on every open like a
real Uno): commands through the service do not reset it, and what they set stays set."""
from __future__ import annotations

import os
import time
from typing import Callable

import pytest

from conftest import Emulator
from simuno.conftest import Simuno, rover_elf

from .conftest import Serve

#: 4 heartbeats of 250 ms make a lost link; three times that, on a slow simulation
LOSS_WINDOW = 3.0


@pytest.fixture
def uno(served_uno: Callable[..., Simuno]) -> Simuno:
    return served_uno("Rover", rover_elf())


def test_commands_through_the_service_neither_reset_the_uno_nor_trip_its_failsafe(
        serve: Serve, uno: Simuno, emulators: Callable[[str], Emulator]) -> None:
    serve.wait_state("rover", "ready", uno.link)
    emulators("e1")  # two emulated Rovers beside it: three boards called "rover"
    emulators("e2")
    serve.wait_state("rover---2", "ready")
    serve.wait_state("rover---3", "ready")
    assert uno.resets() == 1  # the service's open
    serve.cli("set", "rover", "led", "true")
    assert serve.cli("get", "rover", "led").stdout.strip() == "True"
    for key, value in (("rover", "-0.25"), ("rover---2", "0.5"), ("rover---3", "0.75")):
        serve.cli("set", key, "left", value)
    time.sleep(LOSS_WINDOW)
    for key, value in (("rover", "-0.25"), ("rover---2", "0.5"), ("rover---3", "0.75")):
        assert serve.cli("get", key, "left").stdout.strip() == value
        assert serve.cli("get", key, "failsafes").stdout.strip() == "0"
    assert serve.cli("get", "rover", "applied").stdout.strip() == "2"  # each write applied once
    assert uno.resets() == 1  # no command opened the port: no reset
    assert sorted(b["port"] for b in serve.boards()) == sorted(
        [uno.link] + [os.path.join(serve.boards_dir, n) for n in ("e1", "e2")])
