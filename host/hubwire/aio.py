"""The asyncio API: the same session core as :func:`hubwire.connect`, on the caller's event loop.

::

    import hubwire.aio

    async with hubwire.aio.connect("/dev/ttyACM0") as rover:
        await rover.write("left", 0.5)
        print(await rover.read("battery"))
        print(await rover.call("beep", 200))
        async for imu in rover.stream("imu", hz=50):
            ...
        async for ev in rover.events("bumper"):
            print(ev.name, ev.value)

Every method is a coroutine (or returns an async iterator) and must be used from the loop the
device was connected on. Callbacks given to :meth:`AsyncDevice.on` run on that loop; a callback
that returns a coroutine has it run as a task (so it may ``await`` the device).
"""
from __future__ import annotations

import asyncio
from collections import deque
from typing import Any, Callable, Deque, Dict, FrozenSet, Generator, List, Optional, Tuple, TypeVar, cast

from . import ops, roads
from .board import AsyncBoardAPI
from .descriptor import Channel, Descriptor
from .errors import HubwireError, NakError, Timeout
from .hub_face import HubMethods
from .job import AsyncJob, start_async_job
from .ports import find_port
from .session import AsyncSubscription, LinkHealth, ReceivedEvent, SessionCore, StreamSample
from .session.events import EventSink
from .session.hub_channels import HubSide
from .session.runner import LoopDispatcher
from .session.windows import read_async
from .text import clip
from .transport import SerialTransport, Transport
from .wire import messages as m

__all__ = ["connect", "AsyncDevice", "AsyncStream", "AsyncEventStream", "EventIterator", "AsyncJob"]


def connect(url: Optional[str] = None, baudrate: int = 115200, *, timeout: float = 5.0,
            transport: Optional[Transport] = None, **kwargs: Any) -> "_Connecting":
    """Connect to the device on ``url`` (or ``transport``); ``await`` it for an :class:`AsyncDevice`
    or use it as ``async with hubwire.aio.connect(url) as dev:`` (closed at the end).

    Keyword arguments as :func:`hubwire.connect`: ``heartbeat_ms``, ``retry_timeout``, ``tries``,
    ``cache_dir``, ``progress``, ``on_link_lost``, ``on_link_restored``, ``on_reconnect``,
    ``serial_kwargs``, ``max_in_flight``, ``hub`` (hub channels; handlers may be coroutines, run on
    this loop), ``hub_later`` (declare them once connected instead).
    """
    if transport is None:
        road = roads.service_road()
        if road is not None:  # through hubwire serve where it applies
            return cast(_Connecting, road.connecting(url, baudrate, timeout, kwargs))
        transport = SerialTransport(url if url is not None else find_port(), baudrate,
                                    **(kwargs.pop("serial_kwargs", None) or {}))
    return _Connecting(transport, timeout, kwargs)


class _Connecting:
    """What :func:`connect` returns: awaitable, and an async context manager."""

    def __init__(self, transport: Transport, timeout: float, kwargs: Dict[str, Any]) -> None:
        self._transport = transport
        self._timeout = timeout
        self._kwargs = kwargs
        self._dev: Optional[AsyncDevice] = None

    async def _open(self) -> "AsyncDevice":
        kw = dict(self._kwargs)
        cbs: Tuple[Any, ...] = (kw.pop("on_link_lost", None), kw.pop("on_link_restored", None),
                                kw.pop("on_reconnect", None))
        core = SessionCore(self._transport, dispatch=LoopDispatcher(asyncio.get_running_loop()),
                           connect_timeout=self._timeout, **kw)
        lists: Tuple[List[Any], ...] = (core.link_lost_cbs, core.link_restored_cbs, core.reconnect_cbs)
        for lst, cb in zip(lists, cbs):
            if cb is not None:
                lst.append(cb)
        await core.open()
        return AsyncDevice(core)

    def __await__(self) -> Generator[Any, None, "AsyncDevice"]:
        return self._open().__await__()

    async def __aenter__(self) -> "AsyncDevice":
        self._dev = await self._open()
        return self._dev

    async def __aexit__(self, *exc: Any) -> None:
        if self._dev is not None:
            await self._dev.close()


