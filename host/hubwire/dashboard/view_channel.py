"""One channel on the page: its live value with unit, a plot for numbers, an input for a writable
one, a button for an action. Everything is chosen from the channel's descriptor entry.

Elements carry ``data-hw-*`` attributes (board key and channel name) so that tests and benchmarks
find them; ``data-hw-at`` on a value is the time its sample reached the hub (Unix ms)."""
from __future__ import annotations

import json
import time
from typing import Any, Dict, List, Optional

from nicegui import ui

from ..descriptor import Channel
from ..errors import HubwireError
from ..daemon.keys import safe_id
from .attrs import tag
from .feed import READ_MAX_HZ, BoardFeed, outcome_text
from .model import RATES, ChannelRecord, decimate, fmt_value, is_integer, plottable, to_csv, widget_for

__all__ = ["ValueView", "PlotView", "InputView", "ActionView", "WINDOWS"]

#: plot windows offered, s (the history holds model.HISTORY_S)
WINDOWS = {"10 s": 10.0, "1 min": 60.0, "5 min": 300.0}
#: points drawn per line at most (the CSV has every sample)
PLOT_POINTS = 400


def _attr(board: str, ch: str) -> str:
    return f"{board}.{ch}"


def _unit(ch: Channel) -> str:
    return f" {ch.unit}" if ch.unit else ""


class ValueView:
    """The latest value of a readable channel, with its unit."""

    def __init__(self, feed: BoardFeed, rec: ChannelRecord) -> None:
        self.rec = rec
        self._shown: Optional[float] = None
        ch = rec.channel
        self.key = _attr(feed.key, ch.name)
        self.label = tag(ui.label("-").classes("font-mono text-lg"), value=_attr(feed.key, ch.name))
        self.unit = _unit(ch)
        self.note = ui.label("").classes("text-xs text-gray-600")

    def refresh(self, on_screen: bool = True) -> None:
        rec = self.rec
        if not on_screen:
            self._shown = None  # shown afresh once scrolled to
            return
        note = rec.read if rec.read not in ("", "read") else ("" if rec.at is not None else rec.error or "")
        if self.note.text != note:
            self.note.set_text(note)
        if rec.at is None or rec.at == self._shown:
            return
        self._shown = rec.at
        self.label.set_text(fmt_value(rec.value) + self.unit)
        tag(self.label, at=f"{rec.at * 1000:.1f}")


class PlotView:
    """A plot of a channel's numbers over time: rate asked and achieved, window, pause, CSV."""

    def __init__(self, feed: BoardFeed, rec: ChannelRecord) -> None:
        self.feed, self.rec = feed, rec
        ch = rec.channel
        self.window = 60.0
        self.paused = False
        self._drawn_at: Optional[float] = None
        self._cols: List[str] = []
        self._data: Dict[str, Any] = {"times": [], "rows": [], "cols": []}
        with ui.row().classes("items-center gap-2 w-full"):
            rates = [r for r in RATES if ch.streamable or r <= READ_MAX_HZ]  # reads are round trips
            tag(ui.select({r: f"{r} Hz" for r in rates}, value=self._nearest(rec.rate), label="rate",
                          on_change=lambda e: feed.set_rate(ch.name, float(e.value))).classes("w-24"),
                "dense", rate=_attr(feed.key, ch.name))
            self.achieved = tag(ui.label("").classes("text-xs text-gray-600"), achieved=_attr(feed.key, ch.name))
            ui.select(list(WINDOWS), value="1 min", label="window",
                      on_change=lambda e: self._set_window(WINDOWS[str(e.value)])).classes("w-24").props("dense")
            tag(ui.switch("pause", on_change=lambda e: self._pause(bool(e.value))),
                "dense", pause=_attr(feed.key, ch.name))
            tag(ui.button("CSV", on_click=self._csv), "flat", "dense", csv=_attr(feed.key, ch.name))
        self.chart = ui.echart({
            "animation": False,
            "grid": {"left": 50, "right": 10, "top": 30, "bottom": 25},
            "tooltip": {"trigger": "axis"},
            "legend": {"type": "scroll", "top": 0},
            "xAxis": {"type": "time"},
            "yAxis": {"type": "value", "scale": True, "name": ch.unit or ""},
            "series": [],
        }).classes("w-full h-48")
        self.key = _attr(feed.key, ch.name)

    @staticmethod
    def _nearest(rate: float) -> int:
        return min(RATES, key=lambda r: abs(r - rate))

    def _set_window(self, seconds: float) -> None:
        self.window = seconds
        self._drawn_at = None

    def _pause(self, on: bool) -> None:
        self.paused = on
        self._drawn_at = None

    def refresh(self, on_screen: bool = True) -> None:
        rec = self.rec
        if not on_screen:
            self._drawn_at = None  # drawn afresh once scrolled to
            return
        self.achieved.set_text(f"{rec.achieved():.1f} Hz achieved")
        if self.paused or rec.at is None or rec.at == self._drawn_at:
            return
        self._drawn_at = rec.at
        times, rows = rec.window(self.window)
        self._data = {"times": times, "rows": rows, "cols": list(rec.columns)}
        idx = decimate(times, rows, PLOT_POINTS)
        stamps = [round(times[i] * 1000) for i in idx]
        series = [{"type": "line", "name": col, "showSymbol": False,
                   "data": list(zip(stamps, (rows[i][c] for i in idx)))} for c, col in enumerate(rec.columns)]
        # sent as one JSON text for the browser to evaluate: NiceGUI neither wraps nor walks the points
        self.chart.run_chart_method(":setOption", json.dumps({"series": series}, separators=(",", ":")))

    def _csv(self) -> None:
        d = self._data  # what is plotted now (frozen while paused)
        text = to_csv(d["cols"], d["times"], d["rows"])
        # a file name: only [A-Za-z0-9_-] of the key and channel
        ui.download.content(text.encode(), f"{safe_id(self.feed.key)}-{safe_id(self.rec.channel.name)}.csv", "text/csv")


