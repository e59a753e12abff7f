"""End to end: the real hub (host/hubwire) against examples/Rover built for the Uno, running in simavr.

Every test starts its own simulated Uno (build/simuno/simuno with --reset-on-open and a bootloader
delay, see conftest.py), so opening the port resets the board exactly like a real Uno's DTR reset.
"""
from __future__ import annotations

import hashlib
import math
import os
import statistics
import struct
import threading
import time
from typing import Any, List

import pytest

import hubwire
from hubwire.errors import InvalidValue, NakError
from hubwire.testing import tap_of, tapped
from hubwire.wire import messages as m
from hubwire.wire.frame import Frame, FrameDecoder
from hubwire.wire.messages import NakCode

from rover import ROVER

from .conftest import BOOT_DELAY_MS, Simuno, drain_events, take, wait_until



def channel_rows(dev: Any) -> List[tuple]:
    return [(c.id, c.name, "".join(sorted(c.access)), c.type_name, c.unit, c.min, c.max, c.failsafe)
            for c in dev.descriptor.channels]


def sent_types(session: Any) -> List[int]:
    """Spy on what the hub writes: returns the list the frame types are appended to."""
    types: List[int] = []
    decoder = FrameDecoder(255)

    def spy(wire: bytes) -> bool:
        types.extend(f.type for f in decoder.feed(wire))
        return True

    tap_of(session).tx_filter = spy
    return types


# -------------------------------------------------------------------------- handshake, discovery

def test_handshake_and_discovery_ride_through_the_uno_boot_delay(uno: Simuno, hub_cache_dir: str) -> None:
    t0 = time.monotonic()
    with hubwire.connect(uno.link) as dev:  # no sleep, no retry loop: the hub rides through the reset
        elapsed = time.monotonic() - t0
        assert uno.resets() == 1, "opening the port must reset the simulated Uno"
        assert BOOT_DELAY_MS / 1000.0 <= elapsed < 5.0, f"connected after {elapsed:.2f} s"
        assert dev.state == "ready"
        assert dev.descriptor.name == "rover" and dev.descriptor.firmware == "1.0.0"
        assert channel_rows(dev) == [(i, n, "".join(sorted(a)), t, u, lo, hi, fs)
                                     for i, n, a, t, u, lo, hi, fs in ROVER]
        hello = dev.session.device_hello
        assert hello.version == 1 and hello.is_device and hello.nonce != 0
        assert hello.max_payload == 32 and hello.heartbeat_ms == 250
        raw = dev.descriptor.raw
        assert hello.descriptor_length == len(raw) and hello.descriptor_hash == m.fnv1a32(raw)
        stats = dev.session.stats
        assert stats.downloads == 1 and stats.cache_hits == 0
        assert stats.chunk_requests >= math.ceil(len(raw) / (hello.max_payload - 4))
        assert hello.digest == hashlib.sha256(raw).digest()[:16]  # worked out by the compiler
        assert os.listdir(hub_cache_dir) == [f"sha256-{hello.digest.hex()}.json"]
        # heartbeats flow and nobody heard garbage (the bootloader swallowed our early hellos)
        wait_until(lambda: dev.health().device_heartbeats >= 2, 2.0, "device heartbeats")
        h = dev.health()
        assert h.state == "ready" and h.device_heartbeat_ms == 250
        assert h.hub_counters == {"crc": 0, "overflow": 0, "dropped": 0}
        # (a hello cut by the end of the bootloader's hold may count as one dropped frame on the device)
        assert h.device_counters["crc"] + h.device_counters["dropped"] <= 1 and h.device_counters["overflow"] == 0
        first_nonce = hello.nonce
        text = dev.table()
        assert "rover" in repr(dev) and "m/s" in text and "-1..1" in text and "str[16]" in text
    # a new connection resets the Uno again (new nonce) and finds the descriptor in the shared cache
    with hubwire.connect(uno.link) as dev:
        assert uno.resets() == 2
        assert dev.session.device_hello.nonce != first_nonce
        assert dev.session.stats.chunk_requests == 0 and dev.session.stats.cache_hits == 1
        assert dev.descriptor.raw == raw
        assert dev.battery > 0


# ---------------------------------------------------------------------------- reads, controls

