"""The device's events and its own requests to the hub share one seq counter (PROTOCOL.md 4.1): with
the soak sketch writing into the hub all along, every bumper event it queues still arrives, once
and in order, on a clean link. A repeated seq would make the hub drop a new event as a duplicate."""
from __future__ import annotations

import os
import time
from typing import Any, List

import pytest

import hubwire
from hubwire.testing.faultlink.soak import soak_emulator_binary, start_emulator
from hubwire.testing.faultlink.soak_hub import HubTraffic
from hubwire.testing.faultlink import stop_process


@pytest.mark.parametrize("hub_load", [False, True], ids=["events alone", "events and hub writes"])
def test_device_events_arrive_while_the_device_writes_to_the_hub(tmp_path: Any, hub_load: bool) -> None:
    binary = soak_emulator_binary()
    if not os.access(binary, os.X_OK):
        pytest.fail(f"soak emulator not found at {binary}: build it with `make emulator`", pytrace=False)
    link = str(tmp_path / "soak")
    emu = start_emulator(binary, link)
    traffic = HubTraffic()
    try:
        with hubwire.connect(link, cache_dir=False, timeout=10, hub=traffic.hub) as dev:
            got: List[Any] = []
            dev.on("bumper", got.append)
            if hub_load:
                traffic.start(dev)
            batches = []
            for _ in range(40):
                batches.append(dev.selftest(4))
                time.sleep(0.05)
            queued = sum(batches)
            end = time.monotonic() + 10
            while len(got) < queued and time.monotonic() < end:
                time.sleep(0.05)
            time.sleep(0.3)
            assert (dev.tally_acked > 20) == hub_load  # the device wrote to the hub all along, or never
            assert got == [i % 2 == 0 for q in batches for i in range(q)]
            # `got` holds every event once, in order: none was lost or taken for a retry. (The device
            # does re-send an event whose ACK comes after its retry interval, 100 ms: on a loaded
            # machine some do, and the hub acknowledges those again without delivering them.)
    finally:
        stop_process(emu)
