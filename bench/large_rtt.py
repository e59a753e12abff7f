#!/usr/bin/env python3
"""Row 6b: round trip of a large value in fragments next to a 4-byte one, measured in the same run.

On the simulated Uno: examples/LargeValues (a 200-byte struct, 32-byte frames) rebuilt per baud rate
with one f32 channel `trim` added (build/bench/sketches/LargeBaud<baud>, generated from the example
so it never drifts), real-time simuno; at 1 Mbaud also with the Arduino core's receive ring at 256
bytes instead of 64. Each round writes `trim`, writes `profile`, reads `trim`,
reads `profile` through the public API (dev.write / dev.read), so both sizes see the same machine
load; the ratio is taken per run. On the emulator (extras/tests/Large1K, native, no UART): the 1 KB
`big` written and read next to a 4-byte read (`checksum`) and a one-element list write (`tail`, 5 B).

    python bench/large_rtt.py [--n 60]
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import tempfile
import time
from typing import Any, Callable, Dict, List

from common import BUILD, OUT, RESULTS, ROOT, Child, build_sketch, md_table, row, save, simuno, tmp_link
from wire_large import BIG, PROFILE, write_read

import hubwire
from hubwire.testing import tapped
from hubwire.wire.values import codec_for

REAL_BAUD = {115200: 117647, 1000000: 1000000}  # what the AVR's UBRR produces at 16 MHz
LARGE_EMULATOR = os.path.join(BUILD, "emulator", "hubwire-large-emulator")


#: (label, baud, extra compiler flags): the third gives the Arduino core a 256-byte receive ring
UNOS = [("simuno 115200", 115200, ""), ("simuno 1000000", 1000000, ""),
        ("simuno 1000000, RX ring 256", 1000000, "-DSERIAL_RX_BUFFER_SIZE=256")]


def large_values_at(baud: int, flags: str = "") -> str:
    src = open(os.path.join(ROOT, "examples/LargeValues/LargeValues.ino")).read()
    anchors = ("Serial.begin(115200)", "uint16_t pathWrites;", 'expose("path_writes", pathWrites));')
    assert all(a in src for a in anchors), "examples/LargeValues changed: update bench/large_rtt.py"
    text = (src.replace(anchors[0], f"Serial.begin({baud}UL)")
            .replace(anchors[1], anchors[1] + "\nfloat trim;  // bench: a 4-byte value beside the 200-byte one")
            .replace(anchors[2], 'expose("path_writes", pathWrites),\n  expose("trim", trim).writable());'))
    d = os.path.join(OUT, "sketches", f"LargeBaud{baud}")
    os.makedirs(d, exist_ok=True)
    path = os.path.join(d, f"LargeBaud{baud}.ino")
    if not os.path.exists(path) or open(path).read() != text:
        with open(path, "w") as f:
            f.write(text)
    return build_sketch(d, os.path.join(OUT, f"LargeBaud{baud}" + ("Ring256" if flags else "")), flags)


def timed(ops: Dict[str, Callable[[int], Any]], n: int, fails: Dict[str, int],
          ok: Dict[str, int]) -> Dict[str, List[float]]:
    """Every op once per round, in order, ``n`` rounds after 5 warm-up rounds; ms. An op that gets
    no answer (hubwire.Timeout after its retries) is counted in ``fails`` and, after 3 in a row,
    left out of the remaining rounds."""
    out: Dict[str, List[float]] = {k: [] for k in ops}
    streak = {k: 0 for k in ops}
    for i in range(n + 5):
        for k, op in ops.items():
            if streak[k] >= 3:
                continue
            t0 = time.perf_counter()
            try:
                op(i)
            except hubwire.Timeout:
                fails[k] = fails.get(k, 0) + 1
                streak[k] += 1
                continue
            streak[k] = 0
            ok[k] = ok.get(k, 0) + 1
            if i >= 5:
                out[k].append((time.perf_counter() - t0) * 1e3)
        time.sleep(0.002)
    return out


def on_uno(link: str, baud: int, n: int) -> Dict[str, Any]:
    # the hub is told the line's rate, as a program opening a real port at that rate does: above 250
    # kbaud it paces the fragments it sends (host/hubwire/session/pacer.py)
    dev = hubwire.connect(transport=tapped(link, baud), cache_dir=tempfile.mkdtemp(prefix="hubwire-bench-cache-"))
    try:
        assert dev.session.device_hello.max_payload == 32
        prof = codec_for(PROFILE)
        values = [prof.decode(bytes((i + k) & 0xFF for i in range(200))) for k in range(2)]
        before = dev.read("profile_writes")
        fails: Dict[str, int] = {}
        ok: Dict[str, int] = {}
        res = timed({"write 4 B (f32)": lambda i: dev.write("trim", i * 0.5, timeout=2),
                     "write 200 B": lambda i: dev.write("profile", values[i % 2], timeout=2),
                     "read 4 B (f32)": lambda i: dev.read("trim", timeout=2),
                     "read 200 B": lambda i: dev.read("profile", timeout=2)}, n, fails, ok)
        time.sleep(0.3)  # one more device heartbeat: its counters as they are after the run
        applied = dev.read("profile_writes") - before
        answered = ok.get("write 200 B", 0)
        assert applied == answered, f"the board applied {applied} writes, the hub got {answered} answers"
        return {"ops": res, "failed": fails, "counters": dict(dev.session.health().device_counters),
                "applied": applied}
    finally:
        dev.close()


def on_emulator(link: str, n: int) -> Dict[str, Any]:
    dev = hubwire.connect(transport=tapped(link), cache_dir=tempfile.mkdtemp(prefix="hubwire-bench-cache-"))
    try:
        big = codec_for(BIG)
        values = [big.decode(bytes((i * 7 + k) & 0xFF for i in range(1024))) for k in range(2)]
        fails: Dict[str, int] = {}
        res = timed({"write 5 B (list of 1 u32)": lambda i: dev.write("tail", [i]),
                     "write 1 KB": lambda i: dev.write("big", values[i % 2]),
                     "read 4 B (u32)": lambda i: dev.read("checksum"),
                     "read 1 KB": lambda i: dev.read("big")}, n, fails, {})
        return {"ops": res, "failed": fails, "counters": dict(dev.session.health().device_counters),
                "max_payload": dev.session.device_hello.max_payload}
    finally:
        dev.close()


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=60)
    a = ap.parse_args()
    prof = codec_for(PROFILE)
    c, ack, r, resp = write_read(prof.encode(prof.decode(bytes(200))), 32)
    wire_ms = {baud: ((len(c) + len(ack)) * 10 / real * 1e3, (len(r) + len(resp)) * 10 / real * 1e3)
               for baud, real in REAL_BAUD.items()}
    runs: Dict[str, Dict[str, Any]] = {}
    for label, baud, flags in UNOS:
        elf = large_values_at(baud, flags)
        link = tmp_link(f"large{baud}{len(runs)}")
        with simuno(elf, link):
            time.sleep(0.5)
            runs[label] = on_uno(link, baud, a.n)
    link = tmp_link("large-emu")
    with Child([LARGE_EMULATOR, "--link", link], link):
        runs["emulator (no UART)"] = on_emulator(link, a.n)
    emu_max = runs["emulator (no UART)"]["max_payload"]

    def med(k: str, op: str) -> float:
        v = runs[k]["ops"][op]
        return statistics.median(v) if v else float("nan")

    lines = []
    for k, r in runs.items():
        names = list(r["ops"])
        for j, op in enumerate(names):
            v = r["ops"][op]
            ratio = f"{med(k, op) / med(k, names[j - 1]):.1f}x" if j % 2 and v and r["ops"][names[j - 1]] else ""
            wire = ""
            if k.startswith("simuno") and op in ("write 200 B", "read 200 B"):
                wire = f"{wire_ms[int(k.split()[1].rstrip(','))][op.startswith('read')]:.2f}"
            lines.append([k, op, wire, f"{med(k, op):.2f}" if v else "-", f"{min(v):.2f}" if v else "-", ratio,
                          r["failed"].get(op, 0)])
    counters = [[k, r["counters"].get("crc", 0), r["counters"].get("overflow", 0), r["counters"].get("dropped", 0)]
                for k, r in runs.items()]
    details = f"""### Row 6b: large values round trip (fragments) next to a 4-byte value, same run

