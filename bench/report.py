#!/usr/bin/env python3
"""Assemble bench/RESULTS.md from build/bench/results/*.json, bench/FOOTPRINT.md and machine facts.

    python bench/report.py SECONDS_TAKEN
"""
from __future__ import annotations

import datetime
import json
import os
import platform
import re
import subprocess
import sys

from common import RESULTS, ROOT, md_table, row

ORDER = ["footprint", "rx_cycles", "wire_bytes", "wire_large", "throughput", "connect", "rtt", "large_rtt", "missions",
         "many", "mqtt", "dashboard"]
SCALE = {
    "footprint": "peers: see Peers below (bash bench/peers.sh)",
    "rx_cycles": "CRC-16 bitwise 108 c/B, PROGMEM table 24 c/B, _crc_xmodem_update 34 c/B; COBS decode 13 c/B",
    "wire_bytes": "MAVLink v2 12, rosserial 8, SerialComm 11",
    "wire_large": "ratio against the raw value size (1.00x = no overhead)",
    "throughput": "pymavlink / pySerialTransfer measured in the same run",
    "connect": "pyFirmata sleeps 5 s, pymata 4 s, rosserial 2.1 s",
    "rtt": "micro-ROS 8.8 ms at 115200",
    "large_rtt": "the same run's 4-byte write / read; wire time of the fragments at the baud",
    "missions": "frames: row 3b's 4 + 2N; times against the device's own clock",
    "many": "",
    "mqtt": "",
    "dashboard": "",
}


def sh(cmd: str) -> str:
    try:
        return subprocess.run(cmd, shell=True, capture_output=True, text=True, cwd=ROOT).stdout.strip()
    except OSError:
        return "?"


def footprint():
    path = os.path.join(ROOT, "bench/FOOTPRINT.md")
    rows = []
    if not os.path.exists(path):
        return None
    text = open(path).read()
    for m in re.finditer(r"^\| (Minimal|Rover) \| (\d+) \| (\d+) \| \+?(-?\d+) \| \+?(-?\d+) \| \+(\d+) / \+(\d+) "
                         r"\| [^|]+\| [^|]+\| (\w+) \|", text, re.M):
        name, f, s, df, ds, tf, ts, heap = m.groups()
        flash_met = int(df) <= int(tf) and heap == "no"
        sram_met = int(ds) <= int(ts) and heap == "no"
        rows.append(row(f"1. Uno flash of {name} over the Serial-echo baseline", f"<= +{int(tf):,} B, no heap",
                        f"+{int(df):,} B, malloc linked: {heap}", flash_met, "bash bench/footprint.sh",
                        "see Misses below" if not flash_met else ""))
        rows.append(row(f"1. Uno static SRAM of {name} over the Serial-echo baseline", f"<= +{ts} B, no heap",
                        f"+{ds} B, malloc linked: {heap}", sram_met, "bash bench/footprint.sh",
                        "see Misses below" if not sram_met else ""))
    return {"rows": rows, "details": "### Row 1: footprint\n\n" + text.split("\n", 1)[1].strip() + "\n"}


def misses() -> str:
    """The hand-written analysis of the rows that miss their target (bench/MISSES.md)."""
    path = os.path.join(ROOT, "bench/MISSES.md")
    return ("\n" + open(path).read()) if os.path.exists(path) else ""


def measured_apart() -> str:
    """Tables measured by scripts that need folders from outside the repository (peers' sources,
    vendor cores), kept from their last run: bench/PEERS.md (run.sh rebuilds it first when PEERS_SRC
    names the peers' sources) and bench/REALCORES.md."""
    out = ""
    for name, title in (("PEERS.md", "Peers"), ("REALCORES.md", "Real Arduino cores")):
        path = os.path.join(ROOT, "bench", name)
        if os.path.exists(path):
            out += f"\n## {title} (bench/{name}, measured apart)\n\n" + open(path).read().strip() + "\n"
    return out


def main() -> None:
    took = float(sys.argv[1]) if len(sys.argv) > 1 else 0.0
    parts = {}
    fp = footprint()
    if fp:
        parts["footprint"] = fp
    for name in ORDER[1:]:
        p = os.path.join(RESULTS, name + ".json")
        if os.path.exists(p):
            parts[name] = json.load(open(p))
    table = []
    for name in ORDER:
        if name not in parts:
            table.append([name, "", "not run (see the bench/run.sh output)", "**failed**", "", ""])
            continue
        for i, r in enumerate(parts[name]["rows"]):
            scale = SCALE.get(name, "") if i == 0 and SCALE.get(name, "") not in r.get("why", "") else ""
            table.append([r["item"], r["target"], r["value"], r["verdict"], f"`{r['command']}`",
                          "; ".join(x for x in (r.get("why", ""), scale) if x)])
    info = [
        ["date (UTC)", datetime.datetime.utcnow().strftime("%Y-%m-%d %H:%M")],
        ["host", f"{platform.system()} {platform.release()} {platform.machine()}"],
        ["nproc", sh("nproc")],
        ["CPU", sh("grep -m1 'model name' /proc/cpuinfo | cut -d: -f2").strip()],
        ["load average at the end", " ".join(f"{x:.2f}" for x in os.getloadavg())],
        ["python (.venv)", sh(".venv/bin/python --version")],
        ["python (bench venv)", sh("build/bench-venv/bin/python -c \"import sys; from importlib.metadata import version as v; "
                                   "print(sys.version.split()[0], 'pymavlink', v('pymavlink'), 'pySerialTransfer', "
                                   "v('pySerialTransfer'))\"")],
        ["gcc", sh("gcc --version | head -1")],
        ["avr-gcc", sh("avr-gcc --version | head -1")],
        ["simavr", sh("dpkg-query -W -f='${Version}' simavr")],
        ["Arduino AVR core", sh("dpkg-query -W -f='${Version}' arduino-core-avr")],
        ["git", sh("git rev-parse --short HEAD") + (" + uncommitted changes" if sh("git status --porcelain") else "")],
        ["bench duration", f"{took:.0f} s"],
    ]
    out = f"""# Hubwire benchmarks

Regenerated by `bash bench/run.sh` (wired as `make bench`); do not edit by hand. Deterministic counts
(avr-size bytes, simavr cycles, wire bytes) are exact; times come from a shared, noisy machine and
ratios are taken within one run. No test asserts on any timing here.

{md_table(["", ""], info)}

## Results

{md_table(["row", "target", "measured", "verdict", "command", "notes / for scale"], table)}

""" + misses() + measured_apart() + """
## Details

""" + "\n".join(parts[n]["details"] for n in ORDER if n in parts)
    with open(os.path.join(ROOT, "bench/RESULTS.md"), "w") as f:
        f.write(out)
    print(md_table(["row", "target", "measured", "verdict"], [t[:4] for t in table]))


if __name__ == "__main__":
    main()
