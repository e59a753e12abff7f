"""The command line, end to end against the emulator (run as a subprocess: stdout is not a tty)."""
from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import time
from typing import Any, List

from conftest import Emulator

from hubwire.cli.command import build_parser, watch_duration


def run(*args: str, cache: str, timeout: float = 30) -> subprocess.CompletedProcess:
    env = dict(os.environ, HUBWIRE_CACHE_DIR=cache)
    return subprocess.run([sys.executable, "-m", "hubwire", *args], capture_output=True, text=True,
                          timeout=timeout, env=env)


def test_info_get_set_call(emulator: Emulator, cache_dir: str) -> None:
    r = run("info", emulator.link, "--json", cache=cache_dir)
    assert r.returncode == 0, r.stderr
    info = json.loads(r.stdout)
    assert info["name"] == "rover" and [c["name"] for c in info["channels"]][:3] == ["left", "right", "imu"]
    assert info["channels"][0] == {"id": 1, "name": "left", "access": "rws", "type": "f32", "unit": "m/s",
                                   "min": -1, "max": 1, "failsafe": 0.0}
    r = run("info", emulator.link, cache=cache_dir)
    assert r.returncode == 0 and "m/s" in r.stdout and "-1..1" in r.stdout and "(u16) -> bool" in r.stdout
    r = run("get", emulator.link, "imu", "--json", cache=cache_dir)
    assert set(json.loads(r.stdout)["value"]) == {"ax", "ay", "az", "gyro"}
    r = run("set", emulator.link, "name", "robbie", "--json", cache=cache_dir)
    assert json.loads(r.stdout) == {"channel": "name", "value": "robbie", "ok": True}
    r = run("get", emulator.link, "name", cache=cache_dir)
    assert r.stdout.strip() == '"robbie"'
    r = run("call", emulator.link, "beep", "100", cache=cache_dir)
    assert r.returncode == 0 and r.stdout.strip() == "True"
    r = run("call", emulator.link, "selftest", "2", "--json", cache=cache_dir)
    assert json.loads(r.stdout) == {"action": "selftest", "result": 2}


def test_errors_are_clear(emulator: Emulator, cache_dir: str) -> None:
    r = run("get", emulator.link, "nope", cache=cache_dir)
    assert r.returncode == 1 and "no channel 'nope'" in r.stderr and "left" in r.stderr
    r = run("set", emulator.link, "left", "3", cache=cache_dir)
    assert r.returncode == 1 and "outside the declared range -1..1" in r.stderr
    r = run("set", emulator.link, "led", "maybe", "--json", cache=cache_dir)
    assert r.returncode == 1 and json.loads(r.stdout)["error"] == "InvalidValue"


def test_watch_plain_lines_ends_by_itself(emulator: Emulator, cache_dir: str) -> None:
    t = time.monotonic()
    r = run("watch", emulator.link, "--duration", "1.5", "--rate", "4", cache=cache_dir)
    took = time.monotonic() - t
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    values = [ln for ln in lines if " left=" in ln]
    health = [ln for ln in lines if " link state=ready" in ln]
    assert len(values) >= 1 and len(health) >= 1
    assert "heartbeat_age_ms=" in health[-1] and "hub_errors=crc:0" in health[-1]
    # changes only: a line is printed when it differs from the one before (6 refreshes ran)
    for kind in (values, health):
        bodies = [re.sub(r"^t=\S+ |heartbeat_age_ms=\d+ ", "", ln) for ln in kind]
        assert all(a != b for a, b in zip(bodies, bodies[1:])), kind
    # the device's own measure of its heartbeat interval: never under the 250 ms it announced
    beat = int(re.search(r"measured_heartbeat_ms=(\d+)", health[-1]).group(1))  # type: ignore[union-attr]
    assert beat >= 250
    assert took < 10


def test_watch_json_shows_events(emulator: Emulator, cache_dir: str) -> None:
    env = dict(os.environ, HUBWIRE_CACHE_DIR=cache_dir)
    p = subprocess.Popen([sys.executable, "-m", "hubwire", "watch", emulator.link, "--json", "--duration", "3"],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    assert p.stdout is not None
    first = json.loads(p.stdout.readline())  # connected and refreshing
    assert first["link"]["state"] == "ready"
    emulator.bump()
    out, err = p.communicate(timeout=20)
    recs: List[Any] = [json.loads(x) for x in out.splitlines()]
    assert p.returncode == 0, err
    assert [r for r in recs if "link" in r][-1]["link"]["measured_heartbeat_ms"] >= 250  # measured by the device
    assert {"event": "bumper", "value": True} in [{k: r[k] for k in ("event", "value")} for r in recs if "event" in r]


def test_watch_defaults_to_10_s_when_not_a_tty() -> None:
    args = build_parser().parse_args(["watch", "/dev/null"])
    assert args.duration is None and args.rate == 2.0
    assert watch_duration(args.duration, stdout_is_tty=False) == 10.0
    assert watch_duration(args.duration, stdout_is_tty=True) is None
    assert watch_duration(2.5, stdout_is_tty=True) == 2.5


def test_ports_json() -> None:
    r = subprocess.run([sys.executable, "-m", "hubwire", "ports", "--json"], capture_output=True, text=True)
    assert r.returncode == 0
    assert isinstance(json.loads(r.stdout), list)


def test_watch_on_a_terminal_redraws_and_ctrl_c_ends_cleanly(emulator: Emulator, cache_dir: str) -> None:
    import pty
    import select
    import signal

    master, slave = pty.openpty()
    env = dict(os.environ, HUBWIRE_CACHE_DIR=cache_dir)
    p = subprocess.Popen([sys.executable, "-m", "hubwire", "watch", emulator.link, "--rate", "5"],
                         stdout=slave, stderr=subprocess.PIPE, stdin=subprocess.DEVNULL, env=env)
    os.close(slave)
    out = b""
    try:
        deadline = time.monotonic() + 15
        redraws = re.compile(rb"\x1b\[(\d+)F")  # back up to the first line of the drawing, no clearing
        while len(redraws.findall(out)) < 2 and time.monotonic() < deadline:
            r, _, _ = select.select([master], [], [], 0.5)
            if r:
                out += os.read(master, 65536)
        assert len(redraws.findall(out)) >= 2, out[-500:]  # redrawn in place, no --duration needed
        assert b"\x1b[2J" not in out and b"\x1b[H" not in out  # the screen (and scrollback) above stays
        first = out[:redraws.search(out).start()]  # type: ignore[union-attr]
        assert int(redraws.findall(out)[0]) == first.count(b"\n")  # exactly over the previous drawing
        text = out.decode(errors="replace")
        assert "battery" in text and "link ready" in text and "Ctrl-C" in text
        p.send_signal(signal.SIGINT)
        _, err = p.communicate(timeout=10)
    finally:
        if p.poll() is None:
            p.kill()
        os.close(master)
    assert p.returncode == 0
    assert b"Traceback" not in err
