"""``hubwire`` command line: ports, info, get, set, call, watch (all with ``--json``)."""
from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from typing import Any, Dict, List, Optional, Sequence, TextIO

from . import __version__, diagnose
from .device import KNOWN_USB_VIDS, Device, connect
from .errors import HubwireError, LinkLost, NakError, Timeout

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


class CliError(Exception):
    """An error the command reports as is: ``kind`` is one of :data:`diagnose.ERROR_TYPES`."""

    def __init__(self, kind: str, message: str) -> None:
        super().__init__(message)
        self.kind = kind


def _open(args: argparse.Namespace) -> Device:
    url = None if args.url in (None, "auto") else args.url
    try:
        return connect(url, args.baud, timeout=args.timeout, progress=_progress_printer(),
                       cache_dir=False if args.no_cache else None)
    except Timeout as e:
        # someone else reading the port takes the answers: say who rather than "no answer"
        holders = diagnose.port_holders(url)
        if holders:
            raise CliError("PortBusy", diagnose.busy_message(str(url), holders)) from e
        raise CliError("ConnectTimeout", str(e)) from e
    except diagnose.PortOpenError:
        raise
    except HubwireError as e:
        if url is not None and isinstance(e.__cause__, OSError):
            raise diagnose.open_error(url, e.__cause__) from e.__cause__
        raise


def _channel(dev: Device, name: str, need: str) -> Any:
    """The channel ``name`` if its access has the letter ``need``; a CliError in words otherwise."""
    try:
        ch = dev.channel(name)
    except KeyError as e:
        raise CliError("UnknownChannel", str(e.args[0] if e.args else e)) from None
    refused = diagnose.access_error(name, ch.access, need)
    if refused:
        raise CliError(*refused)
    return ch


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
        _channel(dev, args.channel, "r")
        v = dev.read(args.channel)
        if args.json:
            _print_json({"channel": args.channel, "value": _jsonable(v)})
        else:
            print(_fmt_value(v))
    return 0


def cmd_set(args: argparse.Namespace) -> int:
    with _open(args) as dev:
        ch = _channel(dev, args.channel, "w")
        value = ch.codec.parse_text(args.value)
        dev.write(args.channel, value)
        warning = None if ch.failsafe is None else diagnose.failsafe_warning(
            ch.name, _fmt_value(ch.failsafe), _fmt_value(ch.codec.check(value)))
        if args.json:
            out = {"channel": args.channel, "value": _jsonable(ch.codec.check(value)), "ok": True}
            _print_json({**out, "warning": warning} if warning else out)
        elif warning:
            sys.stderr.write(f"hubwire: warning: {warning}\n")
    return 0


def cmd_call(args: argparse.Namespace) -> int:
    with _open(args) as dev:
        ch = _channel(dev, args.action, "c")
        if ch.codec.kind == "void" and args.arg is not None:
            raise CliError("InvalidValue", f"{args.action} takes no argument")
        if ch.codec.kind != "void" and args.arg is None:
            raise CliError("InvalidValue", f"{args.action} needs an argument ({ch.codec.name})")
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
    try:
        dev = _open_waiting(args, duration) if args.wait else _open(args)
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
            return _open(args)
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
    while duration is None or time.monotonic() - start < duration:
        _print_events(evs, args, tty, events, start, next_at, duration)
        now = time.monotonic()
        if duration is not None and now - start >= duration:
            break
        next_at = max(next_at + 1.0 / rate, now)
        values = _read_values(dev, readable)
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
            _print_json({"t": t, "event": ev.name, "value": _jsonable(ev.value), "seq": ev.seq})
        elif tty:
            events.append(f"{t:8.3f}  {ev.name} = {_fmt_value(ev.value)}")
            del events[:-8]
        else:
            print(f"t={t:.3f} event {ev.name}={_fmt_value(ev.value)}", flush=True)


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

_VALUE_HELP = ("the new value: a number (1.5, -2, 0x10), a bool (true/false, 1/0, on/off, yes/no), text as "
               "it is (quote it for the shell), JSON for arrays and structs ('[1, 2, 3]', '{\"x\": 1}')")
_EPILOG = ("exit status: 0 done, 1 error, 2 usage error, 130 Ctrl-C, 141 output closed (| head).\n"
           "With --json an error is one line on stdout: {\"error\": TYPE, \"message\": TEXT}, where TYPE is\n"
           + "".join(f"  {k:<21} {v}\n" for k, v in diagnose.ERROR_TYPES.items()))


