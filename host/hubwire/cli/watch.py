"""``hubwire watch``: a live view of a board's values, events and link health."""
from __future__ import annotations

import argparse
import shutil
import sys
import time
from typing import Any, Dict, List, Optional, Sequence, Tuple

from .. import diagnose
from .support import CliError, fmt_value, jsonable, open_device, print_json
from ..device import Device
from ..errors import HubwireError, LinkLost

__all__ = ["cmd_watch", "watch_duration"]


def _health_line(dev: Device) -> Dict[str, Any]:
    h = dev.health()
    return {"state": h.state,
            "heartbeat_age_ms": None if h.heartbeat_age is None else round(h.heartbeat_age * 1000),
            "measured_heartbeat_ms": h.measured_heartbeat_ms,  # the device's own, from its heartbeats
            "hub_errors": h.hub_counters, "device_errors": h.device_counters}


def watch_duration(requested: Optional[float], stdout_is_tty: bool) -> Optional[float]:
    """Seconds ``watch`` runs: as requested, else forever on a terminal and 10 s otherwise."""
    if requested is not None:
        return requested
    return None if stdout_is_tty else 10.0


def cmd_watch(args: argparse.Namespace) -> int:
    tty = sys.stdout.isatty() and not args.json
    duration = watch_duration(args.duration, sys.stdout.isatty())
    try:
        dev = _open_waiting(args, duration) if args.wait else open_device(args)
    except KeyboardInterrupt:
        return 130
    start = time.monotonic()
    try:
        with dev, dev.events() as evs:
            return _watch(dev, evs, args, tty, start, duration)
    except KeyboardInterrupt:
        if tty:
            sys.stdout.write("\n")
        return 0


def _open_waiting(args: argparse.Namespace, duration: Optional[float]) -> Device:
    """``_open`` until a board answers (``--wait``), within ``duration`` if there is one."""
    start = time.monotonic()
    said = False
    while True:
        try:
            return open_device(args)
        except (CliError, diagnose.PortOpenError) as e:
            kind = getattr(e, "kind", "")
            if kind not in ("ConnectTimeout", "NoSuchPort") or (
                    duration is not None and time.monotonic() - start >= duration):
                raise
            if not said:
                sys.stderr.write(f"hubwire: waiting for a board on {args.url} ({e})\n")
                said = True
            time.sleep(0.5 if kind == "NoSuchPort" else 0.0)


def _watch(dev: Device, evs: Any, args: argparse.Namespace, tty: bool, start: float,
           duration: Optional[float]) -> int:
    rate = max(0.1, args.rate)
    events: List[str] = []
    readable = [c for c in dev.descriptor.channels if c.readable]
    next_at = start
    down_since: Optional[float] = None
    printed = [_printed(dev, -1)[0]]  # lines the board printed before the view began are not shown
    drawn = [0]  # lines of the last drawing on the terminal (redrawn in place)
    last: Dict[str, str] = {}  # the last values and link lines printed off a terminal
    while duration is None or time.monotonic() - start < duration:
        _print_events(evs, args, tty, events, start, next_at, duration)
        _print_printed(dev, args, tty, events, start, printed)
        now = time.monotonic()
        if duration is not None and now - start >= duration:
            break
        next_at = max(next_at + 1.0 / rate, now)
        values = _read_values(dev, readable)
        health = _health_line(dev)
        t = round(time.monotonic() - start, 3)
        if args.json:
            print_json({"t": t, "values": {k: jsonable(v) for k, v in values.items()}, "link": health})
        elif tty:
            drawn[0] = _draw(dev, readable, values, events, health, t, drawn[0])
        else:
            _print_changes(t, values, health, last)
        down_since = None if health["state"] == "ready" else (down_since or time.monotonic())
        if down_since is not None and not args.wait and time.monotonic() - down_since >= args.timeout:
            raise CliError("LinkLost", f"the board on {args.url} vanished: the link is down and it did not come "
                                       f"back within {args.timeout:g} s (--timeout); pass --wait to keep watching "
                                       f"until it returns")
    return 0


