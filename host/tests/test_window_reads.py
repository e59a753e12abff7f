"""Reading a large value in windows (PROTOCOL.md 12.8) against device doubles: the whole read once,
then windows; a value that changes between windows comes back as one whole snapshot, never a mix;
windows that claim one hash for bytes of several snapshots are never handed on; a device that
predates windows (NAK BAD_LENGTH) is read whole, and asked for a window only once per boot."""
from __future__ import annotations

import pathlib
import struct
from typing import Any, Dict, List

import pytest

import hubwire
from hubwire.errors import HubwireError, Timeout
from hubwire.session.windows import WINDOW_HEADER, WindowAssembly
from hubwire.wire import messages as m
from hubwire.wire.frame import Frame

from largedevice import CHANNELS, LargeDevice

NakCode = m.NakCode


def snapshot(v: int) -> Dict[str, Any]:
    """Version ``v`` of ``big``: its first and last fields, and every byte between, say which."""
    return {"seq": v, "data": [v] * 1016, "check": v}


class WindowDevice(LargeDevice):
    """Reads of ``big`` (id 1): the whole-value try is lost on the line; windows are answered from
    the value as it is then, which moves to the next version after every ``every`` windows until
    ``last``. ``lie``: every window carries the hash of version 1, whatever its bytes."""

    def __init__(self, every: int = 3, last: int = 6, lie: bool = False, windows: bool = True) -> None:
        super().__init__()
        self.version, self.every, self.last, self.lie, self.has_windows = 1, every, last, lie, windows
        self.codec = self.desc.by_name("big").codec  # type: ignore[union-attr]
        self.wholes = 0
        self.windows: List[int] = []  # offsets asked
        self.refused = 0

    def wire(self, v: int) -> bytes:
        return self.codec.encode(self.codec.check(snapshot(v)))

    def handle(self, f: Frame) -> None:
        if f.type != m.REQUEST or f.id != 1:
            return super().handle(f)
        if not f.payload:
            self.wholes += 1
            if self.has_windows or self.wholes == 1:
                return  # lost on the line
            self.reply(m.RESPONSE, f.seq, f.id, self.wire(self.version))
            return
        if not self.has_windows:
            self.refused += 1
            self.send(m.NAK, f.seq, f.id, bytes((NakCode.BAD_LENGTH,)))
            return
        self.window(f, self.wire(self.version), m.fnv1a32(self.wire(1)) if self.lie else None)
        self.windows.append(struct.unpack_from("<H", f.payload)[0])
        if len(self.windows) % self.every == 0 and self.version < self.last:
            self.version += 1


def as_dict(v: Any) -> Dict[str, Any]:
    return {"seq": v.seq, "data": list(v.data), "check": v.check}


def test_a_value_that_changes_between_windows_is_read_as_one_snapshot(tmp_path: pathlib.Path) -> None:
    with WindowDevice() as fake, hubwire.connect(fake.path, cache_dir=tmp_path, retry_timeout=0.3) as dev:
        got = as_dict(dev.big)
        assert fake.wholes == 1 and fake.version == 6
        assert (got["seq"], got["check"], set(got["data"])) == (6, 6, {6}), \
            f"torn: seq {got['seq']}, check {got['check']}, data versions {sorted(set(got['data']))}"
        per = fake.max_payload - WINDOW_HEADER
        assert len(fake.windows) > -(-1024 // per)  # the changes cost windows asked again


def test_windows_whose_bytes_do_not_match_their_hash_are_never_handed_on(tmp_path: pathlib.Path) -> None:
    with WindowDevice(every=10, last=2, lie=True) as fake, \
            hubwire.connect(fake.path, cache_dir=tmp_path, retry_timeout=0.2) as dev:
        with pytest.raises(Timeout):
            dev.read("big", timeout=0.2)
        assert len(fake.windows) > 1024 // (fake.max_payload - WINDOW_HEADER)


def test_a_device_without_windows_is_read_whole_and_asked_once_per_boot(tmp_path: pathlib.Path) -> None:
    with WindowDevice(windows=False) as fake, hubwire.connect(fake.path, cache_dir=tmp_path, retry_timeout=0.3) as dev:
        assert as_dict(dev.big) == snapshot(1)
        assert as_dict(dev.read("big")) == snapshot(1)
        assert fake.refused == 1  # remembered: the second read went straight to whole reads
        assert fake.wholes >= 3


def test_an_assembly_keeps_only_windows_of_one_snapshot() -> None:
    a, b = bytes(range(40)), bytes(range(100, 140))

    def win(value: bytes, offset: int, n: int) -> bytes:
        return struct.pack("<HHI", offset, len(value), m.fnv1a32(value)) + value[offset:offset + n]

    asm = WindowAssembly()
    assert asm.add(0, win(a, 0, 16)) is None
    assert asm.next_offset() == 16
    assert asm.add(16, win(b, 16, 16)) is None  # the value changed: only b's window is kept
    assert asm.restarts == 1 and asm.next_offset() == 0
    assert asm.add(0, win(b, 0, 16)) is None
    assert asm.next_offset() == 32
    assert asm.add(32, win(b, 32, 16)) == b
    with pytest.raises(HubwireError):
        WindowAssembly().add(8, win(a, 0, 8))  # not the window asked for


def test_a_small_value_is_read_as_before(tmp_path: pathlib.Path) -> None:
    with WindowDevice() as fake, hubwire.connect(fake.path, cache_dir=tmp_path) as dev:
        dev.path = [1, 2, 3]
        assert dev.path == [1, 2, 3]
        assert fake.windows == [] and fake.wholes == 0


class ShrinkingDevice(LargeDevice):
    """``log``, a list of up to 200 bytes, full, shrinks to 10 bytes after the third window; the
    whole-value try is lost on the line."""

    def __init__(self) -> None:
        super().__init__(CHANNELS + [{"id": 8, "n": "log", "a": "r", "t": "u8", "vc": 200}])
        self.values[8] = bytes([200]) + bytes(range(200))
        self.windows = 0

    def handle(self, f: Frame) -> None:
        if f.type != m.REQUEST or f.id != 8 or not f.payload:
            return None if f.type == m.REQUEST and f.id == 8 else super().handle(f)
        super().handle(f)
        self.windows += 1
        if self.windows == 3:
            self.values[8] = bytes([10]) + bytes(range(100, 110))


def test_a_list_that_gets_shorter_between_windows_is_read_again(tmp_path: pathlib.Path) -> None:
    with ShrinkingDevice() as fake, hubwire.connect(fake.path, cache_dir=tmp_path, retry_timeout=0.3) as dev:
        assert dev.log == list(range(100, 110))  # window 4 asked past the new end: BAD_OFFSET, from 0 again
        assert fake.windows == 5
