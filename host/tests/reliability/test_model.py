"""Exactly once for every message kind, for any traffic mix (hubwire.testing.faultlink.model has the
planner, model_run the run, model_count the counts and claims).

The real hub against the soak sketch (extras/tests/Soak) in its emulator, through the in-process
fault transport: a seeded stream of bursts (1..300 messages of one kind, aimed half the time so
that a kind's next message comes 128, 256 or one either side seqs after its last) of every kind in
both directions, some under faults. 0 lost after an ACK, 0 applied twice, 0 torn, 0 corrupt,
counted on both ends.

Bounded by default (HUBWIRE_MODEL_BURSTS, default 100; seed HUBWIRE_MODEL_SEED, default 9).
Long mode: HUBWIRE_MODEL_WRAPS=100 plays until every kind sent 100 x 256 messages and writes
build/reliability/model-wraps<N>-seed<S>.json (``make soak`` runs it).
"""
from __future__ import annotations

import json
import os
from typing import Any, Dict

import pytest

from hubwire.testing.faultlink.model import DEVICE_KINDS, HUB_KINDS, KINDS, Burst, Planner
from hubwire.testing.faultlink.model_count import check_run, summary
from hubwire.testing.faultlink.model_run import run_model
from hubwire.testing.faultlink.soak import soak_emulator_binary

from .conftest import REPO


def test_every_kind_exactly_once_in_any_mix(tmp_path: Any) -> None:
    binary = soak_emulator_binary()
    if not os.access(binary, os.X_OK):
        pytest.fail(f"soak emulator not found at {binary}: build it with `make emulator`", pytrace=False)
    seed = int(os.environ.get("HUBWIRE_MODEL_SEED", "9"))
    wraps = float(os.environ["HUBWIRE_MODEL_WRAPS"]) if os.environ.get("HUBWIRE_MODEL_WRAPS") else None
    bursts = None if wraps else int(os.environ.get("HUBWIRE_MODEL_BURSTS", "100"))
    r = run_model(seed=seed, bursts=bursts, wraps=wraps, workdir=str(tmp_path), binary=binary)
    text = json.dumps(r, indent=1)
    out = os.path.join(REPO, "build", "reliability")
    os.makedirs(out, exist_ok=True)
    name = f"model-wraps{wraps:g}-seed{seed}.json" if wraps else "model-last.json"
    with open(os.path.join(out, name), "w") as fh:
        fh.write(text + "\n")
    print(json.dumps({k: r[k] for k in ("seed", "bursts", "seconds", "kinds", "per_kind", "faults_injected",
                                        "hub_counter_wraps", "device_counter_wraps")}, indent=1))
    again = (f"HUBWIRE_MODEL_SEED={seed} " + (f"HUBWIRE_MODEL_WRAPS={wraps:g}" if wraps else f"HUBWIRE_MODEL_BURSTS={bursts}")
             + " .venv/bin/python -m pytest host/tests/reliability/test_model.py -k any_mix -s")
    assert r["failures"] == [], (f"seed {seed} ({again}; the plan is in {name}): "
                                 + "; ".join(r["failures"][:12]))
    # the run really was a mix: every kind played, the counters wrapped, faults went in
    assert all(r["kinds"][k]["messages"] > 0 for k in KINDS), r["kinds"]
    assert r["hub_counter_wraps"] >= 4 and r["device_counter_wraps"] >= 2, r
    assert sum(r["faults_injected"].values()) > 0 and r["link"]["faults"] > 0
    if wraps:
        assert all(r["kinds"][k]["messages"] >= wraps * 256 for k in KINDS), r["kinds"]


def test_the_planner_is_reproducible_and_aims_at_the_counters_edges() -> None:
    def play(seed: int) -> Any:
        p = Planner(seed)
        hub_seq, count, out = 0, 0, []
        hub_last: Dict[str, int] = {}
        dev_last: Dict[str, int] = {}
        for _ in range(300):
            b = p.next(hub_seq, hub_last, count, dev_last)
            out.append(str(b))
            if b.kind in HUB_KINDS:
                before = hub_last.get(b.kind)
                if b.aimed.startswith("target@") and before is not None:
                    assert (hub_seq + 1 - before) % 256 == int(b.aimed.split("@")[1]) % 256, (b, hub_seq, before)
                hub_seq = (hub_seq + b.n) % 256
                hub_last[b.kind] = hub_seq
            else:
                count += b.n
                dev_last[b.kind] = count
        return out

    plan = play(11)
    assert plan == play(11) and plan != play(12)
    assert any("target@256" in s for s in plan) and any("target@129" in s for s in plan)
    kinds = {s.split()[0] for s in plan}
    assert kinds == set(KINDS)
    assert any("[clean]" not in s for s in plan)
    assert set(DEVICE_KINDS) <= kinds


