"""One channel on the page, as one compact row: its name, its live value with unit, a box to plot it,
and an input when it is writable; an action is a row with its button. Everything is chosen from the
channel's descriptor entry.

While the board is lost its values are marked as the last ones received (``data-hw-stale="1"``) and
its inputs and buttons are off. Elements carry ``data-hw-*`` attributes (board key and channel name)
so that tests and benchmarks find them; ``data-hw-at`` on a value is the time its sample reached the
hub (Unix ms)."""
from __future__ import annotations

import json
import time
from typing import Any, Callable, List, Optional

from nicegui import ui

from ..descriptor import Channel
from ..errors import HubwireError
from .attrs import tag
from .feed import BoardFeed
from .model import ChannelRecord, fmt_value, is_integer, plottable, range_hint, widget_for
from .words import outcome

__all__ = ["ChannelRow", "ActionRow", "channel_rows"]

_NAME = "font-medium w-20 sm:w-24 shrink-0 truncate"
_VALUE = "font-mono text-sm flex-1 min-w-24 max-h-16 overflow-y-auto"  # a 1 KB value scrolls in its row
_STALE = "text-gray-400 italic"


def _attr(board: str, ch: str) -> str:
    return f"{board}.{ch}"


def _unit(ch: Channel) -> str:
    return f" {ch.unit}" if ch.unit else ""


def _hint(ch: Channel) -> str:
    """Hover text: type, range, description (plain text: a tooltip renders no HTML)."""
    rng = f", {fmt_value(ch.min)}..{fmt_value(ch.max)}" if ch.range else ""
    return f"{ch.name}: {ch.type_name}{rng}" + (f". {ch.description}" if ch.description else "")


def _say(label: Any, ok: bool, text: str, code: Optional[str]) -> None:
    label.set_text(text)
    label.classes(replace="text-xs w-full " + ("text-green-700" if ok else "text-red-700"))
    tag(label, ok="1" if ok else "0", code=code or "", t=f"{time.time() * 1000:.0f}")


class ChannelRow:
    """A readable or writable channel: value, unit, how it arrives, plot box, input."""

    def __init__(self, feed: BoardFeed, ch: Channel, pick: Optional[Callable[[str, bool], None]],
                 picked: bool) -> None:
        self.feed, self.ch = feed, ch
        self.key = _attr(feed.key, ch.name)
        self.rec: Optional[ChannelRecord] = feed.records.get(ch.name)
        self._shown: Optional[float] = None
        self._live = True
        self.input: Optional[InputBox] = None
        with tag(ui.row().classes("w-full items-center gap-x-2 gap-y-0 py-0.5"), channel=self.key):
            if self.rec is not None and plottable(ch) and pick is not None:
                tag(ui.checkbox(value=picked, on_change=lambda e: pick(self.key, bool(e.value))),
                    "dense", pick=self.key).tooltip("plot it")
            else:
                ui.element("div").classes("w-5 shrink-0")
            ui.label(ch.name).classes(_NAME).tooltip(_hint(ch))
            self.value = tag(ui.label("-" if self.rec is not None else "").classes(_VALUE),
                             value=self.key, stale="0").style("overflow-wrap: anywhere")
            if ch.writable:
                with ui.row().classes("items-center gap-1 no-wrap shrink-0"):
                    self.input = InputBox(feed, ch)
            self.rate = tag(ui.label("").classes("text-xs text-gray-500 w-12 text-right shrink-0"), achieved=self.key)
            self.note = tag(ui.label("").classes("text-xs text-gray-500 w-full"), note=self.key)
            if self.input is not None:  # under the row
                self.input.status = tag(ui.label("").classes("text-xs w-full"), status=self.key)

    def set_live(self, live: bool) -> None:
        """Mark the value as the last one received (and turn the input off) while the board is lost."""
        if live == self._live:
            return
        self._live = live
        self.value.classes(replace=_VALUE + ("" if live else " " + _STALE))
        tag(self.value, stale="0" if live else "1")
        if self.input is not None:
            self.input.set_live(live)

    def refresh(self, on_screen: bool = True) -> None:
        if self.input is not None:
            self.input.refresh()
        rec = self.rec
        if rec is None or not on_screen:
            self._shown = None  # shown afresh once scrolled to
            return
        if rec.read not in ("", "read"):
            note = rec.read  # a stream the board could not grant: read instead
        elif rec.at is None:
            note = rec.error or ""
        else:
            note = ""
        if self.note.text != note:
            self.note.set_text(note)
        # how fast a stream delivers (channels read now and then say nothing: it would be noise)
        rate = f"{rec.achieved():.3g} Hz" if rec.at is not None and not rec.read and self._live else ""
        if self.rate.text != rate:
            self.rate.set_text(rate)
        if rec.at is None or rec.at == self._shown:
            return
        self._shown = rec.at
        self.value.set_text(fmt_value(rec.value) + _unit(rec.channel))
        tag(self.value, at=f"{rec.at * 1000:.1f}")