def test_read_every_readable_channel(rover: Any) -> None:
    assert rover.left == 0.0 and rover.right == 0.0
    imu = rover.imu
    assert imu._fields == ("ax", "ay", "az", "gyro")
    assert imu.az == pytest.approx(9.81) and imu.gyro == (0, 0, 0)
    rng = rover.range
    assert rng == (150, 150, 150, 150)  # standing still: every obstacle at the sketch's resting distance
    assert rover.battery == 7400  # no load
    assert rover.led is False
    assert rover["name"] == "rover"
    assert rover.failsafes == 0 and rover.applied == 0


def test_controls_are_acked_applied_once_and_seen_by_the_sketch(rover: Any) -> None:
    rover.left = 0.5                       # returns once the device ACKed it
    assert rover.left == 0.5
    assert rover.applied == 1
    # a lost ACK: the hub retries with the same seq, the device re-acks without applying twice
    dropped: List[Frame] = []
    right_id = rover.channel("right").id

    def lose_first_ack(f: Frame) -> bool:
        if f.type == m.ACK and f.id == right_id and not dropped:
            dropped.append(f)
            return False
        return True

    retries = rover.session.stats.retries
    tap_of(rover).rx_filter = lose_first_ack
    rover.right = -0.5
    tap_of(rover).rx_filter = None
    assert dropped and rover.session.stats.retries > retries
    assert rover.right == -0.5
    assert rover.applied == 2
    rover.led = True
    rover["name"] = "uno"
    assert rover.led is True and rover["name"] == "uno" and rover.applied == 4
    # the sketch's loop uses the values: its stand-in IMU turns with left - right
    imu = wait_until(lambda: (lambda v: v if v.gyro[2] == 90 else None)(rover.imu), 2.0, "imu to follow the motors")
    assert imu.ay == pytest.approx(0.2) and imu.ax == pytest.approx(0.0)


def test_out_of_range_is_refused_by_hub_and_by_device(rover: Any) -> None:
    rover.left = 0.25
    applied = rover.applied
    # the hub checks the declared range before sending: nothing goes on the wire
    with pytest.raises(InvalidValue) as e:
        rover.left = 1.5
    assert e.value.code == NakCode.OUT_OF_RANGE and e.value.error == "OUT_OF_RANGE"
    # the device enforces it too: send the raw control past the hub's check
    left = rover.channel("left")
    with pytest.raises(NakError) as nak:
        rover.session.control(left.id, left.codec.encode(1.5), what="left")
    assert nak.value.code == NakCode.OUT_OF_RANGE and nak.value.error == "OUT_OF_RANGE"
    assert nak.value.channel == "left"
    with pytest.raises(NakError) as nak:
        rover.session.control(left.id, b"\x00\x00", what="left")
    assert nak.value.code == NakCode.BAD_LENGTH
    with pytest.raises(NakError) as nak:
        rover.session.control(rover.channel("battery").id, b"\x00\x00", what="battery")
    assert nak.value.code == NakCode.NOT_WRITABLE
    with pytest.raises(NakError) as nak:
        rover.session.request(rover.channel("beep").id, what="beep")
    assert nak.value.code == NakCode.NOT_READABLE
    assert rover.left == 0.25 and rover.applied == applied


def test_nan_is_out_of_range(rover: Any) -> None:
    left = rover.channel("left")
    with pytest.raises(NakError) as nak:  # the device, past the hub's check
        rover.session.control(left.id, struct.pack("<f", float("nan")), what="left")
    assert nak.value.code in (NakCode.OUT_OF_RANGE, NakCode.BAD_VALUE)
    with pytest.raises(InvalidValue):  # the hub
        rover.left = float("nan")
    assert rover.applied == 0 and rover.left == 0.0


def test_callable_actions_return_the_sketch_result(rover: Any) -> None:
    assert rover.beep(100) is True
    # the sketch refuses long beeps by returning false: a normal result, not an error
    assert rover.beep(5000) is False
    assert rover.call("beep", 2000) is True
    with pytest.raises(InvalidValue):
        rover.beep(70000)  # does not fit the u16 argument
    assert rover.selftest(0) == 0


# ---------------------------------------------------------------------------------------- events

