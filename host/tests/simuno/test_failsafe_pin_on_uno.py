"""examples/Failsafe on the simulated Uno, watched at its pins: when the hub goes silent, the failsafe
value reaches the motor driver through the channel's onChange (PROTOCOL.md 4.3), before the sketch's
link-lost hook runs. simuno --watch-pins logs every pin change with its cycle, as a probe would.

Needs `make simuno uno-firmware` (run by `make test-python`).
"""
from __future__ import annotations

import os
import re
import time
from typing import Any, List, Tuple

import pytest

from .conftest import Simuno, example_elf, wait_until

DIR_PIN = 4  # the motor driver's direction input: HIGH while speed < 0
PWM_PIN = 5  # its PWM input: analogWrite(|speed| * 255 / 100), LOW at speed 0
LED_PIN = 13  # LED_BUILTIN: HIGH in linkUp(), LOW in linkLost()
HUB_HEARTBEAT_MS = 250
LOST_AFTER_BEATS = 4  # HUBWIRE_LOST_AFTER_BEATS, the device's default (config.h)
CYCLES_PER_MS = 16000  # the Uno's 16 MHz

PIN_LINE = re.compile(r"^simuno: pin (\d+) = (\d+) at cycle (\d+)$", re.M)


class WatchedUno(Simuno):
    """A simulated Uno that also logs its pin changes."""

    @property
    def argv(self) -> list:
        return super().argv + ["--watch-pins"]

    def pin_changes(self, pin: int) -> List[Tuple[int, int]]:
        """(level, cycle) of every change of ``pin`` so far, in order."""
        return [(int(v), int(c)) for p, v, c in PIN_LINE.findall(self.log_text()) if int(p) == pin]


@pytest.fixture
def failsafe_uno(simuno_build: tuple, tmp_path: Any) -> Any:
    elf = example_elf("Failsafe")
    if not os.path.isfile(elf):
        pytest.fail(f"{elf} missing; build it with `make uno-firmware`", pytrace=False)
    sim = WatchedUno(simuno_build[0], elf, str(tmp_path / "uno"), str(tmp_path / "simuno.log"))
    sim.start()
    yield sim
    assert sim.stop() == 0, sim.log_text()


def last_level(changes: List[Tuple[int, int]]) -> int:
    return changes[-1][0] if changes else -1


def test_failsafe_reaches_the_pin_through_onchange_after_the_link_is_lost(failsafe_uno: WatchedUno) -> None:
    import hubwire

    sim = failsafe_uno
    dev = hubwire.connect(sim.link, heartbeat_ms=HUB_HEARTBEAT_MS)
    try:
        wait_until(lambda: last_level(sim.pin_changes(LED_PIN)) == 1, 15.0, "linkUp() to light the LED")
        dev.speed = -60  # onChange: direction pin HIGH
        wait_until(lambda: last_level(sim.pin_changes(DIR_PIN)) == 1, 15.0, "the direction pin to go HIGH")
        wait_until(lambda: len(sim.pin_changes(PWM_PIN)) > 10, 15.0, "the PWM pin to pulse")
        assert dev.speed == -60
        assert last_level(sim.pin_changes(LED_PIN)) == 1, "the link dropped while the hub was talking"
    finally:
        dev.close()  # the hub goes silent: nothing more is sent
    wait_until(lambda: last_level(sim.pin_changes(LED_PIN)) == 0, 15.0, "linkLost() to turn the LED off")
    time.sleep(0.3)  # the PWM, had it kept running, would pulse hundreds of times meanwhile

    dir_changes, led_changes = sim.pin_changes(DIR_PIN), sim.pin_changes(LED_PIN)
    high_at = dir_changes[-2][1]
    low_level, low_at = dir_changes[-1]
    lost_at = led_changes[-1][1]
    assert dir_changes[-2][0] == 1 and low_level == 0, dir_changes
    # Once, at the link loss: the write was the last thing the hub did before falling silent, so
    # the loss comes no sooner than the device's timeout after it.
    assert low_at - high_at >= HUB_HEARTBEAT_MS * LOST_AFTER_BEATS * CYCLES_PER_MS, (high_at, low_at)
    # speed held 0 and the pin followed (onChange) before the sketch's hook ran: linkLost() itself
    # does not touch the motor pins.
    assert low_at <= lost_at < low_at + CYCLES_PER_MS, (dir_changes, led_changes)
    assert [lv for lv, at in dir_changes if at > high_at] == [0], dir_changes
    pwm_after = [(lv, at) for lv, at in sim.pin_changes(PWM_PIN) if at >= low_at]
    assert len(pwm_after) <= 1 and last_level(sim.pin_changes(PWM_PIN)) == 0, pwm_after[:5]
    assert all(at < lost_at for lv, at in pwm_after), pwm_after
