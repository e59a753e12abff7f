"""What the model-based test (:mod:`.model_run`) counts per device boot, and its claims.

Both ends count. The soak sketch (extras/tests/Soak) counts on the device how each hub write of
``token`` and ``blob``, each hub event ``tick`` and each of its own writes to the hub (``tally``,
``bump``) went; the hub side counts what it sent, what it saw acknowledged, the device events and
mission updates it delivered and what its ``tally``/``bump`` handlers ran. A boot is settled on a
clean link (:meth:`Boot.close`), with the soak's own per-boot checks (:func:`.soak_load.check_segment`,
:func:`.soak_large.check_blob_boot`, :func:`.soak_hub.check_hub_boots`) plus the model's.
"""
from __future__ import annotations

import threading
import time
from typing import Any, Callable, Dict, List

from .soak_large import check_blob_boot
from .soak_load import check_segment, retry, wait_for

__all__ = ["Boot", "Missions", "check_run", "summary"]

FAIL_GOAL, FAIL_CODE = 999, 9
#: a mission goal that cannot end by itself within a burst (cancelled, or cut short by a reboot)
LONG_GOAL = 4000


class Missions:
    """The ``count`` runs of one boot: started, ended how, and what the progress looked like."""

    def __init__(self, log: Callable[[str], None]) -> None:
        self.log = log
        self.jobs: List[Any] = []  # (job, goal, cancelled) still to settle
        self.c = {k: 0 for k in ("started", "start_unknown", "busy", "succeeded", "failed", "cancelled", "lost",
                                 "lost_by_reboot", "duplicated", "corrupt", "progress", "device_starts")}

    def add(self, job: Any, goal: int, cancel: bool) -> None:
        self.c["started"] += 1
        self.jobs.append([job, goal, cancel])

    def settle(self, seconds: float = 5.0) -> None:
        import hubwire

        for job, goal, cancel in self.jobs:
            if cancel and not job.done():  # a cancel that timed out: again, on the clean link
                try:
                    job.cancel()
                except hubwire.HubwireError:
                    pass
            end = time.monotonic() + seconds + goal * 0.01 * (not cancel)
            while not job.done() and time.monotonic() < end:
                time.sleep(0.005)
            self._progress(job, goal)
            if not job.done():
                self.c["lost"] += 1
                self.log(f"model: mission run {job.run} (goal {goal}) never ended: its final was lost")
                continue
            try:
                r = job.result(timeout=0)
                ok = goal not in (FAIL_GOAL, LONG_GOAL) and r == goal * 1000 + job.run
                self.c["succeeded" if ok else "corrupt"] += 1
            except hubwire.MissionFailed as e:
                self.c["failed" if goal == FAIL_GOAL and e.code == FAIL_CODE else "corrupt"] += 1
            except hubwire.MissionCancelled:
                self.c["cancelled" if cancel else "corrupt"] += 1
            except hubwire.MissionLost:
                self.c["lost"] += 1
        self.jobs = []

    def _progress(self, job: Any, goal: int) -> None:
        items, _ = job._rec.progress_from(0)  # every value the hub took, in order
        last = 0
        for v in items:
            self.c["progress"] += 1
            if v <= last:
                self.c["duplicated"] += 1
            elif v >= goal or (goal == FAIL_GOAL and v >= 3):
                self.c["corrupt"] += 1
            last = v


