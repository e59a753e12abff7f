"""End to end against the C++ device library running as a process on a pty (the Rover sketch)."""
from __future__ import annotations

import math
import threading
import time
from typing import Any, List

import pytest

import hubwire
from hubwire.errors import InvalidValue, LinkLost, NakError
from hubwire.wire import messages as m
from hubwire.wire.frame import Frame, FrameDecoder
from hubwire.wire.messages import NakCode

from hubwire.testing import tap_of

from conftest import Emulator, wait_until
from rover import ROVER



def ids(rover: Any, name: str) -> int:
    return rover.channel(name).id


# ----------------------------------------------------------------------------------- discovery

def test_discovery_matches_the_rover(rover: Any) -> None:
    d = rover.descriptor
    assert d.name == "rover"
    got = [(c.id, c.name, "".join(sorted(c.access)), c.type_name, c.unit, c.min, c.max, c.failsafe) for c in d.channels]
    assert got == [(i, n, "".join(sorted(a)), t, u, lo, hi, fs) for i, n, a, t, u, lo, hi, fs in ROVER]
    assert d.hash == m.fnv1a32(d.raw) == rover.session.device_hello.descriptor_hash
    text = rover.table()
    assert "rover" in repr(rover) and "m/s" in text and "-1..1" in text and "str[16]" in text and "event" in text
    assert "\n" not in repr(rover) and "'rover'" in repr(rover) and "ready" in repr(rover)
    assert rover.state == "ready"
    assert "left" in dir(rover) and "left" in rover and "nope" not in rover


def test_first_connect_downloads_then_cache_is_used(emulator: Emulator, cache_dir: str) -> None:
    with hubwire.connect(emulator.link, cache_dir=cache_dir) as dev:
        first = dev.session.stats.as_dict()
        raw = dev.descriptor.raw
    assert first["downloads"] == 1 and first["chunk_requests"] >= math.ceil(len(raw) / 28)
    with hubwire.connect(emulator.link, cache_dir=cache_dir) as dev:
        assert dev.session.stats.chunk_requests == 0
        assert dev.session.stats.cache_hits == 1
        assert dev.descriptor.raw == raw
        assert dev.battery > 0


def test_corrupt_cache_entry_is_ignored(emulator: Emulator, cache_dir: str) -> None:
    import os

    with hubwire.connect(emulator.link, cache_dir=cache_dir) as dev:
        raw = dev.descriptor.raw
    (entry,) = os.listdir(cache_dir)
    with open(os.path.join(cache_dir, entry), "wb") as fh:
        fh.write(b"x" * len(raw))
    with hubwire.connect(emulator.link, cache_dir=cache_dir) as dev:
        assert dev.session.stats.downloads == 1
        assert dev.descriptor.raw == raw


# ----------------------------------------------------------------------------- reads and writes

def test_read_every_readable_channel(rover: Any) -> None:
    assert isinstance(rover.left, float) and rover.left == 0.0
    imu = rover.imu
    assert imu._fields == ("ax", "ay", "az", "gyro") and len(imu.gyro) == 3
    assert isinstance(rover.range, tuple) and len(rover.range) == 4
    assert isinstance(rover.battery, int)
    assert rover.led is False
    assert rover["name"] == "rover"
    assert rover.failsafes == 0 and rover.applied == 0


def test_writes_are_applied_exactly_once(rover: Any) -> None:
    rover.left = 0.5
    assert rover.left == 0.5
    rover["right"] = -0.25
    assert rover.read("right") == -0.25
    rover.led = True
    assert rover.led is True
    rover["name"] = "robbie"  # a channel whose name is a Device property is reached by key
    assert rover["name"] == "robbie"
    rover.write("name", "")
    assert rover["name"] == ""
    rover["name"] = "x" * 16
    assert rover["name"] == "x" * 16
    # every write applied counts once: left, right, led, name x3
    assert rover.applied == 6


