"""Hub session paths the emulator cannot reach, against a scripted device on a pty."""
from __future__ import annotations

import os
from typing import Any, List

import pytest
import serial.tools.list_ports

import hubwire
from hubwire import device as devmod
from hubwire.errors import DescriptorError, NoDeviceFound, ProtocolVersionError, Timeout
from hubwire.wire import messages as m
from hubwire.wire.frame import FrameDecoder

from fakedevice import DESCRIPTOR, FakeDevice


def test_fake_device_works(cache_dir: str) -> None:
    with FakeDevice() as fake, hubwire.connect(fake.path, cache_dir=cache_dir) as dev:
        assert dev.descriptor.raw == DESCRIPTOR
        dev.x = 513
        assert dev.x == 513 and fake.x == 513


def test_boot_noise_is_counted_not_fatal(cache_dir: str) -> None:
    noise = b"\r\nbootloader v1.2\r\n\x00\xff\xfe garbage \x00\x00" + b"\x41" * 600 + b"\x00"
    with FakeDevice(noise=noise) as fake, hubwire.connect(fake.path, cache_dir=cache_dir) as dev:
        c = dev.health().hub_counters
        assert c["dropped"] + c["crc"] + c["overflow"] >= 3 and c["overflow"] >= 1
        assert dev.state == "ready"


def test_protocol_version_mismatch_names_both_versions(cache_dir: str) -> None:
    with FakeDevice(version=2) as fake:
        with pytest.raises(ProtocolVersionError) as e:
            hubwire.connect(fake.path, cache_dir=cache_dir, timeout=2)
    assert e.value.device_version == 2 and e.value.hub_version == 1
    assert "version 2" in str(e.value) and "version 1" in str(e.value)


def test_descriptor_hash_mismatch_is_an_error(cache_dir: str) -> None:
    with FakeDevice(announced_hash=0xDEADBEEF) as fake:
        with pytest.raises(DescriptorError) as e:
            hubwire.connect(fake.path, cache_dir=cache_dir, timeout=2)
        assert all(n == 3 for n in fake.chunk_requests.values())  # downloaded again, three times in all
    assert "hash mismatch" in str(e.value) and "deadbeef" in str(e.value)
    assert os.listdir(cache_dir) == []  # nothing cached


def test_invalid_descriptor_is_rejected(cache_dir: str) -> None:
    bad = b'{"p":1,"n":"fake","ch":[{"id":1,"n":"x","a":"rq","t":"u16"}]}'
    with FakeDevice(bad) as fake:
        with pytest.raises(DescriptorError) as e:
            hubwire.connect(fake.path, cache_dir=cache_dir, timeout=2)
    assert "unknown access letter" in str(e.value)