def test_the_run_check_names_each_kind_of_failure() -> None:
    seg = {"tokens_sent": 10, "first_sent": 1, "last_sent": 10, "acked": 10, "timeouts": 0, "link_lost_errors": 0,
           "not_linked": 0, "events_queued": 4, "selftest_timeouts": 0, "events_delivered": 4,
           "event_seq_repeated": 0, "event_order_ok": True,
           "device": {"tokens_applied": 10, "twice": 0, "gaps": 0, "first_token": 1, "last_token": 10}}
    mis = {"started": 3, "start_unknown": 0, "busy": 0, "succeeded": 3, "failed": 0, "cancelled": 0, "lost": 0,
           "lost_by_reboot": 0, "duplicated": 0, "corrupt": 0, "progress": 9, "device_starts": 3}
    boot = {"tokens": seg, "missions": mis, "stale_reads": 0, "bad_reads": 0, "reads": 5, "naks": 0,
            "chunk_corrupt": 0, "chunks": 3}
    dev = {"tally_token": 8, "tally_acked": 8, "tally_failed": 0, "bump_ok": 2, "bump_wrong": 0, "bump_failed": 0,
           "ticks": 5, "tick_first": 1, "tick_last": 5, "tick_twice": 0, "tick_gaps": 0, "last_hub_failure": 0,
           "hub_queued_now": 0}
    hub = {"device": dev, "notified": 5, "pending": 0, "applied": 8, "applied_twice": 0, "applied_never_sent": 0,
           "called": 2, "called_twice": 0, "called_never_sent": 0}
    blob = {"sent": 3, "acked": 3, "unacknowledged": 0, "applied": 3, "device_corrupt": 0, "twice": 0, "gaps": 0,
            "last_sent": 3, "held": 3, "held_intact": True, "reads": 2, "bad_reads": 0, "read_failures": 0,
            "naks": 0, "lost": 0, "duplicated": 0, "corrupt": 0}
    good = {"boots": [boot], "blobs": [blob], "hub_channels": [hub]}
    assert check_run(good) == [] and all(v == {"lost": 0, "twice": 0, "corrupt": 0} for v in summary(good).values())

    def broken(kind: str, what: str, **change: Any) -> None:
        r = json.loads(json.dumps(good))
        for path, v in change.items():
            d = r
            keys = path.split("__")
            for k in keys[:-1]:
                d = d[k][0] if isinstance(d[k], list) else d[k]
            d[keys[-1]] = v
        assert check_run(r), change
        assert summary(r)[kind][what] > 0, (kind, what, summary(r))

    broken("write", "lost", boots__tokens__device__tokens_applied=9, boots__tokens__device__gaps=1)
    broken("write", "twice", boots__tokens__device__twice=1, boots__tokens__device__tokens_applied=11)
    broken("read", "lost", boots__stale_reads=1)
    broken("read", "corrupt", boots__bad_reads=1)
    broken("chunk", "corrupt", boots__chunk_corrupt=1)
    broken("device_event", "lost", boots__tokens__events_delivered=3)
    broken("device_event", "twice", boots__tokens__event_seq_repeated=1)
    broken("mission", "lost", boots__missions__lost=1)
    broken("mission", "twice", boots__missions__device_starts=4)
    broken("mission", "corrupt", boots__missions__corrupt=1)
    broken("blob", "corrupt", blobs__corrupt=1)
    broken("blob", "lost", blobs__lost=1)
    broken("hub_event", "lost", hub_channels__device__ticks=4, hub_channels__device__tick_gaps=1,
           hub_channels__device__tick_last=5)
    broken("hub_event", "twice", hub_channels__device__tick_twice=1, hub_channels__device__ticks=6)
    broken("device_write", "lost", hub_channels__applied=7)
    broken("device_write", "twice", hub_channels__applied_twice=1)
    broken("device_write", "corrupt", hub_channels__device__bump_wrong=1, hub_channels__device__bump_ok=1)


def test_a_burst_prints_what_it_was() -> None:
    assert str(Burst("read", 255, "drop", aimed="hub_event@256")) == "read x255 [drop] aimed hub_event@256"
