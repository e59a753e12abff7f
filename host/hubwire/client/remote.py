"""The synchronous face of a board through the service: :class:`RemoteSession` stands in for
:class:`hubwire.session.Session` under a :class:`RemoteDevice` (a :class:`hubwire.Device`), so
``hubwire.connect("rover")`` gives the same methods, attributes, streams and events as a direct
connection (:class:`hubwire.board.BoardAPI`), hub channels and missions included.

It runs an :class:`AsyncRemoteDevice` on the process's shared hub loop; callbacks run on a
dispatcher thread of their own, as a direct session's do.
"""
from __future__ import annotations

from typing import Any, Callable, Dict, List, Optional, Tuple

from ..descriptor import Channel, Descriptor
from ..device import Device
from ..errors import HubwireError
from ..session import LinkHealth, State, Stats, StreamSample, ThreadSubscription
from ..session.events import QueueSink
from ..session.runner import ThreadDispatcher, release_loop, run_sync
from ..wire import messages as m
from ..wire.frame import Frame
from .connection import AsyncRemoteDevice
from .streams import ended

__all__ = ["RemoteSession", "RemoteDevice"]

_ident = id  # (``id`` is a channel id in the methods below)
_STATES = {"ready": State.READY, "connecting": State.CONNECTING, "lost": State.LOST, "closed": State.CLOSED}