def test_lost_chunks_are_asked_again(cache_dir: str) -> None:
    # every chunk's first answer is lost; several requests are in flight at once
    with FakeDevice(drop_chunk=lambda off, nth: nth == 0) as fake:
        with hubwire.connect(fake.path, cache_dir=cache_dir) as dev:
            assert dev.descriptor.raw == DESCRIPTOR
            stats = dev.session.stats.as_dict()
        assert len(fake.chunk_requests) == -(-len(DESCRIPTOR) // 28)
        # each chunk was asked again after its first answer was lost (more often only when a busy
        # machine delayed an answer past the retry timeout: retries are idempotent)
        assert all(n >= 2 for n in fake.chunk_requests.values())
    assert stats["retries"] >= len(fake.chunk_requests)


def test_progress_reports_the_download(cache_dir: str) -> None:
    seen: List[Any] = []
    with FakeDevice() as fake, hubwire.connect(fake.path, cache_dir=cache_dir, progress=lambda a, b: seen.append((a, b))):
        pass
    assert seen[-1] == (len(DESCRIPTOR), len(DESCRIPTOR))
    assert [a for a, _ in seen] == sorted(a for a, _ in seen)


def test_connect_timeout_when_nothing_answers(tmp_path: Any) -> None:
    master, slave = os.openpty()
    try:
        os.write(master, b"noise\x00")
        with pytest.raises(Timeout) as e:
            hubwire.connect(os.ttyname(slave), timeout=0.5)
        assert os.ttyname(slave) in str(e.value) and "0.5 s" in str(e.value)
        sent = FrameDecoder().feed(os.read(master, 4096))
        hellos = [f for f in sent if f.type == m.HELLO]
        assert len(hellos) == len(sent) and 3 <= len(hellos) <= 8  # one hello every 100 ms
        h = m.Hello.unpack(hellos[0].payload)
        assert (h.version, h.flags, h.max_payload, h.heartbeat_ms) == (1, m.FLAG_SEQ_RULES, 255, 250) and h.nonce != 0
    finally:
        os.close(master)
        os.close(slave)


class FakePort:
    def __init__(self, device: str, vid: Any, pid: Any, description: str = "") -> None:
        self.device, self.vid, self.pid, self.description = device, vid, pid, description


def test_find_port(monkeypatch: Any) -> None:
    monkeypatch.setattr(serial.tools.list_ports, "comports",
                        lambda: [FakePort("/dev/ttyS0", None, None), FakePort("/dev/ttyACM0", 0x2341, 0x0043, "Uno")])
    assert devmod.find_port() == "/dev/ttyACM0"
    monkeypatch.setattr(serial.tools.list_ports, "comports", lambda: [FakePort("/dev/ttyS0", None, None)])
    with pytest.raises(NoDeviceFound) as e:
        devmod.find_port()
    assert "/dev/ttyS0" in str(e.value) and "2341" in str(e.value)
    monkeypatch.setattr(serial.tools.list_ports, "comports",
                        lambda: [FakePort("/dev/ttyUSB0", 0x1A86, 0x7523), FakePort("/dev/ttyACM1", 0x2E8A, 0x000A)])
    with pytest.raises(NoDeviceFound) as e:
        hubwire.connect()
    assert "2 boards" in str(e.value) and "/dev/ttyUSB0" in str(e.value) and "/dev/ttyACM1" in str(e.value)


def test_same_nonce_but_new_descriptor_is_a_reboot(cache_dir: str) -> None:
    import threading

    new = DESCRIPTOR.replace(b'"n":"x"', b'"n":"y"')
    with FakeDevice() as fake, hubwire.connect(fake.path, cache_dir=cache_dir) as dev:
        done = threading.Event()
        dev.on("reconnect", lambda d: done.set())
        assert "x" in dev and "y" not in dev
        fake.reflash(new)
        assert done.wait(5)
        assert "y" in dev and "x" not in dev
        assert dev.session.stats.reboots == 1 and dev.session.stats.downloads == 2
        dev.y = 7
        assert dev.y == 7


def test_descriptor_over_the_cap_is_refused_from_the_hello(cache_dir: str) -> None:
    big = b'{"p":1,"n":"big","ch":[],"x":"' + b"y" * 20000 + b'"}'
    with FakeDevice(big) as fake:
        with pytest.raises(DescriptorError) as e:
            hubwire.connect(fake.path, cache_dir=cache_dir, timeout=2)
        assert fake.chunk_requests == {}  # nothing downloaded
    assert "20032 bytes" in str(e.value) and "16384" in str(e.value)


def test_connect_deadline_holds_when_the_descriptor_never_comes(cache_dir: str) -> None:
    import time

    with FakeDevice(drop_chunk=lambda off, nth: True) as fake:
        t = time.monotonic()
        with pytest.raises(Timeout) as e:
            hubwire.connect(fake.path, cache_dir=cache_dir, timeout=0.5, retry_timeout=0.5, tries=10)
        took = time.monotonic() - t
        assert fake.chunk_requests  # it was asked
    assert took < 2.0 and "descriptor did not arrive" in str(e.value)
