"""The browser dashboard: every board live, drawn from its descriptor (``pip install './host[dashboard]'`` from the clone).

``hubwire dashboard PORTS... --http 8080`` opens the boards itself; ``hubwire serve --http 8080``
serves the page for the service's boards by calling :func:`run_dashboard` with its fleet::

    from hubwire.dashboard import run_dashboard
    token, made = load_token()      # --token-file, --token, $HUBWIRE_DASHBOARD_TOKEN, or a new one
    await run_dashboard(fleet, host="127.0.0.1", port=8080, token=token)

NiceGUI is imported only when the page is served, so this package imports without it.
"""
from __future__ import annotations

from typing import Any

from .fleet import Board, BoardLike, DeviceFleet, FleetLike
from .auth import load_token
from .server import DEFAULT_PORT, is_loopback

__all__ = ["run_dashboard", "DeviceFleet", "Board", "BoardLike", "FleetLike", "DEFAULT_PORT",
           "is_loopback", "load_token", "address_line", "add_access_options"]


def add_access_options(parser: Any, host_option: str = "--host") -> None:
    """``--token``, ``--token-file``, ``--allow-host`` (``hubwire dashboard`` and ``hubwire serve``)."""
    parser.add_argument("--token", default=None,
                        help="secret browsers must give (?token=...); visible to other users in the process "
                             "list: prefer --token-file or $HUBWIRE_DASHBOARD_TOKEN. Without any, one is made up "
                             "and printed once in the address to open")
    parser.add_argument("--token-file", default=None, metavar="FILE",
                        help="read the dashboard's token from the first line of FILE (never printed)")
    parser.add_argument("--allow-host", action="append", default=[], metavar="NAME",
                        help="also answer to this host name (besides localhost, 127.0.0.1, [::1] and the "
                             f"{host_option} address); may be repeated")


def address_line(host: str, port: int, token: str, made: bool) -> str:
    """The address to open: with the token when it was made up here (printed this once), without it
    when the user gave it (a token the user chose is never printed)."""
    where = {"127.0.0.1": "localhost", "::1": "localhost", "0.0.0.0": _hostname(), "::": _hostname()}.get(host, host)
    url = f"http://{where}:{port}/"
    return url + f"?token={token}" if made else url + "  (add ?token= and the token you gave)"


def _hostname() -> str:
    import socket

    return socket.gethostname()


async def run_dashboard(fleet: FleetLike, host: str = "127.0.0.1", port: int = DEFAULT_PORT,
                        token: Any = None, **kwargs: Any) -> None:
    """Serve the dashboard of ``fleet`` until cancelled (see :func:`hubwire.dashboard.server.run_dashboard`)."""
    from .server import run_dashboard as serve

    await serve(fleet, host, port, token, **kwargs)