class AsyncDevice(HubMethods, AsyncBoardAPI):
    """A connected device for asyncio code: ``await dev.read(name)``, ``await dev.write(name, v)``,
    ``await dev.call(name, arg)``, ``dev.stream(name, hz=...)``, ``dev.events(...)``, ``dev.on(...)``;
    hub channels as on :class:`hubwire.Device` (``dev.provide``, ``dev.action``, ``dev.notify``...).
    Implements :class:`hubwire.board.AsyncBoardAPI`, as the routed ``AsyncRemoteDevice`` does."""

    def __init__(self, core: SessionCore) -> None:
        self._core = core

    def _hub_side(self) -> HubSide:
        return self._core.hub

    async def wait_notified(self, timeout: Optional[float] = 5.0) -> None:
        """Return once every hub event queued with :meth:`notify` was acknowledged by the device;
        :class:`hubwire.Timeout` after ``timeout`` s (None: no limit)."""
        core = self._core
        end = None if timeout is None else core.loop.time() + timeout
        while core.hub.queue and not core.closed:
            left = 3600.0 if end is None else end - core.loop.time()
            if left <= 0:
                raise Timeout(f"{len(core.hub.queue)} hub events still wait for the device after {timeout} s")
            await core.changes(left)

    @property
    def core(self) -> SessionCore:
        """The session core (its ``stats``, ``link``, ...)."""
        return self._core

    @property
    def descriptor(self) -> Descriptor:
        d = self._core.descriptor
        if d is None:
            raise HubwireError("device not discovered yet")
        return d

    @property
    def name(self) -> str:
        """Device name from its descriptor."""
        return self.descriptor.name

    @property
    def state(self) -> str:
        """``"ready"``, ``"connecting"``, ``"lost"`` or ``"closed"``."""
        return self._core.state.value

    @property
    def url(self) -> str:
        return self._core.url

    def health(self) -> LinkHealth:
        """Link health: heartbeat age, error counters of both sides, state."""
        return self._core.health()

    async def fetch_health(self) -> LinkHealth:
        """As :meth:`health` (a direct session knows it all without asking)."""
        return self._core.health()

    def channel(self, name: str) -> Channel:
        """The :class:`Channel` called ``name`` (KeyError listing the channels if there is none)."""
        return ops.channel(self._core.descriptor, name)

    async def board_id(self, *, timeout: Optional[float] = None) -> Optional[str]:
        """This board's id in hex (the chip's unique id, or the one its sketch keeps), which tells
        two boards running one sketch apart; None when the board has none. Read once per boot."""
        known = ops.cached_board_id(self._core)
        if known is not ops.UNASKED:
            return cast(Optional[str], known)
        try:
            a = await self._core.tx.transact(m.REQUEST, 0, b"", timeout=timeout, what="board id")
        except NakError as e:
            return ops.remember_board_id(self._core, None, e)
        return ops.remember_board_id(self._core, a)

    async def read(self, name: str, *, timeout: Optional[float] = None) -> Any:
        """Read a readable channel's current value."""
        ch = ops.readable(self._core.descriptor, name)
        return ch.codec.decode(await read_async(self._core, ch, timeout, name))  # large ones in windows

    async def write(self, name: str, value: Any, *, timeout: Optional[float] = None) -> None:
        """Write a writable channel; returns once the device acknowledged it (exactly once)."""
        ch, payload = ops.write_payload(self._core.descriptor, name, value)
        await self._core.tx.transact(m.CONTROL, ch.id, payload, timeout=timeout, what=name)

    async def call(self, name: str, arg: Any = None, *, timeout: Optional[float] = None) -> Any:
        """Call a callable channel with ``arg`` (None for no argument); return its result."""
        ch, payload = ops.call_payload(self._core.descriptor, name, arg)
        return ops.call_result(ch, await self._core.tx.transact(m.CONTROL, ch.id, payload, timeout=timeout, what=name))

    async def start(self, name: str, goal: Any = None, *, timeout: Optional[float] = None) -> AsyncJob:
        """Start mission ``name`` with ``goal``; the :class:`hubwire.job.AsyncJob` once the board
        answered with the run number (as :meth:`hubwire.Device.start`)."""
        return await start_async_job(self._core, name, goal, timeout)

    def stream(self, name: str, hz: Optional[float] = None, *, interval_ms: Optional[int] = None,
               meta: bool = False, timeout: Optional[float] = None, maxlen: int = 1024) -> "AsyncStream":
        """Samples of a streamable channel at ``hz`` (or ``interval_ms``; default 10 Hz): an async
        iterator that subscribes on first use; ``async with`` (or :meth:`AsyncStream.aclose`) ends it."""
        ch = ops.stream_channel(self._core.descriptor, name)
        return AsyncStream(self._core, ch, ops.interval_for(hz, interval_ms), meta=meta, timeout=timeout, maxlen=maxlen)

    def events(self, *names: str, timeout: Optional[float] = None) -> "AsyncEventStream":
        """Async iterator over incoming events (of ``names``, or all) from now on, as
        :class:`ReceivedEvent`; ends after ``timeout`` s without one (when given)."""
        for n in names:
            self.channel(n)
        return AsyncEventStream(self._core, frozenset(names) if names else None, timeout)

    def on(self, name: str, callback: Callable[..., Any]) -> Callable[[], None]:
        """As :meth:`hubwire.Device.on`, the callback running on this loop; returns its remover."""
        core = self._core
        if name in ("link_lost", "link_restored", "reconnect"):
            lst = getattr(core, f"{name}_cbs")
            lst.append(callback)
            return lambda: lst.remove(callback) if callback in lst else None
        key = ops.event_key(core.descriptor, name)
        core.events.add_callback(key, callback)
        return lambda: core.events.remove_callback(key, callback)

    async def close(self) -> None:
        """Cancel streams and close the link."""
        await self._core.close()

    async def __aenter__(self) -> "AsyncDevice":
        return self

    async def __aexit__(self, *exc: Any) -> None:
        await self.close()

    def __repr__(self) -> str:
        d = self._core.descriptor
        what = clip(d.name) if d is not None else ""
        return f"<hubwire.aio.AsyncDevice {what} on {self._core.url} ({self._core.state.value})>"


