"""How long the link survives heavy noise: link losses per minute against bit-error rate.

    .venv/bin/python bench/noise_curve.py [--seconds 60] [--seed 3] [--ber 1e-4,3e-4,...] [--json FILE]

For each bit-error rate (each with 1 % byte drops, both directions, fixed seed) the Rover emulator
runs behind faultlink's proxy; the hub connects over the clean link, then the faults go on for
``--seconds`` while the hub writes ``left`` once a second (a new value each time, retries as the
hub's defaults), calls ``selftest(1)`` every 2 s (one bumper event each) and otherwise lets the
heartbeats flow: a robot standing still, which is when a needless failsafe is the most likely
(every frame counts as life, and here there are few besides the heartbeats). Afterwards, on the clean link again, the device's ``failsafes`` counter is read:
each link loss the device declares fires its failsafe once.

Reported per BER: link losses per minute seen by the hub and by the device, failsafes fired,
controls acknowledged / sent, events delivered / queued. The frame survival probability for a
heartbeat (17 bytes on the wire) is printed next to it: (1-ber)^(8n) (1-drop)^n.
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from typing import Any, Dict, List


import hubwire
from hubwire.testing import emulator_binary
from hubwire.testing.faultlink import FaultLink, stop_process
from hubwire.testing.faultlink.soak import start_emulator
from hubwire.testing.faultlink.soak_load import retry

BERS = (1e-4, 3e-4, 1e-3, 2e-3, 3e-3)
DROP = 0.01
HEARTBEAT_WIRE_BYTES = 17  # 3 header + 10 payload + 2 CRC, +1 COBS, +1 delimiter


def survival(ber: float, drop: float, n: int = HEARTBEAT_WIRE_BYTES) -> float:
    return (1 - ber) ** (8 * n) * (1 - drop) ** n


def one(ber: float, seconds: float, seed: int, workdir: str, every: float = 1.0) -> Dict[str, Any]:
    dev_link, hub_link = os.path.join(workdir, "noise-dev"), os.path.join(workdir, "noise-hub")
    emu = start_emulator(emulator_binary(), dev_link)
    fl = FaultLink(dev_link, hub_link, seed=seed).start()
    try:
        with hubwire.connect(hub_link, cache_dir=False, timeout=10) as dev:
            hub_lost: List[float] = []
            events: List[Any] = []
            dev.on("link_lost", lambda: hub_lost.append(time.monotonic()))
            dev.on("bumper", events.append)
            failsafes0 = dev.failsafes
            sent = acked = queued = not_linked = 0
            fl.set_faults(ber=ber, drop=DROP)
            t0 = time.monotonic()
            next_event = t0 + 2 * every
            while time.monotonic() - t0 < seconds:
                sent += 1
                try:
                    dev.left = ((sent * 7919) % 2001 - 1000) / 1000.0
                    acked += 1
                except hubwire.NakError:  # NOT_LINKED after every try: the device had dropped the link
                    not_linked += 1
                except (hubwire.Timeout, hubwire.LinkLost):
                    pass
                if time.monotonic() >= next_event:
                    next_event += 2 * every
                    try:
                        queued += dev.selftest(1)
                    except (hubwire.Timeout, hubwire.LinkLost, hubwire.NakError):
                        pass
                time.sleep(max(0.0, t0 + sent * every - time.monotonic()))
            elapsed = time.monotonic() - t0
            fl.set_faults(ber=0.0, drop=0.0)
            time.sleep(1.5)  # let queued events and the re-link through
            failsafes = retry(lambda: dev.failsafes, "read failsafes") - failsafes0
            st = fl.stats()
        minutes = elapsed / 60.0
        return {"ber": ber, "drop": DROP, "seconds": round(elapsed, 1), "seed": seed,
                "hub_losses": len(hub_lost), "hub_losses_per_min": round(len(hub_lost) / minutes, 2),
                "device_losses_per_min": round(failsafes / minutes, 2), "failsafes": failsafes,
                "controls_sent": sent, "controls_acked": acked, "controls_not_linked": not_linked, "events_queued": queued,
                "events_delivered": len(events), "frames": st["frames"],
                "heartbeat_survival": round(survival(ber, DROP), 3)}
    finally:
        fl.stop()
        stop_process(emu)


def table(rows: List[Dict[str, Any]]) -> str:
    out = ["| BER (+1 % drops) | P(heartbeat arrives) | hub losses/min | device losses/min | failsafes "
           "| controls acked/sent | events delivered/queued |",
           "| --- | --- | --- | --- | --- | --- | --- |"]
    for r in rows:
        out.append(f"| {r['ber']:g} | {r['heartbeat_survival']:.3f} | {r['hub_losses_per_min']:.2f} "
                   f"| {r['device_losses_per_min']:.2f} | {r['failsafes']} "
                   f"| {r['controls_acked']}/{r['controls_sent']} | {r['events_delivered']}/{r['events_queued']} |")
    return "\n".join(out)


def main(argv: Any = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--seconds", type=float, default=60.0)
    p.add_argument("--seed", type=int, default=3)
    p.add_argument("--ber", default=",".join(f"{b:g}" for b in BERS))
    p.add_argument("--every", type=float, default=1.0, help="seconds between control writes")
    p.add_argument("--baseline", action="store_true",
                   help="the hub's loss detection as before the probes: heartbeats at the announced "
                        "interval, no probe (to compare both under the same load)")
    p.add_argument("--json", default=None)
    a = p.parse_args(argv)
    if a.baseline:
        from hubwire.session import link
        link.HEARTBEAT_LEAD = 1.0
        link.PROBE_AFTER = link.LOSS_HEARTBEATS + 1  # the loss comes first: never probes
    rows = []
    with tempfile.TemporaryDirectory() as d:
        for i, ber in enumerate(float(b) for b in a.ber.split(",")):
            r = one(ber, a.seconds, a.seed + i, d, a.every)
            print(json.dumps(r), file=sys.stderr, flush=True)
            rows.append(r)
    print(table(rows))
    if a.json:
        with open(a.json, "w") as fh:
            json.dump(rows, fh, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
