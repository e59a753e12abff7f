"""Which boards ``hubwire.connect()``, ``hubwire.aio.connect()`` and the command line reach through
``hubwire serve``: a board name always does (an error says how to start the service when it does
not run); a port the service owns does; no port at all does when the service has exactly one board;
anything else opens the port directly, as without a service. ``HUBWIRE_NO_SERVICE=1`` turns routing off."""
from __future__ import annotations

import os
from typing import Any, Dict, Optional, cast

from ..aio import _Connecting
from ..errors import NoDeviceFound, UnknownBoard
from ..transport import SerialTransport
from .connection import AsyncRemoteDevice, Connection, connect
from .protocol import ServiceNotRunning, socket_path

__all__ = ["looks_like_port", "open_routed", "route_async", "RoutedConnecting", "connecting"]

_CALLBACKS = ("on_link_lost", "on_link_restored", "on_reconnect")


def looks_like_port(url: str) -> bool:
    """A port or pyserial URL (``/dev/ttyACM0``, ``COM3``, ``socket://...``), not a board name."""
    return "/" in url or "://" in url or url.upper().startswith("COM") or os.path.exists(url)


def _enabled() -> bool:
    return os.environ.get("HUBWIRE_NO_SERVICE", "") in ("", "0")


async def route_async(url: Optional[str], timeout: float) -> Optional[AsyncRemoteDevice]:
    """The board through the service, or None: open the port directly."""
    if not _enabled():
        if url is not None and not looks_like_port(url):
            raise ServiceNotRunning(f"{url!r} is not a port, and HUBWIRE_NO_SERVICE is set: name the board's port")
        return None
    path = socket_path()
    if url is not None and not looks_like_port(url):
        return await connect(url, timeout=timeout, path=path)  # a name: the service or an error
    if path is None:
        return None
    try:
        if url is None:
            conn = await Connection.open(path, timeout)
            try:
                boards = (await conn.request("list"))["boards"]
            finally:
                await conn.close()
            if len(boards) > 1:
                raise NoDeviceFound(f"{len(boards)} boards are served by hubwire serve, name the one to use: "
                                    + ", ".join(b["key"] for b in boards))
            if not boards:
                return None
            url = boards[0]["key"]
        return await connect(url, timeout=timeout, path=path)
    except (ServiceNotRunning, UnknownBoard):
        return None  # no service, or a port it does not own


def open_routed(url: Optional[str], timeout: float, kwargs: Dict[str, Any]) -> Any:
    """A :class:`RemoteDevice` (over a :class:`RemoteSession`) when the board is reached through the
    service, else None."""
    from ..session.runner import acquire_loop, release_loop, run_sync
    from .remote import RemoteDevice, RemoteSession

    if _enabled() and socket_path() is None and (url is None or looks_like_port(url)):
        return None  # the common case without a service: no loop thread started for nothing
    loop = acquire_loop()
    try:
        remote = run_sync(loop, route_async(url, timeout))
    except BaseException:
        release_loop()
        raise
    if remote is None:
        release_loop()
        return None
    session = RemoteSession(loop, remote)
    for name in _CALLBACKS:
        if kwargs.get(name) is not None:
            session._add(name[3:], kwargs[name])
    try:
        session.provide_hub(kwargs.get("hub"))  # the board's hub channels, through the service
    except BaseException:
        session.close()
        raise
    return RemoteDevice(cast(Any, session))  # a Device over the stand-in for its Session


class RoutedConnecting(_Connecting):
    """``hubwire.aio.connect(url)`` without a transport: through the service when it applies."""

    def __init__(self, url: Optional[str], baudrate: int, timeout: float, kwargs: Dict[str, Any]) -> None:
        self._url, self._baudrate = url, baudrate
        self._serial_kwargs = kwargs.pop("serial_kwargs", None) or {}
        super().__init__(None, timeout, kwargs)  # type: ignore[arg-type]

    async def _open(self) -> Any:
        remote = await route_async(self._url, self._timeout)
        if remote is not None:
            for name in _CALLBACKS:
                if self._kwargs.get(name) is not None:
                    remote.on(name[3:], self._kwargs[name])
            try:
                await remote.provide_hub(self._kwargs.get("hub"))  # hub channels through the service
            except BaseException:
                await remote.close()
                raise
            return remote
        from ..ports import find_port

        self._transport = SerialTransport(self._url if self._url is not None else find_port(), self._baudrate,
                                          **self._serial_kwargs)
        return await super()._open()


def connecting(url: Optional[str], baudrate: int, timeout: float, kwargs: Dict[str, Any]) -> RoutedConnecting:
    """``hubwire.aio.connect(url)`` without a transport (this module is the package's service road,
    :mod:`hubwire.roads`)."""
    return RoutedConnecting(url, baudrate, timeout, kwargs)
