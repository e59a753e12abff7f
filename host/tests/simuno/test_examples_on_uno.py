"""End to end: every example sketch, built for the Uno and run in simavr, discovered by the real hub
and doing what its comments teach. Rover, Thermostat, LargeValues and Missions have their own files
(test_rover_on_uno.py, test_thermostat_on_uno.py, test_large_values_on_uno.py, test_missions_on_uno.py)."""
from __future__ import annotations

import os
import statistics
import threading
import time

import pytest

from hubwire.errors import InvalidValue, NakError
from hubwire.testing import tap_of
from hubwire.wire.messages import NakCode

from .conftest import REPO, Examples, take, wait_until

# What each sketch declares, as the hub shows it: (name, access, type, unit, min, max, failsafe).
DECLARED = {
    "Minimal": ("minimal", [
        ("blink_ms", "rw", "u16", "ms", 50, 5000, None),
        ("led", "w", "bool", None, None, None, None),
        ("button", "e", "u8", None, None, None, None),
    ]),
    "Failsafe": ("failsafe", [
        ("speed", "rw", "i16", "%", -100, 100, 0),
        ("stops", "r", "u16", None, None, None, None),
    ]),
    "Streaming": ("streaming", [
        ("light", "rs", "u16", None, None, None, None),
        ("uptime", "rs", "u32", "s", None, None, None),
    ]),
    "Actions": ("actions", [
        ("blink", "w", "u8", None, None, None, None),
        ("read_pin", "c", "(u8) -> i8", None, None, None, None),
        ("uptime_ms", "c", "() -> u32", "ms", None, None, None),
        ("calls", "r", "u16", None, None, None, None),
    ]),
    "Structs": ("structs", [
        ("gps", "rs", "struct{lat: f32, lon: f32, altitude: i16, satellites: u8, fix: bool}",
         None, None, None, None),
        ("temps", "rs", "i16[3]", "0.1 C", None, None, None),
        ("label", "rw", "str[20]", None, None, None, None),
    ]),
}


def test_every_example_has_an_end_to_end_test() -> None:
    on_disk = sorted(d for d in os.listdir(os.path.join(REPO, "examples"))
                     if os.path.isfile(os.path.join(REPO, "examples", d, d + ".ino")))
    assert on_disk == sorted(list(DECLARED) + ["LargeValues", "Missions", "Rover", "Thermostat"])  # each with a file of its own


@pytest.mark.parametrize("sketch", sorted(DECLARED))
def test_the_hub_discovers_what_the_example_declares(examples: Examples, sketch: str) -> None:
    dev = examples.start(sketch)
    name, channels = DECLARED[sketch]
    assert dev.descriptor.name == name
    got = [(c.name, c.access, c.type_name, c.unit, c.min, c.max, c.failsafe) for c in dev.descriptor.channels]
    assert got == channels
    assert [c.id for c in dev.descriptor.channels] == list(range(1, len(channels) + 1))


def test_minimal_blink_rate_led_and_one_event_per_press(examples: Examples) -> None:
    dev = examples.start("Minimal")
    assert dev.blink_ms == 500
    dev.blink_ms = 100
    assert dev.blink_ms == 100
    with pytest.raises(InvalidValue):
        dev.blink_ms = 20  # below the declared 50..5000
    dev.led = False
    with dev.events("button") as evs:
        for press in (1, 2):
            examples.sim("Minimal").press()  # pressed
            ev = evs.get(3.0)
            assert ev is not None and ev.value == press
            examples.sim("Minimal").press()  # released: no event
            assert evs.get(0.4) is None


def test_failsafe_stops_the_motor_when_the_hub_goes_silent(examples: Examples) -> None:
    dev = examples.start("Failsafe")
    dev.speed = 50
    assert dev.speed == 50 and dev.stops == 0
    with pytest.raises(InvalidValue):
        dev.speed = 150
    lost = threading.Event()
    dev.on("link_lost", lost.set)
    tap_of(dev).paused = True  # the hub goes silent
    try:
        assert lost.wait(3.0), "the device never dropped the link"
    finally:
        tap_of(dev).paused = False
    wait_until(lambda: dev.state == "ready", 5.0, "the hub to re-link")
    assert dev.speed == 0 and dev.stops == 1
    dev.speed = -30  # the hub drives again
    assert dev.speed == -30


def test_streaming_sends_samples_at_the_asked_rate(examples: Examples) -> None:
    dev = examples.start("Streaming")
    hz = 20
    need = int(0.9 * hz * 1.5)  # 1.5 s worth
    with dev.stream("light", hz=hz, meta=True) as light, dev.stream("uptime", hz=hz, meta=True) as up:
        assert light.granted_ms == 50 and up.granted_ms == 50
        # counted, not timed by the host: 10 x the time they take at the asked rate
        got = {"light": take(light, need, 15.0), "uptime": take(up, need, 15.0)}
    for name, samples in got.items():
        assert len(samples) >= 0.9 * hz * 1.5 - 2, f"{name}: {len(samples)} samples"
        since = [x.since_ms for x in samples[1:]]
        assert statistics.mean(since) == pytest.approx(1000 / hz, rel=0.1), f"{name}: since_ms {since}"
    assert all(0 <= x.value <= 1023 for x in got["light"])
    ups = [x.value for x in got["uptime"]]
    assert ups == sorted(ups) and ups[-1] <= 10


def test_actions_run_once_refuse_and_return(examples: Examples) -> None:
    dev = examples.start("Actions")
    dev.blink = 3
    assert dev.calls == 1
    with pytest.raises(NakError) as nak:
        dev.blink = 11  # the sketch's blink() returns false above 10
    assert nak.value.code == NakCode.REJECTED
    assert dev.calls == 1
    assert dev.read_pin(13) in (0, 1)
    assert dev.read_pin(200) == -1
    assert dev.calls == 3
    t1 = dev.uptime_ms()
    time.sleep(0.2)
    t2 = dev.uptime_ms()
    assert 150 <= t2 - t1 < 1000


def test_structs_arrays_and_strings(examples: Examples) -> None:
    dev = examples.start("Structs")
    gps = dev.gps
    assert gps._fields == ("lat", "lon", "altitude", "satellites", "fix")
    assert gps.lat == pytest.approx(52.52) and gps.lon == pytest.approx(13.405)
    assert (gps.altitude, gps.satellites, gps.fix) == (34, 7, True)
    assert dev.temps == (215, 220, 198)
    assert dev.label == "bench 1"
    dev.label = "bench 2"
    assert dev.label == "bench 2"
    with pytest.raises(InvalidValue):
        dev.label = "x" * 21  # the sketch's char[21] holds 20 characters
    label = dev.channel("label")
    with pytest.raises(NakError) as nak:  # the device checks too, past the hub's check
        dev.session.control(label.id, bytes([21]) + b"x" * 21, what="label")
    assert nak.value.code in (NakCode.BAD_VALUE, NakCode.BAD_LENGTH)
    assert dev.label == "bench 2"
    with dev.stream("gps", hz=10) as s:
        first = s.get(2.0)
    assert first is not None and first.satellites == 7
