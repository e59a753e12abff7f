#!/usr/bin/env python3
"""Row 8: the dashboard with its page open, 16 emulated boards (examples/Rover) streaming at 100 Hz.

`hubwire dashboard` runs as a user starts it, in its own process, on N emulators; headless Debian
chromium (driven by Playwright) keeps the page open. Two loads: `imu` at 100 Hz on every board (the
other streams at 1 Hz: as row 7), and every streamable channel at 100 Hz (the Rover grants 4
streams; its fifth is read at 10 Hz instead).

CPU: utime + stime from /proc of the dashboard process (and of the browser's processes, and of the
emulators) over a fixed window, as a share of one core. Latency: each value on the page carries
`data-hw-at`, the time its sample reached the hub (Unix ms); a MutationObserver in the page notes
each change and, at the next animation frame (the value drawn), `Date.now() - data-hw-at`. Hub and
browser share the machine's clock. The pty hop from the device to the hub is not included (the
sample is stamped when the hub reads its frame; row 6 measures that path).

    python bench/dashboard.py [--boards 16] [--window 20]
"""
from __future__ import annotations

import argparse
import os
import re
import socket
import subprocess
import sys
import time
from typing import Any, Dict, List

from common import ROOT, emulator, md_table, row, save, tmp_link

TICK = os.sysconf("SC_CLK_TCK")
# installed in every page load (a reconnect reloads the page); hands each batch to Python at once
OBSERVER = """document.addEventListener('DOMContentLoaded', () => {
  let pending = [];
  new MutationObserver(muts => {
    for (const m of muts) { const at = parseFloat(m.target.dataset.hwAt); if (at) pending.push(at); }
    requestAnimationFrame(() => {
      const t = Date.now(); if (pending.length) window.hwLat(pending.map(at => t - at)); pending = []; });
  }).observe(document.body, {subtree: true, attributes: true, attributeFilter: ['data-hw-at']});
});"""


def cpu_of(pids: List[int]) -> float:
    total = 0
    for pid in pids:
        try:
            fields = open(f"/proc/{pid}/stat").read().rsplit(")", 1)[1].split()
            total += int(fields[11]) + int(fields[12])  # utime, stime
        except (OSError, IndexError, ValueError):
            pass
    return total / TICK


def descendants(root: int) -> Dict[int, str]:
    """pid -> command name of every process below ``root``."""
    parent: Dict[int, int] = {}
    comm: Dict[int, str] = {}
    for d in os.listdir("/proc"):
        if d.isdigit():
            try:
                stat = open(f"/proc/{d}/stat").read()
                parent[int(d)] = int(stat.rsplit(")", 1)[1].split()[1])
                comm[int(d)] = stat[stat.index("(") + 1:stat.rindex(")")]
            except (OSError, ValueError):
                pass
    out, todo = {}, [root]
    while todo:
        p = todo.pop()
        for c, pp in parent.items():
            if pp == p and c not in out:
                out[c] = comm.get(c, "")
                todo.append(c)
    return out


def pct(xs: List[float], q: float) -> float:
    s = sorted(xs)
    return s[min(len(s) - 1, int(q * len(s)))] if s else float("nan")


