"""`make demo` and `make uno-firmware` build only what changed: each Uno sketch is a make target
depending on its example's files and the library's sources (checked with make's dry run on stand-in
outputs in a private build folder, so that nothing is compiled here), and the demo needs Rover only."""
from __future__ import annotations

import os
import subprocess
import time
from typing import Any, List

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
EXAMPLES = sorted(d for d in os.listdir(os.path.join(ROOT, "examples"))
                  if os.path.isfile(os.path.join(ROOT, "examples", d, d + ".ino")))


def make(build: str, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run(["make", "--no-print-directory", "-C", ROOT, f"BUILD={build}", *args],
                          capture_output=True, text=True, timeout=60)


def outputs(build: str) -> List[str]:
    elfs = [os.path.join(build, "uno", e, f"{e}.ino.elf") for e in EXAMPLES]
    return elfs + [os.path.join(build, "uno", "MinimalBoardId", "Minimal.ino.elf")]


def stand_ins(build: str) -> None:
    """Every firmware present and newer than every source, as after a build."""
    later = time.time() + 3600
    for path in outputs(build):
        os.makedirs(os.path.dirname(path), exist_ok=True)
        open(path, "w").close()
        os.utime(path, (later, later))


def builds(dry_run: str) -> List[str]:
    return [ln for ln in dry_run.splitlines() if "build-sketch.sh" in ln]


def test_nothing_is_rebuilt_when_nothing_changed(tmp_path: Any) -> None:
    build = str(tmp_path / "build")
    assert len(EXAMPLES) >= 8
    assert len(builds(make(build, "-n", "uno-firmware").stdout)) == len(EXAMPLES) + 1  # nothing built yet
    stand_ins(build)
    r = make(build, "-q", "uno-firmware")
    assert r.returncode == 0, make(build, "-n", "uno-firmware").stdout  # up to date
    assert builds(make(build, "-n", "uno-firmware").stdout) == []


def test_a_changed_sketch_rebuilds_only_itself(tmp_path: Any) -> None:
    build = str(tmp_path / "build")
    stand_ins(build)
    old = os.path.join(build, "uno", "Thermostat", "Thermostat.ino.elf")
    os.utime(old, (0, 0))  # older than its sources, as after editing the sketch
    todo = builds(make(build, "-n", "uno-firmware").stdout)
    assert len(todo) == 1 and "examples/Thermostat " in todo[0], todo


def test_the_demo_builds_rover_only_and_says_so(tmp_path: Any) -> None:
    build = str(tmp_path / "build")
    out = make(build, "-n", "demo").stdout
    todo = builds(out)
    assert len(todo) == 1 and "examples/Rover " in todo[0], todo
    assert "building examples/Rover for the Uno" in out  # progress before the quiet compile
