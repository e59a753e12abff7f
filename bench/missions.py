#!/usr/bin/env python3
"""Row 6c: a mission run on the simulated Uno (examples/Missions, `drive`), from the hub's start to
the Job seeing the first progress and the result: frames per run, and times in the device's own
terms where it gives them.

The sketch reports progress = metres driven = speed x its own millis() since the start, every 100 ms;
so a progress value is a device timestamp (value / speed). The device's heartbeats (every 250 ms)
carry the device ms since the previous one: their count between two hub events is a device-clock
measure, and their sum over the session against host time tells whether simuno kept real time.
Every frame in both directions is recorded through a TapTransport.

    python bench/missions.py [--runs 5] [--goal 2.0]
"""
from __future__ import annotations

import argparse
import os
import statistics
import tempfile
import time
from collections import Counter
from typing import Any, Dict, List, Tuple

from common import BUILD, md_table, row, save, simuno, tmp_link

import hubwire
from hubwire.testing import tapped
from hubwire.wire import messages as m
from hubwire.wire.frame import Frame, decode_frame
from hubwire.wire.missions import MissionKind, MissionUpdate

SPEED = 2.0  # m/s, the sketch's largest
MISSIONS_ELF = os.path.join(BUILD, "uno", "Missions", "Missions.ino.elf")
NAMES = {m.CONTROL: "C", m.RESPONSE: "r", m.MISSION: "M", m.ACK: "ACK", m.HEARTBEAT: "H", m.REQUEST: "R",
         m.NAK: "NAK"}


class Recorder:
    """(monotonic time, direction, frame) of every frame the hub sends and receives."""

    def __init__(self) -> None:
        self.log: List[Tuple[float, str, Frame]] = []

    def rx(self, f: Frame) -> bool:
        self.log.append((time.monotonic(), "in", f))
        return True

    def tx(self, data: bytes) -> bool:
        now = time.monotonic()
        for part in data.split(b"\x00"):
            f = decode_frame(part) if part else None
            if f is not None:
                self.log.append((now, "out", f))
        return True

    def between(self, t0: float, t1: float) -> List[Tuple[float, str, Frame]]:
        return [x for x in self.log if t0 <= x[0] <= t1]


def one_run(dev: Any, rec: Recorder, goal: float) -> Dict[str, Any]:
    t0 = time.monotonic()
    job = dev.start("drive", goal, timeout=30)
    t_run = time.monotonic()
    first_at, first = 0.0, 0.0
    values = []
    for p in job.feedback(timeout=60):
        if not values:
            first_at, first = time.monotonic(), float(p)
        values.append(float(p))
    result = job.result(timeout=60)
    t_end = time.monotonic()
    time.sleep(0.05)  # the ACK of the final update goes out right after the Job sees it
    frames = rec.between(t0, t_end + 0.05)
    kinds = Counter(f"{d} {NAMES.get(f.type, hex(f.type))}" for _, d, f in frames)
    ms = [MissionUpdate.unpack(f.payload) for _, d, f in frames if d == "in" and f.type == m.MISSION]
    hb_first = sum(1 for t, d, f in frames if d == "in" and f.type == m.HEARTBEAT and t <= first_at)
    hb_end = sum(1 for _, d, f in frames if d == "in" and f.type == m.HEARTBEAT)
    assert result == goal and values == sorted(values), (result, values)
    assert [u.kind for u in ms][-1] == MissionKind.SUCCEEDED and len(ms) == len(values) + 1
    return {"run": job.run, "progress": len(values), "first_device_ms": first / SPEED * 1e3,
            "last_device_ms": values[-1] / SPEED * 1e3 if values else 0.0,
            "first_host_ms": (first_at - t0) * 1e3, "result_host_ms": (t_end - t0) * 1e3,
            "start_host_ms": (t_run - t0) * 1e3, "hb_first": hb_first, "hb_end": hb_end,
            "frames": sum(v for k, v in kinds.items() if not k.endswith(" H")), "kinds": dict(kinds)}


