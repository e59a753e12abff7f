"""``hubwire serve`` and ``hubwire list``: the service's command line."""
from __future__ import annotations

import argparse
import asyncio
import inspect
import logging
import signal
import ssl
import sys
from typing import Any, Awaitable, Callable, Dict, List, Optional, Sequence, Tuple

from ..errors import HubwireError
from ..bridge.broker import BrokerSettings, argv_options, settings_from_args
from ..bridge.broker import broker_address as parse_address
from ..daemon.fleet import Fleet
from ..client.protocol import default_serve_socket
from ..daemon.server import Server

__all__ = ["add_commands", "serve", "cmd_serve", "cmd_list", "SHUTDOWN_S"]

log = logging.getLogger("hubwire.service")

#: after SIGTERM / SIGINT the service is gone within this long: the bridge says `offline`, the
#: boards' links close; whatever has not finished by then is abandoned
SHUTDOWN_S = 2.0


def add_commands(sub: Any, out: argparse.ArgumentParser) -> None:
    """The ``serve`` and ``list`` subcommands (``out`` gives ``--json``)."""
    s = sub.add_parser("serve", help="own every board and serve them to other programs (docs/SERVICE.md)",
                       description="Find every attached board (USB hotplug), keep each linked and serve them by "
                                   "name on a local socket to `hubwire get/set/call/watch NAME` and "
                                   "hubwire.connect(\"NAME\").")
    s.add_argument("ports", nargs="*", metavar="PORT",
                   help="also serve these ports or URLs (ptys, socket://...), re-opened whenever they come back")
    s.add_argument("--watch", action="append", default=[], metavar="GLOB",
                   help="serve every port matching this glob as it appears ('/dev/serial/by-id/*', '/tmp/boards/*')")
    s.add_argument("--no-usb", action="store_true", help="do not look for USB boards (only PORTs and --watch)")
    s.add_argument("--socket", default=None, help=f"the socket clients use (default {default_serve_socket()})")
    s.add_argument("--state", default=None, metavar="DIR",
                   help="directory (0700) for what survives a restart: hub events not yet delivered, the recent "
                        "events of each board (default $HUBWIRE_STATE_DIR, else /var/lib/hubwire as root, else "
                        "$XDG_STATE_HOME/hubwire)")
    s.add_argument("--timeout", type=float, default=5.0, help="connect deadline per board in seconds (default 5)")
    s.add_argument("--poll", type=float, default=0.5, help="seconds between port scans (default 0.5)")
    s.add_argument("--mqtt", metavar="HOST:PORT", default=None,
                   help="also run the MQTT bridge to this broker (hubwire.bridge.mqtt)")
    s.add_argument("--mqtt-id", default=None, metavar="ID",
                   help="this service's id on the broker (default: the host name); each service on one "
                        "broker needs its own")
    s.add_argument("--mqtt-hub", action="append", default=[], metavar="PATTERN",
                   help="back the hub channels matching BOARD/CHANNEL (fnmatch: 'thermostat/*', '*') from MQTT "
                        "when no client provides them (docs/MQTT.md \"Hub channels\")")
    for flags, kw in argv_options():
        s.add_argument(*flags, **kw)
    s.add_argument("--http", type=int, default=None, metavar="HTTP_PORT",
                   help="also serve the dashboard on this port (hubwire.dashboard; docs/DASHBOARD.md)")
    s.add_argument("--http-host", default="127.0.0.1",
                   help="address the dashboard listens on (default 127.0.0.1: this machine only)")
    from ..dashboard import add_access_options  # (imports without NiceGUI)

    add_access_options(s, "--http-host")
    s.add_argument("-v", "--verbose", action="store_true", help="log every board and link change")
    s.set_defaults(fn=cmd_serve)
    s = sub.add_parser("list", parents=[out], help="boards known to the running hubwire serve")
    s.set_defaults(fn=cmd_list)


async def serve(fleet: Fleet, socket: str, bridge: Optional[Callable[..., Any]] = None,
                mqtt: Optional[str] = None, ready: Any = None,
                clients: Sequence[Callable[[Fleet], Awaitable[Any]]] = (), mqtt_id: Optional[str] = None,
                broker: Optional[BrokerSettings] = None) -> None:
    """Run ``fleet`` and its client socket until cancelled (SIGTERM / SIGINT from :func:`cmd_serve`);
    with ``bridge`` (``hubwire.bridge.mqtt.run_bridge``), ``bridge(fleet, host=, port=)`` for ``mqtt``
    (or for ``broker``: then with its username, password, TLS and reply prefixes too); each of
    ``clients`` (the dashboard) runs on the fleet as one more task until the service stops. A stop
    takes at most :data:`SHUTDOWN_S`."""
    server = Server(fleet, socket)
    await server.start()
    await fleet.start()
    task: Optional["asyncio.Future[Any]"] = None
    others: List["asyncio.Future[Any]"] = []
    try:
        if bridge is not None and (mqtt is not None or broker is not None):
            if broker is None:
                host, port = broker_address(mqtt or "")
                kw: Dict[str, Any] = {"service_id": mqtt_id} if mqtt_id else {}
            else:
                host, port, kw = broker.host, broker.effective_port, broker.bridge_kwargs()
            res = bridge(fleet, host=host, port=port, **kw)
            task = asyncio.ensure_future(res) if inspect.isawaitable(res) else None
        others = [asyncio.ensure_future(c(fleet)) for c in clients]
        if ready is not None:
            ready()
        await asyncio.Event().wait()
    finally:
        deadline = asyncio.get_running_loop().time() + SHUTDOWN_S
        running = ([task] if task is not None else []) + others
        for t in running:
            t.cancel()
        # awaited, not only cancelled: the bridge's clean stop publishes `offline` before it
        # disconnects (a clean disconnect drops the last will)
        if running:
            await asyncio.wait(running, timeout=SHUTDOWN_S)
        await server.close()
        left = max(0.1, deadline - asyncio.get_running_loop().time())
        try:
            await asyncio.wait_for(fleet.close(), left)
        except asyncio.TimeoutError:
            log.warning("hubwire serve: the boards' links did not close within %.0f s; stopping anyway", SHUTDOWN_S)


