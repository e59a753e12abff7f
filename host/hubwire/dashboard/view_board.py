"""One board on the page, compact: a header (name, link state, port), one line on its link, a row
per channel and per action, then sections that open on demand (link details, hub channels, other
parts' sections such as missions, the descriptor).

While the board is not ready a line says since when it is lost, its values are marked as the last
ones received and its inputs are off."""
from __future__ import annotations

import json
import os
import re
import time
from typing import Any, Callable, Container, Dict, List, Optional

from nicegui import ui

from ..descriptor import Channel
from .attrs import tag
from .feed import BoardFeed
from .model import LinkRecord, default_picks
from .view_channel import channel_rows
from .view_plot import PlotPanel
from .view_mission import MissionView

__all__ = ["BoardView", "hub_channels", "SECTIONS"]

#: link details are redrawn every this many value refreshes
HEALTH_EVERY = 5
_STATE_COLOURS = {"ready": "green", "connecting": "orange", "lost": "red", "unplugged": "grey"}

#: more sections of a board, drawn in its card after the hub channels: each is called with the
#: board's feed inside the card and returns an object with ``refresh(board)`` (or None to add none)
SECTIONS: List[Callable[[BoardFeed], Any]] = []


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


class _MissionSection:
    """A mission's controls as a board section (refreshed with the board)."""

    def __init__(self, view: MissionView) -> None:
        self.view = view

    def refresh(self, board: Any) -> None:
        self.view.refresh(True)


def _access(ch: Channel) -> str:
    words = {"r": "read", "w": "write", "c": "call", "e": "event", "s": "stream", "m": "mission"}
    return ", ".join(words[a] for a in ch.access if a in words)


def _slug(label: str) -> str:
    return re.sub("[^a-z]+", "-", label)


