"""``hubwire`` command line: ports, info, get, set, call, watch (all with ``--json``)."""
from __future__ import annotations

import argparse
import json
import math
import sys
import time
from typing import Any, Dict, List, Optional, Sequence, TextIO

from . import __version__
from .device import KNOWN_USB_VIDS, Device, connect
from .errors import HubwireError, LinkLost, NakError

__all__ = ["main"]


def _jsonable(v: Any) -> Any:
    if isinstance(v, tuple) and hasattr(v, "_asdict"):
        return {k: _jsonable(x) for k, x in v._asdict().items()}
    if isinstance(v, (tuple, list)):
        return [_jsonable(x) for x in v]
    if isinstance(v, float) and not math.isfinite(v):
        return str(v)
    return v


def _fmt_value(v: Any) -> str:
    if isinstance(v, float):
        return f"{v:.6g}"
    if isinstance(v, tuple) and hasattr(v, "_asdict"):
        return "{" + ", ".join(f"{k}: {_fmt_value(x)}" for k, x in v._asdict().items()) + "}"
    if isinstance(v, tuple):
        return "[" + ", ".join(_fmt_value(x) for x in v) + "]"
    if isinstance(v, str):
        return json.dumps(v, ensure_ascii=False)
    if v is None:
        return "-"
    return str(v)


def _print_json(obj: Any, out: TextIO = sys.stdout) -> None:
    out.write(json.dumps(obj, ensure_ascii=False) + "\n")
    out.flush()


def _progress_printer() -> Any:
    if not sys.stderr.isatty():
        return None

    def progress(received: int, total: int) -> None:
        sys.stderr.write(f"\rdownloading descriptor: {received}/{total} bytes")
        if received >= total:
            sys.stderr.write("\n")
        sys.stderr.flush()
    return progress


def _open(args: argparse.Namespace) -> Device:
    url = None if args.url in (None, "auto") else args.url
    return connect(url, args.baud, timeout=args.timeout, progress=_progress_printer(),
                   cache_dir=False if args.no_cache else None)


def _channel_json(c: Any) -> Dict[str, Any]:
    d: Dict[str, Any] = {"id": c.id, "name": c.name, "access": c.access, "type": c.type_name}
    for k, v in (("unit", c.unit), ("min", c.min), ("max", c.max), ("failsafe", _jsonable(c.failsafe)),
                 ("description", c.description)):
        if v is not None:
            d[k] = v
    return d


# ------------------------------------------------------------------------------------- commands

def cmd_ports(args: argparse.Namespace) -> int:
    from serial.tools import list_ports

    ports = sorted(list_ports.comports(), key=lambda p: p.device)
    rows = []
    for p in ports:
        rows.append({"device": p.device, "vid": p.vid, "pid": p.pid, "description": p.description,
                     "serial_number": p.serial_number, "board": KNOWN_USB_VIDS.get(p.vid) if p.vid else None})
    if args.json:
        _print_json(rows)
        return 0
    if not rows:
        print("no serial ports found")
        return 0
    for r in rows:
        ids = f"{r['vid']:04x}:{r['pid']:04x}" if r["vid"] is not None else "-"
        mark = f"  [{r['board']}]" if r["board"] else ""
        print(f"{r['device']}  {ids}  {r['description'] or ''}{mark}")
    return 0


def cmd_info(args: argparse.Namespace) -> int:
    with _open(args) as dev:
        d = dev.descriptor
        if args.json:
            _print_json({"url": dev.session.url, "name": d.name, "firmware": d.firmware, "protocol": d.protocol,
                         "descriptor_hash": f"{d.hash:08x}", "descriptor_length": len(d.raw),
                         "channels": [_channel_json(c) for c in d.channels]})
        else:
            print(f"{d.name}{' ' + d.firmware if d.firmware else ''} on {dev.session.url} "
                  f"(descriptor {len(d.raw)} bytes, hash {d.hash:08x})")
            print(dev.table())
    return 0