class RemoteSession:
    """What :class:`hubwire.Device` needs of a session, answered through ``hubwire serve``."""

    def __init__(self, loop: Any, remote: AsyncRemoteDevice) -> None:
        self._loop: Any = loop
        self.remote = remote
        self.url = remote.url
        self.stats = Stats()
        self._dispatcher = ThreadDispatcher()
        self._subs: Dict[int, int] = {}  # id(subscription or sink) -> service subscription
        self._cbs: List[Tuple[Any, Callable[..., Any], int]] = []
        self._removers: Dict[Tuple[str, int], Callable[[], None]] = {}
        # hub channel handlers run on the dispatcher thread, as a direct session's
        remote.hub_dispatch = lambda fn: self._dispatcher(fn)

    @property
    def core(self) -> Any:
        """What :class:`hubwire.Device` reaches for hub channels (client/hub_client.py)."""
        return self.remote._hub_side()

    def hub_status(self) -> List[Dict[str, Any]]:
        """Who provides each hub channel of the board, and its binding (op ``hub``)."""
        return self._run(self.remote._hub_side().fetch_status())  # type: ignore[no-any-return]

    def provide_hub(self, hub: Any) -> None:
        """``connect(name, hub=...)``: offer ``hub`` to the board through the service."""
        self._run(self.remote.provide_hub(hub))

    @property
    def descriptor(self) -> Optional[Descriptor]:
        return self.remote.descriptor

    @property
    def state(self) -> State:
        return State.CLOSED if self._loop is None else _STATES.get(self.remote.state, State.LOST)

    @property
    def board(self) -> Dict[str, Any]:
        """The board as the service describes it: key, name, board_id, port, state."""
        return dict(self.remote.board)

    def _run(self, aw: Any) -> Any:
        if self._loop is None:
            aw.close()
            raise HubwireError("session is closed")
        return run_sync(self._loop, aw)

    def health(self) -> LinkHealth:
        if self._loop is None:  # closed: what a closed direct session reports, without asking
            return LinkHealth("closed", None, None, 0, None, {}, {})
        return self._run(self.remote.fetch_health())  # type: ignore[no-any-return]

    def board_id(self, timeout: Optional[float] = None) -> Optional[str]:
        return self._run(self.remote.board_id(timeout=timeout))  # type: ignore[no-any-return]

    def _channel(self, id: int) -> Channel:
        ch = self.remote.descriptor.by_id(id)
        if ch is None:
            raise HubwireError(f"no channel with id {id}")
        return ch

    def request(self, id: int, *, timeout: Optional[float] = None, what: str = "") -> bytes:
        return self._run(self.remote.read_raw(self._channel(id).name, timeout))  # type: ignore[no-any-return]

    def control(self, id: int, payload: bytes, *, timeout: Optional[float] = None, what: str = "") -> Frame:
        ch = self._channel(id)
        raw = self._run(self.remote.control_raw(ch, payload, timeout))
        return Frame(m.ACK, 0, id, b"") if raw is None else Frame(m.RESPONSE, 0, id, raw)

    # ----------------------------------------------------------------------------- missions

    def start_mission(self, name: str, goal: Any, timeout: Optional[float] = None,
                      run_id: Optional[str] = None) -> Any:
        """``dev.start`` through the service: a :class:`RemoteJob` (status callbacks on the dispatcher)."""
        from .remote_missions import RemoteJob

        rec, rid = self._run(self.remote.start_run(name, goal, timeout=timeout, run_id=run_id,
                                                   dispatch=self._dispatcher))
        return RemoteJob(self, rec, rid)

    def follow(self, run_id: str) -> Any:
        """The job of a run the service has, from its first progress value."""
        from .remote_missions import RemoteJob, follow_run

        rec, rid = self._run(follow_run(self.remote, run_id, self._dispatcher))
        return RemoteJob(self, rec, rid)

    # ------------------------------------------------------------------------------ streams

    def open_stream(self, id: int, interval_ms: int, maxlen: int = 1024, what: str = "") -> ThreadSubscription:
        ch = self._channel(id)
        sub = ThreadSubscription(id, interval_ms, maxlen)
        remote = self.remote

        def push(msg: Dict[str, Any]) -> None:
            if "sample" in msg:
                s: StreamSample = remote.sample(ch, msg["sample"])
                sub.push(s)
            elif "end" in msg:
                sub.end(ended(msg))

        async def start() -> "tuple[int, Dict[str, Any]]":
            return await remote.conn.subscribe("stream", push, board=remote.key, channel=ch.name,
                                               interval_ms=interval_ms)
        sid, reply = self._run(start())
        sub.granted_ms = int(reply["granted_ms"])
        self._subs[_ident(sub)] = sid
        return sub

    def close_stream(self, sub: ThreadSubscription, wait: bool = True) -> None:
        sid = self._subs.pop(_ident(sub), None)
        sub.end(StopIteration())
        if sid is not None and self._loop is not None:
            self._loop.call_soon_threadsafe(lambda: self._loop and self._loop.create_task(
                self.remote.conn.unsubscribe(sid)))

    # ------------------------------------------------------------------------------- events

    def _events(self, names: Optional[List[str]], handler: Callable[[Dict[str, Any]], None]) -> int:
        async def start() -> int:
            sub, fut = self.remote.listen(names or [], handler)
            await self.remote.conn.confirm(sub, fut)
            return sub
        return self._run(start())  # type: ignore[no-any-return]

    def event_queue(self, names: Optional[Any] = None) -> QueueSink:
        sink = QueueSink(self.stats, frozenset(names) if names else None)

        def handler(msg: Dict[str, Any]) -> None:
            if "event" in msg:
                sink.put(self.remote.decode_event(msg["event"]))
            elif "end" in msg:
                sink.close()
        self._subs[_ident(sink)] = self._events(sorted(names) if names else None, handler)
        return sink

    def drop_event_queue(self, sink: QueueSink) -> None:
        self._unsubscribe(self._subs.pop(_ident(sink), None))

    def add_event_callback(self, name: Optional[str], cb: Callable[[Any], Any]) -> None:
        def handler(msg: Dict[str, Any]) -> None:
            if "event" in msg:
                ev = self.remote.decode_event(msg["event"])
                self._dispatcher(cb, ev if name is None else ev.value)
        self._cbs.append((name, cb, self._events(None if name is None else [name], handler)))

    def remove_event_callback(self, name: Optional[str], cb: Callable[[Any], Any]) -> None:
        for entry in list(self._cbs):
            if entry[0] == name and entry[1] == cb:
                self._cbs.remove(entry)
                self._unsubscribe(entry[2])

    def _unsubscribe(self, sid: Optional[int]) -> None:
        if sid is not None and self._loop is not None:
            self._loop.call_soon_threadsafe(lambda: self._loop and self._loop.create_task(
                self.remote.conn.unsubscribe(sid)))

    def _add(self, kind: str, cb: Callable[..., Any]) -> None:
        self._removers[(kind, id(cb))] = self.remote.on(kind, lambda *a: self._dispatcher(cb, *a))

    def add_link_lost(self, cb: Callable[[], Any]) -> None:
        self._add("link_lost", cb)

    def add_link_restored(self, cb: Callable[[], Any]) -> None:
        self._add("link_restored", cb)

    def add_reconnect(self, cb: Callable[[Descriptor], Any]) -> None:
        self._add("reconnect", cb)

    def remove_callback(self, kind: str, cb: Callable[..., Any]) -> None:
        remove = self._removers.pop((kind, id(cb)), None)
        if remove is not None:
            remove()

    # ---------------------------------------------------------------------------- lifecycle

    def close(self) -> None:
        """End this client's subscriptions; the board stays with the service (no reset, no failsafe)."""
        loop, self._loop = self._loop, None
        if loop is None:
            return
        try:
            run_sync(loop, self.remote.close())
        finally:
            self._dispatcher.stop()
            release_loop()

    def __enter__(self) -> "RemoteSession":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()



class RemoteDevice(Device):
    """:class:`hubwire.Device` through ``hubwire serve`` (``hubwire.connect("rover")``): the same
    :class:`hubwire.board.BoardAPI`; hub channels go through the service (client/hub_client.py)."""

    __slots__ = ()
    _session: Any  # a RemoteSession

    def board_id(self, *, timeout: Optional[float] = None) -> Optional[str]:
        """The id the service knows the board by (its USB serial number, else its own id, else None)."""
        return self._session.board_id(timeout)  # type: ignore[no-any-return]
