"""Missions in the soak: the hub runs the soak sketch's ``count`` mission over and over through the
faults and counts every run: started, finished, failed, cancelled, lost, duplicated, corrupt.

The sketch (extras/tests/Soak): ``count`` takes a u16 goal ``n``, reports progress 1, 2, ... below
``n`` (latest wins: the hub may see a subset, never one twice nor out of order) and finishes with
``n * 1000 + run``; a goal of 999 fails with code 9 at step 3; a goal of 0 is refused. Its readable
``missionStarts`` counts the starts it accepted, so a start applied twice shows on the device.

- **lost**: a run that ended ``MissionLost`` without a reboot, or did not end at all;
- **duplicated**: a progress value not above the one before it, or a start the device counted twice;
- **corrupt**: a result, failure code or progress value other than the sketch's rule gives.
"""
from __future__ import annotations

import time
from typing import Any, Callable, Dict, List, Optional

__all__ = ["MissionTraffic", "check_missions", "FAIL_GOAL", "FAIL_CODE"]

FAIL_GOAL, FAIL_CODE = 999, 9
GOALS = (3, 8, 20, FAIL_GOAL, 40, 5, 60)  # steps of >= 5 ms: a run lasts 15 ms .. 0.3 s on the board
CANCEL_EVERY, CANCEL_GOAL = 5, 400  # every 5th run is a long one, cancelled once it reported progress
#: a long run the reboot cuts short (it cannot end before the board is killed)
LONG_GOAL = 4000
#: seconds a run may take on the clean link before it counts as lost
SETTLE_S = 30.0


