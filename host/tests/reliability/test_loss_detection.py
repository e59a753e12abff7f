"""A dead link is still noticed within 4 heartbeat intervals (PROTOCOL.md 4.3), on both sides, while
the hub's probes and heartbeat grid make a noisy link survive longer (bench/noise_curve.py).

The soak sketch (extras/tests/Soak) records millis() when its failsafe fires and exposes its clock,
so the device's own detection time is measured on the device's clock, not guessed from the hub.
Bounds come from the configured intervals: 4 intervals after the cut, plus one of margin.
"""
from __future__ import annotations

import os
import time
from typing import Any, Iterator, List, Tuple

import pytest

import hubwire
from hubwire.session.link import LOSS_HEARTBEATS, PROBE_EVERY
from hubwire.testing import tapped
from hubwire.testing.faultlink import FaultLink, stop_process
from hubwire.testing.faultlink.soak import soak_emulator_binary, start_emulator
from hubwire.testing.faultlink.soak_load import wait_for
from hubwire.wire import messages as m

HUB_HEARTBEAT_MS = 250


@pytest.fixture
def soak_link(tmp_path: Any) -> Iterator[Tuple[Any, FaultLink]]:
    binary = soak_emulator_binary()
    if not os.access(binary, os.X_OK):
        pytest.fail(f"soak emulator not found at {binary}: build it with `make emulator`", pytrace=False)
    emu = start_emulator(binary, str(tmp_path / "dev"))
    fl = FaultLink(str(tmp_path / "dev"), str(tmp_path / "hub"), seed=9).start()
    dev = hubwire.connect(str(tmp_path / "hub"), cache_dir=False, timeout=10, heartbeat_ms=HUB_HEARTBEAT_MS,
                          hub_later=True)
    try:
        yield dev, fl
    finally:
        dev.close()
        fl.stop()
        stop_process(emu)


def device_clock_at(dev: Any) -> Tuple[float, int]:
    """(host time, device millis) at the same moment, within half a round trip on a clean link."""
    t0 = time.monotonic()
    up = dev.uptime
    return (t0 + time.monotonic()) / 2, up


def test_a_dead_link_is_noticed_within_four_intervals_on_both_sides(soak_link: Any) -> None:
    dev, fl = soak_link
    device_beat = dev.session.core.link.device_hello.heartbeat_ms
    lost: List[float] = []
    dev.on("link_lost", lambda: lost.append(time.monotonic()))
    fs0 = dev.failsafes
    time.sleep(0.6)  # an idle link: heartbeats only
    host_t, dev_ms = device_clock_at(dev)
    time.sleep(0.3)
    fl.set_faults(cut=True)
    cut = time.monotonic()
    assert wait_for(lambda: bool(lost), 10 * LOSS_HEARTBEATS * device_beat / 1000)
    time.sleep(0.5)
    fl.set_faults(cut=False)
    assert wait_for(lambda: dev.state == "ready", 10)
    assert dev.failsafes == fs0 + 1
    device_detect_ms = dev.failsafe_at - (dev_ms + (cut - host_t) * 1000)
    hub_detect_ms = (lost[0] - cut) * 1000
    # the device times the hub's announced interval, the hub the device's
    assert 2 * HUB_HEARTBEAT_MS < device_detect_ms <= (LOSS_HEARTBEATS + 1) * HUB_HEARTBEAT_MS
    assert 2 * device_beat < hub_detect_ms <= (LOSS_HEARTBEATS + 1) * device_beat
    assert fl.stats()["h2d"]["bytes_cut"] > 0 and fl.stats()["d2h"]["bytes_cut"] > 0


def test_a_device_whose_heartbeats_vanish_is_probed_and_its_answers_keep_the_link(tmp_path: Any) -> None:
    binary = soak_emulator_binary()
    emu = start_emulator(binary, str(tmp_path / "dev"))
    tap = tapped(str(tmp_path / "dev"))
    try:
        with hubwire.connect(transport=tap, cache_dir=False, timeout=10, hub_later=True) as dev:
            link = dev.session.core.link
            beat = link.device_hello.heartbeat_ms / 1000
            lost: List[float] = []
            dev.on("link_lost", lambda: lost.append(time.monotonic()))
            fs0 = dev.failsafes
            time.sleep(2 * beat * LOSS_HEARTBEATS)
            assert link.probes == 0  # a healthy link is never probed
            # the hub hears no heartbeat for three loss windows: only the answers to its probes
            tap.rx_filter = lambda f: f.type != m.HEARTBEAT
            time.sleep(3 * beat * LOSS_HEARTBEATS)
            tap.rx_filter = None
            assert lost == [] and dev.state == "ready"
            assert link.probes >= 3 * LOSS_HEARTBEATS * PROBE_EVERY / 2  # about one per device interval
            assert dev.failsafes == fs0  # the device never lost the hub either
    finally:
        stop_process(emu)
