"""``hubwire dashboard PORTS... --http PORT``: the dashboard on boards opened directly (without the
service)."""
from __future__ import annotations

import argparse
import asyncio
import contextlib
import signal
import sys
from typing import Any, Dict, List, Tuple

from ..ports import board_ports as known_boards
from . import add_access_options, address_line
from .auth import load_token
from .server import DEFAULT_PORT, run_dashboard

__all__ = ["add_parser", "cmd_dashboard", "board_ports", "parse_rates"]


def add_parser(sub: Any, parents: List[argparse.ArgumentParser]) -> None:
    s = sub.add_parser(
        "dashboard", parents=parents, help="every board live in the browser (pip install './host[dashboard]')",
        description="Serve a web page showing each board: live values and plots, inputs for writable "
                    "channels, action buttons, events, link health and the descriptor. Listens on "
                    "this machine only unless --host says otherwise; a token is always required.")
    s.add_argument("ports", nargs="*", metavar="PORT",
                   help="serial ports or pyserial URLs of the boards (default: every port with a known board "
                        "USB id); a port that is absent yet is tried again every second")
    s.add_argument("--http", type=int, default=DEFAULT_PORT, metavar="HTTP_PORT",
                   help=f"web server port (default {DEFAULT_PORT})")
    s.add_argument("--host", default="127.0.0.1",
                   help="address to listen on (default 127.0.0.1: this machine only; 0.0.0.0: the network)")
    add_access_options(s)
    s.add_argument("--rate", action="append", default=[], metavar="[CHANNEL=]HZ",
                   help="samples per second asked at first of each streamable channel (default 10), or of "
                        "one channel (imu=100; rover.imu=100 for one board's); may be repeated")
    s.set_defaults(fn=cmd_dashboard)


def board_ports() -> List[str]:
    """Every serial port with a known board USB id."""
    return [str(p.device) for p in known_boards()]


def parse_rates(items: List[str]) -> Tuple[float, Dict[str, float]]:
    """``["20", "imu=100"]`` -> (20.0, {"imu": 100.0}); the default rate is 10 Hz."""
    default, rates = 10.0, {}
    for item in items:
        name, _, hz = item.rpartition("=")
        value = float(hz)
        if not 0 < value <= 1000:
            raise ValueError(f"{item}: a rate is 0..1000 Hz")
        if name:
            rates[name] = value
        else:
            default = value
    return default, rates


def cmd_dashboard(args: argparse.Namespace) -> int:
    try:
        import nicegui  # noqa: F401
    except ImportError:
        from ..diagnose import install_hint

        sys.stderr.write(f"hubwire: the dashboard needs NiceGUI (Python 3.10+): {install_hint('dashboard')}\n")
        return 1
    ports = list(args.ports) or board_ports()
    if not ports:
        sys.stderr.write("hubwire: no board found: name its port (hubwire dashboard /dev/ttyACM0)\n")
        return 1
    try:
        args.stream_hz, args.rates = parse_rates(args.rate)
    except ValueError as e:
        sys.stderr.write(f"hubwire: --rate: {e}\n")
        return 2
    try:
        token = load_token(args.token, args.token_file)
    except (OSError, ValueError) as e:
        sys.stderr.write(f"hubwire: dashboard token: {e}\n")
        return 2
    try:
        return asyncio.run(_main(args, ports, token))
    except KeyboardInterrupt:
        return 130


async def _main(args: argparse.Namespace, ports: List[str], token: Any) -> int:
    """Serve until SIGINT (status 130, as Ctrl-C ends other commands) or SIGTERM (0), shutting the
    web server and the boards' sessions down in order."""
    from .fleet import DeviceFleet

    loop = asyncio.get_running_loop()
    me = asyncio.current_task()
    got: List[int] = []

    def stop(sig: int) -> None:
        got.append(sig)
        if me is not None:
            me.cancel()

    for sig in (signal.SIGINT, signal.SIGTERM):
        with contextlib.suppress(NotImplementedError):  # no add_signal_handler on Windows
            loop.add_signal_handler(sig, stop, sig)

    def started() -> None:
        print(f"hubwire dashboard: {address_line(args.host, args.http, *token)}  ({', '.join(ports)}; "
              "Ctrl-C to stop)", flush=True)

    kwargs = {"timeout": args.timeout, "baudrate": args.baud}
    if args.no_cache:
        kwargs["cache_dir"] = False
    try:
        async with DeviceFleet(ports, **kwargs) as fleet:
            await run_dashboard(fleet, args.host, args.http, token[0], stream_hz=args.stream_hz, rates=args.rates,
                                started=started, allow_hosts=args.allow_host)
    except asyncio.CancelledError:
        if not got:
            raise
    return 130 if got and got[0] == signal.SIGINT else 0
