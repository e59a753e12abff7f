"""The service's board registry: every board ``hubwire serve`` owns, known by identity, not by port.

A board's identity is its descriptor name plus a board id: the USB serial number of its port where
there is one, else the id the device reports (``AsyncDevice.board_id()``, PROTOCOL.md 3.4), else
none. A board that comes back (replugged, on the same or another port) is the same :class:`Board`
when name and id match; an id-less board is taken for the unplugged one of its name (a caveat when
two id-less boards share a name: after a replug they may swap keys).

Keys clients use (:func:`hubwire.daemon.keys.board_key`): the name, then ``--<board id>`` when the
board has one, each part escaped where it is not plain (``rover``, ``rover--A1B2``,
``a_b-xc14cddc0``); boards claiming the same name and id get ``---2``, ``---3``... The key depends on
the board only, so restarts and replugs never move it. A name only one board has, ``name-<board id>``
and the current port path resolve too (:meth:`Fleet.resolve`).

Everything here runs on the service's one asyncio loop.
"""
from __future__ import annotations

import asyncio
import dataclasses
import logging
import os
import time
from dataclasses import dataclass
from typing import Any, Callable, Dict, List, Optional, Set

from ..aio import AsyncDevice, connect
from ..descriptor import Descriptor
from ..errors import LinkLost, UnknownBoard
from ..transport import SerialTransport
from . import durable
from .hub_providers import HubProviders
from .ports import PortInfo, PortScanner
from .keys import board_key

__all__ = ["Board", "Fleet", "Changes", "UnknownBoard"]

log = logging.getLogger("hubwire.service")

#: seconds between two tries of a port that did not answer as a Hubwire board (doubling up to the max)
RETRY_FIRST = 1.0
RETRY_MAX = 30.0


@dataclass
class Board:
    """One board the service knows (a snapshot: :meth:`Fleet.changes` yields a new one per change)."""

    key: str                          # stable name clients use
    name: str                         # descriptor name
    board_id: Optional[str]           # USB serial number, else the device's own id (hex), else None
    port: Optional[str]               # current port path, None while unplugged
    state: str                        # "connecting" | "ready" | "lost" | "unplugged"
    device: Optional[AsyncDevice]     # the live session, None while unplugged
    #: times this board was attached (1 on first sight; +1 per replug)
    attached: int = 0
    #: the last port it was seen on (kept while unplugged)
    last_port: Optional[str] = None
    #: events the service received from it (each one is handed to every client listening then)
    events: int = 0
    #: device sessions the service has seen (+1 per attach and per reboot): clients tell a reboot
    #: (``reconnect``) from a link restored by it
    sessions: int = 0


class Changes:
    """The async iterator :meth:`Fleet.changes` returns (registered at once, so nothing between the
    call and the first ``await`` is missed)."""

    def __init__(self, watchers: "Set[asyncio.Queue[Board]]") -> None:
        self._watchers = watchers
        self._q: "asyncio.Queue[Board]" = asyncio.Queue()
        watchers.add(self._q)

    def __aiter__(self) -> "Changes":
        return self

    async def __anext__(self) -> Board:
        if self._q not in self._watchers:
            raise StopAsyncIteration
        return await self._q.get()

    async def aclose(self) -> None:
        self._watchers.discard(self._q)

    def __del__(self) -> None:
        self._watchers.discard(self._q)


@dataclass
class _Attempt:
    failures: int = 0
    next_at: float = 0.0
    task: Optional["asyncio.Task[None]"] = None
    #: why the last try failed
    error: str = ""


