"""The browser dashboard: every board live, drawn from its descriptor (``pip install 'hubwire[dashboard]'``).

``hubwire dashboard PORTS... --http 8080`` opens the boards itself; ``hubwire serve --http 8080``
serves the page for the service's boards by calling :func:`run_dashboard` with its fleet::

    from hubwire.dashboard import run_dashboard
    await run_dashboard(fleet, host="127.0.0.1", port=8080, token=None)

NiceGUI is imported only when the page is served, so this package imports without it.
"""
from __future__ import annotations

from typing import Any

from .fleet import Board, BoardLike, DeviceFleet, FleetLike
from .server import DEFAULT_PORT, is_loopback, resolve_token

__all__ = ["run_dashboard", "DeviceFleet", "Board", "BoardLike", "FleetLike", "DEFAULT_PORT",
           "is_loopback", "resolve_token"]


async def run_dashboard(fleet: FleetLike, host: str = "127.0.0.1", port: int = DEFAULT_PORT,
                        token: Any = None, **kwargs: Any) -> None:
    """Serve the dashboard of ``fleet`` until cancelled (see :func:`hubwire.dashboard.server.run_dashboard`)."""
    from .server import run_dashboard as serve

    await serve(fleet, host, port, token, **kwargs)
