"""The synchronous :class:`Session`: a thin facade over a :class:`SessionCore` that runs on the
process's shared hub event loop (see :mod:`hubwire.session.runner`). Thread-safe.

Transactions are driven by the calling thread (:mod:`.blocking`: it writes its frame and the loop
wakes it with the answer); everything else runs on the loop through :func:`run_sync`."""
from __future__ import annotations

from typing import Any, Callable, Dict, Optional

from ..descriptor import Descriptor
from ..errors import HubwireError
from ..hub import HubChannels
from ..transport import SerialTransport, Transport
from ..wire import messages as m
from ..wire.frame import Frame
from . import blocking
from .core import SessionCore
from .events import QueueSink
from .records import LinkHealth, State, Stats
from .slots import DEFAULT_MAX_IN_FLIGHT
from .runner import ThreadDispatcher, acquire_loop, on_loop_thread, release_loop, run_sync
from .streams import ThreadSubscription, granted_interval
from .windows import read_sync

__all__ = ["Session"]


class Session:
    """One hub-side session with a device, for the synchronous API.

    Construct, then :meth:`open` (handshake + discovery); :meth:`close` when done.

    Parameters: ``url`` (anything ``serial.serial_for_url`` accepts) and ``baudrate``, or a
    ``transport`` (:class:`hubwire.transport.Transport`); ``connect_timeout`` (handshake deadline, s),
    ``heartbeat_ms`` (hub heartbeat interval), ``retry_timeout`` (s) and ``tries`` (per transaction),
    ``cache_dir`` (descriptor cache directory, ``None`` default, ``False`` disables), ``progress``
    (``callable(received, total)`` during descriptor downloads), ``on_link_lost`` /
    ``on_link_restored`` / ``on_reconnect`` callbacks, ``serial_kwargs`` (to ``serial_for_url``),
    ``hub`` (the :class:`hubwire.HubChannels` offered to the device), ``hub_later`` (True: the
    hub channels the device expects are declared after connecting, not checked by ``open()``), ``max_in_flight`` (transactions
    in flight at once, 1..200, default 64: more wait their turn, asleep, in the order they came).
    """

    def __init__(self, url: Optional[str] = None, baudrate: int = 115200, *, connect_timeout: float = 5.0,
                 heartbeat_ms: int = 250, retry_timeout: float = 0.1, tries: int = 5, cache_dir: Any = None,
                 progress: Optional[Callable[[int, int], None]] = None,
                 on_link_lost: Optional[Callable[[], None]] = None,
                 on_link_restored: Optional[Callable[[], None]] = None,
                 on_reconnect: Optional[Callable[[Descriptor], None]] = None,
                 serial_kwargs: Optional[Dict[str, Any]] = None, transport: Optional[Transport] = None,
                 hub: Optional[HubChannels] = None, max_in_flight: int = DEFAULT_MAX_IN_FLIGHT,
                 hub_later: bool = False) -> None:
        if transport is None:
            if url is None:
                raise ValueError("Session needs a url or a transport")
            transport = SerialTransport(url, baudrate, **(serial_kwargs or {}))
        self.transport = transport
        self.url = transport.url
        self._options = dict(connect_timeout=connect_timeout, heartbeat_ms=heartbeat_ms, retry_timeout=retry_timeout,
                             tries=tries, cache_dir=cache_dir, progress=progress, hub=hub,
                             max_in_flight=max_in_flight, hub_later=hub_later)
        self._initial_cbs = (on_link_lost, on_link_restored, on_reconnect)
        self._core: Optional[SessionCore] = None
        self._loop: Any = None
        self._dispatcher: Optional[ThreadDispatcher] = None
        self._gate = blocking.ThreadGate()

    # ---------------------------------------------------------------------------- lifecycle

    def open(self) -> "Session":
        """Open the port, handshake and discover. Raises Timeout, ProtocolVersionError,
        DescriptorError or HubwireError (port cannot be opened)."""
        if self._core is not None:
            raise HubwireError("session already opened")
        self._loop = acquire_loop()
        self._dispatcher = ThreadDispatcher()
        self._core = run_sync(self._loop, self._make_core())
        try:
            run_sync(self._loop, self._core.open())
        except BaseException:
            self._shutdown()
            raise
        return self

    async def _make_core(self) -> SessionCore:
        core = SessionCore(self.transport, dispatch=self._dispatcher, **self._options)
        lost, restored, reconnect = self._initial_cbs
        for lst, cb in ((core.link_lost_cbs, lost), (core.link_restored_cbs, restored)):
            if cb is not None:
                lst.append(cb)
        if reconnect is not None:
            core.reconnect_cbs.append(reconnect)
        return core

    def close(self) -> None:
        """Cancel streams, stop the session and close the port. Idempotent."""
        if self._loop is None:
            return
        try:
            run_sync(self._loop, self.core.close())
        finally:
            self._shutdown()

    def _shutdown(self) -> None:
        loop, self._loop = self._loop, None
        if self._dispatcher is not None:
            self._dispatcher.stop()
        if loop is not None:
            release_loop()

    def __enter__(self) -> "Session":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

    # ------------------------------------------------------------------------------ queries

    @property
    def core(self) -> SessionCore:
        """The :class:`SessionCore` behind this facade (after :meth:`open`)."""
        if self._core is None:
            raise HubwireError("session not opened")
        return self._core

    @property
    def state(self) -> State:
        return self._core.state if self._core is not None else State.CONNECTING

    @property
    def descriptor(self) -> Optional[Descriptor]:
        return self._core.descriptor if self._core is not None else None

    @property
    def device_hello(self) -> Optional[m.Hello]:
        return self._core.device_hello if self._core is not None else None

    @property
    def nonce(self) -> int:
        """This hub session's nonce (PROTOCOL.md §4.2)."""
        return self.core.link.nonce

    @property
    def stats(self) -> Stats:
        """Counters for diagnostics and tests (:class:`Stats`)."""
        return self.core.stats

    def health(self) -> LinkHealth:
        """Current :class:`LinkHealth`."""
        return self.core.health()

    def started_on_open(self) -> bool:
        """True when the board seems to have restarted as the port opened (as an Uno does: the
        next program to open the port restarts it again)."""
        return bool(self.core.link.started_on_open)

    def printed(self) -> "tuple[int, list[str]]":
        """Lines of text the board printed on the line (``Serial.println``): how many in all, and the
        latest (newest last); the frames they ran into were dropped (``dropped`` in :meth:`health`)."""
        return self.core.link.printed.recent(self.core.link.decoder)

    # ------------------------------------------------------------------------- transactions

    def _run(self, aw: Any) -> Any:
        if self._loop is None:
            aw.close()
            raise HubwireError("session is closed")
        return run_sync(self._loop, aw)

    def transact(self, type: int, id: int, payload: bytes = b"", *, timeout: Optional[float] = None,
                 what: str = "", tries: Optional[int] = None) -> Frame:
        """Send one transaction and return its answer; see :meth:`Transactions.transact`."""
        if self._loop is None:
            raise HubwireError("session is closed")
        if on_loop_thread():
            raise RuntimeError("hubwire: a synchronous call cannot be made on the hub's event loop thread")
        return blocking.transact(self.core, self._gate, type, id, payload, timeout=timeout, what=what, tries=tries)

    def request(self, id: int, *, timeout: Optional[float] = None, what: str = "") -> bytes:
        """``R``: read a channel; returns the ``r`` payload (a large value's in windows: windows.py)."""
        ch = self.descriptor.by_id(id) if self.descriptor is not None else None
        if ch is not None:
            return read_sync(self, ch, timeout, what)
        a = self.transact(m.REQUEST, id, b"", timeout=timeout, what=what)
        if a.type != m.RESPONSE:
            raise HubwireError(f"unexpected answer type 0x{a.type:02x} to a read of {what or id}")
        return a.payload

    def control(self, id: int, payload: bytes, *, timeout: Optional[float] = None, what: str = "") -> Frame:
        """``C``: write or call; returns the ACK or ``r`` frame."""
        return self.transact(m.CONTROL, id, payload, timeout=timeout, what=what)

    def subscribe(self, id: int, interval_ms: int, *, timeout: Optional[float] = None, what: str = "") -> int:
        """``S``: (re)subscribe or cancel (0); returns the granted interval."""
        a = self.transact(m.SUBSCRIBE, id, m.Subscribe(interval_ms).pack(), timeout=timeout, what=what)
        return granted_interval(a, interval_ms)

    # ------------------------------------------------------------------------------ streams

    def open_stream(self, id: int, interval_ms: int, maxlen: int = 1024, what: str = "") -> ThreadSubscription:
        """Subscribe; returns a subscription whose queue receives :class:`StreamSample`."""
        sub = ThreadSubscription(id, interval_ms, maxlen)
        streams = self.core.streams
        interval = self._run(self._call(streams.attach, sub))
        try:
            sub.granted_ms = self.subscribe(id, interval, what=what)
        except BaseException:
            self._run(self._call(streams.forget, sub))
            raise
        return sub

    def close_stream(self, sub: ThreadSubscription, wait: bool = True) -> None:
        """End a subscription; cancels it on the device when it was the channel's last consumer."""
        if self._loop is None:
            sub.end(StopIteration())
            return
        if wait:
            interval = self._run(self._call(self.core.streams.detach, sub))
            if interval is not None:
                try:
                    self.subscribe(sub.channel_id, interval)
                except HubwireError:
                    pass
        elif on_loop_thread():  # a Stream collected by the garbage collector on the loop thread
            self.core.streams.close_nowait(sub)
        else:
            self._run(self._call(self.core.streams.close_nowait, sub))

    @property
    def subscriptions(self) -> Dict[int, Any]:
        """Consumers per channel id (a snapshot)."""
        return {k: list(v) for k, v in self.core.streams.subs.items()}

    # ------------------------------------------------------------------------------- events

    def add_link_lost(self, cb: Callable[[], Any]) -> None:
        """Call ``cb()`` (on the dispatcher thread) when the link is lost."""
        self.core.link_lost_cbs.append(cb)

    def add_link_restored(self, cb: Callable[[], Any]) -> None:
        """Call ``cb()`` when the link is back (same device session, or a rebooted device)."""
        self.core.link_restored_cbs.append(cb)

    def add_reconnect(self, cb: Callable[[Descriptor], Any]) -> None:
        """Call ``cb(descriptor)`` after a rebooted device was handshaken and rediscovered."""
        self.core.reconnect_cbs.append(cb)

    def remove_callback(self, kind: str, cb: Callable[..., Any]) -> None:
        """Undo :meth:`add_link_lost` (``kind="link_lost"``), ``link_restored`` or ``reconnect``."""
        lst = getattr(self.core, f"{kind}_cbs")
        if cb in lst:
            lst.remove(cb)

    async def _call(self, fn: Callable[..., Any], *args: Any) -> Any:
        return fn(*args)

    def add_event_callback(self, name: Optional[str], cb: Callable[[Any], Any]) -> None:
        """Call ``cb(value)`` (``cb(event)`` when ``name`` is None: every event) on the dispatcher;
        events that arrived while nobody listened are handed to the first matching listener."""
        self._run(self._call(self.core.events.add_callback, name, cb))

    def remove_event_callback(self, name: Optional[str], cb: Callable[[Any], Any]) -> None:
        """Undo :meth:`add_event_callback`."""
        self._run(self._call(self.core.events.remove_callback, name, cb))

    def event_queue(self, names: Optional[Any] = None) -> QueueSink:
        """A new sink whose ``q`` receives every event (of ``names``) from now on, the backlog first."""
        sink = QueueSink(self.core.stats, frozenset(names) if names else None)
        self._run(self._call(self.core.events.add_sink, sink))
        return sink

    def drop_event_queue(self, sink: QueueSink) -> None:
        """Stop feeding a sink made by :meth:`event_queue`."""
        if self._loop is not None:
            self._loop.call_soon_threadsafe(self.core.events.remove_sink, sink)
