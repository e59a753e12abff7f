"""What the dashboard needs of a board registry, and the service's registry over ports given by name.

``hubwire serve`` owns the boards of a machine and hands the dashboard its ``Fleet``; the dashboard
only uses the part described by :class:`FleetLike` and :class:`BoardLike` (docs/DASHBOARD.md).
:class:`DeviceFleet` is the same fleet over the serial ports given on the command line, for
``hubwire dashboard PORTS...`` when no service runs.
"""
from __future__ import annotations

from typing import Any, AsyncIterator, List, Optional, Protocol, Union

from .. import aio
from ..daemon.fleet import Board, Fleet

__all__ = ["BoardLike", "FleetLike", "Board", "DeviceFleet"]


class BoardLike(Protocol):
    """One board of a fleet (read-only view of ``hubwire.daemon.fleet.Board``)."""

    @property
    def key(self) -> str: ...
    @property
    def name(self) -> str: ...
    @property
    def board_id(self) -> Optional[str]: ...
    @property
    def port(self) -> Optional[str]: ...
    @property
    def state(self) -> str: ...  # "connecting" | "ready" | "lost" | "unplugged"
    @property
    def device(self) -> Optional[aio.AsyncDevice]: ...


class FleetLike(Protocol):
    """A board registry living on the caller's event loop."""

    def boards(self) -> List[Any]: ...  # of BoardLike
    def get(self, key: str) -> Any: ...  # BoardLike; KeyError for an unknown key
    def changes(self) -> AsyncIterator[Any]: ...  # BoardLike each time one is added or changes


class DeviceFleet(Fleet):
    """The service's fleet over the ports (or pyserial URLs) given, and nothing else: no USB scan, no
    udev, no store. A port that is absent or does not answer yet is tried again (``pending`` says
    why it serves no board); a board rides through link losses and replugs by itself (state
    ``lost`` meanwhile, then ``ready``). Keys are the service's (docs/SERVICE.md)."""

    def __init__(self, ports: List[str], *, timeout: float = 5.0, baudrate: int = 115200,
                 cache_dir: Union[str, bool, None] = None, poll: float = 0.5) -> None:
        super().__init__(ports=ports, usb=False, udev=False, connect_timeout=timeout, cache_dir=cache_dir,
                         poll_interval=poll, baudrate=baudrate)
