"""The Tight firmware (exact Minimal descriptor) and TightS (blink_ms also streamable) on the
repo's simulated Uno, driven by the real Python hub.

    bash bench/lowerbound/run.sh      (builds both, prints their size, runs this file)

ELFs: $TIGHT_ELF (default build/lowerbound/Tight/Tight.ino.elf), $TIGHTS_ELF (default
build/lowerbound/TightS/Tight.ino.elf); the simulator: $HUBWIRE_SIMUNO (default build/simuno/simuno).
"""
from __future__ import annotations

import os
import selectors
import signal
import statistics
import subprocess
import threading
import time

import pytest

import hubwire
from hubwire.errors import InvalidValue, NakError
from hubwire.testing import tap_of, tapped
from hubwire.wire import messages as m
from hubwire.wire.frame import decode_frame
from hubwire.wire.messages import NakCode

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
SIMUNO = os.environ.get("HUBWIRE_SIMUNO", os.path.join(ROOT, "build/simuno/simuno"))
TIGHT_ELF = os.environ.get("TIGHT_ELF", os.path.join(ROOT, "build/lowerbound/Tight/Tight.ino.elf"))
TIGHTS_ELF = os.environ.get("TIGHTS_ELF", os.path.join(ROOT, "build/lowerbound/TightS/Tight.ino.elf"))
REFERENCE = open(os.path.join(HERE, "minimal_descriptor.json"), "rb").read()  # served by the real library

MINIMAL = [
    ("blink_ms", "rw", "u16", "ms", 50, 5000, None),
    ("led", "w", "bool", None, None, None, None),
    ("button", "e", "u8", None, None, None, None),
]


class Sim:
    def __init__(self, elf: str, link: str, log: str) -> None:
        self.proc = None
        self.link = link
        err = open(log, "ab")
        self.proc = subprocess.Popen([SIMUNO, elf, "--link", link, "--boot-delay", "1000", "--reset-on-open"],
                                     stdout=subprocess.PIPE, stderr=err, stdin=subprocess.DEVNULL)
        sel = selectors.DefaultSelector()
        sel.register(self.proc.stdout, selectors.EVENT_READ)
        assert sel.select(10), "simuno did not start"
        assert self.proc.stdout.readline().decode().strip() == f"READY {link}"

    def press(self) -> None:  # toggles pin 2 (pressed / released)
        self.proc.send_signal(signal.SIGUSR2)

    def stop(self) -> None:
        self.proc.send_signal(signal.SIGTERM)
        self.proc.wait(5)


@pytest.fixture(autouse=True)
def cache(tmp_path, monkeypatch):
    d = tmp_path / "cache"
    d.mkdir()
    monkeypatch.setenv("HUBWIRE_CACHE_DIR", str(d))
    return d


def start(tmp_path, elf):
    assert os.path.isfile(elf), elf
    sim = Sim(elf, str(tmp_path / "uno"), str(tmp_path / "simuno.log"))
    dev = hubwire.connect(transport=tapped(sim.link))
    return sim, dev


@pytest.fixture
def tight(tmp_path):
    sim, dev = start(tmp_path, TIGHT_ELF)
    yield sim, dev
    dev.close()
    sim.stop()


@pytest.fixture
def tights(tmp_path):
    sim, dev = start(tmp_path, TIGHTS_ELF)
    yield sim, dev
    dev.close()
    sim.stop()


def recorder(dev):
    got = []
    tap_of(dev).rx_filter = lambda f: (got.append(f), True)[1]
    return got


def test_discovery_is_byte_identical_to_the_library(tight, cache):
    sim, dev = tight
    assert dev.descriptor.name == "minimal"
    got = [(c.name, c.access, c.type_name, c.unit, c.min, c.max, c.failsafe) for c in dev.descriptor.channels]
    assert got == MINIMAL
    assert [c.id for c in dev.descriptor.channels] == [1, 2, 3]
    files = os.listdir(cache)
    assert files == ["%08x-%d.json" % (m.fnv1a32(REFERENCE), len(REFERENCE))]
    assert open(os.path.join(cache, files[0]), "rb").read() == REFERENCE
    h = dev.session.device_hello
    assert (h.version, h.max_payload, h.heartbeat_ms) == (1, 32, 250)
    assert h.nonce != 0


def test_read_write_range_and_led(tight):
    sim, dev = tight
    assert dev.blink_ms == 500
    dev.blink_ms = 100
    assert dev.blink_ms == 100
    with pytest.raises(InvalidValue):
        dev.blink_ms = 10  # the hub refuses it itself
    s = dev.session
    for payload in ((10).to_bytes(2, "little"), (49).to_bytes(2, "little"), (5001).to_bytes(2, "little")):
        with pytest.raises(NakError) as e:  # past the hub: the device checks the range
            s.control(1, payload)
        assert e.value.code == NakCode.OUT_OF_RANGE
    s.control(1, (50).to_bytes(2, "little"))
    s.control(1, (5000).to_bytes(2, "little"))
    assert dev.blink_ms == 5000
    dev.blink_ms = 100
    dev.led = False
    dev.led = True
    dev.led = False