def test_hub_checks_types_and_ranges_before_sending(rover: Any) -> None:
    sent = rover.session.stats.retries, rover.applied
    with pytest.raises(InvalidValue) as e:
        rover.left = 1.5
    assert e.value.code == NakCode.OUT_OF_RANGE
    with pytest.raises(InvalidValue) as e:
        rover.led = "yes"
    assert e.value.code == NakCode.BAD_VALUE
    with pytest.raises(InvalidValue):
        rover["name"] = "x" * 17
    with pytest.raises(AttributeError):
        rover.lfet = 0.5
    with pytest.raises(hubwire.HubwireError):
        rover.battery = 5
    with pytest.raises(KeyError):
        rover["nope"]
    assert (rover.session.stats.retries, rover.applied) == sent


def test_lost_ack_is_retried_with_same_seq_and_applied_once(rover: Any) -> None:
    s = rover.session
    dropped: List[Frame] = []
    tx: List[bytes] = []

    def drop_first_ack(f: Frame) -> bool:
        if f.type == m.ACK and f.id == ids(rover, "left") and not dropped:
            dropped.append(f)
            return False
        return True

    def record(wire: bytes) -> bool:
        tx.extend(FrameDecoder().feed(wire))
        return True

    before = rover.applied
    tap_of(s).rx_filter = drop_first_ack
    tap_of(s).tx_filter = record
    rover.left = 0.75
    tap_of(s).rx_filter = None
    tap_of(s).tx_filter = None
    assert dropped, "the first ACK was not dropped"
    controls = [f for f in tx if f.type == m.CONTROL]
    assert len(controls) == 2 and controls[0] == controls[1]  # a retry repeats the same seq
    assert rover.applied == before + 1
    assert rover.left == 0.75


# ------------------------------------------------------------------------------------- NAK paths

def nak(fn: Any, *args: Any, **kw: Any) -> str:
    with pytest.raises(NakError) as e:
        fn(*args, **kw)
    return e.value.error


def test_every_reachable_nak(rover: Any) -> None:
    s = rover.session
    left, led, battery, bumper = (ids(rover, n) for n in ("left", "led", "battery", "bumper"))
    assert nak(s.request, 99) == "UNKNOWN_CHANNEL"
    assert nak(s.control, 99, b"") == "UNKNOWN_CHANNEL"
    assert nak(s.request, bumper) == "NOT_READABLE"
    assert nak(s.control, battery, b"\x01\x00") == "NOT_WRITABLE"
    assert nak(s.control, left, b"\x00") == "BAD_LENGTH"
    assert nak(s.transact, m.REQUEST, battery, b"\x00") == "BAD_LENGTH"
    assert nak(s.control, left, rover.channel("left").codec.encode(1.5)) == "OUT_OF_RANGE"
    assert nak(s.control, led, b"\x02") == "BAD_VALUE"
    assert nak(s.control, ids(rover, "name"), b"\x11" + b"a" * 17) in ("BAD_VALUE", "BAD_LENGTH")
    assert nak(s.control, ids(rover, "name"), b"\x03ab") == "BAD_LENGTH"
    assert nak(s.subscribe, led, 20) == "NOT_STREAMABLE"
    assert nak(s.transact, m.SUBSCRIBE, battery, b"\x14") == "BAD_LENGTH"
    total = s.device_hello.descriptor_length
    assert nak(s.transact, m.CHUNK, 0, m.ChunkRequest(total + 1, 8).pack()) == "BAD_OFFSET"
    end = s.transact(m.CHUNK, 0, m.ChunkRequest(total, 8).pack())
    assert m.Chunk.unpack(end.payload) == m.Chunk(total, total, b"")
    assert nak(s.transact, 0x99, 1, b"") == "UNKNOWN_TYPE"
    # nothing above was applied
    assert rover.applied == 0 and rover.left == 0.0 and rover.led is False
    # the public API names the error and the channel
    with pytest.raises(NakError) as e:
        rover.session.control(left, b"\x00", what="left")
    assert e.value.code == NakCode.BAD_LENGTH and "left" in str(e.value) and "BAD_LENGTH" in str(e.value)


