"""A mission on the page (PROTOCOL.md 11): a start form with the goal's field (from its declared type
and range), a progress bar against the declared progress at completion, a cancel button, the run's
status and its result.

Runs go through the service's one table (:mod:`hubwire.daemon.mission_runs`), so the page shows
the latest run of the mission whoever started it (this page, another tab, `hubwire call`, MQTT),
and a start here is followed by MQTT and socket clients the same way.

Elements carry ``data-hw-*`` attributes with ``<board key>.<mission>``: ``goal``, ``start``,
``cancel``, ``progress`` (its ``data-hw-fraction`` 0..1), ``progress-value``, ``run`` (status
text, ``data-hw-run-status``), ``mission-result`` and ``mission-error``.
"""
from __future__ import annotations

from typing import Any, Optional, Tuple

from nicegui import ui

from ..descriptor import Channel
from ..errors import HubwireError
from ..daemon.mission_ops import outcome_json
from ..daemon.mission_runs import MissionRuns, RunEntry, runs_of
from .attrs import tag
from .feed import BoardFeed, outcome_text
from .model import fmt_value, is_integer, range_hint

__all__ = ["MissionView"]


def _numeric(codec: Any) -> bool:
    return codec is not None and codec.kind == "scalar" and codec.scalar not in ("bool",)


class MissionView:
    """Start form, progress bar, cancel button and result of mission ``ch`` of ``feed``'s board."""

    def __init__(self, feed: BoardFeed, ch: Channel, fleet: Any) -> None:
        self.feed, self.ch, self.fleet = feed, ch, fleet
        self.runs: MissionRuns = runs_of(fleet)
        a = self.key = f"{feed.key}.{ch.name}"
        self.unit = f" {ch.unit}" if ch.unit else ""
        self._shown: Optional[Tuple[str, int, str]] = None
        with ui.column().classes("gap-1 w-full"):
            with ui.row().classes("items-center gap-2"):
                self.goal: Any = None
                if ch.codec.kind != "void":
                    label = f"goal ({ch.codec.name}{self.unit.rstrip()})"
                    if _numeric(ch.codec):
                        if range_hint(ch):
                            label = f"{label[:-1]}, {range_hint(ch)})"
                        self.goal = ui.number(label=label, format="%d" if is_integer(ch) else None).classes("w-48")
                    else:
                        self.goal = ui.input(label=label + ", as JSON").classes("w-64")
                    tag(self.goal, "dense", goal=a)
                    self.goal.on("keydown.enter", self._start)
                tag(ui.button("start", on_click=self._start), "dense", start=a)
                self.cancel = tag(ui.button("cancel", on_click=self._cancel), "dense", "outline", cancel=a)
                self.cancel.disable()
            self.bar = tag(ui.linear_progress(value=0.0, show_value=False).classes("w-full"), progress=a, fraction=0)
            with ui.row().classes("items-baseline gap-3 text-sm"):
                self.status = tag(ui.label("no run yet").classes("text-gray-600"), run=a, run_status="")
                self.value = tag(ui.label("").classes("font-mono"), progress_value=a)
                self.result = tag(ui.label("").classes("font-mono"), mission_result=a)
            self.error = tag(ui.label("").classes("text-xs text-red-700"), mission_error=a)

    # ------------------------------------------------------------------------------ actions

    async def _start(self) -> None:
        goal: Any = None
        if self.goal is not None:
            raw = self.goal.value
            try:
                if _numeric(self.ch.codec):
                    if raw is None:
                        raise HubwireError("give a goal first")
                    goal = int(raw) if is_integer(self.ch) and float(raw).is_integer() else float(raw)
                else:
                    goal = self.ch.codec.parse_text(str(raw or ""))
            except (HubwireError, ValueError) as e:
                self._error(outcome_text(e))
                return
        self._error("")
        try:
            await self.runs.start(self.fleet, self.feed.key, self.ch.name, goal)
        except HubwireError as e:  # refused (BUSY, REJECTED, out of range) or the link is down
            self._error(outcome_text(e))
        self.refresh()

    async def _cancel(self) -> None:
        e = self._latest()
        if e is None or e.job is None or e.done:
            return
        try:
            await e.job.cancel()
        except HubwireError as err:
            self._error(outcome_text(err))
        self.refresh()

    def _error(self, text: str) -> None:
        self.error.set_text(text)

    # ------------------------------------------------------------------------------ drawing

    def _latest(self) -> Optional[RunEntry]:
        """The mission's latest run that reached the board (a refused start is shown as an error)."""
        for e in reversed(self.runs.of_board(self.feed.key)):
            if e.mission == self.ch.name and e.job is not None:
                return e
        return None

    def refresh(self, on_screen: bool = True) -> None:
        e = self._latest()
        if e is None or not on_screen:
            return
        rec = e.job._rec
        now = (e.run_id, rec.received, rec.status)
        if now == self._shown:
            return
        self._shown = now
        last = rec.progress[-1] if rec.progress else None
        self.status.set_text(f"run {rec.run} ({e.run_id}): {rec.status}")
        tag(self.status, run_status=rec.status)
        self.value.set_text("" if last is None else fmt_value(last) + self.unit)
        pmax = self.ch.progress_max
        frac = 0.0
        if rec.status == "succeeded":
            frac = 1.0
        elif pmax and _numeric(self.ch.progress) and isinstance(last, (int, float)):
            frac = max(0.0, min(1.0, float(last) / float(pmax)))
        self.bar.set_value(frac)
        tag(self.bar, fraction=f"{frac:.3g}")
        self.bar.update()
        if rec.done:
            o = outcome_json(e)
            self.result.set_text(("-> " + fmt_value(o.get("value")) + self.unit) if rec.status == "succeeded"
                                 else str(o.get("message", rec.status)))
            self.cancel.disable()
        else:
            self.result.set_text("")
            self.cancel.enable()
        self.status.update()
