"""One board on the page: name and link state, link health, every channel, the event log and the
descriptor itself."""
from __future__ import annotations

import json
import re
import time
from typing import Any, Container, Dict, List, Optional

from nicegui import ui

from ..descriptor import Channel
from .attrs import tag
from .feed import BoardFeed
from .model import fmt_value
from .view_channel import PlotView, channel_views
from .view_mission import MissionView

__all__ = ["BoardView", "hub_channels"]

#: events shown per board (the feed keeps more)
EVENTS_SHOWN = 100
#: link health is redrawn every this many value refreshes
HEALTH_EVERY = 5
_STATE_COLOURS = {"ready": "green", "connecting": "orange", "lost": "red", "unplugged": "grey"}


def hub_channels(feed: BoardFeed) -> List[Channel]:
    """The hub channels the board uses (its descriptor's "hub" list: values it reads or writes on
    the hub, actions it calls, events it hears), drawn below its own channels with their binding."""
    d = feed.dev.descriptor if feed is not None else None
    return list(d.hub) if d is not None else []


def hub_binding(feed: BoardFeed) -> Dict[str, str]:
    """Each hub channel's binding as this hub sees it: "ok", or why not (no such channel here...)."""
    try:
        return dict(feed.dev.hub_binding())
    except Exception:  # noqa: BLE001 - a board not discovered yet: nothing to say
        return {}


def _access(ch: Channel) -> str:
    words = {"r": "read", "w": "write", "c": "call", "e": "event", "s": "stream", "m": "mission"}
    return ", ".join(words[a] for a in ch.access if a in words)