def test_busy_when_all_stream_slots_are_used(rover: Any) -> None:
    streams = [rover.stream(n, hz=10) for n in ("left", "right", "imu", "range")]
    try:
        with pytest.raises(NakError) as e:
            rover.stream("battery", hz=10)
        assert e.value.error == "BUSY"
    finally:
        for st in streams:
            st.close()
    with rover.stream("battery", hz=10) as st:  # a slot is free again
        assert st.granted_ms == 100


def test_not_linked_nak_when_the_device_dropped_the_link(rover: Any) -> None:
    s = rover.session
    lost, restored = threading.Event(), threading.Event()
    rover.on("link_lost", lost.set)
    rover.on("link_restored", restored.set)
    # the hub sends no hello or heartbeat: the device declares the link lost, goes silent (the hub
    # declares it lost too) and announces itself a second later; the hub's answer is suppressed, so
    # the device stays UNLINKED while the hub believes the link is back
    tap_of(s).tx_filter = lambda w: FrameDecoder().feed(w)[0].type not in (m.HELLO, m.HEARTBEAT)
    try:
        assert lost.wait(5)
        assert restored.wait(5), "device announce not seen"
        with pytest.raises(NakError) as e:
            s.transact(m.REQUEST, ids(rover, "battery"), b"")
        assert e.value.error == "NOT_LINKED"
        assert s.stats.not_linked >= 1
    finally:
        tap_of(s).tx_filter = None
    wait_until(lambda: rover.state == "ready", 5, "link restored")
    assert rover.battery > 0
    assert rover.failsafes == 1


# ------------------------------------------------------------------------------------- callables

def test_callables(rover: Any) -> None:
    assert rover.beep(200) is True
    assert rover.beep(2001) is False  # the sketch refuses long beeps
    assert rover.call("beep", 100) is True
    assert rover["beep"](50) is True
    with rover.events("bumper") as evs:
        assert rover.selftest(2) == 2
        got = [evs.get(2.0), evs.get(2.0)]
    assert [e.name for e in got if e] == ["bumper", "bumper"]
    with pytest.raises(InvalidValue):
        rover.beep(70000)
    with pytest.raises(hubwire.HubwireError):
        rover.beep()


# ---------------------------------------------------------------------------------------- events

def test_events_exactly_once_in_order_with_lost_acks(rover: Any) -> None:
    s = rover.session
    acks: List[int] = []

    def drop_every_other_ack(wire: bytes) -> bool:
        f = FrameDecoder().feed(wire)[0]
        if f.type == m.ACK and f.id == ids(rover, "bumper"):
            acks.append(f.seq)
            return len(acks) % 2 == 0  # the first ack of each event is lost: the device retries it
        return True

    with rover.events("bumper") as evs:
        tap_of(s).tx_filter = drop_every_other_ack
        try:
            assert rover.selftest(4) == 4
            got = [evs.get(5.0) for _ in range(4)]
            assert None not in got
            assert evs.get(0.3) is None  # and nothing more
        finally:
            tap_of(s).tx_filter = None
    seqs = [e.seq for e in got]  # type: ignore[union-attr]
    assert len(set(seqs)) == 4 and all((b - a) & 0xFF == 1 for a, b in zip(seqs, seqs[1:]))
    assert [e.value for e in got] == [True, False, True, False]  # type: ignore[union-attr]
    assert s.stats.duplicate_events >= 4
    assert len(acks) >= 8


def test_events_before_any_listener_are_kept_for_the_first_one(rover: Any) -> None:
    assert rover.selftest(3) == 3
    wait_until(lambda: rover.session.stats.events == 3, 5, "three events acknowledged")
    got: List[Any] = []
    done = threading.Event()

    def cb(v: Any) -> None:
        got.append(v)
        if len(got) == 3:
            done.set()

    rover.on("bumper", cb)
    assert done.wait(5)
    assert got == [True, False, True]
    with rover.events() as evs:  # already handed out: not delivered twice
        assert evs.get(0.2) is None