def broker_address(where: str) -> Tuple[str, int]:
    """``HOST:PORT`` (or ``HOST``: port 1883)."""
    host, port = parse_address(where)
    return host, port if port is not None else 1883


def mqtt_bridge() -> Callable[..., Any]:
    """``hubwire.bridge.mqtt.run_bridge``, or SystemExit saying it is missing."""
    try:
        from ..bridge.mqtt import run_bridge
    except ImportError as e:
        raise SystemExit(f"hubwire serve: --mqtt needs the MQTT client libraries, which this installation "
                         f"lacks ({e}); install them with: pip install 'hubwire[mqtt]'") from None
    return run_bridge


def dashboard(args: argparse.Namespace) -> Callable[[Fleet], Awaitable[Any]]:
    """The dashboard on the service's boards (``--http``), or SystemExit saying how to install it."""
    try:
        from ..dashboard import address_line, load_token, run_dashboard
    except ImportError as e:
        raise SystemExit(f"hubwire serve: --http needs the dashboard's libraries, which this installation "
                         f"lacks ({e}); install them with: pip install 'hubwire[dashboard]'") from None
    try:
        token, made = load_token(args.token, args.token_file)
    except (OSError, ValueError) as e:
        raise SystemExit(f"hubwire serve: dashboard token: {e}") from None

    def started() -> None:
        # a token the user gave is never printed (this goes to the journal under systemd)
        print(f"hubwire serve: dashboard at {address_line(args.http_host, args.http, token, made)}",
              file=sys.stderr, flush=True)

    async def run(fleet: Fleet) -> None:
        await run_dashboard(fleet, args.http_host, args.http, token, started=started, allow_hosts=args.allow_host)
    return run


def cmd_serve(args: argparse.Namespace) -> int:
    logging.basicConfig(level=logging.INFO if args.verbose else logging.WARNING,
                        format="hubwire serve: %(message)s" if not args.verbose else "%(asctime)s %(message)s")
    logging.getLogger("hubwire.service").setLevel(logging.INFO)
    sock = args.socket or default_serve_socket()
    try:
        broker = settings_from_args(args)
        if broker is not None:
            broker.tls_context()  # unreadable certificate or key files: say so now, not on each retry
    except (OSError, ValueError, ssl.SSLError) as e:
        raise SystemExit(f"hubwire serve: MQTT settings: {e}") from None
    bridge = mqtt_bridge() if broker is not None else None
    clients = [dashboard(args)] if args.http is not None else []
    if broker is not None:  # hub channels on the broker: their status, and those --mqtt-hub backs
        from ..bridge.hub_topics import hub_bridge_task

        clients.append(hub_bridge_task(broker, args.mqtt_hub))
    from ..daemon.store import Store, state_dir

    try:
        store = Store(state_dir(args.state))
    except (OSError, HubwireError) as e:
        raise SystemExit(f"hubwire serve: {e}") from None
    fleet = Fleet(ports=args.ports, globs=args.watch, usb=not args.no_usb, connect_timeout=args.timeout,
                  poll_interval=args.poll, store=store)

    async def main() -> None:
        task = asyncio.current_task()
        loop = asyncio.get_running_loop()
        for sig in (signal.SIGTERM, signal.SIGINT):
            loop.add_signal_handler(sig, task.cancel)  # type: ignore[union-attr]
        await serve(fleet, sock, bridge, ready=lambda: print(f"READY {sock}", flush=True),
                    clients=clients, broker=broker)

    try:
        asyncio.run(main())
    except asyncio.CancelledError:
        pass
    finally:
        store.close()
    return 0


def cmd_list(args: argparse.Namespace) -> int:
    from .support import print_json
    from ..client.connection import Connection

    async def boards() -> List[Any]:
        conn = await Connection.open()
        try:
            return list((await conn.request("list"))["boards"])
        finally:
            await conn.close()

    rows = asyncio.run(boards())
    if args.json:
        print_json(rows)
        return 0
    if not rows:
        print("hubwire serve runs, and has found no board yet")
    for b in rows:
        sys.stdout.write(f"{b['key']}  {b['name']}  id {b['board_id'] or '-'}  {b['state']}"
                         f"{'  on ' + b['port'] if b['port'] else ''}\n")
    return 0
