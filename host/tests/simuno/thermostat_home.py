"""The hub's side of examples/Thermostat (the README's Python half, "Both directions"), shared by
the tests that run the sketch on a simulated Uno, directly or through `hubwire serve`."""
from __future__ import annotations

import threading
from typing import List

import hubwire


class Home:
    """The README's hub channels for the thermostat, recording what the board did."""

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.reports: List[int] = []
        self.alarms: List[float] = []
        self.hub = hubwire.HubChannels("home")
        self.setpoint = self.hub.provide("setpoint", 21.5, type="f32", unit="C")
        self.hub.accept("report", self.on_report, type="u16")
        self.hub.action("alarm", self.on_alarm)
        self.hub.event("mode", type="u8")

    def on_report(self, tenths: int) -> None:
        with self.lock:
            self.reports.append(tenths)

    def on_alarm(self, temperature: float) -> bool:
        with self.lock:
            self.alarms.append(temperature)
        return True
