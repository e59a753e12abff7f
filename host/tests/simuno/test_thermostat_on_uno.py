"""End to end, both directions: examples/Thermostat built for the Uno and run in simavr, with the
real hub offering it the channels of the README's "Both directions": the board reads the hub's
setpoint (R), writes its report into the hub (C), calls the hub's alarm action (C, r) and takes the
hub's mode events (!), after the hub's bind report (C id 0)."""
from __future__ import annotations

from typing import Any

import pytest

import hubwire
from hubwire.wire.messages import NakCode

from .conftest import Examples, wait_until
from .thermostat_home import Home


def settled(dev: Any, home: Home) -> bool:
    """The board's acknowledged counts equal what the hub's handlers saw (between two of its steps)."""
    with home.lock:
        return bool(dev.reports == len(home.reports) and dev.alarms == len(home.alarms))


def test_thermostat_uses_every_new_message_kind(examples: Examples) -> None:
    home = Home()
    dev = examples.start("Thermostat", hub=home.hub)
    assert [(c.id, c.name, c.access, c.type_name) for c in dev.descriptor.hub] == [
        (1, "setpoint", "r", "f32"), (2, "report", "w", "u16"), (3, "alarm", "c", "(f32) -> bool"), (4, "mode", "e", "u8")]
    assert dev.hub_binding() == {"setpoint": "ok", "report": "ok", "alarm": "ok", "mode": "ok"}
    # R: the board asks once a second and counts the answers
    wait_until(lambda: dev.setpoints >= 2, 20, "two setpoints read by the board")
    # C (write): every report the board saw acknowledged reached the hub's handler exactly once,
    # and each is the board's temperature in tenths of a degree
    wait_until(lambda: dev.reports >= 2 and settled(dev, home), 20, "reports counted on both sides")
    assert all(150 <= r <= 300 for r in home.reports), home.reports
    # !: mode 1 turns the heating on below the setpoint; events in order, each applied once
    temp = dev.temperature
    dev.notify("mode", 1)
    wait_until(lambda: dev.modes == 1 and dev.heating, 20, "heating on after mode 1")
    wait_until(lambda: dev.temperature > temp, 20, "the temperature to rise")
    for m in (0, 1, 0):
        dev.notify("mode", m)
    wait_until(lambda: dev.modes == 4 and dev.notifications_pending == 0, 20, "four mode events applied")
    assert dev.session.stats.hub_events_delivered == 4
    # C (call): a setpoint far below the temperature makes the board call the alarm action
    calls = len(home.alarms)
    home.setpoint.value = 5.0
    wait_until(lambda: len(home.alarms) > calls and settled(dev, home), 20, "the alarm called and answered")
    assert home.alarms[-1] > 10.0
    assert dev.failures == 0 and dev.last_failure == 0
    assert dev.health().measured_heartbeat_ms >= 250  # the board's own measure of its heartbeat
    st = dev.session.stats
    assert st.device_refused == 0 and st.binds_sent >= 1 and st.device_reads >= 2


def test_thermostat_connect_raises_for_a_missing_hub_channel(examples: Examples) -> None:
    home = Home()
    home.hub.remove("alarm")
    with pytest.raises(hubwire.HubChannelError, match="calls hub channel 'alarm'"):
        examples.start("Thermostat", hub=home.hub)


def test_thermostat_sees_a_refused_report(examples: Examples) -> None:
    dev = examples.start("Thermostat", hub_later=True)  # declared below, once connected
    dev.provide("setpoint", 21.5)
    dev.accept("report", lambda v: False, type="u16")  # every report refused: REJECTED
    dev.action("alarm", lambda t: True, type="f32", returns="bool")
    dev.event("mode", type="u8")
    # the board reports once a second of its own time, which a busy machine slows down
    wait_until(lambda: dev.failures >= 1, 60, "a refused report counted by the board")
    assert dev.last_failure == NakCode.REJECTED and dev.reports == 0
