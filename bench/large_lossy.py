"""1 KB writes and reads through a line that drops bytes (PROTOCOL.md 12.4): how many get through and
how long each takes, against the device library in the emulator (extras/tests/Large1K, a 1 KB
struct: 38 fragments of 27 bytes on a device that accepts 32-byte payloads).

Each write carries a fresh value; the sketch's own checksum of what it applied is read back (a
small value, retried until it is read) and compared with the value sent: a write counts only when
the board holds exactly that value. A read counts when it returns the whole value last written.

    .venv/bin/python bench/large_lossy.py            # 0.5 % and 1 % byte drops, 20 of each
    .venv/bin/python bench/large_lossy.py --n 50 --drops 0.005 0.01 0.02
"""
from __future__ import annotations

import argparse
import json
import os
import random
import struct
import sys
import tempfile
import time
from typing import Any, Dict, List

import hubwire
from hubwire.errors import HubwireError
from hubwire.testing import emulator_binary
from hubwire.testing.faultlink import Faults, FaultyTransport, stop_process
from hubwire.testing.faultlink.soak import start_emulator
from hubwire.transport import SerialTransport


def fnv(data: bytes) -> int:
    h = 2166136261
    for b in data:
        h = ((h ^ b) * 16777619) & 0xFFFFFFFF
    return h


def value(rng: random.Random) -> Dict[str, Any]:
    words = [rng.getrandbits(32) for _ in range(200)]
    f = [float(struct.unpack("<f", struct.pack("<f", rng.uniform(-1e3, 1e3)))[0]) for _ in range(56)]
    return {"words": words, "f": f}


def wire(v: Dict[str, Any]) -> bytes:
    return struct.pack("<200I", *v["words"]) + struct.pack("<56f", *v["f"])


def read_small(dev: Any, name: str) -> Any:
    for _ in range(50):
        try:
            return dev.read(name)
        except HubwireError:
            continue
    raise RuntimeError(f"{name} could not be read")


def run(drop: float, n: int, seed: int) -> Dict[str, Any]:
    binary = os.path.join(os.path.dirname(emulator_binary()), "hubwire-large-emulator")
    rng = random.Random(seed)
    with tempfile.TemporaryDirectory() as tmp:
        link = os.path.join(tmp, "large")
        emu = start_emulator(binary, link)
        try:
            faulty = FaultyTransport(SerialTransport(link), seed=seed, both=Faults(drop=drop))
            with hubwire.connect(transport=faulty, cache_dir=False, timeout=30, tries=5) as dev:
                writes: List[float] = []
                write_fail = 0
                last = None
                for _ in range(n):
                    v = value(rng)
                    t0 = time.monotonic()
                    try:
                        dev.write("big", v)
                    except HubwireError:
                        write_fail += 1
                        continue
                    if read_small(dev, "checksum") == fnv(wire(v)):
                        writes.append(time.monotonic() - t0)
                        last = wire(v)
                    else:
                        write_fail += 1
                reads: List[float] = []
                read_fail = torn = 0
                for _ in range(n if last is not None else 0):
                    t0 = time.monotonic()
                    try:
                        got = dev.read("big")
                    except HubwireError:
                        read_fail += 1
                        continue
                    if wire(got) != last:
                        torn += 1
                    else:
                        reads.append(time.monotonic() - t0)
                stats = faulty.stats()
        finally:
            stop_process(emu)
    return {
        "drop": drop, "n": n,
        "writes_ok": len(writes), "writes_failed": write_fail,
        "write_s_median": sorted(writes)[len(writes) // 2] if writes else None,
        "reads_ok": len(reads), "reads_failed": read_fail, "reads_torn": torn,
        "read_s_median": sorted(reads)[len(reads) // 2] if reads else None,
        "bytes_dropped": {k: v.get("bytes_dropped") for k, v in stats.items() if isinstance(v, dict)},
    }


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=20)
    ap.add_argument("--drops", type=float, nargs="+", default=[0.005, 0.01])
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    rows = [run(d, args.n, args.seed) for d in args.drops]
    for r in rows:
        print(json.dumps(r))
    return 0


if __name__ == "__main__":
    sys.exit(main())
