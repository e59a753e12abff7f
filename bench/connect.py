#!/usr/bin/env python3
"""Row 5: connect time (port open -> READY) with Rover's 12-channel descriptor at 115200 baud.

Against the simulated Uno (`simuno --reset-on-open --boot-delay B`: opening the port resets the
MCU and holds it B ms, like the bootloader) and against the Linux emulator. For each: a cold
connect (empty descriptor cache: the descriptor is downloaded), a warm connect (descriptor cached
on disk), and, on simuno, a device reboot inside an open session (SIGUSR1): device hello ->
READY again with the cached descriptor. Times are wall-clock medians of a few runs (noisy host).

    python bench/connect.py [--runs 3]
"""
from __future__ import annotations

import argparse
import os
import signal
import statistics
import tempfile
import threading
import time

from common import ROOT, emulator, md_table, row, save, simuno, tmp_link

from hubwire.session import Session
from hubwire.testing import tapped
from hubwire.wire import messages as m

BOOT_DELAY_MS = 300
ROVER_ELF = os.path.join(ROOT, "build/uno/Rover/Rover.ino.elf")


class Timed:
    """A Session whose first device hello and READY moments are recorded."""

    def __init__(self, url: str, cache_dir: str) -> None:
        self.hellos: list = []
        self.reconnected = threading.Event()
        self.reconnect_at = 0.0
        tap = tapped(url, 115200)
        tap.rx_filter = self._rx
        self.s = Session(transport=tap, cache_dir=cache_dir, on_reconnect=self._on_reconnect)

    def _rx(self, f) -> bool:
        if f.type == m.HELLO:
            self.hellos.append((time.monotonic(), m.Hello.unpack(f.payload).nonce))
        return True

    def _on_reconnect(self, desc) -> None:
        self.reconnect_at = time.monotonic()
        self.reconnected.set()

    def open(self):
        t0 = time.monotonic()
        self.s.open()
        t1 = time.monotonic()
        return t0, t1


