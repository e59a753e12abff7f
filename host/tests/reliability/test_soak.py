"""Soak through a faulty link (hubwire.testing.faultlink.soak has the scenario and the claims).

Bounded by default (HUBWIRE_SOAK_SECONDS, default 75 s). Long mode: HUBWIRE_SOAK_FRAMES=1000000
runs until that many frames went through the proxy (also: python -m hubwire.testing.faultlink.soak
--frames 1000000). The counts are printed and written to build/reliability/soak-last.json.
"""
from __future__ import annotations

import json
import os
import time
from typing import Any


import hubwire

from hubwire.transport import SerialTransport

from .conftest import REPO, Faults, FaultyTransport
from hubwire.testing.faultlink.soak import check, run_soak


def test_soak_exactly_once_no_corruption_no_reset(emulator_bin: str, tmp_path: Any) -> None:
    frames = int(os.environ["HUBWIRE_SOAK_FRAMES"]) if os.environ.get("HUBWIRE_SOAK_FRAMES") else None
    seconds = float(os.environ.get("HUBWIRE_SOAK_SECONDS", "75")) if frames is None else None
    r = run_soak(seconds=seconds, frames=frames, seed=int(os.environ.get("HUBWIRE_SOAK_SEED", "1")),
                 workdir=str(tmp_path), binary=emulator_bin)
    text = json.dumps(r, indent=1)
    print(text)
    out = os.path.join(REPO, "build", "reliability")
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(out, "soak-last.json"), "w") as fh:
        fh.write(text + "\n")
    assert check(r) == []
    # the link really was faulty, in every way asked for
    for d in ("h2d", "d2h"):
        p = r["proxy"][d]
        assert p["bits_flipped"] > 0 and p["bytes_dropped"] > 0 and p["garbage_bursts"] > 0, p
    assert r["proxy"]["h2d"]["frames_duplicated"] + r["proxy"]["d2h"]["frames_duplicated"] > 0
    assert r["acked"] > 500 and r["events_delivered"] > 50 and r["reads"] > 50


def test_connect_and_discover_through_a_lossy_link(emu: Any) -> None:
    fl = FaultyTransport(SerialTransport(emu.link), seed=5, both=Faults(drop=0.02, ber=1e-4))
    failures = []
    for _ in range(4):
        t = time.monotonic()
        try:
            with hubwire.connect(transport=fl, cache_dir=False, timeout=15) as dev:
                assert dev.battery > 0
        except hubwire.HubwireError as e:
            failures.append(f"{type(e).__name__} after {time.monotonic() - t:.1f} s: {e}")
    assert failures == []
    assert fl.stats()["h2d"]["bytes_dropped"] > 0 and fl.stats()["d2h"]["bits_flipped"] > 0  # it was lossy
