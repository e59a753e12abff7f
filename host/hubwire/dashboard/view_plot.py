"""The page's one plot: the channels the user picked (from any board) on one shared time axis, with a
window, the rate of the plotted channels, zoom (mouse wheel or the slider under it), pause and CSV of
what is plotted.

Time labels are spaced by ECharts and any that would overlap a neighbour is hidden (a time axis
packs labels every few seconds whatever the width, which made them run together on narrow plots)."""
from __future__ import annotations

import json
import time
from typing import Any, Callable, Dict, List, Optional, Set, Tuple

from nicegui import ui

from .attrs import tag
from .model import RATES, ChannelRecord, decimate, merge_csv

__all__ = ["PlotPanel", "WINDOWS", "PLOT_POINTS"]

#: plot windows offered, s (the history holds model.HISTORY_S)
WINDOWS = {"10 s": 10.0, "1 min": 60.0, "5 min": 300.0}
#: points drawn per line at most (the CSV has every sample)
PLOT_POINTS = 400

_OPTIONS: Dict[str, Any] = {
    "animation": False,
    "grid": {"left": 50, "right": 50, "top": 34, "bottom": 58},
    "tooltip": {"trigger": "axis"},
    "legend": {"type": "scroll", "top": 0},
    "xAxis": {"type": "time", "axisLabel": {"hideOverlap": True}, "splitNumber": 4},
    "yAxis": [{"type": "value", "scale": True}],
    "dataZoom": [{"type": "inside", "filterMode": "none"},
                 {"type": "slider", "height": 16, "bottom": 6, "filterMode": "none", "showDetail": False}],
    "series": [],
}


class PlotPanel:
    """One chart of every picked channel; ``lookup("board.channel")`` gives its record (None when the
    board is gone or has no such channel now)."""

    def __init__(self, lookup: Callable[[str], Optional[ChannelRecord]],
                 set_rate: Optional[Callable[[str, float], None]] = None) -> None:
        self.lookup = lookup
        self.set_rate = set_rate
        self.picks: Set[str] = set()
        #: True until the user picks or unpicks a channel: boards that come add their first channels
        self.auto = True
        self.window = 60.0
        self.paused = False
        self._drawn: Any = None
        self._parts: List[Tuple[List[str], List[float], List[Tuple[float, ...]]]] = []
        with tag(ui.card().classes("w-full p-2 gap-1"), plot="main"):
            with ui.row().classes("w-full items-center gap-x-3 gap-y-0"):
                ui.label("Plot").classes("font-bold")
                self.hint = ui.label("").classes("text-xs text-gray-500 grow")
                if set_rate is not None:
                    tag(ui.select({r: f"{r} Hz" for r in RATES}, label="rate", on_change=lambda e: self._rate(e.value)),
                        "dense", "options-dense", rate="main").classes("w-20") \
                        .tooltip("samples a second of the plotted channels (values read now and then: 10 at most)")
                tag(ui.select(list(WINDOWS), value="1 min", on_change=lambda e: self._set_window(WINDOWS[str(e.value)])),
                    "dense", "options-dense", window="main").classes("w-20")
                tag(ui.switch("pause", on_change=lambda e: self._pause(bool(e.value))), "dense", pause="main")
                tag(ui.button("all", on_click=self._unzoom), "flat", "dense", "no-caps", unzoom="main") \
                    .tooltip("show the whole window (zoom with the mouse wheel or the slider)")
                tag(ui.button("CSV", on_click=self._csv), "flat", "dense", csv="main") \
                    .tooltip("every sample plotted in the window, one column per line")
            self.chart = ui.echart(dict(_OPTIONS)).classes("w-full").style("height: clamp(220px, 40vh, 560px)")

    def pick(self, key: str, on: bool) -> None:
        """Plot ``key`` ("board.channel") or stop plotting it (from a row's box)."""
        self.auto = False
        (self.picks.add if on else self.picks.discard)(key)
        self._drawn = None

    def offer(self, keys: List[str]) -> None:
        """A board's first channels, plotted while the user has picked nothing."""
        if self.auto and not self.picks:
            self.picks.update(keys)
            self._drawn = None

    def _rate(self, hz: Any) -> None:
        if hz is None or self.set_rate is None:
            return
        for key in sorted(self.picks):
            self.set_rate(key, float(hz))

    def _set_window(self, seconds: float) -> None:
        self.window = seconds
        self._drawn = None

    def _pause(self, on: bool) -> None:
        self.paused = on
        self._drawn = None

    def _unzoom(self) -> None:
        self.chart.run_chart_method("dispatchAction", {"type": "dataZoom", "start": 0, "end": 100})

    def refresh(self) -> None:
        if self.paused:
            return
        recs = [(k, r) for k, r in ((k, self.lookup(k)) for k in sorted(self.picks)) if r is not None]
        state = (tuple((k, r.at) for k, r in recs), self.window)
        self.hint.set_text("" if self.picks else "tick the box beside a channel to plot it")
        if state == self._drawn:
            return
        self._drawn = state
        now = time.time()
        boards = {k.split(".", 1)[0] for k, _ in recs}
        units: List[str] = []
        for _, r in recs:
            if (r.channel.unit or "") not in units:
                units.append(r.channel.unit or "")
        series: List[Dict[str, Any]] = []
        self._parts = []
        for key, rec in recs:
            times, rows = rec.window(self.window, now)
            prefix = key.split(".", 1)[0] + "." if len(boards) > 1 else ""
            cols = [prefix + c for c in rec.columns]
            self._parts.append((cols, times, rows))
            idx = decimate(times, rows, PLOT_POINTS)
            stamps = [round(times[i] * 1000) for i in idx]
            axis = 0 if (rec.channel.unit or "") == units[0] else 1
            series += [{"type": "line", "name": col, "showSymbol": False, "yAxisIndex": axis,
                        "data": list(zip(stamps, (rows[i][c] for i in idx)))} for c, col in enumerate(cols)]
        y = [{"type": "value", "scale": True, "name": units[0] if units else ""}]
        if len(units) > 1:
            y.append({"type": "value", "scale": True, "name": " / ".join(u for u in units[1:] if u),
                      "splitLine": {"show": False}})
        option = {"xAxis": {"min": round((now - self.window) * 1000), "max": round(now * 1000)},
                  "yAxis": y, "series": series}
        # sent as JSON text for the browser to evaluate: NiceGUI neither wraps nor walks the points;
        # series and axes replaced, so that an unpicked channel's lines go
        self.chart.run_chart_method(":setOption", json.dumps(option, separators=(",", ":")),
                                    '{"replaceMerge":["series","yAxis"]}')

    def _csv(self) -> None:
        # what is plotted now (frozen while paused)
        ui.download.content(merge_csv(self._parts).encode(), "hubwire-plot.csv", "text/csv")
