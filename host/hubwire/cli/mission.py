"""``hubwire call PORT MISSION [GOAL]``: start a mission, show its progress (a tqdm bar against the
progress value at completion when the mission declares one, else one line per value), print its
result; Ctrl-C cancels the run on the board and says so."""
from __future__ import annotations

import argparse
import sys
from typing import Any, Optional

from .support import fmt_value, goal_or_argument, jsonable, print_json
from ..device import Device
from ..errors import MissionCancelled, MissionError, Timeout
from ..job import Job

__all__ = ["run_mission"]

#: seconds to wait for the board to confirm a cancel after Ctrl-C: within what a clean ending may take
#: (hubwire.cli.interrupt), leaving time to say how it ended and to close the link
CANCEL_WAIT = 0.8


class _Progress:
    """Where progress values go: a bar, plain lines, or JSON lines."""

    def __init__(self, job: Job, ch: Any, as_json: bool) -> None:
        self.job = job
        self.as_json = as_json
        self.bar: Any = None
        numeric = ch.progress is not None and ch.progress.kind == "scalar" and ch.progress.scalar != "bool"
        if ch.progress_max is not None and numeric and not as_json:
            from tqdm import tqdm

            unit = f" {ch.unit}" if ch.unit else ""
            self.bar = tqdm(total=ch.progress_max, file=sys.stderr, desc=f"{ch.name} run {job.run}",
                            bar_format="{desc}: {percentage:3.0f}%|{bar}| {n:.6g}/{total:.6g}" + unit)

    def show(self, value: Any) -> None:
        if self.bar is not None:
            self.bar.n = max(0.0, min(float(value), float(self.bar.total)))
            self.bar.refresh()
        elif self.as_json:
            print_json({"mission": self.job.mission, "run": self.job.run, "progress": jsonable(value)})
        else:
            print(f"{self.job.mission} run {self.job.run}: {fmt_value(value)}", flush=True)

    def complete(self) -> None:
        """The run succeeded: the bar shows it whole (a goal below pmax leaves it short otherwise)."""
        if self.bar is not None:
            self.bar.n = self.bar.total
            self.bar.refresh()

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def run_mission(dev: Device, args: argparse.Namespace) -> int:
    ch = dev.channel(args.action)
    job = dev.start(ch.name, goal_or_argument(ch, args.arg))
    progress: Optional[_Progress] = None
    try:  # from here on Ctrl-C cancels the run
        if not args.json:
            sys.stderr.write(f"hubwire: {ch.name} run {job.run} started (Ctrl-C cancels it)\n")
        progress = _Progress(job, ch, args.json)
        try:
            for value in job.feedback():
                progress.show(value)
            result = job.result()
            progress.complete()
        finally:
            progress.close()
    except KeyboardInterrupt:
        return _cancel(job, args.json)
    if args.json:
        print_json({"mission": job.mission, "run": job.run, "status": job.status, "result": jsonable(result)})
    elif result is not None:
        print(fmt_value(result))
    return 0


def _cancel(job: Job, as_json: bool) -> int:
    """Ctrl-C: cancel the run on the board, say how it ended; exit status 130."""
    was_running = job.cancel()
    outcome: Optional[str] = None
    try:
        job.result(timeout=CANCEL_WAIT)
        outcome = "it had already succeeded"
    except MissionCancelled:
        outcome = "cancelled on the board" if was_running else "it was cancelled"
    except MissionError as e:
        outcome = str(e)
    except Timeout:
        outcome = f"cancel sent; the board did not confirm it within {CANCEL_WAIT:g} s"
    except KeyboardInterrupt:
        outcome = None
    message = f"{job.mission} run {job.run}: " + (outcome or "cancel sent")
    if as_json:
        print_json({"mission": job.mission, "run": job.run, "status": job.status, "cancelled": was_running,
                    "message": message})
    else:
        sys.stderr.write(f"\nhubwire: {message}\n")
    return 130