class _Parser(argparse.ArgumentParser):
    """Reports usage errors as JSON when ``--json`` was asked for."""

    json_errors = False

    def error(self, message: str) -> Any:
        if _Parser.json_errors:
            _print_json({"error": "Usage", "message": f"{self.prog}: {message}"})
            sys.exit(2)
        super().error(message)


def build_parser() -> argparse.ArgumentParser:
    out = _Parser(add_help=False)
    out.add_argument("--json", action="store_true", help="machine-readable JSON output (errors too)")
    common = _Parser(add_help=False, parents=[out])
    common.add_argument("--baud", type=int, default=115200, help="baud rate (default 115200)")
    common.add_argument("--timeout", type=float, default=5.0, help="connect deadline in seconds (default 5)")
    common.add_argument("--no-cache", action="store_true", help="do not use the descriptor cache")
    p = _Parser(prog="hubwire", description="Talk to a board running the Hubwire library.", epilog=_EPILOG,
                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--version", action="version", version=f"hubwire {__version__}")
    sub = p.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    url_help = "serial port or pyserial URL (/dev/ttyACM0, COM3, socket://host:port); 'auto' finds the board"
    s = sub.add_parser("ports", parents=[out], help="list serial ports, marking known boards")
    s.set_defaults(fn=cmd_ports)
    s = sub.add_parser("info", parents=[common], help="show the device and its channels")
    s.add_argument("url", help=url_help)
    s.set_defaults(fn=cmd_info)
    s = sub.add_parser("get", parents=[common], help="read a channel")
    s.add_argument("url", help=url_help)
    s.add_argument("channel", help="name of a readable channel (`hubwire info` lists them)")
    s.set_defaults(fn=cmd_get)
    s = sub.add_parser("set", parents=[common], help="write a channel (JSON for arrays and structs)",
                       description="Write a channel. A channel with a failsafe value goes back to it when "
                                   "this command's connection ends (a warning says so).")
    s.add_argument("url", help=url_help)
    s.add_argument("channel", help="name of a writable channel (`hubwire info` lists them)")
    s.add_argument("value", help=_VALUE_HELP)
    s.set_defaults(fn=cmd_set)
    s = sub.add_parser("call", parents=[common], help="call an action")
    s.add_argument("url", help=url_help)
    s.add_argument("action", help="name of an action (access 'call' in `hubwire info`)")
    s.add_argument("arg", nargs="?", help="the action's argument, written like a `set` value; "
                                          "none for actions that take none")
    s.set_defaults(fn=cmd_call)
    s = sub.add_parser("watch", parents=[common], help="live view of channels, events and link health")
    s.add_argument("url", help=url_help)
    s.add_argument("--duration", type=float, default=None,
                   help="stop after this many seconds (default: until Ctrl-C on a terminal, 10 s otherwise)")
    s.add_argument("--rate", type=float, default=2.0, help="refreshes per second (default 2)")
    s.add_argument("--wait", action="store_true",
                   help="wait for the board to appear and to come back when it goes away (default: end with "
                        "an error once it has been gone for --timeout seconds)")
    s.set_defaults(fn=cmd_watch)
    return p


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Entry point of the ``hubwire`` command; returns the exit status."""
    argv = sys.argv[1:] if argv is None else list(argv)
    _Parser.json_errors = "--json" in argv
    try:
        args = build_parser().parse_args(argv)
        try:
            status = int(args.fn(args))
        except KeyboardInterrupt:
            return 130
        except (CliError, HubwireError) as e:
            _error(args, e)
            status = 1
        sys.stdout.flush()  # here, where a closed pipe can still be handled
        return status
    except BrokenPipeError:
        if not _stdout_closed():
            raise
        # like any Unix tool whose reader went away (`hubwire info P | head -2`): no traceback, and
        # nothing more for Python to flush at exit; the status a shell shows for SIGPIPE
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 141


def _stdout_closed() -> bool:
    try:
        import select

        poller = select.poll()
        poller.register(sys.stdout.fileno(), select.POLLOUT)
        return any(ev & (select.POLLERR | select.POLLHUP) for _, ev in poller.poll(0))
    except (AttributeError, OSError, ValueError):  # no poll (Windows), or no real stdout
        return True


def _error(args: argparse.Namespace, exc: BaseException) -> None:
    """Report ``exc`` once: as JSON on stdout with ``--json``, else as text on stderr."""
    if getattr(args, "json", False):
        obj = {"error": diagnose.error_type(exc), "message": str(exc)}
        if isinstance(exc, NakError):
            obj["nak"] = exc.error
        _print_json(obj)
    else:
        sys.stderr.write(f"hubwire: {exc}\n")


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