def test_every_nak_code_that_can_arise(tight):
    sim, dev = tight
    s = dev.session

    def nak(fn):
        with pytest.raises(NakError) as e:
            fn()
        return e.value.code

    assert nak(lambda: s.control(1, b"\x64")) == NakCode.BAD_LENGTH
    assert nak(lambda: s.control(2, b"\x02")) == NakCode.BAD_VALUE
    assert nak(lambda: s.control(2, b"")) == NakCode.BAD_LENGTH
    assert nak(lambda: s.control(3, b"\x01")) == NakCode.NOT_WRITABLE
    assert nak(lambda: s.control(9, b"")) == NakCode.UNKNOWN_CHANNEL
    assert nak(lambda: s.control(0, b"")) == NakCode.UNKNOWN_CHANNEL
    assert nak(lambda: s.request(2)) == NakCode.NOT_READABLE
    assert nak(lambda: s.request(3)) == NakCode.NOT_READABLE
    assert nak(lambda: s.request(4)) == NakCode.UNKNOWN_CHANNEL
    assert nak(lambda: s.transact(m.REQUEST, 1, b"x")) == NakCode.BAD_LENGTH
    assert nak(lambda: s.subscribe(1, 50)) == NakCode.NOT_STREAMABLE  # Minimal: blink_ms is "rw"
    assert nak(lambda: s.subscribe(3, 50)) == NakCode.NOT_STREAMABLE
    assert nak(lambda: s.subscribe(7, 50)) == NakCode.UNKNOWN_CHANNEL
    n = len(REFERENCE)
    assert nak(lambda: s.transact(m.CHUNK, 0, (n + 1).to_bytes(2, "little") + b"\x10")) == NakCode.BAD_OFFSET
    assert nak(lambda: s.transact(m.CHUNK, 0, b"\x00\x00")) == NakCode.BAD_LENGTH
    a = s.transact(m.CHUNK, 0, n.to_bytes(2, "little") + b"\x10")
    assert a.payload == n.to_bytes(2, "little") + n.to_bytes(2, "little")  # offset == total: empty
    a = s.transact(m.CHUNK, 0, b"\x05\x00\x00")  # want 0: empty
    assert a.payload == b"\x05\x00" + n.to_bytes(2, "little")
    a = s.transact(m.CHUNK, 0, b"\x0a\x00\xff")  # capped at 32 - 4
    assert a.payload[4:] == REFERENCE[10:38]
    # An unknown type: NAK UNKNOWN_TYPE with its seq/id, counted as dropped in the next heartbeat.
    got = recorder(dev)
    before = dev.health().device_counters["dropped"]
    s._send_frame(0x5A, 77, 5, b"")
    s._send_frame(m.RESPONSE, 78, 5, b"")  # a type only ever sent the other way
    time.sleep(0.6)
    naks = [(f.seq, f.id, f.payload) for f in got if f.type == m.NAK]
    assert (77, 5, bytes([NakCode.UNKNOWN_TYPE])) in naks and (78, 5, bytes([NakCode.UNKNOWN_TYPE])) in naks
    assert dev.health().device_counters["dropped"] == before + 2
    # A hello that is too short: NAK BAD_LENGTH, dropped.
    s._send_frame(m.HELLO, 0, 0, b"\x01\x00")
    time.sleep(0.6)
    assert (0, 0, bytes([NakCode.BAD_LENGTH])) in [(f.seq, f.id, f.payload) for f in got if f.type == m.NAK]
    assert dev.health().device_counters["dropped"] == before + 3
    # A bad CRC and garbage are counted too.
    assert m.fnv1a32(b"") and __import__("binascii").crc_hqx(b"\x52\xc8\x01", 0xFFFF) != 0x3412
    s._write(b"\x00\x06\x52\xc8\x01\x12\x34\x00")
    time.sleep(0.6)
    assert dev.health().device_counters["crc"] >= 1
    assert dev.blink_ms == 500