def device_clock(rec: Recorder) -> Tuple[float, float]:
    """(device ms, host ms) spanned by the device's heartbeats of the session."""
    hbs = [(t, m.Heartbeat.unpack(f.payload)) for t, d, f in rec.log if d == "in" and f.type == m.HEARTBEAT]
    hbs = hbs[1:]  # the first carries 0 or the time before the link
    if len(hbs) < 2:
        return 0.0, 0.0
    return float(sum(h.since_ms for _, h in hbs[1:])), (hbs[-1][0] - hbs[0][0]) * 1e3


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--goal", type=float, default=2.0, help="metres per run (at 2 m/s)")
    a = ap.parse_args()
    rec = Recorder()
    link = tmp_link("missions")
    with simuno(MISSIONS_ELF, link):
        tap = tapped(link)
        tap.rx_filter, tap.tx_filter = rec.rx, rec.tx
        dev = hubwire.connect(transport=tap, cache_dir=tempfile.mkdtemp(prefix="hubwire-bench-cache-"))
        try:
            hb_ms = dev.session.device_hello.heartbeat_ms
            dev.speed = SPEED
            runs = [one_run(dev, rec, a.goal) for _ in range(a.runs)]
            dev_ms, host_ms = device_clock(rec)
        finally:
            dev.close()
    rt = dev_ms / host_ms if host_ms else 0.0
    med = {k: statistics.median(r[k] for r in runs) for k in runs[0] if k != "kinds"}
    lines = [[r["run"], r["progress"], f"{r['first_device_ms']:.0f}", f"{r['first_host_ms']:.0f}", r["hb_first"],
              f"{r['last_device_ms']:.0f}", f"{r['result_host_ms']:.0f}", r["hb_end"], r["frames"],
              ", ".join(f"{v} {k}" for k, v in sorted(r["kinds"].items()))] for r in runs]
    nominal = a.goal / SPEED * 1e3
    details = f"""### Row 6c: a mission run on the simulated Uno (examples/Missions `drive`, {a.goal:g} m at {SPEED:g} m/s)

{a.runs} runs one after the other, real-time simuno at 115200. "device ms" = the progress value / speed,
the sketch's own millis() since the start (it reports every 100 ms; the run lasts {nominal:.0f} device ms);
"H" = device heartbeats ({hb_ms} ms apart on the device) the hub received from the start call until then;
host ms from the `dev.start()` call. Frames: every frame of the run both ways, heartbeats apart.
The device's heartbeats summed {dev_ms:.0f} device ms over {host_ms:.0f} host ms: simuno ran at
**{rt:.2f}x real time**, so host ms and device ms are comparable within that factor.

{md_table(["run", "progress seen", "1st progress, device ms", "host ms", "H", "last progress, device ms",
           "result, host ms", "H", "frames", "by kind"], lines)}

Median: start answered after {med['start_host_ms']:.1f} ms; first progress reported at {med['first_device_ms']:.0f} device
ms and seen by the Job {med['first_host_ms']:.0f} host ms after the start call ({med['hb_first']:.0f} device heartbeats);
result seen after {med['result_host_ms']:.0f} host ms ({med['hb_end']:.0f} heartbeats, nominal run {nominal:.0f} ms);
the Job saw the first progress {med['first_host_ms'] - med['first_device_ms']:.0f} ms after the device reported it and
the result {med['result_host_ms'] - nominal:.0f} ms after the nominal end (host minus device time, at the real-time factor above);
{med['frames']:.0f} frames per run without heartbeats ({med['progress']:.0f} progress updates; row 3b: 4 + 2N).
"""
    lag1 = med["first_host_ms"] - med["first_device_ms"]
    rows = [row("6c. Mission on the simulated Uno: start to first progress / result", "",
                f"first progress reported {med['first_device_ms']:.0f} device ms after the start, seen "
                f"+{lag1:.0f} ms later; result after {med['hb_end']:.0f} device heartbeats "
                f"({med['result_host_ms']:.0f} host ms for a {nominal:.0f} ms run)", None,
                "python bench/missions.py", f"simuno at {rt:.2f}x real time; the sketch reports every 100 ms"),
            row("6c. Frames per mission run", "", f"{med['frames']:.0f} ({med['progress']:.0f} progress updates)",
                None, "python bench/missions.py", "4 + 2N, heartbeats apart")]
    save("missions", rows, details, {"runs": runs, "device_ms": dev_ms, "host_ms": host_ms})


if __name__ == "__main__":
    main()