def connect_once(url: str, cache_dir: str):
    t = Timed(url, cache_dir)
    t0, t1 = t.open()
    hello = t.hellos[0][0] if t.hellos else t1
    info = (t.s.stats.downloads, t.s.stats.chunk_requests, len(t.s.descriptor.raw), len(t.s.descriptor.channels))
    return t, (t1 - t0) * 1e3, (hello - t0) * 1e3, (t1 - hello) * 1e3, info


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", type=int, default=3)
    a = ap.parse_args()
    res: dict = {}
    info = None
    for target in ("simuno", "emulator"):
        link = tmp_link(f"connect-{target}")
        child = (simuno(ROVER_ELF, link, "--reset-on-open", "--boot-delay", str(BOOT_DELAY_MS))
                 if target == "simuno" else emulator(link))
        try:
            for kind in ("cold", "warm"):
                for _ in range(a.runs):
                    cache = tempfile.mkdtemp(prefix="hubwire-bench-cache-")
                    if kind == "warm":  # fill the cache first
                        t, *_ = connect_once(link, cache)
                        t.s.close()
                        time.sleep(0.3)
                    t, total, to_hello, after_hello, inf = connect_once(link, cache)
                    if kind == "cold":
                        info = inf
                    res.setdefault((target, kind), []).append((total, to_hello, after_hello))
                    if target == "simuno" and kind == "warm":
                        # reboot inside the session: device hello (new nonce) -> READY with the cached descriptor
                        old = t.s.device_hello.nonce
                        t.reconnected.clear()
                        t.hellos.clear()
                        child.signal(signal.SIGUSR1)
                        if t.reconnected.wait(10):
                            h = next(x for x, n in t.hellos if n != old)
                            res.setdefault((target, "reboot"), []).append(
                                (None, None, (t.reconnect_at - h) * 1e3))
                    t.s.close()
                    time.sleep(0.3)
        finally:
            child.stop()

    def med(key, i):
        v = [x[i] for x in res.get(key, []) if x[i] is not None]
        return statistics.median(v) if v else float("nan")

    lines = []
    for (target, kind), v in res.items():
        lines.append([target, kind, f"{med((target, kind), 0):.0f}" if kind != "reboot" else "",
                      f"{med((target, kind), 1):.0f}" if kind != "reboot" else "",
                      f"{med((target, kind), 2):.0f}", " / ".join(f"{x[2]:.0f}" for x in v)])
    cold_sim = med(("simuno", "cold"), 0) - BOOT_DELAY_MS
    cold_sim_after = med(("simuno", "cold"), 2)
    warm_sim_after = med(("simuno", "warm"), 2)
    reboot_after = med(("simuno", "reboot"), 2)
    cold_emu = med(("emulator", "cold"), 0)
    warm_emu_after = med(("emulator", "warm"), 2)
    downloads, chunks, dlen, nch = info
    details = f"""### Row 5: connect time (hubwire.Session.open(), 115200 baud, Rover: {nch} channels, {dlen}-byte descriptor)

simuno runs `build/uno/Rover/Rover.ino.elf` with `--reset-on-open --boot-delay {BOOT_DELAY_MS}`: the port open
resets the MCU, which is held {BOOT_DELAY_MS} ms (bootloader), then runs setup() (begin(): 48.6 ms of AVR time,
row 2c) and announces itself. The emulator runs the same sketch natively (no boot). Cold = empty cache
({chunks} chunk requests); warm = descriptor in the disk cache; reboot = SIGUSR1 to simuno inside an
open session. Medians of {a.runs} runs; ms.

{md_table(["device", "case", "open -> READY", "open -> first device hello", "hello -> READY", "hello -> READY per run"], lines)}

- simuno cold: open -> READY minus the {BOOT_DELAY_MS} ms boot delay = **{cold_sim:.0f} ms**, of which
  **{cold_sim_after:.0f} ms** after the device's hello: the descriptor download. Each 28-byte chunk costs the
  Uno 11.5-12 ms of CPU (row 2d: the JSON is regenerated from offset 0 for every chunk) and 39+10 bytes
  of wire (4.3 ms at 115200): {-(-dlen // 28)} chunks ~ {-(-dlen // 28) * 12:.0f} ms of device CPU alone, four requests in flight
  do not help because the device answers them one after the other.
- emulator cold (native speed, no UART): {cold_emu:.0f} ms; warm hello -> READY {warm_emu_after:.0f} ms.
- cached: hello -> READY **{warm_sim_after:.0f} ms** (new session, disk cache) and **{reboot_after:.0f} ms** (device reboot
  inside a session).
"""
    # device boot = bootloader hold + setup(); the target allows boot + 150 ms
    rows = [
        row("5a. Connect, simulated Uno, cold cache (open -> READY minus the boot delay)", "device boot + <= 150 ms",
            f"{cold_sim:.0f} ms (boot ~{med(('simuno', 'cold'), 1) - BOOT_DELAY_MS:.0f} ms after the hold, "
            f"then {cold_sim_after:.0f} ms hello -> READY)", cold_sim_after <= 150, "python bench/connect.py",
            f"descriptor download: {-(-dlen // 28)} chunks of 28 B, copied from flash (row 2d)"),
        row("5b. Connect, emulator, cold cache (open -> READY)", "<= 150 ms", f"{cold_emu:.0f} ms",
            cold_emu <= 150, "python bench/connect.py"),
        row("5c. Cached reconnect, simulated Uno (device hello -> READY)", "<= 30 ms",
            f"{warm_sim_after:.0f} ms new session / {reboot_after:.0f} ms after a reboot",
            max(warm_sim_after, reboot_after) <= 30, "python bench/connect.py"),
        row("5d. Cached reconnect, emulator (device hello -> READY)", "<= 30 ms", f"{warm_emu_after:.0f} ms",
            warm_emu_after <= 30, "python bench/connect.py"),
    ]
    save("connect", rows, details, {"raw": {f"{k[0]}/{k[1]}": v for k, v in res.items()}})


if __name__ == "__main__":
    main()