def _print_events(evs: Any, args: argparse.Namespace, tty: bool, events: List[str], start: float,
                  next_at: float, duration: Optional[float]) -> None:
    """Print the events that arrive until the next refresh is due."""
    while True:
        left = next_at - time.monotonic()
        if duration is not None:
            left = min(left, start + duration - time.monotonic())
        ev = evs.get(max(0.0, left)) if left > 0 else evs.get(0)
        if ev is None:
            return
        t = round(ev.time - start, 3)
        if args.json:
            print_json({"t": t, "event": ev.name, "value": jsonable(ev.value), "seq": ev.seq})
        elif tty:
            events.append(f"{t:8.3f}  {ev.name} = {fmt_value(ev.value)}")
            del events[:-8]
        else:
            print(f"t={t:.3f} event {ev.name}={fmt_value(ev.value)}", flush=True)


def _printed(dev: Device, seen: int) -> Tuple[int, List[str]]:
    """Lines of text the board printed since ``seen`` of them (none through hubwire serve)."""
    printed = getattr(dev.session, "printed", None)
    if printed is None:
        return seen, []
    count, latest = printed()
    return count, latest[len(latest) - min(count - seen, len(latest)):] if seen >= 0 and count > seen else []


def _print_printed(dev: Device, args: argparse.Namespace, tty: bool, events: List[str], start: float,
                   printed: List[int]) -> None:
    printed[0], lines = _printed(dev, printed[0])
    t = round(time.monotonic() - start, 3)
    for line in lines:
        if args.json:
            print_json({"t": t, "printed": line})
        elif tty:
            events.append(f"{t:8.3f}  the board printed: {line}")
            del events[:-8]
        else:
            print(f"t={t:.3f} the board printed: {line}", flush=True)


def _read_values(dev: Device, readable: Sequence[Any]) -> Dict[str, Any]:
    values: Dict[str, Any] = {}
    for c in readable:
        try:
            values[c.name] = dev.read(c.name)
        except LinkLost:
            values[c.name] = None
        except HubwireError as e:
            values[c.name] = f"<{e}>"
    return values


def _fmt_counters(c: Dict[str, int]) -> str:
    if not c:
        return "-"
    return ",".join(f"{k}:{v}" for k, v in c.items())


def _print_changes(t: float, values: Dict[str, Any], health: Dict[str, Any], last: Dict[str, str]) -> None:
    """Off a terminal: the values line when a value changed, the link line when its state, heartbeat
    interval or a counter changed (so that a log shows movement, not the same lines over and over)."""
    lines = {"values": " ".join(f"{k}={fmt_value(v)}" for k, v in values.items()),
             "link": f"link state={health['state']} measured_heartbeat_ms={health['measured_heartbeat_ms']} "
                     f"hub_errors={_fmt_counters(health['hub_errors'])} "
                     f"device_errors={_fmt_counters(health['device_errors'])}"}
    for key, line in lines.items():
        if last.get(key) != line:
            last[key] = line
            if key == "link":
                line = line.replace(" measured", f" heartbeat_age_ms={health['heartbeat_age_ms']} measured", 1)
            print(f"t={t:.3f} {line}", flush=True)


def _draw(dev: Device, readable: Sequence[Any], values: Dict[str, Any], events: List[str], health: Dict[str, Any],
          t: float, drawn: int) -> int:
    """The view on a terminal, drawn over the previous one (``drawn`` lines) rather than below it, so
    the scrollback keeps what came before; cut to the terminal's height. Returns the lines drawn."""
    d = dev.descriptor
    lines = [f"{d.name}{' ' + d.firmware if d.firmware else ''} on {dev.session.url}",
             f"t={t:.1f}s   link {health['state']}, heartbeat {health['heartbeat_age_ms']} ms ago, "
             f"every {health['measured_heartbeat_ms']} ms", ""]
    w = max((len(c.name) for c in readable), default=4)
    for c in readable:
        unit = f" {c.unit}" if c.unit else ""
        lines.append(f"  {c.name.ljust(w)}  {fmt_value(values.get(c.name))}{unit}")
    lines += ["", f"  errors heard by hub: {_fmt_counters(health['hub_errors'])}   "
                  f"by device: {_fmt_counters(health['device_errors'])}", "", "  events:"]
    lines += [f"  {e}" for e in events] or ["  (none yet)"]
    lines += ["", "  Ctrl-C to quit"]
    size = shutil.get_terminal_size()
    lines = [ln[:size.columns] for ln in lines[:max(1, size.lines - 1)]]
    up = f"\x1b[{drawn}F" if drawn else ""  # to the first line of the previous drawing
    sys.stdout.write(up + "".join(f"{ln}\x1b[K\n" for ln in lines) + "\x1b[J")
    sys.stdout.flush()
    return len(lines)


# ----------------------------------------------------------------------------------------- main
