"""What the page shows, without the page: per channel its latest value and history, per board its
events, and the choices made from a channel's descriptor entry (which widget, which plot columns).

Nothing here draws; every browser tab reads the same records (one device subscription per channel,
however many tabs are open)."""
from __future__ import annotations

import bisect
import csv
import io
import json
import time
from collections import deque
from dataclasses import dataclass, field
from typing import Any, Deque, List, Optional, Sequence, Tuple

from ..descriptor import Channel

__all__ = ["HISTORY_S", "RATE_WINDOW_S", "RATES", "ChannelRecord", "EventRecord", "LinkRecord", "widget_for",
           "flatten", "fmt_value", "decimate", "to_csv", "merge_csv", "default_picks", "key_channels"]

#: seconds of history kept per plotted channel
HISTORY_S = 300.0
#: window over which the achieved sample rate is measured, s
RATE_WINDOW_S = 2.0
#: rates offered on the page, Hz
RATES = (1, 2, 5, 10, 20, 50, 100)
_NUMERIC = ("bool", "u8", "u16", "u32", "i8", "i16", "i32", "f32", "f64")


def widget_for(ch: Channel) -> str:
    """The input a writable channel gets: ``toggle`` (bool), ``slider`` (a number with both ends of
    its range declared), ``number`` (other numbers), ``text`` (strings), ``json`` (arrays, structs)."""
    kind = ch.codec.kind
    if kind == "scalar":
        if ch.codec.scalar == "bool":
            return "toggle"
        return "slider" if ch.min is not None and ch.max is not None else "number"
    return "text" if kind == "str" else "json"


def is_integer(ch: Channel) -> bool:
    return bool(ch.codec.scalar) and str(ch.codec.scalar)[0] in "ui"


def range_hint(ch: Channel) -> str:
    """The declared range in words, for a number field's label or placeholder. The field itself gets
    no min/max: NiceGUI clamps what was typed to them when the field loses focus, so 20 typed where
    10 is the maximum would be written or started as 10 without a word; out of range, the hub
    refuses it and says why."""
    lo, hi = (None if b is None else fmt_value(b) for b in (ch.min, ch.max))
    if lo is not None and hi is not None:
        return f"{lo} to {hi}"
    return f"from {lo}" if lo is not None else f"up to {hi}" if hi is not None else ""


def plottable(ch: Channel) -> bool:
    """A channel with numbers in it (scalars, arrays, structs of numbers) that can be read or streamed."""
    if not (ch.readable or ch.streamable) or ch.codec.kind in ("str", "void"):
        return False
    return _all_numeric(ch.type)


def _all_numeric(t: Any) -> bool:
    if "f" in t:
        return all(_all_numeric(f) for f in t["f"])
    return t.get("t") in _NUMERIC


def flatten(value: Any, prefix: str = "") -> List[Tuple[str, float]]:
    """``[(column, number)]`` of a value's JSON form: ``imu.ax``, ``imu.gyro[2]``, ``range[0]``."""
    if isinstance(value, dict):
        out: List[Tuple[str, float]] = []
        for k, v in value.items():
            out += flatten(v, f"{prefix}.{k}" if prefix else k)
        return out
    if isinstance(value, (list, tuple)):
        out = []
        for i, v in enumerate(value):
            out += flatten(v, f"{prefix}[{i}]")
        return out
    if isinstance(value, (bool, int, float)):
        return [(prefix, float(value))]
    return []