Simulated Uno: examples/LargeValues plus a `trim` f32, rebuilt per baud, real-time simuno; emulator:
extras/tests/Large1K (its hello announces {emu_max} B, so 1 KB is {write_read(bytes(1024), emu_max)[0].count(0)}
fragments each way). {a.n} rounds after 5 warm-up rounds, each op once per round; ms, median and min;
ratio = large / small median in the same run. Wire time = the bytes of row 3b x 10 bits / the baud the
Uno really gets. "no answer" = calls that raised Timeout after the hub's retries (an op is left out
after 3 in a row). After the run the board's own write counter must equal the writes the hub saw
answered (checked).

{md_table(["device", "op", "wire time", "median", "min", "large / small", "no answer"], lines)}

The device's receive counters at the end (its heartbeat): a fragment lost in the Uno's receive path
shows as `crc` / `overflow` / `dropped` and abandons the whole message (PROTOCOL.md 12.4).

{md_table(["device", "crc", "overflow", "dropped"], counters)}
"""
    try:
        c18 = float(json.load(open(os.path.join(RESULTS, "rx_cycles.json")))["extra"]["cycles"]["18"])
    except (OSError, KeyError, ValueError):
        c18 = 0.0
    if c18:
        details += f"""
A full Uno fragment is a 39-byte frame (32-byte payload). Row 2, region 18 (an `H` of that size through
the receive path, nothing dispatched) costs {c18:,.0f} cycles = {c18 / 39:.0f} cycles per byte before the
Arduino core's RX interrupt (not counted there); at 1,000,000 baud a byte arrives every 160 cycles (176 in
simavr, which counts 11 bits). A single frame fits the core's 64-byte receive ring whatever the speed;
8 fragments back to back (276 bytes) do not when the receive path is slower than the line: one lost
byte would abandon the whole write (12.4) and every retry would meet the same burst. So above 250 kbaud
the hub leaves a fragment's time between the fragments it sends (PROTOCOL.md 12.3; unpaced, every
200 B write at 1 Mbaud went unanswered). The third Uno above is the same sketch built with
`-DSERIAL_RX_BUFFER_SIZE=256` (the core's ring, +192 B of SRAM), paced as well.
"""
    rows = []
    for k, name in (("simuno 115200", "115200"), ("simuno 1000000", "1 Mbaud"),
                    ("simuno 1000000, RX ring 256", "1 Mbaud, -DSERIAL_RX_BUFFER_SIZE=256")):
        r = runs[k]
        fail = r["failed"].get("write 200 B", 0)
        wtxt = (f"{med(k, 'write 200 B'):.1f} ms ({med(k, 'write 200 B') / med(k, 'write 4 B (f32)'):.1f}x)"
                if r["ops"]["write 200 B"] else f"no answer ({fail} of {fail} calls, each with the hub's retries)")
        rows.append(row(f"6b. 200 B write / read round trip, simulated Uno, {name}", "",
                        f"write {wtxt} / read {med(k, 'read 200 B'):.1f} ms "
                        f"({med(k, 'read 200 B') / med(k, 'read 4 B (f32)'):.1f}x); x = against a 4 B write / read",
                        None, "python bench/large_rtt.py",
                        "8 fragments each way; ratio within one run" if not fail else
                        "the device counted " + ", ".join(f"{v} {k}" for k, v in r["counters"].items())
                        + ": the burst of 8 fragments overruns the core's 64-byte receive ring"))
    e = "emulator (no UART)"
    rows.append(row("6b. 1 KB write / read round trip, emulator (no UART)", "",
                    f"{med(e, 'write 1 KB'):.1f} / {med(e, 'read 1 KB'):.1f} ms median "
                    f"({med(e, 'write 1 KB') / med(e, 'write 5 B (list of 1 u32)'):.1f}x / "
                    f"{med(e, 'read 1 KB') / med(e, 'read 4 B (u32)'):.1f}x a 5 B write / 4 B read)", None,
                    "python bench/large_rtt.py", "hub + pty + native device"))
    save("large_rtt", rows, details, {"runs": runs, "wire_ms": wire_ms})


if __name__ == "__main__":
    main()