def cmd_get(args: argparse.Namespace) -> int:
    with _open(args) as dev:
        v = dev.read(args.channel)
        if args.json:
            _print_json({"channel": args.channel, "value": _jsonable(v)})
        else:
            print(_fmt_value(v))
    return 0


def cmd_set(args: argparse.Namespace) -> int:
    with _open(args) as dev:
        ch = dev.channel(args.channel)
        value = ch.codec.parse_text(args.value)
        dev.write(args.channel, value)
        if args.json:
            _print_json({"channel": args.channel, "value": _jsonable(ch.codec.check(value)), "ok": True})
    return 0


def cmd_call(args: argparse.Namespace) -> int:
    with _open(args) as dev:
        ch = dev.channel(args.action)
        arg = None if args.arg is None else ch.codec.parse_text(args.arg)
        result = dev.call(args.action, arg)
        if args.json:
            _print_json({"action": args.action, "result": _jsonable(result)})
        elif result is not None:
            print(_fmt_value(result))
    return 0


def _health_line(dev: Device) -> Dict[str, Any]:
    h = dev.health()
    return {"state": h.state,
            "heartbeat_age_ms": None if h.heartbeat_age is None else round(h.heartbeat_age * 1000),
            "hub_errors": h.hub_counters, "device_errors": h.device_counters}


def watch_duration(requested: Optional[float], stdout_is_tty: bool) -> Optional[float]:
    """Seconds ``watch`` runs: as requested, else forever on a terminal and 10 s otherwise."""
    if requested is not None:
        return requested
    return None if stdout_is_tty else 10.0


def cmd_watch(args: argparse.Namespace) -> int:
    tty = sys.stdout.isatty() and not args.json
    duration = watch_duration(args.duration, sys.stdout.isatty())
    rate = max(0.1, args.rate)
    try:
        dev = _open(args)
    except KeyboardInterrupt:
        return 130
    events: List[str] = []
    start = time.monotonic()
    try:
        with dev, dev.events() as evs:
            readable = [c for c in dev.descriptor.channels if c.readable]
            next_at = start
            while duration is None or time.monotonic() - start < duration:
                # wait for events until the next refresh is due
                while True:
                    left = next_at - time.monotonic()
                    if duration is not None:
                        left = min(left, start + duration - time.monotonic())
                    ev = evs.get(max(0.0, left)) if left > 0 else evs.get(0)
                    if ev is None:
                        break
                    t = round(ev.time - start, 3)
                    if args.json:
                        _print_json({"t": t, "event": ev.name, "value": _jsonable(ev.value), "seq": ev.seq})
                    elif tty:
                        events.append(f"{t:8.3f}  {ev.name} = {_fmt_value(ev.value)}")
                        del events[:-8]
                    else:
                        print(f"t={t:.3f} event {ev.name}={_fmt_value(ev.value)}", flush=True)
                if duration is not None and time.monotonic() - start >= duration:
                    break
                next_at = max(next_at + 1.0 / rate, time.monotonic())
                values: Dict[str, Any] = {}
                for c in readable:
                    try:
                        values[c.name] = dev.read(c.name)
                    except LinkLost:
                        values[c.name] = None
                    except HubwireError as e:
                        values[c.name] = f"<{e}>"
                health = _health_line(dev)
                t = round(time.monotonic() - start, 3)
                if args.json:
                    _print_json({"t": t, "values": {k: _jsonable(v) for k, v in values.items()}, "link": health})
                elif tty:
                    _draw(dev, readable, values, events, health, t)
                else:
                    print(f"t={t:.3f} " + " ".join(f"{k}={_fmt_value(v)}" for k, v in values.items()), flush=True)
                    print(f"t={t:.3f} link state={health['state']} heartbeat_age_ms={health['heartbeat_age_ms']} "
                          f"hub_errors={_fmt_counters(health['hub_errors'])} "
                          f"device_errors={_fmt_counters(health['device_errors'])}", flush=True)
    except KeyboardInterrupt:
        if tty:
            sys.stdout.write("\n")
        return 0
    return 0


def _fmt_counters(c: Dict[str, int]) -> str:
    if not c:
        return "-"
    return ",".join(f"{k}:{v}" for k, v in c.items())