class Fleet:
    """Finds boards (USB hotplug, explicit ports, watched globs), keeps each connected, and tells
    consumers about every change. ``await fleet.start()``; ``await fleet.close()`` at the end."""

    def __init__(self, *, ports: Optional[List[str]] = None, globs: Optional[List[str]] = None,
                 usb: bool = True, connect_timeout: float = 5.0, cache_dir: Any = None,
                 poll_interval: float = 0.5, lister: Optional[Callable[[], List[Any]]] = None,
                 udev: bool = True, store: Any = None, baudrate: int = 115200) -> None:
        self.scanner = PortScanner(ports or [], globs or [], usb=usb, lister=lister)
        self.connect_timeout = connect_timeout
        self.baudrate = baudrate
        self.cache_dir = cache_dir
        self.poll_interval = poll_interval
        self.use_udev = udev
        self._boards: Dict[str, Board] = {}
        self._by_port: Dict[str, Board] = {}          # realpath of an attached port -> its board
        self._info: Dict[str, PortInfo] = {}           # realpath -> what the scan saw there
        self._attempts: Dict[str, _Attempt] = {}
        self._watchers: Set["asyncio.Queue[Board]"] = set()
        self._wake: Optional[asyncio.Event] = None
        self._task: Optional["asyncio.Task[None]"] = None
        self._udev: Any = None
        self._closed = False
        #: each board's last descriptor (kept while it is unplugged)
        self._descriptors: Dict[str, Descriptor] = {}
        #: what survives a restart (a :class:`~.store.Store`), or None
        self.store = store
        #: ports whose kept hub session the next connection resumes (loaded once, then only shrinks)
        self._resumable: Optional[Set[str]] = None
        #: who answers each board's hub channels (clients, the MQTT bridge)
        self.hub = HubProviders(self)

    # --------------------------------------------------------------------------- the FLEET.md API

    def boards(self) -> List[Board]:
        """Every known board, plugged or not (a snapshot, in the order they were first seen)."""
        return [dataclasses.replace(b) for b in self._boards.values()]

    def get(self, key: str) -> Board:
        """The board of this key (a snapshot); :class:`UnknownBoard` (a KeyError) listing the keys."""
        b = self._boards.get(key)
        if b is None:
            raise UnknownBoard(self._unknown(key))
        return dataclasses.replace(b)

    def changes(self) -> "Changes":
        """Yields a board snapshot each time one is added, changes state, or changes device/port:
        every change from this call on (``async for``; ``aclose()`` or leaving the loop ends it)."""
        return Changes(self._watchers)

    @property
    def pending(self) -> Dict[str, str]:
        """The ports named to the fleet that serve no board now, each with why."""
        out: Dict[str, str] = {}
        for url in self.scanner.ports:
            real = self._real(url)
            if real in self._by_port:
                continue
            a = self._attempts.get(real)
            out[url] = a.error if a is not None and a.error else "absent" if real not in self._info else "connecting"
        return out

    # ------------------------------------------------------------------------------- additions

    def resolve(self, what: str) -> Board:
        """The board a client means by ``what``: a key, ``name-<board id>``, a name only one board
        has, or its current port path; "" the only board. UnknownBoard (listing the keys) otherwise."""
        if what == "" and len(self._boards) == 1:
            return self.boards()[0]
        b = self._boards.get(what)
        if b is not None:
            return dataclasses.replace(b)
        real = os.path.realpath(what) if "://" not in what else what
        for b in self._boards.values():
            if (b.board_id is not None and what in (f"{b.name}-{b.board_id}", f"{b.name}--{b.board_id}")) or (
                    b.port is not None and (b.port == what or self._real(b.port) == real)):
                return dataclasses.replace(b)
        named = [b for b in self._boards.values() if b.name == what]
        if len(named) == 1:
            return dataclasses.replace(named[0])
        if named:
            raise UnknownBoard(f"{len(named)} boards are called {what!r}: use one of their keys "
                               f"({', '.join(b.key for b in named)})")
        raise UnknownBoard(self._unknown(what))

    async def wait_device(self, key: str, timeout: Optional[float] = None) -> AsyncDevice:
        """The board's device once it is plugged (at once if it is); Timeout-free when ``timeout`` is None."""
        changes = self.changes()
        try:
            deadline = None if timeout is None else time.monotonic() + timeout
            while True:
                b = self._boards.get(key)
                if b is None:
                    raise UnknownBoard(self._unknown(key))
                if b.device is not None:
                    return b.device
                if self._closed:
                    raise LinkLost("the service is shutting down")
                left = None if deadline is None else deadline - time.monotonic()
                if left is not None and left <= 0:
                    raise LinkLost(f"board {key} is unplugged")
                try:
                    await asyncio.wait_for(changes.__anext__(), left)
                except asyncio.TimeoutError:
                    pass
        finally:
            await changes.aclose()

    def descriptor(self, key: str) -> Descriptor:
        """The board's descriptor: its device's, or the last one it had while it is unplugged."""
        b = self._boards.get(key)
        if b is None:
            raise UnknownBoard(self._unknown(key))
        if b.device is not None and b.device.core.descriptor is not None:
            return b.device.descriptor
        return self._descriptors[key]

    def _unknown(self, what: str) -> str:
        known = ", ".join(f"{b.key} ({b.state})" for b in self._boards.values()) or "none yet"
        return f"no board {what!r}; boards known to the service: {known}"

    @staticmethod
    def _real(path: str) -> str:
        return os.path.realpath(path) if "://" not in path else path

    # ------------------------------------------------------------------------------- lifecycle

    async def start(self) -> None:
        """Scan now and keep scanning (woken at once by udev where there is pyudev)."""
        self._wake = asyncio.Event()
        if self.use_udev and self.scanner.usb:
            self._udev = self.scanner.udev_monitor(asyncio.get_running_loop(), self._wake.set)
        self._scan()
        self._task = asyncio.get_running_loop().create_task(self._run())

    async def __aenter__(self) -> "Fleet":
        await self.start()
        return self

    async def __aexit__(self, *exc: Any) -> None:
        await self.close()

    async def close(self) -> None:
        """Stop scanning and close every board's session."""
        self._closed = True
        if self._udev is not None:
            self._udev()
        if self._task is not None:
            self._task.cancel()
        for a in self._attempts.values():
            if a.task is not None:
                a.task.cancel()
        for b in list(self._by_port.values()):
            if b.device is not None:
                await b.device.close()
        self._by_port.clear()

    async def _run(self) -> None:
        assert self._wake is not None
        while not self._closed:
            try:
                await asyncio.wait_for(self._wake.wait(), self.poll_interval)
            except asyncio.TimeoutError:
                pass
            self._wake.clear()
            try:
                self._scan()
            except Exception:  # noqa: BLE001 - one bad scan must not end the service
                log.exception("hubwire serve: port scan failed")

    # ---------------------------------------------------------------------------------- scanning

    def _scan(self) -> None:
        seen = self.scanner.scan()
        now = time.monotonic()
        for real, info in seen.items():
            old = self._info.get(real)
            self._info[real] = info
            board = self._by_port.get(real)
            if board is not None:
                if old is not None and old.serial != info.serial:
                    self._detach(real)  # another board on the same port name
                else:
                    self._refresh(board)
                    continue
            a = self._attempts.setdefault(real, _Attempt())
            if a.task is None and now >= a.next_at:
                a.task = asyncio.get_running_loop().create_task(self._attach(real, info))
        for real in [r for r in self._info if r not in seen]:
            del self._info[real]
            gone = self._attempts.pop(real, _Attempt())
            if gone.task is not None:
                gone.task.cancel()
            if real in self._by_port:
                self._detach(real)

    async def _attach(self, real: str, info: PortInfo) -> None:
        a = self._attempts[real]
        try:
            # a transport of its own: the port itself, never routed through a service (this one)
            # the first session on a port since the service started resumes the hub session kept
            # for it (the same hub nonce: the device keeps its duplicate memories, durable.py)
            if self._resumable is None:
                self._resumable = set(self.store.hub_session_ports()) if self.store is not None else set()
            hs = durable.hub_session(self.store, info.path, info.path in self._resumable)
            # the service offers the board's hub events itself (durable.offer_hub_events)
            dev = await connect(transport=SerialTransport(info.path, self.baudrate), timeout=self.connect_timeout,
                                hub_later=True,
                                cache_dir=self.cache_dir, hub_session=hs)
            self._resumable.discard(info.path)
        except asyncio.CancelledError:
            raise
        except Exception as e:  # noqa: BLE001 - any port that is no Hubwire board
            a.failures += 1
            a.error = str(e)
            delay = min(RETRY_FIRST * 2 ** (a.failures - 1), RETRY_MAX)
            a.next_at, a.task = time.monotonic() + delay, None
            log.warning("hubwire serve: %s: %s (trying again in %g s)", info.path, e, delay)
            return
        a.task, a.failures = None, 0
        board_id = info.serial
        if board_id is None:  # no USB serial number: the id the device reports, if it has one
            try:
                board_id = await dev.board_id(timeout=self.connect_timeout)
            except asyncio.CancelledError:
                raise
            except Exception as e:  # noqa: BLE001 - a board that cannot say is still served
                log.warning("hubwire serve: %s: no board id (%s)", info.path, e)
        if self._closed or real not in self._info:
            await dev.close()
            return
        self._adopt(real, info, dev, board_id)

    def _adopt(self, real: str, info: PortInfo, dev: AsyncDevice, board_id: Optional[str]) -> None:
        name = dev.name
        board = self._match(name, board_id, info.path)
        board.port = board.last_port = info.path
        board.device = dev
        board.attached += 1
        board.sessions += 1
        board.state = dev.state
        self._descriptors[board.key] = dev.descriptor
        self._by_port[real] = board
        # first: the events that came before it are stored (kept hub events go out before new ones)
        durable.attach(self.store, board.key, dev, info.path)
        self.hub.attach(board.key, dev)
        # the service always listens, so an event nobody else hears is counted (and kept by the store)
        dev.on("*", lambda _ev, b=board: setattr(b, "events", b.events + 1))
        for kind in ("link_lost", "link_restored", "reconnect"):
            dev.on(kind, lambda *_a, b=board, d=dev, r=real, k=kind: self._device_changed(b, d, r, k))
        # name and id as repr: a device's strings never reach the log as raw text
        log.info("hubwire serve: %s (name %r, board id %r) on %s", board.key, name, board_id, info.path)
        self._emit(board)

    def _match(self, name: str, board_id: Optional[str], path: str) -> Board:
        free = [b for b in self._boards.values() if b.device is None and b.name == name and b.board_id == board_id]
        if free:
            free.sort(key=lambda b: b.last_port != path)  # an id-less board: its old port first
            return free[0]
        # the key is a function of the board's identity, never of the order boards are found in;
        # only boards that claim the same name and id (id-less twins) are numbered
        n = 1
        while board_key(name, board_id, n) in self._boards:
            n += 1
        key = board_key(name, board_id, n)
        board = Board(key=key, name=name, board_id=board_id, port=None, state="connecting", device=None)
        self._boards[key] = board
        return board

    def _device_changed(self, board: Board, dev: AsyncDevice, real: str, kind: str = "") -> None:
        if board.device is not dev:
            return
        if kind == "reconnect":  # the device rebooted: a new device session, rediscovered
            board.sessions += 1
        d = dev.core.descriptor
        if d is not None and d.name != board.name:
            # new firmware with another name on the same port: another board now
            self._detach(real)
            return
        if d is not None:
            self._descriptors[board.key] = d
        self._refresh(board, kind == "reconnect")

    def _refresh(self, board: Board, changed: bool = False) -> None:
        """Emit the board when its state changed (or ``changed``: a new device session)."""
        if board.device is not None and (changed or board.device.state != board.state):
            board.state = board.device.state
            self._emit(board)

    def _detach(self, real: str) -> None:
        board = self._by_port.pop(real)
        dev, board.device, board.port, board.state = board.device, None, None, "unplugged"
        if real in self._attempts:
            del self._attempts[real]
        if dev is not None:
            asyncio.get_running_loop().create_task(dev.close())
        log.info("hubwire serve: %s unplugged", board.key)
        self._emit(board)

    def _emit(self, board: Board) -> None:
        snap = dataclasses.replace(board)
        for q in list(self._watchers):
            q.put_nowait(snap)
