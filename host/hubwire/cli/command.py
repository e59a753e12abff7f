"""``hubwire`` command line: ports, info, get, set, call, watch (all with ``--json``); serve and list
(:mod:`hubwire.cli.serve`); dashboard (:mod:`hubwire.dashboard`)."""
from __future__ import annotations

import argparse
import os
import sys
from typing import Any, Optional, Sequence

from .. import __version__, diagnose
from .support import (CliError, channel, channel_json, fmt_value, goal_or_argument, jsonable, open_device,
                          print_json)
from .mission import run_mission
from .watch import cmd_watch, watch_duration
from ..device import channel_table
from ..errors import HubwireError, error_json
from ..ports import board_kind, serial_ports

__all__ = ["main", "build_parser", "watch_duration"]


# ------------------------------------------------------------------------------------- commands

def cmd_ports(args: argparse.Namespace) -> int:
    rows = []
    for p in serial_ports():
        rows.append({"device": p.device, "vid": p.vid, "pid": p.pid, "description": p.description,
                     "serial_number": p.serial_number, "board": board_kind(p)})
    if args.json:
        print_json(rows)
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
    with open_device(args) as dev:
        d = dev.descriptor
        # through hubwire serve: who provides each hub channel (client/hub_client.py)
        providers = dev.session.hub_status() if d.hub and hasattr(dev.session, "hub_status") else None
        if args.json:
            print_json({"url": dev.session.url, "name": d.name, "firmware": d.firmware, "protocol": d.protocol,
                         "descriptor_hash": f"{d.hash:08x}", "descriptor_length": len(d.raw),
                         "channels": [channel_json(c) for c in d.channels],
                         "hub": [channel_json(c) for c in d.hub],
                         **({"hub_providers": providers} if providers is not None else {})})
        else:
            print(f"{d.name}{' ' + d.firmware if d.firmware else ''} on {dev.session.url} "
                  f"(descriptor {len(d.raw)} bytes, hash {d.hash:08x})")
            print(dev.table())
            if d.hub:
                print(f"\nhub channels {d.name} uses (id: hub id; access: what the board does with it):")
                print(channel_table(d, hub=True))
            if providers is not None:
                from ..client.hub_client import status_lines

                print(f"\nprovided through hubwire serve:\n{status_lines(providers)}")
    return 0


def cmd_get(args: argparse.Namespace) -> int:
    with open_device(args) as dev:
        channel(dev, args.channel, "r")
        v = dev.read(args.channel)
        if args.json:
            print_json({"channel": args.channel, "value": jsonable(v)})
        else:
            print(fmt_value(v))
    return 0


def cmd_set(args: argparse.Namespace) -> int:
    with open_device(args) as dev:
        ch = channel(dev, args.channel, "w")
        value = ch.codec.parse_text(args.value)
        dev.write(args.channel, value)
        # through hubwire serve the board stays linked after the command: no failsafe to warn of
        held = getattr(dev.session, "remote", None) is not None
        warning = None if ch.failsafe is None or held else diagnose.failsafe_warning(
            ch.name, fmt_value(ch.failsafe), fmt_value(ch.codec.check(value)))
        if args.json:
            out = {"channel": args.channel, "value": jsonable(ch.codec.check(value)), "ok": True}
            print_json({**out, "warning": warning} if warning else out)
        elif warning:
            sys.stderr.write(f"hubwire: warning: {warning}\n")
    return 0


def cmd_call(args: argparse.Namespace) -> int:
    with open_device(args) as dev:
        if args.action in dev and dev.channel(args.action).mission:
            return run_mission(dev, args)
        ch = channel(dev, args.action, "c")
        arg = goal_or_argument(ch, args.arg)
        result = dev.call(args.action, arg)
        if args.json:
            print_json({"action": args.action, "result": jsonable(result)})
        elif result is not None:
            print(fmt_value(result))
    return 0


_VALUE_HELP = ("the new value: a number (1.5, -2, 0x10), a bool (true/false, 1/0, on/off, yes/no), text as "
               "it is (quote it for the shell), JSON for arrays and structs ('[1, 2, 3]', '{\"x\": 1}')")
_EPILOG = ("exit status: 0 done, 1 error, 2 usage error, 130 Ctrl-C, 141 output closed (| head).\n"
           "With --json an error is one line on stdout: {\"error\": TYPE, \"message\": TEXT} (a Nak adds \"nak\",\n"
           "\"code\" and \"channel\", an InvalidValue \"code\"), where TYPE is\n"
           + "".join(f"  {k:<21} {v}\n" for k, v in diagnose.ERROR_TYPES.items()))


class _Parser(argparse.ArgumentParser):
    """Reports usage errors as JSON when ``--json`` was asked for."""

    json_errors = False

    def error(self, message: str) -> Any:
        if _Parser.json_errors:
            print_json({"error": "Usage", "message": f"{self.prog}: {message}"})
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
    url_help = ("serial port or pyserial URL (/dev/ttyACM0, COM3, socket://host:port), or a board's name when "
                "hubwire serve runs; 'auto' finds the board")
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
    s = sub.add_parser("call", parents=[common], help="call an action, or run a mission",
                       description="Call an action and print its result; or start a mission, show its "
                                   "progress (a bar when it declares its progress at completion) and print "
                                   "its result. Ctrl-C cancels a mission on the board.")
    s.add_argument("url", help=url_help)
    s.add_argument("action", help="name of an action or a mission (access 'call' or 'mission' in `hubwire info`)")
    s.add_argument("arg", nargs="?", help="the action's argument or the mission's goal, written like a `set` "
                                          "value; none for those that take none")
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
    from .serve import add_commands

    add_commands(sub, out)
    from ..dashboard.cli import add_parser as add_dashboard  # imports NiceGUI only when run

    add_dashboard(sub, [common])
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
        print_json(error_json(exc))
    else:
        sys.stderr.write(f"hubwire: {exc}\n")


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
