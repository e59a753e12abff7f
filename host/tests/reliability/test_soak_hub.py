"""The hub's channels through the soak's faulty link (hubwire.testing.faultlink.soak_hub has the
scenario): device writes and calls applied exactly once, hub events all delivered once and in
order, no corrupt value accepted. Bounded by HUBWIRE_SOAK_HUB_SECONDS (default 20 s)."""
from __future__ import annotations

import json
import os
from typing import Any

from hubwire.testing.faultlink.soak_hub import check_hub_soak, run_hub_soak

from .conftest import REPO


def test_hub_channels_exactly_once_through_faults(tmp_path: Any) -> None:
    seconds = float(os.environ.get("HUBWIRE_SOAK_HUB_SECONDS", "20"))
    r = run_hub_soak(seconds=seconds, seed=int(os.environ.get("HUBWIRE_SOAK_SEED", "1")), workdir=str(tmp_path))
    text = json.dumps(r, indent=1)
    print(text)
    out = os.path.join(REPO, "build", "reliability")
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(out, "soak-hub-last.json"), "w") as fh:
        fh.write(text + "\n")
    assert check_hub_soak(r) == []
    # the link really was faulty both ways, and the faults reached the new frames
    for d in ("h2d", "d2h"):
        p = r["proxy"][d]
        assert p["bits_flipped"] > 0 and p["bytes_dropped"] > 0 and p["garbage_bursts"] > 0, p
    assert r["hub"]["device_duplicates"] > 0 and r["hub"]["hub_event_retries"] > 0
    dev = r["device"]
    assert dev["writes_acked"] > 100 and dev["calls_answered"] > 20 and dev["reads"] > 10
    assert r["ticks"] > 200


def test_the_check_sees_each_kind_of_failure() -> None:
    good = {"applied_twice": 0, "acked_not_applied": 0, "applied_never_sent": 0, "called_twice": 0,
            "reads_never_produced": 0, "events_pending": 0, "device": {"calls_wrong": 0},
            "ticks": 5, "events_notified": 5, "ticks_in_order": True}
    assert check_hub_soak(good) == []
    for key in ("applied_twice", "acked_not_applied", "applied_never_sent", "called_twice",
                "reads_never_produced", "events_pending"):
        assert any(key in b for b in check_hub_soak(dict(good, **{key: 1}))), key
    assert check_hub_soak(dict(good, device={"calls_wrong": 1}))
    assert check_hub_soak(dict(good, ticks=4))
    assert check_hub_soak(dict(good, ticks_in_order=False))


def test_the_per_boot_hub_check_sees_each_kind_of_failure() -> None:
    from hubwire.testing.faultlink.soak_hub import check_hub_boots

    dev = {"tally_token": 8, "tally_acked": 7, "tally_failed": 1, "bump_ok": 2, "bump_wrong": 0, "bump_failed": 0,
           "ticks": 5, "tick_first": 1, "tick_last": 5, "tick_twice": 0, "tick_gaps": 0, "last_hub_failure": 0,
           "hub_queued_now": 0}
    boot = {"device": dev, "notified": 5, "pending": 0, "applied": 8, "applied_twice": 0, "applied_never_sent": 0,
            "called": 2, "called_twice": 0, "called_never_sent": 0}
    second = dict(boot, device=dict(dev, tick_first=6, tick_last=9, ticks=4), notified=9)
    assert check_hub_boots([boot, second]) == []
    broken = [
        dict(boot, applied_twice=1), dict(boot, applied_never_sent=1), dict(boot, called_twice=1),
        dict(boot, applied=6),                                   # an acked token never applied
        dict(boot, device=dict(dev, tally_acked=6)),            # a write neither acked nor failed
        dict(boot, device=dict(dev, bump_wrong=1, bump_ok=1)),  # a wrong answer accepted
        dict(boot, device=dict(dev, tick_twice=1)), dict(boot, device=dict(dev, tick_gaps=1)),
        dict(boot, pending=1),
    ]
    for b in broken:
        assert check_hub_boots([b, second]), b
    assert check_hub_boots([boot, dict(second, device=dict(second["device"], tick_first=7, ticks=3))])
    assert check_hub_boots([boot, dict(second, notified=10)])   # the last event never arrived