def run(links: List[str], rates: List[str], window: float, label: str) -> Dict[str, Any]:
    from playwright.sync_api import sync_playwright

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    dash = subprocess.Popen([sys.executable, "-m", "hubwire", "dashboard", *links, "--http", str(port), "--no-cache",
                             *(x for r in rates for x in ("--rate", r))],
                            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, cwd=ROOT)
    try:
        line = dash.stdout.readline().decode()  # type: ignore[union-attr]
        url = re.search(r"(http://\S+)", line).group(1)  # type: ignore[union-attr]
        with sync_playwright() as p:
            browser = p.chromium.launch(executable_path="/usr/bin/chromium", args=["--no-sandbox"])
            page = browser.new_page(viewport={"width": 1400, "height": 1000})
            lat: List[float] = []
            loads: List[str] = []
            on = [False]
            page.expose_function("hwLat", lambda xs: lat.extend(xs) if on[0] else None)
            page.add_init_script(OBSERVER)
            page.on("load", lambda _: loads.append("load"))
            page.goto(url)
            n = len(links)
            page.wait_for_function(
                "n => [...document.querySelectorAll('[data-hw-state]')].filter(e => e.innerText == 'ready').length >= n"
                " && [...document.querySelectorAll('[data-hw-achieved$=\".imu\"]')]"
                ".some(e => parseFloat(e.innerText) >= 90)", arg=n, timeout=120_000)
            page.wait_for_timeout(3000)  # every subscription made
            samples = "[...document.querySelectorAll('[data-hw-health$=\".samples\"]')].reduce((a, e) => a + parseInt(e.innerText), 0)"
            s0 = page.evaluate(samples)
            on[0] = True
            loads.clear()
            kids = descendants(os.getpid())
            chrome = [pid for pid, c in kids.items() if "chrom" in c]
            emus = [pid for pid, c in kids.items() if c.startswith("hubwire-emul")]
            c0 = (cpu_of([dash.pid]), cpu_of(chrome), cpu_of(emus))
            w0 = time.monotonic()
            page.wait_for_timeout(window * 1000)
            w1 = time.monotonic()
            c1 = (cpu_of([dash.pid]), cpu_of(chrome), cpu_of(emus))
            on[0] = False
            s1 = page.evaluate(samples)
            states = page.evaluate("[...document.querySelectorAll('[data-hw-state]')].map(e => e.innerText)")
            plots = page.evaluate("[...document.querySelectorAll('[data-hw-plot] [_echarts_instance_]')].map(e => e.getBoundingClientRect())"
                                  ".filter(r => r.top < innerHeight + 300 && r.bottom > -300).length")
            browser.close()
        wall = w1 - w0
        return {"label": label, "boards": n, "dash": (c1[0] - c0[0]) / wall, "browser": (c1[1] - c0[1]) / wall,
                "emulators": (c1[2] - c0[2]) / wall, "samples": (s1 - s0) / wall, "lat": lat,
                "states": sorted(set(states)), "window": wall, "plots": plots, "reloads": len(loads)}
    finally:
        dash.terminate()
        dash.wait(20)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--boards", type=int, default=16)
    ap.add_argument("--window", type=float, default=20.0)
    a = ap.parse_args()
    kids = [emulator(tmp_link(f"dash{i}")) for i in range(a.boards)]
    try:
        links = [k.link for k in kids]
        res = [run(links, ["1", "imu=100"], a.window, "imu at 100 Hz, other streams 1 Hz"),
               run(links, ["100"], a.window, "every stream at 100 Hz")]
    finally:
        for k in kids:
            k.stop()
    lines = []
    for r in res:
        lat = r["lat"]
        lines.append([r["label"], f"{r['samples']:,.0f}", f"{r['dash']:.0%}", f"{r['browser']:.0%}", f"{r['emulators']:.0%}",
                      r["plots"], f"{len(lat):,}", *(f"{pct(lat, q):.0f}" for q in (0.5, 0.9, 0.99)), f"{max(lat):.0f}",
                      ", ".join(r["states"]), r["reloads"]])
    load = os.getloadavg()
    first = res[0]
    details = f"""### Row 8: the dashboard, page open, {a.boards} emulated boards streaming at 100 Hz

`hubwire dashboard` (its own process) on {a.boards} emulated Rovers, the page open in headless Debian
chromium driven by Playwright, {a.window:g} s window per load. CPU = utime + stime from /proc over the
window / wall time (one core = 100 %). Latency: from a sample's arrival at the hub to the animation
frame after the page's DOM shows it (`data-hw-at` read by a MutationObserver), every value change on
the page. The page is refreshed every 100 ms (values) and 500 ms (plots), so about half of 100 ms is
the wait for the next refresh. Only channels on screen are redrawn, values and plots (a 1400 x 1000
window here: the top of the first board), so the values timed are those; health, states and events
of every board are updated. Load average at the end {load[0]:.1f} on {os.cpu_count()} cores (shared machine).

{md_table(["load", "samples/s (hub's count)", "dashboard CPU", "chromium CPU", "emulators CPU",
           "plots on screen", "values timed", "p50 ms", "p90 ms", "p99 ms", "max ms", "states",
           "page reloads"], lines)}
"""
    lat = first["lat"]
    rows = [row(f"9. Dashboard, {a.boards} boards x imu at 100 Hz, page open: CPU of the dashboard process",
                "(measured)", f"{first['dash']:.0%} of one core (browser {first['browser']:.0%})", None,
                "python bench/dashboard.py", f"all streams at 100 Hz: {res[1]['dash']:.0%}"),
            row("9. Dashboard: sample at the hub -> value drawn on the page", "(measured)",
                f"p50 {pct(lat, 0.5):.0f} ms, p90 {pct(lat, 0.9):.0f} ms, p99 {pct(lat, 0.99):.0f} ms", None,
                "python bench/dashboard.py", "100 ms page refresh; all streams at 100 Hz: "
                f"p50 {pct(res[1]['lat'], 0.5):.0f} / p99 {pct(res[1]['lat'], 0.99):.0f} ms")]
    for r in res:
        r["lat"] = {"n": len(r["lat"]), **{f"p{int(q * 100)}": pct(r["lat"], q) for q in (0.5, 0.9, 0.99)}}
    save("dashboard", rows, details, {"runs": res})


if __name__ == "__main__":
    main()
