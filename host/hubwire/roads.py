"""The two roads to a board: a port this program opens itself, or ``hubwire serve`` (docs/SERVICE.md).

:func:`hubwire.connect` and :func:`hubwire.aio.connect` ask the service road installed here before
they open a port; the package installs the service's client (:mod:`hubwire.client.route`) when it
is imported. So the face never imports the client: the client is built on the face, and the
package joins the two (docs/ARCHITECTURE.md, "The layers of host/hubwire").
"""
from __future__ import annotations

from typing import Any, Dict, Optional, Protocol

__all__ = ["ServiceRoad", "install", "service_road"]


class ServiceRoad(Protocol):
    """What the face needs of the service's client."""

    def open_routed(self, url: Optional[str], timeout: float, kwargs: Dict[str, Any]) -> Optional[Any]:
        """The board (a ``Device`` over a stand-in for its ``Session``) when it is reached through
        the service, else None: open the port directly."""

    def connecting(self, url: Optional[str], baudrate: int, timeout: float, kwargs: Dict[str, Any]) -> Any:
        """What ``hubwire.aio.connect(url)`` returns: awaitable and an async context manager, through
        the service where it applies, else on the port."""


_road: Optional[ServiceRoad] = None


def install(road: Optional[ServiceRoad]) -> None:
    """Use ``road`` for every later connect without a transport (None: ports only)."""
    global _road
    _road = road


def service_road() -> Optional[ServiceRoad]:
    return _road