def test_selftest_events_arrive_exactly_once_in_order_despite_lost_acks(rover: Any) -> None:
    bumper_id = rover.channel("bumper").id
    with rover.events("bumper") as evs:
        boot = drain_events(evs)
        assert boot == [], "the bumper is released at boot: no event"
        dropped: List[int] = []

        def lose_first_ack_of_each_event(wire: bytes) -> bool:
            for f in FrameDecoder(255).feed(wire):
                if f.type == m.ACK and f.id == bumper_id and f.seq not in dropped:
                    dropped.append(f.seq)
                    return False
            return True

        before = rover.session.stats.as_dict()
        tap_of(rover).tx_filter = lose_first_ack_of_each_event
        assert rover.selftest(3) == 3
        got = []
        deadline = time.monotonic() + 5.0
        while len(got) < 3 and time.monotonic() < deadline:
            ev = evs.get(deadline - time.monotonic())
            if ev is not None:
                got.append(ev)
        got += drain_events(evs, 0.6)  # and nothing more (retries after our re-ACKs included)
        tap_of(rover).tx_filter = None
    assert [(e.name, e.value) for e in got] == [("bumper", True), ("bumper", False), ("bumper", True)]
    seqs = [e.seq for e in got]
    assert [(s - seqs[0]) & 0xFF for s in seqs] == [0, 1, 2], seqs
    assert sorted(dropped) == sorted(seqs), "every event's first ACK was lost, so the device retried"
    stats = rover.session.stats
    assert stats.events - before["events"] == 3
    assert stats.duplicate_events - before["duplicate_events"] >= 3


# --------------------------------------------------------------------------------------- streams

def test_streams_at_the_requested_rate(rover: Any) -> None:
    hz, seconds = 20, 2.0
    need = int(0.9 * hz * seconds)
    with rover.stream("battery", hz=hz, meta=True) as bat, rover.stream("imu", hz=hz, meta=True) as imu:
        assert bat.granted_ms == 50 and imu.granted_ms == 50
        # counted, not timed by the host: 10 x the time they take at the asked rate
        samples = {"battery": take(bat, need, 10 * seconds), "imu": take(imu, need, 10 * seconds)}  # type: Dict[str, List[Any]]
    for name, got in samples.items():
        assert len(got) >= 0.9 * hz * seconds - 1, f"{name}: {len(got)} samples in {seconds} s"
        assert all(x.lost == 0 for x in got), f"{name}: samples lost"
        seqs = [x.seq for x in got]
        assert all((b - a) & 0xFF == 1 for a, b in zip(seqs, seqs[1:])), f"{name}: seq gaps {seqs}"
        # the device's own clock: ms since the previous sample
        since = [x.since_ms for x in got[1:]]
        # the first sample: ms since the subscription (0 when sent at once, a few ms when the
        # device's frame buffer was busy with the next request arriving), well under one interval
        assert 0 <= got[0].since_ms < 1000 / hz / 2, f"{name}: first since_ms {got[0].since_ms}"
        assert statistics.mean(since) == pytest.approx(1000 / hz, rel=0.10), f"{name}: since_ms {since}"
        assert statistics.median(since) == pytest.approx(1000 / hz, rel=0.10)
        # the hub's clock: samples arrive in order and spread as the device sent them, not held
        # back and bunched up (a simulator slower than real time on a busy machine only spreads them)
        span, device_span = got[-1].time - got[0].time, sum(since) / 1000.0
        assert all(b.time >= a.time for a, b in zip(got, got[1:]))
        assert span >= 0.9 * device_span - 2 / hz, f"{name}: {span:.3f} s by arrival time, {device_span:.3f} s sent"
    assert all(isinstance(x.value, int) and 7100 <= x.value <= 7400 for x in samples["battery"])  # sags under load
    assert all(x.value.az == pytest.approx(9.81) for x in samples["imu"])
    # unsubscribed: the device stops sending
    n = rover.session.stats.samples
    time.sleep(0.3)
    assert rover.session.stats.samples - n <= 2


# ------------------------------------------------------------------------------------- link loss

def test_silent_hub_fires_the_device_failsafe(rover: Any) -> None:
    rover.left = 0.5
    rover.right = -0.75
    assert rover.failsafes == 0 and rover.left == 0.5
    lost = threading.Event()
    rover.on("link_lost", lost.set)
    s = rover.session
    tap_of(s).paused = True  # the hub goes silent: no heartbeats, no answers (PROTOCOL.md 4.3: lost after 1 s)
    try:
        # the device declares the link lost, applies the failsafes and announces itself with a hello,
        # which tells the hub (still listening) that the device dropped the link
        assert lost.wait(3.0), "the hub never learned that the device dropped the link"
    finally:
        tap_of(s).paused = False
    wait_until(lambda: rover.state == "ready", 5.0, "the hub to re-link")
    assert rover.failsafes == 1
    assert rover.left == 0.0 and rover.right == 0.0
    assert rover.applied == 2, "failsafe values are not writes from the hub"
    rover.left = 0.1  # and the link works again
    assert rover.left == pytest.approx(0.1)
    assert s.stats.link_lost >= 1


