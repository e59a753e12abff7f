"""Helpers shared by the bench scripts: paths, child processes on a pty, result files."""
from __future__ import annotations

import json
import os
import signal
import subprocess
import tempfile
import time
from typing import Any, Dict, List, Optional

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BUILD = os.path.join(ROOT, "build")
OUT = os.path.join(BUILD, "bench")
RESULTS = os.path.join(OUT, "results")
SIMUNO = os.path.join(BUILD, "simuno", "simuno")
EMULATOR = os.path.join(BUILD, "emulator", "hubwire-emulator")


def build_sketch(sketch_dir: str, build_dir: str, extra_flags: str = "") -> str:
    """Compile a sketch for the Uno with tools/arduino/build-sketch.sh; returns the ELF path."""
    env = dict(os.environ)
    if extra_flags:
        env["EXTRA_FLAGS"] = extra_flags
    subprocess.run(["bash", os.path.join(ROOT, "tools/arduino/build-sketch.sh"), sketch_dir, "arduino:avr:uno",
                    build_dir], check=True, stdout=subprocess.DEVNULL, env=env, cwd=ROOT)
    return os.path.join(build_dir, os.path.basename(os.path.normpath(sketch_dir)) + ".ino.elf")


class Child:
    """A simuno or emulator process that prints ``READY PATH``; stopped with SIGTERM."""

    def __init__(self, argv: List[str], link: str, timeout: float = 20.0) -> None:
        self.link = link
        self.err = tempfile.TemporaryFile()
        self.proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=self.err, cwd=ROOT)
        deadline = time.monotonic() + timeout
        line = b""
        while time.monotonic() < deadline:
            line = self.proc.stdout.readline()  # type: ignore[union-attr]
            if line.startswith(b"READY") or not line:
                break
        if not line.startswith(b"READY"):
            self.stop()
            raise RuntimeError(f"{argv[0]} did not become ready: {line!r}")

    def signal(self, sig: int) -> None:
        self.proc.send_signal(sig)

    def stop(self) -> None:
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.proc.wait(5)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()

    def __enter__(self) -> "Child":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.stop()


def simuno(elf: str, link: str, *extra: str) -> Child:
    return Child([SIMUNO, elf, "--link", link, *extra], link)


def emulator(link: str) -> Child:
    return Child([EMULATOR, "--link", link], link)


def tmp_link(name: str) -> str:
    d = os.path.join(tempfile.gettempdir(), f"hubwire-bench-{os.getpid()}")
    os.makedirs(d, exist_ok=True)
    return os.path.join(d, name)


def save(name: str, rows: List[Dict[str, Any]], details: str, extra: Optional[Dict[str, Any]] = None) -> None:
    """Write build/bench/results/NAME.json: table rows plus a markdown details section."""
    os.makedirs(RESULTS, exist_ok=True)
    with open(os.path.join(RESULTS, name + ".json"), "w") as f:
        json.dump({"rows": rows, "details": details, "extra": extra or {}}, f, indent=1)
    print(details)


def row(item: str, target: str, value: str, met: Optional[bool], command: str, why: str = "") -> Dict[str, Any]:
    return {"item": item, "target": target, "value": value,
            "verdict": "n/a" if met is None else ("met" if met else "**missed**"), "command": command, "why": why}


def md_table(header: List[str], rows: List[List[Any]]) -> str:
    out = ["| " + " | ".join(header) + " |", "| " + " | ".join("---" for _ in header) + " |"]
    out += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    return "\n".join(out)