class MissionTraffic:
    """The mission load of one soak run; ``step`` is called between the other loads' steps."""

    def __init__(self, log: Callable[[str], None]) -> None:
        self.log = log
        self.enabled = False
        self.job: Any = None
        self.goal = 0
        self.seen = 0  # progress values read of the current job
        self.last = 0  # the last progress value
        self.cancelling = False
        self.n = 0  # runs started in all
        self.counts: Dict[str, int] = {k: 0 for k in (
            "started", "succeeded", "failed", "cancelled", "lost", "lost_by_reboot", "duplicated", "corrupt",
            "busy", "start_unknown", "cancel_unknown", "progress")}
        self.boots: List[Dict[str, Any]] = []
        self.boot: Dict[str, Any] = {}

    # ------------------------------------------------------------------------------ boots

    def start(self, dev: Any) -> None:
        """A new board session (first connect or after a reboot): count its starts afresh."""
        self.enabled = "count" in dev and dev.channel("count").mission
        self.boot = {"hub_starts": 0, "unknown": 0}

    def close_boot(self, dev: Any) -> None:
        """On a clean link: let the current run end, then compare the board's start count."""
        if not self.enabled:
            return
        if self.job is not None:
            self._settle(self.job)
        from .soak_load import retry

        device = retry(lambda: dev.missionStarts, "read missionStarts")
        self.boot["device_starts"] = device
        lo, hi = self.boot["hub_starts"], self.boot["hub_starts"] + self.boot["unknown"]
        if not lo <= device <= hi:
            self.counts["duplicated" if device > hi else "lost"] += 1
            self.log(f"soak: missions: the board counted {device} starts, the hub {lo} (+{self.boot['unknown']} unknown)")
        self.boots.append(dict(self.boot))

    def cut_by_reboot(self, dev: Any) -> Any:
        """Start a run too long to end before the board is killed; ``ended_by_reboot`` checks it."""
        if not self.enabled:
            return None
        from .soak_load import retry

        job = retry(lambda: dev.start("count", LONG_GOAL), "start a long mission")
        self.counts["started"] += 1
        return job

    def ended_by_reboot(self, job: Any) -> None:
        import hubwire

        if job is None:
            return
        try:
            job.result(timeout=SETTLE_S)
            self.counts["corrupt"] += 1  # a run of LONG_GOAL steps cannot have ended
        except hubwire.MissionLost:
            self.counts["lost_by_reboot"] += 1
        except hubwire.HubwireError as e:
            self.log(f"soak: missions: the run cut by the reboot ended with {e!r}")
            self.counts["lost"] += 1

    # ------------------------------------------------------------------------------ steps

    def step(self, dev: Any) -> None:
        import hubwire

        if not self.enabled or dev.state != "ready":
            return
        if self.job is None:
            self._start(dev)
            return
        job = self.job
        self._read_progress(job)
        if job.done():
            self._outcome(job)
            self.job = None
        elif self.n % CANCEL_EVERY == 0 and self.seen and not self.cancelling:
            self.cancelling = True
            try:
                job.cancel()
            except hubwire.HubwireError:  # Timeout / LinkLost: the board may or may not have it
                self.counts["cancel_unknown"] += 1

    def _start(self, dev: Any) -> None:
        import hubwire

        # a run to cancel is long enough to be cancelled while it runs (2 s on the board)
        goal = CANCEL_GOAL if (self.n + 1) % CANCEL_EVERY == 0 else GOALS[self.n % len(GOALS)]
        try:
            job = dev.start("count", goal)
        except hubwire.NakError as e:
            if e.error == "BUSY":  # a start that timed out earlier did start: its run is going
                self.counts["busy"] += 1
                return
            raise
        except (hubwire.Timeout, hubwire.LinkLost):
            self.boot["unknown"] += 1
            self.counts["start_unknown"] += 1
            return
        self.n += 1
        self.boot["hub_starts"] += 1
        self.counts["started"] += 1
        self.job, self.goal, self.seen, self.last, self.cancelling = job, goal, 0, 0, False

    def _read_progress(self, job: Any) -> None:
        rec = job._rec  # the values arrived so far, without waiting
        items, self.seen = rec.progress_from(self.seen)
        for v in items:
            self.counts["progress"] += 1
            if v <= self.last:
                self.counts["duplicated"] += 1
            elif v >= self.goal or (self.goal == FAIL_GOAL and v >= 3):
                self.counts["corrupt"] += 1
            self.last = v

    def _outcome(self, job: Any) -> None:
        import hubwire

        try:
            result = job.result(timeout=0)
        except hubwire.MissionFailed as e:
            ok = self.goal == FAIL_GOAL and e.code == FAIL_CODE
            self.counts["failed" if ok else "corrupt"] += 1
            return
        except hubwire.MissionCancelled:
            self.counts["cancelled" if self.cancelling else "corrupt"] += 1
            return
        except hubwire.MissionLost:
            self.counts["lost"] += 1
            return
        ok = self.goal != FAIL_GOAL and result == self.goal * 1000 + job.run
        self.counts["succeeded" if ok else "corrupt"] += 1

    def _settle(self, job: Any) -> None:
        end = time.monotonic() + SETTLE_S
        while not job.done() and time.monotonic() < end:
            self._read_progress(job)
            time.sleep(0.01)
        self._read_progress(job)
        if job.done():
            self._outcome(job)
        else:
            self.counts["lost"] += 1
        self.job = None

    def report(self) -> Optional[Dict[str, Any]]:
        if not self.enabled and not self.counts["started"]:
            return None
        return {**self.counts, "boots": self.boots}


def check_missions(m: Optional[Dict[str, Any]]) -> List[str]:
    """What went wrong with the missions of a soak report (empty: nothing)."""
    if m is None:
        return []
    bad = [f"missions: {m[k]} {k}" for k in ("lost", "duplicated", "corrupt") if m[k]]
    ended = m["succeeded"] + m["failed"] + m["cancelled"] + m["lost_by_reboot"]
    if ended != m["started"]:
        bad.append(f"missions: {m['started']} started, {ended} ended")
    if m["succeeded"] < 10 or m["failed"] < 1 or m["cancelled"] < 1:
        bad.append(f"missions: too few runs of each kind: {m['succeeded']} succeeded, {m['failed']} failed, "
                   f"{m['cancelled']} cancelled")
    if m["lost_by_reboot"] != 1:
        bad.append(f"missions: the reboot ended {m['lost_by_reboot']} runs, not 1")
    return bad
