"""What the dashboard needs of a board registry, and a small registry of directly opened devices.

``hubwire serve`` owns the boards of a machine and hands the dashboard its ``Fleet``; the dashboard
only uses the part described by :class:`FleetLike` and :class:`BoardLike` (docs/DASHBOARD.md).
:class:`DeviceFleet` is that shape built from serial ports given on the command line, for
``hubwire dashboard PORTS...`` when no service runs.
"""
from __future__ import annotations

import asyncio
import contextlib
import logging
import os
from dataclasses import dataclass
from typing import Any, AsyncIterator, Dict, List, Optional, Protocol, Set

from .. import aio
from ..errors import HubwireError
from ..service.topics import board_key

__all__ = ["BoardLike", "FleetLike", "Board", "DeviceFleet", "board_id_of"]

log = logging.getLogger("hubwire.dashboard")


class BoardLike(Protocol):
    """One board of a fleet (read-only view of ``hubwire.service.fleet.Board``)."""

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


@dataclass
class Board:
    """A board of a :class:`DeviceFleet` (the fields of :class:`BoardLike`)."""

    key: str
    name: str
    board_id: Optional[str]
    port: Optional[str]
    state: str
    device: Optional[aio.AsyncDevice]


def board_id_of(dev: aio.AsyncDevice, port: str) -> Optional[str]:
    """The id the device reports (once the hub asks for it), else the port's USB serial number."""
    reported = getattr(dev, "board_id", None)
    if isinstance(reported, str) and reported:
        return reported
    with contextlib.suppress(Exception):  # pyserial cannot always describe a port (ptys, sockets)
        from serial.tools import list_ports

        real = os.path.realpath(port)
        for p in list_ports.comports():
            if p.device in (port, real) and p.serial_number:
                return str(p.serial_number)
    return None


class DeviceFleet:
    """Boards opened directly from serial ports (or pyserial URLs), one session each.

    A port that does not answer yet is tried again every ``retry`` s; a board joins the fleet once
    it has been discovered. After that its session rides through link losses and port replugs by
    itself (state ``lost`` meanwhile, then ``ready``), so its ``device`` stays the same object.
    Its key is the device name, or ``name-<board id or port>`` when two boards share a name.
    """

    def __init__(self, ports: List[str], *, retry: float = 1.0, poll: float = 0.1, **connect_kwargs: Any) -> None:
        self.ports = list(ports)
        self.retry = retry
        self.poll = poll
        self.connect_kwargs = connect_kwargs
        self._boards: Dict[str, Board] = {}
        self._queues: Set["asyncio.Queue[Board]"] = set()
        self._tasks: List["asyncio.Task[None]"] = []
        #: ports not opened yet, with the last reason
        self.pending: Dict[str, str] = {p: "not tried yet" for p in ports}

    async def start(self) -> "DeviceFleet":
        """Start opening every port (returns at once; boards appear through :meth:`changes`)."""
        self._tasks = [asyncio.ensure_future(self._keep(p)) for p in self.ports]
        return self

    async def close(self) -> None:
        for t in self._tasks:
            t.cancel()
        for t in self._tasks:
            with contextlib.suppress(asyncio.CancelledError, Exception):
                await t
        for b in list(self._boards.values()):
            if b.device is not None:
                await b.device.close()
        for q in list(self._queues):
            q.put_nowait(Board("", "", None, None, "closed", None))  # wakes changes() to end

    async def __aenter__(self) -> "DeviceFleet":
        return await self.start()

    async def __aexit__(self, *exc: Any) -> None:
        await self.close()

    # ------------------------------------------------------------------------- the FleetLike API

    def boards(self) -> List[Board]:
        return list(self._boards.values())

    def get(self, key: str) -> Board:
        try:
            return self._boards[key]
        except KeyError:
            raise KeyError(f"no board {key!r}; boards: {', '.join(sorted(self._boards)) or 'none'}") from None

    async def changes(self) -> AsyncIterator[Board]:
        q: "asyncio.Queue[Board]" = asyncio.Queue()
        self._queues.add(q)
        try:
            while True:
                b = await q.get()
                if b.state == "closed" and not b.key:
                    return
                yield b
        finally:
            self._queues.discard(q)

    # ------------------------------------------------------------------------------ inside

    def _changed(self, b: Board) -> None:
        for q in self._queues:
            q.put_nowait(b)

    def _key_for(self, name: str, board_id: Optional[str], port: str) -> str:
        # the service's rule (docs/SERVICE.md): from the board's identity, never the order found
        n = 1
        while board_key(name, board_id, n) in self._boards:
            n += 1
        return board_key(name, board_id, n)

    async def _keep(self, port: str) -> None:
        """Open ``port`` (retrying while it is absent), then follow its state until cancelled."""
        while True:
            try:
                dev = await aio.connect(port, **{"hub_later": True, **self.connect_kwargs})
                break
            except (HubwireError, OSError) as e:
                self.pending[port] = str(e)
                log.info("hubwire dashboard: %s: %s (trying again in %g s)", port, e, self.retry)
                await asyncio.sleep(self.retry)
        del self.pending[port]
        board = Board(self._key_for(dev.name, board_id_of(dev, port), port), dev.name,
                      board_id_of(dev, port), port, dev.state, dev)
        self._boards[board.key] = board
        self._changed(board)
        wake = asyncio.Event()
        for what in ("link_lost", "link_restored", "reconnect"):
            dev.on(what, lambda *a: wake.set())
        try:
            while True:
                # callbacks make changes prompt; the poll catches the ones without a callback
                with contextlib.suppress(asyncio.TimeoutError):
                    await asyncio.wait_for(wake.wait(), self.poll)
                wake.clear()
                if dev.state != board.state:
                    board.state = dev.state
                    self._changed(board)
        finally:
            await dev.close()