class BoardView:
    """A board's card; :meth:`refresh` updates what changed since the last call."""

    def __init__(self, board: Any, feed: Optional[BoardFeed], fleet: Any = None) -> None:
        self.key = board.key
        self.feed = feed
        self.generation = feed.generation if feed is not None else 0
        self.values: List[Any] = []
        self.plots: List[PlotView] = []
        self._events_shown = 0
        self._health_text: Dict[str, str] = {}
        self._ticks = 0
        self.card = tag(ui.card().classes("w-full"), board=board.key)
        with self.card:
            with ui.row().classes("items-center gap-4"):
                ui.label(board.key).classes("text-xl font-bold")
                self.state = tag(ui.badge(board.state), state=board.key)
                self.where = ui.label("").classes("text-sm text-gray-600")
            self._set_state(board)
            if feed is None:
                ui.label("waiting for the board's descriptor").classes("text-gray-600")
                return
            d = feed.descriptor
            ui.label(f"{d.name} {d.firmware or ''} - {len(d.channels)} channels, protocol {d.protocol}") \
                .classes("text-sm")
            self._health_grid()
            with ui.grid().classes("w-full gap-3 grid-cols-1 lg:grid-cols-2"):
                for ch in d.channels:
                    if ch.is_event:
                        continue
                    with tag(ui.card().classes("w-full"), channel=f"{board.key}.{ch.name}"):
                        with ui.row().classes("items-baseline gap-2"):
                            ui.label(ch.name).classes("font-bold")
                            ui.label(f"{ch.type_name} ({_access(ch)})"
                                     + (f", {fmt_value(ch.min)}..{fmt_value(ch.max)}" if ch.range else "")) \
                                .classes("text-xs text-gray-600")
                        if ch.description:
                            ui.label(ch.description).classes("text-xs italic")
                        for v in channel_views(feed, ch):
                            (self.plots if isinstance(v, PlotView) else self.values).append(v)
                        if ch.mission and fleet is not None:  # start form, progress bar, cancel
                            self.values.append(MissionView(feed, ch, fleet))
            hub = hub_channels(feed)
            if hub:
                binding = hub_binding(feed)
                by = feed.hub_providers() if feed is not None else {}
                with ui.expansion(f"hub channels it uses ({len(hub)})", value=True).classes("w-full"):
                    for ch in hub:
                        state = binding.get(ch.name, "-")
                        with ui.row().classes("gap-4 items-baseline text-sm"):
                            ui.label(ch.name).classes("font-bold")
                            ui.label(f"{_access(ch)}, {ch.type_name}").classes("text-gray-600")
                            tag(ui.label("bound here" if state == "ok" else f"not bound here: {state}"),
                                hub=f"{board.key}.{ch.name}")
                            if by.get(ch.name):  # through hubwire serve: which client, or MQTT
                                ui.label(f"provided by {by[ch.name]}").classes("text-gray-600")
            events = [c.name for c in d.channels if c.is_event]
            with ui.expansion(f"events ({', '.join(events) or 'none declared'})", value=True).classes("w-full"):
                self.events = tag(ui.column().classes("gap-0 font-mono text-sm max-h-64 overflow-auto"),
                                  events=board.key)
            with ui.expansion("descriptor").classes("w-full"):
                text = json.dumps(json.loads(d.raw), indent=2) if d.raw else "{}"
                # a label, not ui.code: that one renders Markdown, this one only text
                ui.label(text).classes("w-full font-mono text-xs whitespace-pre overflow-auto")

    def _health_grid(self) -> None:
        self.health: Dict[str, Any] = {}
        with ui.expansion("link health", value=True).classes("w-full"):
            with ui.grid(columns=4).classes("gap-x-6 gap-y-0 text-sm"):
                for k in ("heartbeat age", "device heartbeat", "hub heartbeat", "state",
                          "hub receiver", "device receiver", "retries", "link lost / restored",
                          "reboots", "samples", "events", "dropped events"):
                    ui.label(k).classes("text-gray-600")
                    self.health[k] = tag(ui.label("-").classes("font-mono"),
                                         health=f'{self.key}.{re.sub("[^a-z]+", "-", k)}')

    def _set_state(self, board: Any) -> None:
        self.state.set_text(board.state)
        self.state.props["color"] = _STATE_COLOURS.get(board.state, "grey")
        self.where.set_text(" ".join(x for x in (board.port or "unplugged",
                                                   f"id {board.board_id}" if board.board_id else "") if x))

    def refresh(self, board: Any, visible: Container[str]) -> None:
        """Update state, events, health, and the channels on screen (``visible``: "key.channel")."""
        if self.state.text != board.state or not self.where.text:
            self._set_state(board)
        feed = self.feed
        if feed is None:
            return
        for v in self.values:
            v.refresh(v.key in visible)
        self._refresh_events(feed)
        self._ticks += 1
        if self._ticks % HEALTH_EVERY == 1:
            self._refresh_health(feed)

    def refresh_plots(self, visible: Container[str]) -> None:
        """Redraw the plots on screen."""
        for p in self.plots:
            p.refresh(p.key in visible)

    def _refresh_events(self, feed: BoardFeed) -> None:
        new = [e for e in feed.events if e.n > self._events_shown]
        if not new:
            return
        self._events_shown = new[-1].n
        with self.events:
            for e in new[-EVENTS_SHOWN:]:
                stamp = time.strftime("%H:%M:%S", time.localtime(e.at)) + f".{int(e.at * 1000) % 1000:03d}"
                lbl = tag(ui.label(f"#{e.n} {stamp} {e.name} = {fmt_value(e.value)}"),
                          event=f"{self.key}.{e.name}", n=e.n)
                lbl.move(self.events, target_index=0)  # newest first
        rows = list(self.events)
        for old in rows[EVENTS_SHOWN:]:
            self.events.remove(old)

    def _refresh_health(self, feed: BoardFeed) -> None:
        h = feed.dev.health()
        st = h.stats

        def beat(declared: Optional[int], measured: Optional[int]) -> str:
            if not declared:
                return "-"
            return f"{declared} ms declared" + (f", last {measured} ms" if measured else "")

        cells = {
            "heartbeat age": "-" if h.heartbeat_age is None else f"{h.heartbeat_age:.2f} s",
            "device heartbeat": beat(h.device_heartbeat_ms, h.measured_heartbeat_ms),
            "hub heartbeat": beat(h.hub_heartbeat_ms, h.hub_heartbeat_since_ms),
            "state": h.state,
            "hub receiver": " ".join(f"{k} {v}" for k, v in h.hub_counters.items()),
            "device receiver": " ".join(f"{k} {v}" for k, v in h.device_counters.items()) or "-",
            "retries": str(st.get("retries", 0)),
            "link lost / restored": f"{st.get('link_lost', 0)} / {st.get('link_restored', 0)}",
            "reboots": str(st.get("reboots", 0)),
            "samples": str(st.get("samples", 0)),
            "events": f"{st.get('events', 0)} ({st.get('duplicate_events', 0)} repeats dropped)",
            "dropped events": str(st.get("events_dropped", 0)),
        }
        for k, text in cells.items():
            if self._health_text.get(k) != text:
                self._health_text[k] = text
                self.health[k].set_text(text)
