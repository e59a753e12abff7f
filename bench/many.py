#!/usr/bin/env python3
"""Row 7: one hub, many devices: N emulators (examples/Rover), each streaming `imu` at 100 Hz.

One Python process opens N hubwire Sessions, subscribes each to `imu` every 10 ms and drains the
sample queues from the main thread every 50 ms (a minimal application). Hub CPU = this process's
user + system time (getrusage, all threads) over a fixed window, as a share of one core; the sample
count checks that 100 Hz x N really arrived.

    python bench/many.py [--devices 1,4,16] [--window 5]
"""
from __future__ import annotations

import argparse
import os
import resource
import tempfile
import time

from common import emulator, md_table, row, save, tmp_link

from hubwire.session import Session


def cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def children_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def run_n(n: int, window: float):
    cache = tempfile.mkdtemp(prefix="hubwire-bench-cache-")
    kids = [emulator(tmp_link(f"many{i}")) for i in range(n)]
    sessions, subs = [], []
    try:
        for k in kids:
            s = Session(k.link, 115200, cache_dir=cache)
            s.open()
            sessions.append(s)
            cid = s.descriptor.by_name("imu").id
            subs.append(s.open_stream(cid, 10))
        granted = {sub.granted_ms for sub in subs}

        def drain() -> int:
            got = 0
            for sub in subs:
                with sub.cv:
                    got += len(sub.queue)
                    sub.queue.clear()
            return got

        time.sleep(1.0)  # settle
        drain()
        lost0 = sum(sub.dropped for sub in subs)
        c0, w0 = cpu(), time.monotonic()
        samples = 0
        while time.monotonic() - w0 < window:
            time.sleep(0.05)
            samples += drain()
        c1, w1 = cpu(), time.monotonic()
        samples += drain()
        states = {s.state.value for s in sessions}
        return {"n": n, "cpu": (c1 - c0) / (w1 - w0), "rate": samples / (w1 - w0), "granted": sorted(granted),
                "states": sorted(states), "dropped": sum(sub.dropped for sub in subs) - lost0}
    finally:
        for s in sessions:
            try:
                s.close()
            except Exception:  # noqa: BLE001
                pass
        for k in kids:
            k.stop()


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--devices", default="1,4,16")
    ap.add_argument("--window", type=float, default=5.0)
    a = ap.parse_args()
    res = []
    for n in (int(x) for x in a.devices.split(",")):
        res.append(run_n(n, a.window))
        time.sleep(0.5)
    lines = [[r["n"], f"{r['cpu']:.1%}", f"{r['cpu'] / r['n']:.2%}", f"{r['rate']:,.0f}", f"{r['n'] * 100:,}",
              f"{r['rate'] / (r['n'] * 100):.0%}", r["granted"], ", ".join(r["states"])] for r in res]
    big = res[-1]
    load = os.getloadavg()
    details = f"""### Row 7: one hub, many devices (emulators streaming imu at 100 Hz each)

One hub process, N `Session`s (all on one event loop thread; a dispatcher thread each), `open_stream(imu, 10 ms)` on every
device, queues drained every 50 ms. CPU = getrusage(RUSAGE_SELF) user+sys over a {a.window:g} s window / wall
time (1.0 = one core). The emulators run on the same 2-core machine (load average {load[0]:.1f} at the end).

{md_table(["devices", "hub CPU (one core = 100 %)", "per device", "samples/s received", "expected", "delivered",
           "granted ms", "states"], lines)}
"""
    rows = [row(f"7. One hub, {big['n']} devices x 100 Hz: hub CPU", "<= 30 % of one core", f"{big['cpu']:.1%} "
                f"({big['rate']:,.0f} samples/s = {big['rate'] / (big['n'] * 100):.0%} of expected)",
                big["cpu"] <= 0.30 and big["rate"] >= 0.9 * big["n"] * 100, "python bench/many.py",
                f"per device {big['cpu'] / big['n']:.2%}")]
    save("many", rows, details, {"runs": res})


if __name__ == "__main__":
    main()