# ------------------------------------------------------------------------------------ MCU reset

def test_mcu_reset_mid_session_resyncs_from_the_cached_descriptor(uno: Simuno, hub_cache_dir: str) -> None:
    reconnected = threading.Event()
    with hubwire.connect(transport=tapped(uno.link)) as dev:
        s = dev.session
        assert s.stats.downloads == 1
        chunk_requests = s.stats.chunk_requests
        nonce = s.device_hello.nonce
        desc = dev.descriptor
        dev.on("reconnect", lambda d: reconnected.set())
        dev.left = 0.5
        types = sent_types(s)

        resets = uno.resets()
        uno.reset()  # SIGUSR1: the MCU restarts (bootloader delay, then setup()) under the hub's feet
        assert reconnected.wait(BOOT_DELAY_MS / 1000.0 + 5.0), "no on_reconnect after the MCU reset"
        wait_until(lambda: dev.state == "ready", 5.0, "ready after the reset")
        assert uno.resets() == resets + 1
        assert s.stats.reboots == 1
        assert s.device_hello.nonce != nonce, "the device announced the same nonce after a reset"
        # re-synced without downloading the descriptor again
        assert s.stats.downloads == 1 and s.stats.chunk_requests == chunk_requests
        assert m.CHUNK not in types, "the hub sent J (descriptor chunk) requests after the reset"
        assert m.HELLO in types
        assert dev.descriptor.hash == desc.hash
        # the board really restarted: its RAM is back to the sketch's initial values
        assert dev.left == 0.0 and dev.applied == 0 and dev.failsafes == 0
        dev.left = 0.25
        assert dev.left == 0.25
        assert m.CHUNK not in types


def test_nonce_changes_on_every_reset(uno: Simuno) -> None:
    """Each open (DTR reset) and each SIGUSR1 reset must give a new session nonce."""
    nonces = []
    for _ in range(2):
        with hubwire.connect(uno.link, cache_dir=False) as dev:
            nonces.append(dev.session.device_hello.nonce)
    with hubwire.connect(uno.link, cache_dir=False) as dev:
        nonces.append(dev.session.device_hello.nonce)
        uno.reset()
        wait_until(lambda: dev.session.stats.reboots == 1 and dev.state == "ready",
                   BOOT_DELAY_MS / 1000.0 + 5.0, "re-sync after the reset")
        nonces.append(dev.session.device_hello.nonce)
    assert len(set(nonces)) == len(nonces), [f"{n:08x}" for n in nonces]


def test_power_cycle_is_a_new_device_session(uno: Simuno) -> None:
    """Power-cycle the board (stop simuno, start a fresh one on the same link) while the hub stays
    connected: the hub must see a reboot and deliver the new boot's events."""
    with hubwire.connect(uno.link) as dev, dev.events("bumper") as evs:
        nonce = dev.session.device_hello.nonce
        before = drain_events(evs)
        uno.stop()
        uno.start()
        wait_until(lambda: dev.state == "ready" and dev.session.stats.port_reopens >= 1
                   and dev.session.device_hello.nonce != nonce,
                   BOOT_DELAY_MS / 1000.0 + 6.0, f"the hub to re-sync with a new nonce (old {nonce:08x})")
        # The new boot's first event (seq 1 again) must not be taken for a duplicate of the old one.
        uno.press()
        after = drain_events(evs, 1.5)
        assert before == [] and [e.value for e in after] == [True]


def test_pressing_the_bumper_is_one_event_each_way(uno: Simuno) -> None:
    """The real sketch's pin-2 bumper, pressed and released in the simulator."""
    with hubwire.connect(uno.link) as dev, dev.events("bumper") as evs:
        assert drain_events(evs, 0.3) == []
        uno.press()
        pressed = drain_events(evs, 1.0)
        uno.press()
        released = drain_events(evs, 1.0)
    assert [e.value for e in pressed] == [True]
    assert [e.value for e in released] == [False]