def test_event_callbacks_run_on_dispatcher_and_may_call(rover: Any, emulator: Emulator) -> None:
    done = threading.Event()
    seen: List[Any] = []

    def cb(value: bool) -> None:
        seen.append((value, threading.current_thread().name, rover.battery))
        done.set()

    remove = rover.on("bumper", cb)
    emulator.bump()  # a real pin change, as a finger would do
    assert done.wait(5)
    remove()
    value, thread, battery = seen[0]
    assert value is True and thread == "hubwire-dispatch" and battery > 0


# --------------------------------------------------------------------------------------- streams

def test_stream_samples_and_unsubscribe(rover: Any) -> None:
    s = rover.session
    with rover.stream("imu", hz=50, meta=True, timeout=2) as st:
        assert st.granted_ms == 20
        samples = [next(st) for _ in range(10)]
    assert [x.seq for x in samples] == list(range(samples[0].seq, samples[0].seq + 10))
    # the device's own clock: it keeps a 20 ms schedule (a late sample may be followed by an early
    # one, never more than one interval early), so 9 intervals span 9 x 20 ms minus at most one
    span = sum(x.since_ms for x in samples[1:])
    assert 8 * 20 <= span, [x.since_ms for x in samples]
    assert span <= 9 * 20 * 3, [x.since_ms for x in samples]  # and it was not starved for long
    assert all(isinstance(x.value.az, float) and len(x.value.gyro) == 3 for x in samples)
    # after the subscription ended the device sends nothing more
    count = s.stats.samples
    assert not threading.Event().wait(0.3)
    assert s.stats.samples == count
    with rover.stream("range", hz=1000) as fast:
        assert fast.granted_ms == 10  # the device's minimum interval
        value = next(iter(fast))
        assert len(value) == 4


def test_stream_generator_loop_and_break(rover: Any) -> None:
    n = 0
    for sample in rover.stream("battery", hz=100, timeout=2):
        assert isinstance(sample, int)
        n += 1
        if n == 3:
            break
    assert n == 3
    # the abandoned stream unsubscribed itself (without waiting for the ACK)
    assert rover.session.subscriptions == {}
    with rover.stream("battery", hz=100, timeout=2) as st:  # and the device accepts a new one
        assert isinstance(next(st), int)


def test_concurrent_calls_from_many_threads(rover: Any) -> None:
    errors: List[BaseException] = []

    def reader() -> None:
        try:
            for _ in range(30):
                assert rover.battery > 0
                assert len(rover.range) == 4
        except BaseException as e:  # noqa: BLE001
            errors.append(e)

    def writer(name: str, value: float) -> None:
        try:
            for i in range(20):
                rover.write(name, value if i % 2 else -value)
        except BaseException as e:  # noqa: BLE001
            errors.append(e)

    threads = [threading.Thread(target=reader) for _ in range(3)]
    threads += [threading.Thread(target=writer, args=("left", 0.5)), threading.Thread(target=writer, args=("right", 0.25))]
    for t in threads:
        t.start()
    for t in threads:
        t.join(30)
    assert errors == []
    assert rover.applied == 40
    assert (rover.left, rover.right) == (0.5, 0.25)


# ------------------------------------------------------------------------------------ link loss

def test_link_loss_on_the_hub_side_fails_fast_and_recovers(rover: Any, emulator: Emulator) -> None:
    lost, restored = threading.Event(), threading.Event()
    rover.on("link_lost", lost.set)
    rover.on("link_restored", restored.set)
    rover.left = 0.5
    st = rover.stream("battery", hz=20, timeout=5)
    assert isinstance(next(st), int)
    emulator.pause()  # the device falls silent
    try:
        assert lost.wait(3)
        assert rover.state == "lost"
        assert st._sub is not None and st._sub.ended is None  # the stream waits for the link
        t = time.monotonic()
        with pytest.raises(LinkLost):
            rover.battery
        with pytest.raises(LinkLost):
            rover.left = 0.1
        assert time.monotonic() - t < 0.1  # fail fast
    finally:
        emulator.resume()
    assert restored.wait(5)
    assert rover.state == "ready"
    assert rover.battery > 0
    assert rover.session.stats.reboots == 0
    while st.gaps == 0:  # the stream rode through: subscribed again, the outage reported
        assert isinstance(next(st), int)
    assert st.gaps == 1
    st.close()


