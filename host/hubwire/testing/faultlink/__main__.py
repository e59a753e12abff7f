"""Command line: ``python -m hubwire.testing.faultlink --device /tmp/rover --link /tmp/rover-faulty ...``

Every fault option exists three times: ``--ber`` (both directions), ``--ber-h2d`` (hub to device
only) and ``--ber-d2h`` (device to hub only). Prints ``READY <link>`` once forwarding, the counters
as JSON on SIGUSR1 and at exit (SIGINT / SIGTERM / ``--seconds`` elapsed).
"""
from __future__ import annotations

import argparse
import json
import signal
import sys
import threading
from dataclasses import replace

from . import FaultLink, Faults

FIELDS = {
    "ber": (float, "bit-error rate (probability per bit)"),
    "drop": (float, "probability that a byte is dropped"),
    "dup": (float, "probability that a frame is duplicated"),
    "truncate": (float, "probability that a frame is truncated"),
    "garbage_every": (float, "seconds between garbage bursts (0 = none)"),
    "garbage_len": (str, "garbage burst length LO:HI bytes"),
    "delay_ms": (float, "added delay, ms"),
    "stall_every": (float, "seconds between stalls (0 = none)"),
    "stall_ms": (float, "stall length, ms"),
}


def _faults(args: argparse.Namespace, suffix: str, base: Faults) -> Faults:
    f = base
    for name in FIELDS:
        v = getattr(args, name + suffix)
        if v is None:
            continue
        if name == "garbage_len":
            lo, _, hi = v.partition(":")
            f = replace(f, garbage_len=(int(lo), int(hi or lo)))
        elif name == "delay_ms":
            f = replace(f, delay=v / 1000.0)
        else:
            f = replace(f, **{name: v})
    return f.validate()


def main(argv: None = None) -> int:
    p = argparse.ArgumentParser(prog="faultlink", description="Fault-injecting pty proxy between a Hubwire hub and device.")
    p.add_argument("--device", required=True, help="the device's pty path (e.g. the emulator's --link)")
    p.add_argument("--link", required=True, help="path of the pty link to create for the hub")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--seconds", type=float, default=0, help="stop after this long (0 = until a signal)")
    for name, (typ, help_) in FIELDS.items():
        opt = "--" + name.replace("_", "-")
        p.add_argument(opt, dest=name, type=typ, help=help_ + " (both directions)")
        p.add_argument(opt + "-h2d", dest=name + "_h2d", type=typ, help=argparse.SUPPRESS)
        p.add_argument(opt + "-d2h", dest=name + "_d2h", type=typ, help=argparse.SUPPRESS)
    args = p.parse_args(argv)
    both = _faults(args, "", Faults())
    fl = FaultLink(args.device, args.link, seed=args.seed, hub_to_device=_faults(args, "_h2d", both),
                   device_to_hub=_faults(args, "_d2h", both))
    done = threading.Event()
    signal.signal(signal.SIGINT, lambda *a: done.set())
    signal.signal(signal.SIGTERM, lambda *a: done.set())
    signal.signal(signal.SIGUSR1, lambda *a: print(json.dumps(fl.stats()), flush=True))
    fl.start()
    print(f"READY {args.link}", flush=True)
    print(json.dumps({"config": fl.config()}), flush=True)
    done.wait(args.seconds or None)
    stats = fl.stats()
    fl.stop()
    print(json.dumps(stats), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