async def _wait(ready: asyncio.Event, timeout: Optional[float], what: Callable[[], str]) -> None:
    ready.clear()
    try:
        await asyncio.wait_for(ready.wait(), timeout)
    except asyncio.TimeoutError:
        raise Timeout(what()) from None


class AsyncStream:
    """A subscription to a streamable channel for ``async for`` (values, or :class:`StreamSample`
    with ``meta=True``). Rides through link losses and device reboots as :class:`hubwire.Stream`
    does (the first sample after an outage has ``gap`` >= 1, :attr:`gaps` counts them); raises
    Timeout after ``timeout`` s without a sample (when given), StreamEnded when a rebooted device
    no longer has the channel, LinkLost once the session is closed."""

    def __init__(self, core: SessionCore, channel: Channel, interval_ms: int, *, meta: bool,
                 timeout: Optional[float], maxlen: int) -> None:
        self._core = core
        self.channel = channel
        self.meta = meta
        self.timeout = timeout
        self._sub: Optional[AsyncSubscription] = AsyncSubscription(channel.id, interval_ms, maxlen)
        self._opened = False
        #: interval the device granted, ms (once subscribed)
        self.granted_ms = 0
        #: samples lost (gaps in the device's sample counter)
        self.lost = 0
        #: link outages ridden through (each reported on the next sample's ``gap``)
        self.gaps = 0

    async def open(self) -> "AsyncStream":
        """Subscribe now (iteration does it on first use)."""
        if not self._opened and self._sub is not None:
            self._opened = True
            await self._core.streams.open(self._sub, self.channel.name)
            self.granted_ms = self._sub.granted_ms
        return self

    def __aiter__(self) -> "AsyncStream":
        return self

    async def __anext__(self) -> Any:
        await self.open()
        sub = self._sub
        if sub is None:
            raise StopAsyncIteration
        while not sub.queue:
            if sub.ended is not None:
                if isinstance(sub.ended, StopIteration):
                    raise StopAsyncIteration
                raise sub.ended
            await _wait(sub.ready, self.timeout, lambda: f"no sample of {self.channel.name} within {self.timeout:g} s")
        s: StreamSample = sub.queue.popleft()
        self.lost += s.lost
        self.gaps += s.gap
        return s if self.meta else s.value

    async def aclose(self) -> None:
        """End the subscription (cancelled on the device when this was its last consumer)."""
        sub, self._sub = self._sub, None
        if sub is not None and self._opened:
            await self._core.streams.close(sub)

    async def __aenter__(self) -> "AsyncStream":
        return await self.open()

    async def __aexit__(self, *exc: Any) -> None:
        await self.aclose()

    def __del__(self) -> None:
        sub = self._sub
        if sub is not None and self._opened and not self._core.closed:
            try:
                self._core.loop.call_soon_threadsafe(self._core.streams.close_nowait, sub)
            except RuntimeError:  # the loop is closed
                pass