def test_duplicate_control_is_answered_not_applied(tight):
    sim, dev = tight
    s = dev.session
    got = recorder(dev)
    s.control(1, (200).to_bytes(2, "little"))
    seq = s._seq
    s._send_frame(m.CONTROL, seq, 1, (300).to_bytes(2, "little"))  # same seq and id: a retry
    time.sleep(0.3)
    acks = [f for f in got if f.type == m.ACK and f.seq == seq and f.id == 1]
    assert len(acks) == 2  # answered again
    assert dev.blink_ms == 200  # but not applied
    # A remembered NAK is replayed too.
    with pytest.raises(NakError):
        s.control(1, (10).to_bytes(2, "little"))
    seq = s._seq
    s._send_frame(m.CONTROL, seq, 1, (400).to_bytes(2, "little"))
    time.sleep(0.3)
    naks = [f for f in got if f.type == m.NAK and f.seq == seq and f.id == 1]
    assert [f.payload for f in naks] == [bytes([NakCode.OUT_OF_RANGE])] * 2
    assert dev.blink_ms == 200
    # After another transaction (the read above) the same seq is a new control.
    s._send_frame(m.CONTROL, seq, 1, (400).to_bytes(2, "little"))
    time.sleep(0.3)
    assert dev.blink_ms == 400


def test_button_event_exactly_once_per_press(tight):
    sim, dev = tight
    with dev.events("button") as evs:
        for press in (1, 2, 3):
            sim.press()
            ev = evs.get(3.0)
            assert ev is not None and ev.value == press
            sim.press()  # released
            assert evs.get(0.5) is None


def test_event_retried_with_same_seq_until_acked(tight):
    sim, dev = tight
    s = dev.session
    got = recorder(dev)
    dropped = []

    def drop_two_event_acks(wire):
        f = decode_frame(wire[:-1] if wire[:1] != b"\x00" else wire[1:-1])
        if f is not None and f.type == m.ACK and f.id == 3 and len(dropped) < 2:
            dropped.append(f.seq)
            return False
        return True

    tap_of(s).tx_filter = drop_two_event_acks
    with dev.events("button") as evs:
        sim.press()
        ev = evs.get(3.0)
        assert ev is not None and ev.value == 1
        time.sleep(0.8)
        assert evs.get(0.2) is None  # delivered once
    sim.press()
    evframes = [f for f in got if f.type == m.EVENT]
    assert len(evframes) == 3 and len({f.seq for f in evframes}) == 1
    assert s.stats.duplicate_events == 2
    assert len(dropped) == 2


def test_link_loss_relink_and_queued_event(tight):
    sim, dev = tight
    s = dev.session
    lost, restored = threading.Event(), threading.Event()
    dev.on("link_lost", lost.set)
    dev.on("link_restored", restored.set)
    hb = dev.health()
    assert hb.device_heartbeat_ms == 250
    n0 = hb.device_heartbeats
    time.sleep(1.0)
    assert 3 <= dev.health().device_heartbeats - n0 <= 5  # every 250 ms
    with dev.events("button") as evs:
        tap_of(s).paused = True  # the hub goes silent: the device must drop the link after 4 x 250 ms
        try:
            assert lost.wait(3.0), "the device never dropped the link"
            sim.press()  # emitted while unlinked: queued
            time.sleep(0.3)
            sim.press()
        finally:
            tap_of(s).paused = False
        assert restored.wait(5.0)
        ev = evs.get(3.0)
        assert ev is not None and ev.value == 1
        assert evs.get(0.6) is None
    assert dev.blink_ms == 500


def test_stream_blink_ms_at_20_hz(tights):
    sim, dev = tights
    assert dev.channel("blink_ms").access == "rws"
    dev.blink_ms = 120
    hz = 20
    with dev.stream("blink_ms", hz=hz, meta=True) as st:
        assert st.granted_ms == 50
        time.sleep(1.5)
        samples = []
        while True:
            x = st.get(0)
            if x is None:
                break
            samples.append(x)
    assert len(samples) >= 0.9 * hz * 1.5 - 2, len(samples)
    since = [x.since_ms for x in samples[1:]]
    assert statistics.mean(since) == pytest.approx(50, rel=0.1), since
    assert all(x.value == 120 for x in samples)
    s = dev.session
    assert s.subscribe(1, 1) == 10  # raised to the minimum
    assert s.subscribe(1, 65000) == 60000  # capped
    assert s.subscribe(1, 0) == 0
    with pytest.raises(NakError) as e:
        s.transact(m.SUBSCRIBE, 1, b"\x01")
    assert e.value.code == NakCode.BAD_LENGTH


def test_stream_ends_on_link_loss(tights):
    sim, dev = tights
    s = dev.session
    got = recorder(dev)
    assert s.subscribe(1, 20) == 20
    time.sleep(0.3)
    assert any(f.type == m.SAMPLE for f in got)
    lost = threading.Event()
    dev.on("link_lost", lost.set)
    tap_of(s).paused = True
    try:
        assert lost.wait(3.0)
    finally:
        tap_of(s).paused = False
    time.sleep(1.5)
    got.clear()
    time.sleep(0.5)
    assert not any(f.type == m.SAMPLE for f in got)