def test_link_loss_on_the_device_side_fires_failsafe(rover: Any) -> None:
    lost, restored = threading.Event(), threading.Event()
    rover.on("link_lost", lost.set)
    rover.on("link_restored", restored.set)
    rover.left = 0.5
    rover.right = -0.5
    assert rover.failsafes == 0
    tap_of(rover).paused = True  # the hub falls silent: the device's failsafe fires
    try:
        assert lost.wait(5)  # seen through the device's announce hello
    finally:
        tap_of(rover).paused = False
    assert restored.wait(5), (rover.session.stats, rover.health())
    wait_until(lambda: rover.state == "ready", 5, "ready")
    assert rover.failsafes == 1
    assert rover.left == 0.0 and rover.right == 0.0


# ------------------------------------------------------------------------------------- restarts

def test_device_restart_mid_session(rover: Any, emulator: Emulator) -> None:
    reconnected = threading.Event()
    got: List[Any] = []

    def on_reconnect(desc: Any) -> None:
        got.append((desc.name, rover.applied))  # a callback may call the device
        reconnected.set()

    rover.on("reconnect", on_reconnect)
    rover.left = 0.5
    assert rover.applied == 1
    old_nonce = rover.session.device_hello.nonce
    chunks = rover.session.stats.chunk_requests
    emulator.stop()
    emulator.start()
    assert reconnected.wait(10)
    assert got == [("rover", 0)]  # a fresh device: nothing restored by the hub
    assert rover.session.device_hello.nonce != old_nonce
    assert rover.session.stats.reboots == 1
    assert rover.session.stats.port_reopens >= 1  # the pty vanished and came back
    assert rover.session.stats.chunk_requests == chunks  # same descriptor: not downloaded again
    assert rover.left == 0.0
    rover.left = 0.25
    assert rover.left == 0.25


def test_hub_restart_is_a_new_session(emulator: Emulator, cache_dir: str) -> None:
    with hubwire.connect(emulator.link, cache_dir=cache_dir) as a:
        a.left = 0.5
        nonce = a.session.nonce
        with a.stream("imu", hz=20) as st:
            next(st)
    with hubwire.connect(emulator.link, cache_dir=cache_dir) as b:
        assert b.session.nonce != nonce
        assert b.left == 0.5  # the device kept its state
        assert b.applied == 1
        b.left = 0.5  # a new hub session: same seq no longer counts as duplicate
        assert b.applied == 2


def test_connect_to_a_missing_port_fails_clearly(tmp_path: Any) -> None:
    with pytest.raises(hubwire.HubwireError) as e:
        hubwire.connect(str(tmp_path / "nothing"), timeout=0.5)
    assert str(e.value).startswith(f"there is no serial port {tmp_path / 'nothing'}: is the board plugged in?")


def test_health_reports_heartbeats(rover: Any) -> None:
    wait_until(lambda: rover.health().device_heartbeats >= 2, 3, "two device heartbeats")
    h = rover.health()
    assert h.device_heartbeat_ms == 250 and h.hub_heartbeat_ms == 250
    # each side's measured interval: on a fixed grid, so a late beat is followed by an early one
    wait_until(lambda: rover.health().hub_heartbeat_since_ms is not None, 3, "two hub heartbeats")
    h = rover.health()
    assert h.measured_heartbeat_ms is not None and 0 < h.measured_heartbeat_ms < 4 * 250
    assert h.hub_heartbeat_since_ms is not None and 0 < h.hub_heartbeat_since_ms < 4 * 250
    # younger than the loss timeout (4 device heartbeat intervals), or the link would not be ready
    assert h.state == "ready" and h.heartbeat_age is not None and h.heartbeat_age < 4 * 0.250
    assert h.hub_counters == {"crc": 0, "overflow": 0, "dropped": 0}
    assert h.device_counters == {"crc": 0, "overflow": 0, "dropped": 0}