class Boot:
    """The hub's counts for one device boot."""

    def __init__(self, first_token: int, log: Callable[[str], None]) -> None:
        self.seg: Dict[str, Any] = {"tokens_sent": 0, "first_sent": first_token, "last_sent": first_token - 1,
                                    "acked": 0, "timeouts": 0, "link_lost_errors": 0, "not_linked": 0,
                                    "events_queued": 0, "selftest_timeouts": 0}
        self.last_acked = 0  # the last token acknowledged: a read below it is a write lost
        self.batches: List[int] = []
        self.events: List[Any] = []
        self.lock = threading.Lock()
        self.missions = Missions(log)
        self.x = {"stale_reads": 0, "bad_reads": 0, "reads": 0, "naks": 0, "chunk_corrupt": 0, "chunks": 0}

    def on_event(self, ev: Any) -> None:
        with self.lock:
            self.events.append((ev.seq, ev.value))

    def close(self, dev: Any, token: int, reboot: bool) -> Dict[str, Any]:
        """On a clean link: every queued thing in, one last acknowledged token, the device's counts."""
        import hubwire

        self.missions.settle()
        seg = self.seg
        end = time.monotonic() + 60
        while True:  # the link is clean: should a write still fail, the next token is the last
            if time.monotonic() > end:
                raise RuntimeError("no token write was acknowledged on the clean link for 60 s")
            token += 1
            seg["tokens_sent"] += 1
            seg["last_sent"] = token
            wait_for(lambda: dev.state == "ready", 30)
            try:
                dev.token = token
                seg["acked"] += 1
                break
            except hubwire.Timeout:
                seg["timeouts"] += 1
            except hubwire.LinkLost:
                seg["link_lost_errors"] += 1
        wait_for(lambda: len(self.events) >= seg["events_queued"], 15)
        time.sleep(0.3)  # an event delivered twice would come in now
        names = ("tokens_applied", "twice", "gaps", "first_token", "last_token")
        seg["device"] = {n: retry(lambda: getattr(dev, n), f"read {n}") for n in names}
        with self.lock:
            evs = list(self.events)
        expected = [i % 2 == 0 for q in self.batches if q >= 0 for i in range(q)]
        seg["events_delivered"] = len(evs)
        seg["event_seq_repeated"] = sum(1 for a, b in zip(evs, evs[1:]) if a[0] == b[0])
        seg["event_order_ok"] = seg["selftest_timeouts"] > 0 or [v for _, v in evs] == expected
        self.missions.c["device_starts"] = retry(lambda: dev.missionStarts, "read missionStarts")
        return {"tokens": seg, "missions": dict(self.missions.c), **self.x, "token": token, "reboot": reboot}


def check_run(r: Dict[str, Any]) -> List[str]:
    """Every claim of the model run that does not hold (empty: exactly once everywhere)."""
    from .soak_hub import check_hub_boots

    bad: List[str] = []
    for i, b in enumerate(r["boots"]):
        where = f"boot {i + 1}"
        bad += check_segment(i, b["tokens"])
        for k in ("stale_reads", "bad_reads", "naks", "chunk_corrupt"):
            if b[k]:
                bad.append(f"{where}: {b[k]} {k}")
        mc = b["missions"]
        for k in ("lost", "duplicated", "corrupt"):
            if mc[k]:
                bad.append(f"{where}: missions {k} {mc[k]}")
        if not mc["started"] <= mc["device_starts"] <= mc["started"] + mc["start_unknown"]:
            bad.append(f"{where}: the board counted {mc['device_starts']} mission starts, the hub "
                       f"{mc['started']} (+{mc['start_unknown']} unknown)")
    for i, b in enumerate(r["blobs"]):
        bad += check_blob_boot(i, b)
    bad += check_hub_boots(r["hub_channels"])
    return bad


def summary(r: Dict[str, Any]) -> Dict[str, Dict[str, int]]:
    """Per message kind: lost after an ACK, applied twice, corrupt or torn (all must be 0)."""
    s: Dict[str, Dict[str, int]] = {}

    def add(kind: str, **v: int) -> None:
        d = s.setdefault(kind, {"lost": 0, "twice": 0, "corrupt": 0})
        for k, n in v.items():
            d[k] += max(0, n)

    for b in r["boots"]:
        t, d = b["tokens"], b["tokens"]["device"]
        unknown = t["timeouts"] + t["link_lost_errors"] + t["not_linked"]
        never = d["gaps"] + d["first_token"] - t["first_sent"]
        add("write", lost=never - unknown, twice=d["twice"])
        add("read", lost=b["stale_reads"], corrupt=b["bad_reads"])
        add("chunk", corrupt=b["chunk_corrupt"])
        hi = t["events_queued"] + 4 * t["selftest_timeouts"]
        add("device_event", lost=t["events_queued"] - t["events_delivered"],
            twice=t["event_seq_repeated"] + t["events_delivered"] - hi)
        mc = b["missions"]
        add("mission", lost=mc["lost"], twice=mc["duplicated"] + mc["device_starts"] - mc["started"] - mc["start_unknown"],
            corrupt=mc["corrupt"])
    for b in r["blobs"]:
        add("blob", lost=b["lost"], twice=b["duplicated"], corrupt=b["corrupt"])
    for h in r["hub_channels"]:
        c = h["device"]
        add("hub_event", twice=c["tick_twice"])
        add("device_write", lost=c["tally_acked"] - h["applied"] + c["bump_ok"] - h["called"],
            twice=h["applied_twice"] + h["called_twice"], corrupt=h["applied_never_sent"] + c["bump_wrong"])
    if r["hub_channels"]:  # every event notified arrived once: what did not is lost
        hc = r["hub_channels"]
        add("hub_event", lost=hc[-1]["notified"] - sum(h["device"]["ticks"] - h["device"]["tick_twice"] for h in hc))
    return s