class InputBox:
    """An input for a writable channel, chosen by type and range. A slider or toggle goes back to
    what the board holds when it refuses; a typed entry stays as typed, to be corrected."""

    def __init__(self, feed: BoardFeed, ch: Channel) -> None:
        self.feed, self.ch = feed, ch
        self.kind = widget_for(ch)
        self._quiet = False
        a = _attr(feed.key, ch.name)
        rec = feed.records.get(ch.name)
        start = rec.value if rec is not None else None
        self.buttons: List[Any] = []
        if self.kind == "toggle":
            self.el: Any = ui.switch(value=bool(start), on_change=self._toggled).props("dense")
        elif self.kind == "slider":
            step = 1.0 if is_integer(ch) else ((ch.max or 0) - (ch.min or 0)) / 100.0
            self.el = ui.slider(min=ch.min or 0, max=ch.max or 0, step=step,
                                value=start if isinstance(start, (int, float)) else ch.min) \
                .props("label dense").classes("w-36 shrink-0")
            self.el.on("change", lambda: self._apply(self.el.value))
        elif self.kind == "number":
            self.el = ui.number(value=start if isinstance(start, (int, float)) else None,
                                format="%d" if is_integer(ch) else None).props("dense").classes("w-24 shrink-0")
            if range_hint(ch):  # a number field has at most one bound here (both: a slider)
                self.el.props["placeholder"] = range_hint(ch)
        else:
            self.el = ui.input(value="" if start is None else (start if isinstance(start, str) else json.dumps(start))) \
                .props("dense").classes("w-32 shrink-0")
        tag(self.el, input=a)
        if self.kind in ("number", "text", "json"):
            self.el.on("keydown.enter", self._submit)
            self.buttons.append(tag(ui.button("set", on_click=self._submit), "dense", "flat", "no-caps", set=a))
        #: where the outcome of a write shows (placed by the row)
        self.status: Any = None
        self.acked: Any = start
        self._started = start is not None

    def set_live(self, live: bool) -> None:
        for el in [self.el] + self.buttons:
            el.set_enabled(live)

    def refresh(self) -> None:
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
            self.el.value = (v if isinstance(v, str) else json.dumps(v)) if self.kind in ("text", "json") else v
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
                _say(self.status, False, *outcome(e))
                return
        else:
            if raw is None:
                return
            value = int(raw) if is_integer(self.ch) and float(raw).is_integer() else raw
        await self._apply(value)

    async def _apply(self, value: Any) -> None:
        self.status.set_text("sending...")
        ok, msg, code = await self.feed.write_coded(self.ch, value)
        if ok:
            self.acked = value
        elif self.acked is not None and self.kind in ("toggle", "slider"):
            self._show(self.acked)  # the device did not take it: show what it holds
        _say(self.status, ok, f"{fmt_value(value)}: {msg}" if ok else msg, code)


class ActionRow:
    """A button calling an action, with an argument field when it takes one, and its result."""

    def __init__(self, feed: BoardFeed, ch: Channel) -> None:
        self.feed, self.ch = feed, ch
        a = self.key = _attr(feed.key, ch.name)
        self.arg = None
        with tag(ui.row().classes("w-full items-center gap-x-2 gap-y-0 py-0.5"), action=a):
            ui.element("div").classes("w-5 shrink-0")
            self.button = tag(ui.button(ch.name, on_click=self._call), "dense", "no-caps", "outline", call=a) \
                .classes("shrink-0").tooltip(_hint(ch))
            if ch.codec.kind != "void":
                self.arg = tag(ui.input(placeholder=ch.codec.name).classes("w-20 shrink-0"), "dense", arg=a)
                self.arg.on("keydown.enter", self._call)
            self.result = tag(ui.label("").classes("font-mono text-sm grow min-w-0"), result=a)
            if ch.description:
                ui.label(ch.description).classes("text-xs text-gray-500 w-full pl-7")
        self.calls = 0

    def set_live(self, live: bool) -> None:
        for el in (self.button, self.arg):
            if el is not None:
                el.set_enabled(live)

    def refresh(self, on_screen: bool = True) -> None:
        pass  # a result shows when its call returns

    async def _call(self) -> None:
        arg = None
        if self.arg is not None:
            try:
                arg = self.ch.codec.parse_text(str(self.arg.value or ""))
            except HubwireError as e:
                self._show(False, *outcome(e))
                return
        self._show(*(await self.feed.call_coded(self.ch, arg)))

    def _show(self, ok: bool, msg: str, code: Optional[str]) -> None:
        self.calls += 1
        self.result.set_text(("-> " if ok else "") + msg)
        self.result.classes(replace="font-mono text-sm grow min-w-0 " + ("" if ok else "text-red-700"))
        tag(self.result, ok="1" if ok else "0", n=self.calls, code=code or "")


def channel_rows(feed: BoardFeed, pick: Optional[Callable[[str, bool], None]], picked: Callable[[str], bool]) -> List[Any]:
    """A row for each of the board's channels (events go to the log), in the descriptor's order,
    actions last; returns the rows to refresh."""
    rows: List[Any] = []
    channels = [c for c in feed.descriptor.channels if not c.is_event]
    for ch in [c for c in channels if not c.callable]:
        rows.append(ChannelRow(feed, ch, pick, picked(_attr(feed.key, ch.name))))
    for ch in [c for c in channels if c.callable]:
        rows.append(ActionRow(feed, ch))
    return rows
