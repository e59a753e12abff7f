"""A 200-byte write to the simulated Uno at 1,000,000 baud. At that speed a byte arrives every 160
AVR cycles, less than the Uno's receive path needs (its 64-byte receive ring fills during a burst of
fragments and the write is lost every time), so the hub leaves a frame's time between the fragments
it sends on a fast line (PROTOCOL.md 12.3)."""
from __future__ import annotations

import os
import subprocess
from typing import Any

import hubwire
from hubwire.testing import tapped

from .conftest import REPO, Simuno
from .test_large_values_on_uno import as_json, profile

BAUD = 1_000_000


def build_at(baud: int, tmp_path: Any) -> str:
    """examples/LargeValues with Serial.begin(baud), built for the Uno; the ELF's path."""
    src = open(os.path.join(REPO, "examples", "LargeValues", "LargeValues.ino")).read()
    assert "Serial.begin(115200);" in src
    d = tmp_path / "LargeFast"
    d.mkdir()
    (d / "LargeFast.ino").write_text(src.replace("Serial.begin(115200);", f"Serial.begin({baud}UL);"))
    out = tmp_path / "build"
    subprocess.run(["bash", os.path.join(REPO, "tools", "arduino", "build-sketch.sh"), str(d), "arduino:avr:uno",
                    str(out)], check=True, stdout=subprocess.DEVNULL, cwd=REPO)
    return str(out / "LargeFast.ino.elf")


def test_a_200_byte_write_at_1_mbaud_is_applied_once(simuno_build: tuple, tmp_path: Any) -> None:
    sim = Simuno(simuno_build[0], build_at(BAUD, tmp_path), str(tmp_path / "link"), str(tmp_path / "sim.log"))
    sim.start()
    dev = hubwire.connect(transport=tapped(sim.link, BAUD))
    try:
        for n in (1, 2, 3):
            dev.profile = profile(n)  # 8 fragments; lost whole, and retried, if sent back to back
            assert dev.profile_writes == n  # applied exactly once each
            assert as_json(dev.profile) == profile(n)
    finally:
        dev.close()
        assert sim.stop() == 0, sim.log_text()