class _AsyncSink(EventSink):
    def __init__(self, core: SessionCore, names: Optional[FrozenSet[str]]) -> None:
        self.names = names
        self.core = core
        self.q: Deque[Optional[ReceivedEvent]] = deque()
        self.ready = asyncio.Event()

    def put(self, ev: Optional[ReceivedEvent]) -> None:
        self.note_size(len(self.q))
        if len(self.q) >= self.limit:
            self.q.popleft()
            self.note_dropped(self.core.stats)
        self.q.append(ev)
        self.ready.set()

    def close(self) -> None:
        self.put(None)


_Events = TypeVar("_Events", bound="EventIterator")


class EventIterator:
    """``async for`` and ``async with`` over :meth:`get` and :meth:`close`, for the event streams of
    a session (:class:`AsyncEventStream`) and of a board through the service."""

    timeout: Optional[float] = None

    async def get(self, timeout: Optional[float] = None) -> Optional[ReceivedEvent]:
        raise NotImplementedError

    def close(self) -> None:
        raise NotImplementedError

    def __aiter__(self: _Events) -> _Events:
        return self

    async def __anext__(self) -> ReceivedEvent:
        ev = await self.get(self.timeout)
        if ev is None:
            raise StopAsyncIteration
        return ev

    async def __aenter__(self: _Events) -> _Events:
        return self

    async def __aexit__(self, *exc: Any) -> None:
        self.close()


class AsyncEventStream(EventIterator):
    """``async for ev in dev.events(...)``: incoming :class:`ReceivedEvent` objects from its creation
    on, riding through link losses and device reboots; ends when the session closes, or after
    ``timeout`` s without an event (when given)."""

    def __init__(self, core: SessionCore, names: Optional[FrozenSet[str]], timeout: Optional[float]) -> None:
        self._core = core
        self.timeout = timeout
        self._sink: Optional[_AsyncSink] = _AsyncSink(core, names)
        core.events.add_sink(self._sink)

    async def get(self, timeout: Optional[float] = None) -> Optional[ReceivedEvent]:
        """Next event within ``timeout`` s (None: wait forever), or None."""
        sink = self._sink
        if sink is None:
            return None
        try:
            while not sink.q:
                await _wait(sink.ready, timeout, lambda: "")
        except Timeout:
            return None
        ev = sink.q.popleft()
        if ev is None:
            self.close()
        return ev

    def close(self) -> None:
        sink, self._sink = self._sink, None
        if sink is not None:
            self._core.events.remove_sink(sink)

