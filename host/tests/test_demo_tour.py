"""`make demo`'s tour, run against the emulated Rover: every step it shows must hold."""
from __future__ import annotations

import os
import subprocess
import sys

TOUR = os.path.join(os.path.dirname(__file__), "..", "..", "tools", "demo_tour.py")


def test_tour_passes_every_step(emulator) -> None:  # type: ignore[no-untyped-def]
    r = subprocess.run([sys.executable, TOUR, emulator.link, "--pause", "0"], capture_output=True, text=True,
                       timeout=120)
    assert r.returncode == 0, r.stdout + r.stderr
    out = r.stdout
    assert "every step did what the protocol promises" in out
    # the steps a newcomer is promised, in order
    marks = ["Discovery", "Reads", "Writes with ACK", "Values refused", "events delivered exactly once",
             "A failsafe", "Link health"]
    positions = [out.index(m) for m in marks]
    assert positions == sorted(positions)
    assert out.count("  event   ->  bumper = ") == 3
    assert "InvalidValue OUT_OF_RANGE" in out
    assert "the link came back by itself, the motors stopped" in out  # failsafes counted up, left is 0


def test_tour_exits_nonzero_without_a_board(tmp_path) -> None:  # type: ignore[no-untyped-def]
    r = subprocess.run([sys.executable, TOUR, str(tmp_path / "nothing-here"), "--pause", "0"],
                       capture_output=True, text=True, timeout=60)
    assert r.returncode != 0
