"""The top of the page and the event log: a tile per board (name, link state, a few key values; a
click goes to its card) and every board's events, newest first."""
from __future__ import annotations

import time
from typing import Any, Dict, List, Optional, Tuple

from nicegui import ui

from .attrs import tag
from .feed import BoardFeed
from .model import fmt_value, key_channels

__all__ = ["Tile", "EventLog", "EVENTS_SHOWN"]

#: events shown on the page (each feed keeps more)
EVENTS_SHOWN = 100
_DOT = {"ready": "text-green-600", "connecting": "text-orange-500", "lost": "text-red-600", "unplugged": "text-gray-400"}


class Tile:
    """A board at a glance."""

    def __init__(self, board: Any, feed: Optional[BoardFeed]) -> None:
        self.key = board.key
        self.feed = feed
        self.generation = feed.generation if feed is not None else 0
        self._state = ""
        self.values: List[Tuple[str, Any]] = []
        self.card = tag(ui.card().classes("p-2 gap-0 cursor-pointer min-w-36 max-w-full"), tile=board.key)
        with self.card:
            with ui.row().classes("items-center gap-2 no-wrap"):
                self.dot = ui.label("●")
                ui.label(board.key).classes("font-bold truncate")
                self.state = tag(ui.label("").classes("text-xs text-gray-600"), tile_state=board.key)
            if feed is None:
                return
            with ui.row().classes("gap-x-3 gap-y-0 text-xs"):
                for name in key_channels(feed.descriptor.channels):
                    with ui.row().classes("gap-1 no-wrap"):
                        ui.label(name).classes("text-gray-600")
                        self.values.append((name, tag(ui.label("-").classes("font-mono"),
                                                      tile_value=f"{board.key}.{name}")))

    def refresh(self, board: Any) -> None:
        if board.state != self._state:
            self._state = board.state
            self.state.set_text(board.state)
            self.dot.classes(replace=_DOT.get(board.state, "text-gray-400"))
            for _, label in self.values:
                label.classes(replace="font-mono" + ("" if board.state == "ready" else " text-gray-400 italic"))
        if self.feed is None:
            return
        for name, label in self.values:
            rec = self.feed.records.get(name)
            if rec is not None and rec.at is not None:
                unit = f" {rec.channel.unit}" if rec.channel.unit else ""
                text = fmt_value(rec.value) + unit
                if label.text != text:
                    label.set_text(text)


class EventLog:
    """Every board's events, newest first, numbered per board, with their arrival times."""

    def __init__(self) -> None:
        self._shown: Dict[Tuple[str, int], int] = {}  # (board, feed generation): last number shown
        with tag(ui.card().classes("w-full p-2 gap-1"), eventlog="main"):
            with ui.row().classes("items-baseline gap-2"):
                ui.label("Events").classes("font-bold")
                self.hint = ui.label("none yet").classes("text-xs text-gray-500")
            self.rows = tag(ui.column().classes("w-full gap-0 font-mono text-xs overflow-auto")
                            .style("max-height: clamp(120px, 24vh, 480px)"), events="all")

    def refresh(self, feeds: List[BoardFeed]) -> None:
        new = []
        for feed in feeds:
            mark = (feed.key, feed.generation)
            last = self._shown.get(mark, 0)
            fresh = [e for e in feed.events if e.n > last]
            if fresh:
                self._shown[mark] = fresh[-1].n
                new += [(feed.key, e) for e in fresh[-EVENTS_SHOWN:]]
        if not new:
            return
        self.hint.set_text("newest first")
        new.sort(key=lambda x: x[1].at)
        with self.rows:
            for key, e in new[-EVENTS_SHOWN:]:
                stamp = time.strftime("%H:%M:%S", time.localtime(e.at)) + f".{int(e.at * 1000) % 1000:03d}"
                lbl = tag(ui.label(f"#{e.n} {stamp} {key} {e.name} = {fmt_value(e.value)}")
                          .classes("break-all"), event=f"{key}.{e.name}", n=e.n)
                lbl.move(self.rows, target_index=0)  # newest first
        for old in list(self.rows)[EVENTS_SHOWN:]:
            self.rows.remove(old)