def _draw(dev: Device, readable: Sequence[Any], values: Dict[str, Any], events: List[str], health: Dict[str, Any],
          t: float) -> None:
    d = dev.descriptor
    lines = [f"{d.name}{' ' + d.firmware if d.firmware else ''} on {dev.session.url}   t={t:.1f}s   "
             f"link {health['state']}, heartbeat {health['heartbeat_age_ms']} ms ago", ""]
    w = max((len(c.name) for c in readable), default=4)
    for c in readable:
        unit = f" {c.unit}" if c.unit else ""
        lines.append(f"  {c.name.ljust(w)}  {_fmt_value(values.get(c.name))}{unit}")
    lines += ["", f"  errors heard by hub: {_fmt_counters(health['hub_errors'])}   "
                  f"by device: {_fmt_counters(health['device_errors'])}", "", "  events:"]
    lines += [f"  {e}" for e in events] or ["  (none yet)"]
    lines.append("\n  Ctrl-C to quit")
    sys.stdout.write("\x1b[H\x1b[2J" + "\n".join(lines) + "\n")
    sys.stdout.flush()


# ----------------------------------------------------------------------------------------- main

def build_parser() -> argparse.ArgumentParser:
    common = argparse.ArgumentParser(add_help=False)
    common.add_argument("--json", action="store_true", help="machine-readable JSON output")
    common.add_argument("--baud", type=int, default=115200, help="baud rate (default 115200)")
    common.add_argument("--timeout", type=float, default=5.0, help="connect deadline in seconds (default 5)")
    common.add_argument("--no-cache", action="store_true", help="do not use the descriptor cache")
    p = argparse.ArgumentParser(prog="hubwire", description="Talk to a board running the Hubwire library.")
    p.add_argument("--version", action="version", version=f"hubwire {__version__}")
    sub = p.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    url_help = "serial port or pyserial URL (/dev/ttyACM0, COM3, socket://host:port); 'auto' finds the board"
    s = sub.add_parser("ports", parents=[common], help="list serial ports, marking known boards")
    s.set_defaults(fn=cmd_ports)
    s = sub.add_parser("info", parents=[common], help="show the device and its channels")
    s.add_argument("url", help=url_help)
    s.set_defaults(fn=cmd_info)
    s = sub.add_parser("get", parents=[common], help="read a channel")
    s.add_argument("url", help=url_help)
    s.add_argument("channel")
    s.set_defaults(fn=cmd_get)
    s = sub.add_parser("set", parents=[common], help="write a channel (JSON for arrays and structs)")
    s.add_argument("url", help=url_help)
    s.add_argument("channel")
    s.add_argument("value")
    s.set_defaults(fn=cmd_set)
    s = sub.add_parser("call", parents=[common], help="call an action")
    s.add_argument("url", help=url_help)
    s.add_argument("action")
    s.add_argument("arg", nargs="?")
    s.set_defaults(fn=cmd_call)
    s = sub.add_parser("watch", parents=[common], help="live view of channels, events and link health")
    s.add_argument("url", help=url_help)
    s.add_argument("--duration", type=float, default=None,
                   help="stop after this many seconds (default: until Ctrl-C on a terminal, 10 s otherwise)")
    s.add_argument("--rate", type=float, default=2.0, help="refreshes per second (default 2)")
    s.set_defaults(fn=cmd_watch)
    return p


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Entry point of the ``hubwire`` command; returns the exit status."""
    args = build_parser().parse_args(argv)
    try:
        return int(args.fn(args))
    except KeyboardInterrupt:
        return 130
    except KeyError as e:
        msg = e.args[0] if e.args else str(e)
        _error(args, str(msg))
        return 1
    except NakError as e:
        _error(args, str(e), e.error)
        return 1
    except HubwireError as e:
        _error(args, str(e), type(e).__name__)
        return 1


def _error(args: argparse.Namespace, msg: str, kind: str = "error") -> None:
    if getattr(args, "json", False):
        _print_json({"error": kind, "message": msg})
    sys.stderr.write(f"hubwire: {msg}\n")


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
