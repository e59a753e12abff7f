"""examples/Thermostat on a simulated Uno, served by `hubwire serve`, its hub channels provided by a
client of the service with the README's own calls (docs/SERVICE.md "Hub channels"): the board reads
the client's setpoint and heats toward it, its reports and alarm calls reach the client's handlers,
the client's mode events reach it; when the client goes the board is unbound and stops asking; a
client that declares the channels after connecting binds them again."""
from __future__ import annotations

import os
import time
from typing import Callable

import pytest

import hubwire
from simuno.conftest import Simuno
from simuno.thermostat_home import Home

from .conftest import Serve, wait_for

#: the sketch asks for its setpoint once a second while bound
STEP_S = 1.0


@pytest.fixture
def thermostat(served_uno: Callable[..., Simuno]) -> Simuno:
    return served_uno("Thermostat")


def test_the_thermostat_through_the_service(serve: Serve, thermostat: Simuno) -> None:
    serve.wait_state("thermostat", "ready")
    watcher = hubwire.connect("thermostat")
    try:
        # nobody provides them: unbound, and the sketch does not ask
        assert watcher.hub_binding() == {"setpoint": "UNKNOWN_CHANNEL", "report": "UNKNOWN_CHANNEL",
                                         "alarm": "UNKNOWN_CHANNEL", "mode": "ok"}
        time.sleep(2.5 * STEP_S)
        assert watcher.setpoints == 0
        home = Home()
        with hubwire.connect("thermostat", hub=home.hub) as dev:
            assert dev.hub_binding() == {"setpoint": "ok", "report": "ok", "alarm": "ok", "mode": "ok"}
            wait_for(lambda: dev.setpoints >= 2, 30, "two setpoints read")
            dev.notify("mode", 1)
            wait_for(lambda: dev.modes == 1 and dev.heating, 30, "heating toward the client's setpoint")
            wait_for(lambda: len(home.reports) >= 2, 30, "reports at the client")
            with home.lock:
                assert all(150 <= r <= 300 for r in home.reports), home.reports
            home.setpoint.value = 5.0  # far below: heating stops and the board raises the alarm
            wait_for(lambda: not dev.heating, 30, "heating off")
            wait_for(lambda: dev.alarms >= 1, 30, "an alarm answered")
            with home.lock:
                assert home.alarms and all(a > 10.0 for a in home.alarms)
            # no request refused; one may time out (240: kHubTimeout) on a loaded machine
            assert dev.last_failure in (0, 240), dev.last_failure
        # the provider went: the board is unbound again and stops asking
        wait_for(lambda: watcher.hub_binding()["setpoint"] == "UNKNOWN_CHANNEL", 30, "unbound after the client left")

        def stopped() -> bool:  # no setpoint read for 2.5 of the sketch's steps (its bind report may be late)
            before = watcher.setpoints
            time.sleep(2.5 * STEP_S)
            return bool(watcher.setpoints == before)
        wait_for(stopped, 60, "the board stopped asking")
        asked = watcher.setpoints
        # declared after connecting, on the same device: bound again
        watcher.provide("setpoint", 30.0, type="f32")
        watcher.accept("report", lambda v: None, type="u16")
        watcher.action("alarm", lambda t: True, type="f32", returns="bool")
        wait_for(lambda: watcher.hub_binding() == {"setpoint": "ok", "report": "ok", "alarm": "ok", "mode": "ok"},
                 30, "bound by the declarations")
        wait_for(lambda: watcher.setpoints >= asked + 2, 30, "asking again")
        rows = {r["channel"]: r for r in watcher.session.hub_status()}
        assert f"pid {os.getpid()}" in rows["setpoint"]["by"]
    finally:
        watcher.close()