class InputView:
    """An input for a writable channel, chosen by type and range; written on the device's ACK,
    put back (with the reason) on a NAK or a value the hub's checks refuse."""

    def __init__(self, feed: BoardFeed, ch: Channel) -> None:
        self.feed, self.ch = feed, ch
        self.key = _attr(feed.key, ch.name)
        self.kind = widget_for(ch)
        self.acked: Any = None
        self._quiet = False
        a = _attr(feed.key, ch.name)
        rec = feed.records.get(ch.name)
        start = rec.value if rec is not None else None
        with ui.row().classes("items-center gap-2 w-full"):
            if self.kind == "toggle":
                self.el: Any = ui.switch(value=bool(start), on_change=self._toggled)
            elif self.kind == "slider":
                step = 1.0 if is_integer(ch) else ((ch.max or 0) - (ch.min or 0)) / 100.0
                self.el = ui.slider(min=ch.min or 0, max=ch.max or 0, step=step,
                                    value=start if isinstance(start, (int, float)) else ch.min) \
                    .props("label-always").classes("w-64")
                self.el.on("change", lambda: self._apply(self.el.value))
            elif self.kind == "number":
                self.el = ui.number(value=start if isinstance(start, (int, float)) else None,
                                    min=ch.min, max=ch.max, format="%d" if is_integer(ch) else None).classes("w-32")
            else:
                self.el = ui.input(value="" if start is None else (start if isinstance(start, str) else
                                                                   json.dumps(start))).classes("w-64")
            tag(self.el, input=a)
            if self.kind in ("number", "text", "json"):
                self.el.on("keydown.enter", self._submit)
                tag(ui.button("set", on_click=self._submit), "dense", set=a)
            self.status = tag(ui.label("").classes("text-xs"), status=a)
        self.acked = start
        self._started = start is not None

    def refresh(self, on_screen: bool = True) -> None:
        """Start from the device's value once it is known."""
        if self._started:
            return
        rec = self.feed.records.get(self.ch.name)
        if rec is not None and rec.value is not None:
            self._started = True
            self.acked = rec.value
            self._show(rec.value)

    def _show(self, v: Any) -> None:
        self._quiet = True
        try:
            if self.kind in ("text", "json"):
                self.el.value = v if isinstance(v, str) else json.dumps(v)
            else:
                self.el.value = v
        finally:
            self._quiet = False

    async def _toggled(self, e: Any) -> None:
        if not self._quiet:
            await self._apply(bool(e.value))

    async def _submit(self) -> None:
        raw = self.el.value
        if self.kind in ("text", "json"):
            try:
                value = self.ch.codec.parse_text(str(raw)) if self.kind == "json" else str(raw)
            except HubwireError as e:
                self._done(False, outcome_text(e))
                return
        else:
            if raw is None:
                return
            value = int(raw) if is_integer(self.ch) and float(raw).is_integer() else raw
        await self._apply(value)

    async def _apply(self, value: Any) -> None:
        self.status.set_text("writing...")
        ok, msg = await self.feed.write(self.ch, value)
        if ok:
            self.acked = value
        elif self.acked is not None:
            self._show(self.acked)  # the device did not take it: show what it holds
        self._done(ok, f"{fmt_value(value)}: {msg}" if ok else msg)

    def _done(self, ok: bool, msg: str) -> None:
        self.status.set_text(msg)
        self.status.classes(replace="text-xs " + ("text-green-700" if ok else "text-red-700"))
        tag(self.status, ok="1" if ok else "0", t=f"{time.time() * 1000:.0f}")


class ActionView:
    """A button calling an action, with an argument field when it takes one, and its result."""

    def __init__(self, feed: BoardFeed, ch: Channel) -> None:
        self.feed, self.ch = feed, ch
        a = self.key = _attr(feed.key, ch.name)
        with ui.row().classes("items-center gap-2"):
            self.arg = None
            if ch.codec.kind != "void":
                self.arg = tag(ui.input(label=ch.codec.name).classes("w-32"), "dense", arg=a)
                self.arg.on("keydown.enter", self._call)
            tag(ui.button(ch.name, on_click=self._call), "no-caps", call=a)
            self.result = tag(ui.label("").classes("font-mono"), result=a)
        self.calls = 0

    def refresh(self, on_screen: bool = True) -> None:
        pass  # a result shows when its call returns

    async def _call(self) -> None:
        arg = None
        if self.arg is not None:
            try:
                arg = self.ch.codec.parse_text(str(self.arg.value or ""))
            except HubwireError as e:
                self._show(False, outcome_text(e))
                return
        ok, msg = await self.feed.call(self.ch, arg)
        self._show(ok, msg)

    def _show(self, ok: bool, msg: str) -> None:
        self.calls += 1
        self.result.set_text(("-> " if ok else "") + msg)
        self.result.classes(replace="font-mono " + ("" if ok else "text-red-700"))
        tag(self.result, ok="1" if ok else "0", n=self.calls)


def channel_views(feed: BoardFeed, ch: Channel) -> List[Any]:
    """Build what ``ch`` gets on the page (in the current container); returns the views to refresh."""
    views: List[Any] = []
    rec = feed.records.get(ch.name)
    if rec is not None:
        views.append(ValueView(feed, rec))
    if ch.writable:
        views.append(InputView(feed, ch))
    if ch.callable:
        views.append(ActionView(feed, ch))
    if rec is not None and plottable(ch):
        views.append(PlotView(feed, rec))
    return views
