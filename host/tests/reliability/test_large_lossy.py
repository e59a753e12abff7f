"""A 1 KB write through a line that drops bytes (PROTOCOL.md 12.4), against the device library in the
emulator (extras/tests/Large1K: 38 fragments of 27 bytes). Each try of a large control carries on
where the one before it left off, so the write needs tries in proportion to the fragments lost; it
used to need one try with all 38 fragments whole, which at 0.5 % byte drops almost never came
(0 of 10 writes). The board's own checksum of what it applied proves the value whole."""
from __future__ import annotations

import os
import random
import struct
from typing import Any, Dict

import pytest

import hubwire
from hubwire.errors import HubwireError
from hubwire.testing import emulator_binary
from hubwire.testing.faultlink import Faults, FaultyTransport, stop_process
from hubwire.testing.faultlink.soak import start_emulator
from hubwire.transport import SerialTransport


def _fnv(data: bytes) -> int:
    h = 2166136261
    for b in data:
        h = ((h ^ b) * 16777619) & 0xFFFFFFFF
    return h


def _value(rng: random.Random) -> Dict[str, Any]:
    f = [struct.unpack("<f", struct.pack("<f", rng.uniform(-1e3, 1e3)))[0] for _ in range(56)]
    return {"words": [rng.getrandbits(32) for _ in range(200)], "f": f}


def _wire(v: Dict[str, Any]) -> bytes:
    return struct.pack("<200I", *v["words"]) + struct.pack("<56f", *v["f"])


def _read(dev: Any, name: str) -> Any:
    """A small value, read again until a read gets through the lossy line."""
    for _ in range(50):
        try:
            return dev.read(name)
        except HubwireError:
            continue
    raise AssertionError(f"{name} could not be read in 50 tries")


@pytest.mark.parametrize("drop", [0.005, 0.01])
def test_a_kilobyte_write_gets_through_a_lossy_line(tmp_path: Any, drop: float) -> None:
    binary = os.path.join(os.path.dirname(emulator_binary()), "hubwire-large-emulator")
    if not os.access(binary, os.X_OK):
        pytest.fail(f"{binary} missing: build it with `make emulator`", pytrace=False)
    rng = random.Random(7)
    emu = start_emulator(binary, str(tmp_path / "large"))
    try:
        faulty = FaultyTransport(SerialTransport(str(tmp_path / "large")), seed=3, both=Faults(drop=drop))
        with hubwire.connect(transport=faulty, cache_dir=False, timeout=30) as dev:
            for _ in range(3):
                v = _value(rng)
                dev.write("big", v)  # raises Timeout if the tries run out
                assert _read(dev, "checksum") == _fnv(_wire(v))
            assert _read(dev, "big_writes") == 3  # each write applied once, none twice
            assert faulty.stats()["h2d"]["bytes_dropped"] > 100  # the line really lost bytes
    finally:
        stop_process(emu)
