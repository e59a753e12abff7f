"""Soak through a faulty link (hubwire.testing.faultlink.soak has the scenario and the claims).

Bounded by default (HUBWIRE_SOAK_SECONDS, default 75 s). Long mode: HUBWIRE_SOAK_FRAMES=1000000
runs until that many frames went through the proxy (also: python -m hubwire.testing.faultlink.soak
--frames 1000000). The counts are printed and written to build/reliability/soak-last.json (the long
mode: soak-1M.json). Runs the soak sketch (extras/tests/Soak) in its own emulator build.
"""
from __future__ import annotations

import json
import os
import time
from typing import Any

import pytest

import hubwire

from hubwire.transport import SerialTransport

from .conftest import REPO, Faults, FaultyTransport
from hubwire.testing.faultlink.soak import check, run_soak, soak_emulator_binary


def test_soak_exactly_once_no_corruption_no_reset(emulator_bin: str, tmp_path: Any) -> None:
    binary = soak_emulator_binary()
    if not os.access(binary, os.X_OK):
        pytest.fail(f"soak emulator not found at {binary}: build it with `make emulator`", pytrace=False)
    frames = int(os.environ["HUBWIRE_SOAK_FRAMES"]) if os.environ.get("HUBWIRE_SOAK_FRAMES") else None
    seconds = float(os.environ.get("HUBWIRE_SOAK_SECONDS", "75")) if frames is None else None
    r = run_soak(seconds=seconds, frames=frames, seed=int(os.environ.get("HUBWIRE_SOAK_SEED", "1")),
                 workdir=str(tmp_path), binary=binary)
    text = json.dumps(r, indent=1)
    print(text)
    out = os.path.join(REPO, "build", "reliability")
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(out, "soak-1M.json" if frames else "soak-last.json"), "w") as fh:
        fh.write(text + "\n")
    assert check(r) == []
    # the link really was faulty, in every way asked for, and cut once
    for d in ("h2d", "d2h"):
        p = r["proxy"][d]
        assert p["bits_flipped"] > 0 and p["bytes_dropped"] > 0 and p["garbage_bursts"] > 0, p
        assert p["bytes_cut"] > 0, p
    assert r["proxy"]["h2d"]["frames_duplicated"] + r["proxy"]["d2h"]["frames_duplicated"] > 0
    # both boots carried real load, the device counted every token
    for boot in r["boots"]:
        assert boot["acked"] > 100 and boot["device"]["tokens_applied"] >= boot["acked"], boot
    # (a bound on time, not frames: a machine busy with other work gets through fewer. The floors only
    # show that every kind of traffic ran; the run's own counts are what the checks above hold to.
    # Two CPU burners at load average 9.5 gave 502 acked, 48 events, more than 50 reads)
    assert r["acked"] > 100 and r["events_delivered"] > 10 and r["reads"] > 10, r
    assert r["applied_twice"] == 0
    # the other direction carried real load in both boots too, and went through the faults
    for boot in r["hub_channels"]["boots"]:
        c = boot["device"]
        assert c["tally_acked"] > 50 and c["bump_ok"] > 10 and c["ticks"] > 50, boot
    assert r["hub_channels"]["device_duplicates"] > 0 and r["hub_channels"]["hub_event_retries"] > 0
    # missions ran all along (check() holds them to 0 lost, 0 duplicated, 0 corrupt)
    m = r["missions"]
    assert m is not None, "the soak sketch declares no mission"
    assert m["started"] > 20 and m["progress"] > 50 and m["succeeded"] > 10, m
    assert [b["device_starts"] for b in m["boots"]] == [b["hub_starts"] for b in m["boots"]] or m["start_unknown"], m


def test_connect_and_discover_through_a_lossy_link(emu: Any) -> None:
    fl = FaultyTransport(SerialTransport(emu.link), seed=5, both=Faults(drop=0.02, ber=1e-4))
    failures = []
    for _ in range(4):
        t = time.monotonic()
        try:
            with hubwire.connect(transport=fl, cache_dir=False, timeout=15, hub_later=True) as dev:
                assert dev.battery > 0
        except hubwire.HubwireError as e:
            failures.append(f"{type(e).__name__} after {time.monotonic() - t:.1f} s: {e}")
    assert failures == []
    assert fl.stats()["h2d"]["bytes_dropped"] > 0 and fl.stats()["d2h"]["bits_flipped"] > 0  # it was lossy


def test_the_per_boot_check_sees_a_write_applied_twice_and_a_lost_one() -> None:
    from hubwire.testing.faultlink.soak_load import check_segment

    boot = {"tokens_sent": 10, "first_sent": 1, "last_sent": 10, "acked": 9, "timeouts": 1, "link_lost_errors": 0,
            "device": {"tokens_applied": 10, "twice": 0, "gaps": 0, "first_token": 1, "last_token": 10},
            "events_queued": 4, "selftest_timeouts": 0, "events_delivered": 4, "event_seq_repeated": 0,
            "event_order_ok": True}
    assert check_segment(0, boot) == []
    twice = dict(boot, device=dict(boot["device"], tokens_applied=11, twice=1))
    assert any("applied twice" in b for b in check_segment(0, twice))
    # a token never applied although the hub saw every write acknowledged
    lost = dict(boot, timeouts=0, acked=10, device=dict(boot["device"], tokens_applied=9, gaps=1))
    assert any("not within" in b for b in check_segment(0, lost))
    uncounted = dict(boot, device=dict(boot["device"], tokens_applied=9))
    assert any("never applied" in b for b in check_segment(0, uncounted))