def fmt_value(v: Any) -> str:
    """A value as the page shows it: numbers to 6 significant digits, structs as ``{k: v}``."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return f"{v:.6g}"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{k}: {fmt_value(x)}" for k, x in v.items()) + "}"
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(fmt_value(x) for x in v) + "]"
    if isinstance(v, str):
        return json.dumps(v, ensure_ascii=False)
    return "-" if v is None else str(v)


@dataclass
class ChannelRecord:
    """Latest value and recent history of one readable or streamable channel."""

    channel: Channel
    #: Hz asked for (streamed channels: the subscription; others: how often it is read)
    rate: float
    value: Any = None  # JSON form of the latest value
    #: wall-clock time (time.time()) the latest value arrived at the hub
    at: Optional[float] = None
    count: int = 0
    columns: List[str] = field(default_factory=list)
    error: Optional[str] = None
    #: how a channel that is not streamed gets its values: "" (streamed), else a note ("read")
    read: str = ""
    # history in time order from index _start on (lists trimmed now and then: cheap to slice)
    _times: List[float] = field(default_factory=list)
    _rows: List[Tuple[float, ...]] = field(default_factory=list)
    _start: int = 0
    _names: List[str] = field(default_factory=list)
    _arrivals: Deque[float] = field(default_factory=deque)

    def add(self, value_json: Any, at: Optional[float] = None) -> None:
        """Record a value (in its JSON form) that arrived at ``at`` (default now)."""
        now = time.time() if at is None else at
        self.value, self.at, self.error = value_json, now, None
        self.count += 1
        self._arrivals.append(now)
        while self._arrivals[0] < now - RATE_WINDOW_S:
            self._arrivals.popleft()
        pairs = flatten(value_json)
        if not pairs:
            return
        names = [c for c, _ in pairs]
        if names != self._names:  # first sample, or the device came back with another layout
            n = self.channel.name
            self._names = names
            self.columns = [n + c if not c or c.startswith("[") else f"{n}.{c}" for c in names]
            self._times, self._rows, self._start = [], [], 0
        self._times.append(now)
        self._rows.append(tuple(v for _, v in pairs))
        self._start = bisect.bisect_left(self._times, now - HISTORY_S, lo=self._start)
        if self._start > 1024 and self._start * 2 > len(self._times):
            del self._times[:self._start], self._rows[:self._start]
            self._start = 0

    def achieved(self, now: Optional[float] = None) -> float:
        """Samples per second that arrived over the last :data:`RATE_WINDOW_S` seconds."""
        now = time.time() if now is None else now
        n = len(self._arrivals) - bisect.bisect_left(self._arrivals, now - RATE_WINDOW_S)
        return n / RATE_WINDOW_S

    def window(self, seconds: float, now: Optional[float] = None) -> Tuple[List[float], List[Tuple[float, ...]]]:
        """Times and rows of the last ``seconds`` seconds (of the :data:`HISTORY_S` kept)."""
        now = time.time() if now is None else now
        lo = bisect.bisect_left(self._times, now - min(seconds, HISTORY_S), lo=self._start)
        return self._times[lo:], self._rows[lo:]


@dataclass(frozen=True)
class EventRecord:
    """An event as the page lists it: running number ``n`` (per board), arrival time, name, value."""

    n: int
    at: float
    name: str
    value: Any


def decimate(times: Sequence[float], rows: Sequence[Tuple[float, ...]], points: int) -> List[int]:
    """Indexes of at most about ``points`` rows spread evenly over the window, always the last one
    (what is drawn; the CSV has every row)."""
    n = len(times)
    if n <= points:
        return list(range(n))
    step = n / float(points)
    idx = [int(i * step) for i in range(points)]
    if idx[-1] != n - 1:
        idx.append(n - 1)
    return idx


def to_csv(columns: Sequence[str], times: Sequence[float], rows: Sequence[Tuple[float, ...]]) -> str:
    """CSV of a plot's rows: ``time`` (Unix seconds) then one column per plotted number."""
    out = io.StringIO()
    w = csv.writer(out, lineterminator="\n")
    w.writerow(["time"] + list(columns))
    for t, row in zip(times, rows):
        w.writerow([f"{t:.6f}"] + [repr(v) if isinstance(v, float) and not v.is_integer() else f"{v:g}" for v in row])
    return out.getvalue()


def merge_csv(parts: Sequence[Tuple[Sequence[str], Sequence[float], Sequence[Tuple[float, ...]]]]) -> str:
    """One CSV of several plotted channels (``(columns, times, rows)`` each) on their shared time axis:
    ``time`` then every column; a row per sample, in time order, empty where that channel had none."""
    columns = [c for cols, _, _ in parts for c in cols]
    merged: List[Tuple[float, int, Tuple[float, ...]]] = []
    offset = 0
    for cols, times, rows in parts:
        merged += [(t, offset, row) for t, row in zip(times, rows)]
        offset += len(cols)
    merged.sort(key=lambda x: (x[0], x[1]))
    out = io.StringIO()
    w = csv.writer(out, lineterminator="\n")
    w.writerow(["time"] + columns)
    for t, at, row in merged:
        cells = [""] * len(columns)
        for i, v in enumerate(row):
            cells[at + i] = repr(v) if not v.is_integer() else f"{v:g}"
        w.writerow([f"{t:.6f}"] + cells)
    return out.getvalue()


def default_picks(channels: Sequence[Channel], most: int = 2) -> List[str]:
    """Channels plotted when the page opens: the first streamable numbers that are not booleans
    (a user picks others on the page)."""
    fit = [c.name for c in channels if c.streamable and plottable(c) and c.codec.scalar != "bool"]
    return fit[:most]


def key_channels(channels: Sequence[Channel], most: int = 3) -> List[str]:
    """The values a board's overview tile shows: streamed single numbers first (a battery, a speed),
    then other readable single numbers."""
    scalars = [c for c in channels if plottable(c) and c.codec.kind == "scalar"]
    ordered = [c for c in scalars if c.streamable and c.unit] + [c for c in scalars if c.streamable and not c.unit] \
        + [c for c in scalars if not c.streamable]
    return [c.name for c in ordered][:most]


@dataclass
class LinkRecord:
    """A board's link as the page has seen it: how often it was lost and how long it took to come back
    (counted from its state changes, so that every loss shown has its return shown too)."""

    lost: int = 0
    #: wall-clock time the current loss began; None while the board is ready
    lost_at: Optional[float] = None
    #: seconds the last loss lasted (None: not back from one yet)
    back_after: Optional[float] = None
    _ready: bool = False  # ready once at least

    def observe(self, state: str, now: Optional[float] = None) -> None:
        """Note the board's state. A loss is ``lost`` or ``unplugged`` after it was ready; it is back
        once ready again (``connecting`` on the way, or after a reboot it noticed, is no loss)."""
        now = time.time() if now is None else now
        if state in ("lost", "unplugged"):
            if self._ready and self.lost_at is None:
                self.lost += 1
                self.lost_at = now
        elif state == "ready":
            self._ready = True
            if self.lost_at is not None:
                self.back_after = now - self.lost_at
                self.lost_at = None

    def text(self) -> str:
        """``never``, ``1 time, lost now``, ``2 times, back after 1.5 s``."""
        if not self.lost:
            return "never"
        times = f"{self.lost} time{'s' if self.lost != 1 else ''}"
        if self.lost_at is not None:
            return times + ", lost now"
        return times + (f", back after {self.back_after:.1f} s" if self.back_after is not None else "")
