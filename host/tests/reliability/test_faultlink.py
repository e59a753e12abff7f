"""The proxy itself: transparent when clean, faults as configured and counted, stall holds bytes,
survives the device side disappearing."""
from __future__ import annotations

import os
import select
import time
import tty
from typing import Any, List

from hubwire.wire.frame import FrameDecoder, encode_frame

from .conftest import FaultLink, Faults, settle


class Pair:
    """A fake device pty (we hold the master) and the hub side opened on the proxy's link."""

    def __init__(self, tmp_path: Any, **kw: Any) -> None:
        self.dev_master, dev_slave = os.openpty()
        tty.setraw(dev_slave)
        self.dev_path = str(tmp_path / "dev")
        os.symlink(os.ttyname(dev_slave), self.dev_path)
        self._dev_slave = dev_slave
        self.fl = FaultLink(self.dev_path, str(tmp_path / "hub"), **kw).start()
        self.hub = os.open(self.fl.link, os.O_RDWR | os.O_NOCTTY)
        tty.setraw(self.hub)

    def close(self) -> None:
        self.fl.stop()
        for fd in (self.hub, self.dev_master, self._dev_slave):
            os.close(fd)


def read_all(fd: int, quiet: float = 0.3) -> bytes:
    out = b""
    while True:
        r, _, _ = select.select([fd], [], [], quiet)
        if not r:
            return out
        out += os.read(fd, 65536)


def frames(n: int) -> List[bytes]:
    return [encode_frame(0x43, i & 0xFF, 1, bytes(range(i % 20))) for i in range(n)]


def test_clean_link_is_transparent_both_ways(tmp_path: Any) -> None:
    p = Pair(tmp_path)
    try:
        data = b"".join(frames(200))
        os.write(p.hub, data)
        assert read_all(p.dev_master) == data
        os.write(p.dev_master, data)
        assert read_all(p.hub) == data
        s = p.fl.stats()
        assert s["h2d"]["frames"] == s["d2h"]["frames"] == 200 and s["faults"] == 0
    finally:
        p.close()


def test_faults_are_injected_and_counted(tmp_path: Any) -> None:
    p = Pair(tmp_path, seed=3, hub_to_device=Faults(dup=0.2, truncate=0.1, drop=0.01, ber=1e-3))
    try:
        sent = frames(500)
        for i in range(0, 500, 50):
            os.write(p.hub, b"".join(sent[i:i + 50]))
            time.sleep(0.01)
        got = read_all(p.dev_master)
        s = p.fl.stats()["h2d"]
        assert s["frames"] == 500
        assert s["frames_duplicated"] > 50 and s["frames_truncated"] > 20
        assert s["bytes_dropped"] > 0 and s["bits_flipped"] > 0
        assert s["bytes_out"] == len(got)
        dec = FrameDecoder()
        valid = dec.feed(got)
        assert len(valid) < 500 + s["frames_duplicated"]
        assert dec.crc + dec.dropped > 0
    finally:
        p.close()


def test_garbage_delay_and_stall(tmp_path: Any) -> None:
    p = Pair(tmp_path, device_to_hub=Faults(garbage_every=0.1, garbage_len=(4, 4), delay=0.2))
    try:
        t = time.monotonic()
        os.write(p.dev_master, encode_frame(0x48, 0, 0, b"x"))
        r, _, _ = select.select([p.hub], [], [], 2)
        assert r and time.monotonic() - t >= 0.15  # delayed
        time.sleep(0.5)
        assert p.fl.stats()["d2h"]["garbage_bursts"] >= 3
        p.fl.set_faults("d2h", garbage_every=0.0, delay=0.0)
        read_all(p.hub, 0.2)
        p.fl.stall(600, "h2d")
        t = time.monotonic()
        os.write(p.hub, b"\x05hello\x00")
        r, _, _ = select.select([p.dev_master], [], [], 3)
        assert r and time.monotonic() - t >= 0.5  # held during the stall, then delivered
        assert read_all(p.dev_master) == b"\x05hello\x00"
    finally:
        p.close()


def test_device_side_disappears_and_comes_back(tmp_path: Any) -> None:
    p = Pair(tmp_path)
    try:
        os.close(p.dev_master)  # the device's pty goes away: the proxy sees EIO
        os.unlink(p.dev_path)
        assert settle(lambda: p.fl.stats()["device_losses"] == 1, 3)
        m2, s2 = os.openpty()
        tty.setraw(s2)
        os.symlink(os.ttyname(s2), p.dev_path)
        assert settle(lambda: p.fl.stats()["device_opens"] == 2, 3)
        os.write(p.hub, b"\x02a\x00")
        assert read_all(m2) == b"\x02a\x00"
        p.dev_master = m2
        os.close(p._dev_slave)
        p._dev_slave = s2
    finally:
        p.close()


# ----------------------------------------------------------------- faultlink as a transport

class TransportPair:
    """A fake device pty (we hold the master) and a FaultyTransport over its slave, on a private loop."""

    def __init__(self, **kw: Any) -> None:
        import asyncio

        from hubwire.testing.faultlink import FaultyTransport
        from hubwire.transport import SerialTransport

        self.master, slave = os.openpty()
        tty.setraw(slave)
        self._slave = slave
        self.loop = asyncio.new_event_loop()
        self.got = bytearray()
        self.t = FaultyTransport(SerialTransport(os.ttyname(slave)), **kw)
        self.t.open(self.loop, self.got.extend, lambda e: None)

    def run(self, seconds: float) -> None:
        self.loop.run_until_complete(__import__("asyncio").sleep(seconds))

    def write(self, data: bytes) -> None:
        self.loop.call_soon(self.t.write, data)

    def close(self) -> None:
        self.t.close()
        self.loop.close()
        os.close(self.master)
        os.close(self._slave)


def test_transport_is_transparent_when_clean() -> None:
    p = TransportPair()
    try:
        data = b"".join(frames(100))
        os.write(p.master, data)
        p.write(data)
        p.run(0.3)
        assert bytes(p.got) == data  # device to hub
        assert read_all(p.master) == data  # hub to device
        s = p.t.stats()
        assert s["h2d"]["frames"] == s["d2h"]["frames"] == 100 and s["faults"] == 0
    finally:
        p.close()


def test_transport_injects_and_counts_faults() -> None:
    p = TransportPair(seed=3, both=Faults(drop=0.05, dup=0.05))
    try:
        data = b"".join(frames(400))
        os.write(p.master, data)
        p.run(0.5)
        s = p.t.stats()["d2h"]
        assert s["bytes_dropped"] > 0 and s["frames_duplicated"] > 0
        assert s["bytes_in"] == len(data) and len(p.got) == s["bytes_out"]
        decoded = FrameDecoder(255).feed(bytes(p.got))
        assert 0 < len(decoded) < 400 + s["frames_duplicated"] + 1
    finally:
        p.close()


def test_transport_stall_holds_bytes_then_delivers_them() -> None:
    p = TransportPair()
    try:
        t0 = time.monotonic()
        p.t.stall(2000)
        p.run(0.01)
        data = b"".join(frames(10))
        os.write(p.master, data)
        p.run(0.2)
        assert bytes(p.got) == b""  # held (the stall has 1.8 s to go)
        while len(p.got) < len(data) and time.monotonic() - t0 < 10:
            p.run(0.05)
        assert time.monotonic() - t0 >= 2.0  # not before the stall ended
        assert bytes(p.got) == data and p.t.stats()["d2h"]["stalls"] == 1
    finally:
        p.close()