class BoardView:
    """A board's card; :meth:`refresh` updates what changed since the last call."""

    def __init__(self, board: Any, feed: Optional[BoardFeed], link: LinkRecord,
                 plot: Optional[PlotPanel] = None, fleet: Any = None) -> None:
        self.key = board.key
        self.feed = feed
        self.link = link
        self.generation = feed.generation if feed is not None else 0
        self.rows: List[Any] = []
        self.sections: List[Any] = []
        self._health_text: Dict[str, str] = {}
        self._ticks = 0
        self._live: Optional[bool] = None
        self.card = tag(ui.card().classes("w-full p-3 gap-1"), board=board.key)
        with self.card:
            with ui.row().classes("w-full items-center gap-x-3 gap-y-0"):
                ui.label(board.key).classes("text-lg font-bold")
                self.state = tag(ui.badge(board.state), state=board.key)
                self.where = ui.label("").classes("text-xs text-gray-600 min-w-0 break-all")
            self.lost = tag(ui.label("").classes("text-sm text-red-700 w-full"), lost=board.key)
            self._set_state(board)
            if feed is None:
                ui.label("waiting for the board's description").classes("text-gray-600")
                return
            d = feed.descriptor
            ui.label(f"{d.name} {d.firmware or ''}").classes("text-xs text-gray-600")
            self._link_line()
            if plot is not None:
                plot.offer([f"{self.key}.{n}" for n in default_picks(d.channels)])
            self.rows = channel_rows(feed, plot.pick if plot is not None else None,
                                     (lambda k: k in plot.picks) if plot is not None else (lambda k: False))
            self._details()
            self._hub_section(feed)
            if fleet is not None:  # through hubwire serve: a start form, progress bar and cancel per mission
                for ch in d.channels:
                    if ch.mission:
                        self.sections.append(_MissionSection(MissionView(feed, ch, fleet)))
            for make in SECTIONS:
                section = make(feed)
                if section is not None:
                    self.sections.append(section)
            with ui.expansion("description the board sent").classes("w-full text-sm"):
                text = json.dumps(json.loads(d.raw), indent=2) if d.raw else "{}"
                # a label, not ui.code: that one renders Markdown, this one only text
                ui.label(text).classes("w-full font-mono text-xs whitespace-pre overflow-auto")

    def _cell(self, label: str, parent_classes: str = "") -> Any:
        with ui.row().classes("gap-1 items-baseline " + parent_classes):
            ui.label(label).classes("text-gray-600")
            cell = tag(ui.label("-").classes("font-mono"), health=f"{self.key}.{_slug(label)}")
        self.health[label] = cell
        return cell

    def _link_line(self) -> None:
        """What a user glances at: the board's heartbeat, its losses, the errors on the line."""
        self.health: Dict[str, Any] = {}
        with ui.row().classes("w-full gap-x-4 gap-y-0 text-xs"):
            for k in ("heartbeat", "link lost", "line errors"):
                self._cell(k)

    def _details(self) -> None:
        with ui.expansion("link details").classes("w-full text-sm"):
            with ui.grid().classes("w-full gap-x-4 gap-y-0 text-xs grid-cols-1 sm:grid-cols-2"):
                for k in ("heartbeat age", "device heartbeat", "hub heartbeat", "state", "hub receiver",
                          "device receiver", "retries", "reboots", "samples", "events", "dropped events"):
                    self._cell(k)

    def _hub_section(self, feed: BoardFeed) -> None:
        hub = hub_channels(feed)
        if not hub:
            return
        binding = hub_binding(feed)
        by = feed.hub_providers() if feed is not None else {}
        with ui.expansion(f"hub channels it uses ({len(hub)})").classes("w-full text-sm"):
            for ch in hub:
                state = binding.get(ch.name, "-")
                with ui.row().classes("gap-x-4 gap-y-0 items-baseline text-sm"):
                    ui.label(ch.name).classes("font-bold")
                    ui.label(f"{_access(ch)}, {ch.type_name}").classes("text-gray-600")
                    tag(ui.label("bound here" if state == "ok" else f"not bound here: {state}"),
                        hub=f"{self.key}.{ch.name}")
                    if by.get(ch.name):  # through hubwire serve: which client, or MQTT
                        ui.label(f"provided by {by[ch.name]}").classes("text-gray-600")

    def _set_state(self, board: Any) -> None:
        self.state.set_text(board.state)
        self.state.props["color"] = _STATE_COLOURS.get(board.state, "grey")
        self.link.observe(board.state)
        port = board.port or "unplugged"
        # a device path by its name (its folder in the hover text): /dev/serial/by-id/... is long
        self.where.set_text(" ".join(x for x in (os.path.basename(port) if port.startswith("/") else port,
                                                   f"id {board.board_id}" if board.board_id else "") if x))
        self.where.props["title"] = port
        live = board.state == "ready"
        if live == self._live:
            return
        self._live = live
        for row in self.rows:
            row.set_live(live)
        since = self.link.lost_at
        if live or self.feed is None:
            text = ""
        else:
            text = (f"{board.state} since " + time.strftime("%H:%M:%S", time.localtime(since)) if since else board.state) \
                + ": values are the last received, controls are off until it is back"
        self.lost.set_text(text)
        self.lost.set_visibility(bool(text))

    def refresh(self, board: Any, visible: Container[str]) -> None:
        """Update state and the channels on screen (``visible``: "key.channel")."""
        if self.state.text != board.state or not self.where.text:
            self._set_state(board)
        feed = self.feed
        if feed is None:
            return
        for v in self.rows:
            v.refresh(v.key in visible)
        for s in self.sections:
            s.refresh(board)
        self._ticks += 1
        if self._ticks % HEALTH_EVERY == 1:
            self._refresh_health(feed)

    def _refresh_health(self, feed: BoardFeed) -> None:
        h = feed.dev.health()
        st = h.stats

        def beat(declared: Optional[int], measured: Optional[int]) -> str:
            if not declared:
                return "-"
            return f"{declared} ms declared" + (f", last {measured} ms" if measured else "")

        errors = sum(h.hub_counters.values()) + sum(h.device_counters.values())
        if h.state != "ready" and h.heartbeat_age is not None:
            heartbeat = f"none for {h.heartbeat_age:.0f} s"
        elif h.device_heartbeat_ms:
            heartbeat = f"every {h.device_heartbeat_ms} ms" + (f", last {h.measured_heartbeat_ms} ms"
                                                                if h.measured_heartbeat_ms else "")
        else:
            heartbeat = "-"
        cells = {
            "heartbeat": heartbeat,
            "link lost": self.link.text(),
            "line errors": "none" if not errors else f"{errors} (see link details)",
            "heartbeat age": "-" if h.heartbeat_age is None else f"{h.heartbeat_age:.2f} s",
            "device heartbeat": beat(h.device_heartbeat_ms, h.measured_heartbeat_ms),
            "hub heartbeat": beat(h.hub_heartbeat_ms, h.hub_heartbeat_since_ms),
            "state": h.state,
            "hub receiver": " ".join(f"{k} {v}" for k, v in h.hub_counters.items()),
            "device receiver": " ".join(f"{k} {v}" for k, v in h.device_counters.items()) or "-",
            "retries": str(st.get("retries", 0)),
            "reboots": str(st.get("reboots", 0)),
            "samples": str(st.get("samples", 0)),
            "events": f"{st.get('events', 0)} ({st.get('duplicate_events', 0)} repeats dropped)",
            "dropped events": str(st.get("events_dropped", 0)),
        }
        for k, text in cells.items():
            if self._health_text.get(k) != text:
                self._health_text[k] = text
                self.health[k].set_text(text)
