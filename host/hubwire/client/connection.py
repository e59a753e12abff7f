"""The client side of the service's protocol (docs/SERVICE.md), on asyncio: :class:`Connection`
(requests and pushed messages on one Unix socket) and :class:`AsyncRemoteDevice`, a board reached
by name through ``hubwire serve`` with the methods of :class:`hubwire.aio.AsyncDevice`.

Values travel as the channel's payload bytes (hex) both ways, so a value read through the service is
exactly what a direct connection decodes, and a value written was checked here first (type, range)
as a direct write is, and again by the service.
"""
from __future__ import annotations

import asyncio
import json
import time
from typing import Any, Callable, Dict, List, Optional

from .. import ops
from ..board import AsyncBoardAPI
from ..descriptor import Channel, Descriptor
from ..descriptor.parse import parse_descriptor
from ..errors import HubwireError, LinkLost
from ..hub import HubChannels
from ..hub_face import HubMethods
from ..session import LinkHealth, ReceivedEvent, StreamSample
from .hub_client import RemoteHub
from .remote_missions import RemoteMissions
from .protocol import MAX_LINE, PROTOCOL, ServiceNotRunning, encode, raise_error, socket_path
from .streams import RemoteEvents, RemoteStream

__all__ = ["Connection", "AsyncRemoteDevice", "connect", "not_running_message", "RemoteStream", "RemoteEvents"]

Handler = Callable[[Dict[str, Any]], None]


def not_running_message(path: Optional[str]) -> str:
    where = f" (nothing answers on {path})" if path else ""
    return (f"hubwire serve is not running{where}: start it with `hubwire serve` (or `sudo systemctl start "
            "hubwire` where it is installed as a service), or name the board's port instead of its name")


class Connection:
    """One client connection to the service, on the running loop."""

    def __init__(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter, path: str) -> None:
        self.path = path
        self._reader = reader
        self._writer = writer
        self._next = 0
        self._pending: Dict[int, "asyncio.Future[Dict[str, Any]]"] = {}
        self._subs: Dict[int, Handler] = {}
        self._task: Optional["asyncio.Task[None]"] = None
        self.closed = False

    @classmethod
    async def open(cls, path: Optional[str] = None, timeout: float = 5.0) -> "Connection":
        """Connect (ServiceNotRunning when no service answers; HubwireError for another protocol)."""
        path = path or socket_path()
        if path is None:
            raise ServiceNotRunning(not_running_message(None))
        try:
            reader, writer = await asyncio.open_unix_connection(path, limit=MAX_LINE)
        except OSError:
            raise ServiceNotRunning(not_running_message(path)) from None
        try:
            hello = json.loads(await asyncio.wait_for(reader.readline(), timeout) or b"{}")
        except (asyncio.TimeoutError, ValueError, OSError):
            writer.close()
            raise ServiceNotRunning(not_running_message(path)) from None
        if hello.get("protocol") != PROTOCOL:
            writer.close()
            raise HubwireError(f"the service on {path} speaks client protocol {hello.get('protocol')!r}, this "
                               f"hub speaks {PROTOCOL}: run the same Hubwire version for both")
        conn = cls(reader, writer, path)
        conn._task = asyncio.get_running_loop().create_task(conn._read())
        return conn

    def _send(self, op: str, **kw: Any) -> "asyncio.Future[Dict[str, Any]]":
        if self.closed:
            raise LinkLost("the connection to hubwire serve is closed")
        self._next += 1
        fut: "asyncio.Future[Dict[str, Any]]" = asyncio.get_running_loop().create_future()
        self._pending[self._next] = fut
        self._writer.write(encode({"id": self._next, "op": op, **kw}))
        return fut

    @staticmethod
    async def _result(fut: "asyncio.Future[Dict[str, Any]]") -> Dict[str, Any]:
        msg = await fut
        if not msg.get("ok"):
            raise_error(msg)
        return msg

    async def request(self, op: str, **kw: Any) -> Dict[str, Any]:
        """Send a request and return its answer (or raise the error it reports)."""
        return await self._result(self._send(op, **kw))

    def subscribe_nowait(self, op: str, handler: Handler, **kw: Any) -> "tuple[int, asyncio.Future[Dict[str, Any]]]":
        """Start a subscription now (pushed messages go to ``handler`` from the first one on);
        returns its id and the future of its answer (see :meth:`confirm`)."""
        self._next += 1
        sub = self._next
        self._subs[sub] = handler
        return sub, self._send(op, sub=sub, **kw)

    async def confirm(self, sub: int, fut: "asyncio.Future[Dict[str, Any]]") -> Dict[str, Any]:
        try:
            return await self._result(fut)
        except BaseException:
            self._subs.pop(sub, None)
            raise

    async def subscribe(self, op: str, handler: Handler, **kw: Any) -> "tuple[int, Dict[str, Any]]":
        sub, fut = self.subscribe_nowait(op, handler, **kw)
        return sub, await self.confirm(sub, fut)

    async def unsubscribe(self, sub: int) -> None:
        if self._subs.pop(sub, None) is not None and not self.closed:
            self._send("unsubscribe", sub=sub)  # the answer needs no wait

    async def _read(self) -> None:
        try:
            while True:
                line = await self._reader.readline()
                if not line:
                    break
                msg = json.loads(line)
                fut = self._pending.pop(msg["id"], None) if "id" in msg else None
                if fut is not None:
                    if not fut.done():
                        fut.set_result(msg)
                elif "sub" in msg and msg["sub"] in self._subs:
                    self._subs[msg["sub"]](msg)
        except (OSError, ValueError):
            pass
        finally:
            self._gone()

    def _gone(self) -> None:
        # closed by this client (close()), as a direct session says, or by the service
        why = "session closed" if self.closed else "hubwire serve went away"
        self.closed = True
        gone = {"ok": False, "error": "LinkLost", "message": why}
        for fut in self._pending.values():
            if not fut.done():
                fut.set_result(gone)
        self._pending.clear()
        for sub, h in list(self._subs.items()):
            h({"sub": sub, "end": "LinkLost", "message": gone["message"]})
        self._subs.clear()

    async def close(self) -> None:
        self.closed = True
        self._writer.close()
        if self._task is not None:
            await asyncio.gather(self._task, return_exceptions=True)


async def connect(board: str, *, timeout: float = 5.0, path: Optional[str] = None) -> "AsyncRemoteDevice":
    """The board ``board`` (key, name, ``name-<board id>`` or port) through the service."""
    conn = await Connection.open(path, timeout)
    try:
        reply = await conn.request("describe", board=board, timeout=timeout)
        dev = AsyncRemoteDevice(conn, reply["board"], parse_descriptor(reply["descriptor"]))
        await dev._watch()
        await dev._mark_events()
        if dev.descriptor.hub:  # hub_binding() as the service binds the board now
            await dev._hub_side().fetch_binding()
    except BaseException:
        await conn.close()
        raise
    return dev


class AsyncRemoteDevice(HubMethods, RemoteMissions, AsyncBoardAPI):
    """A board through ``hubwire serve``: :class:`hubwire.board.AsyncBoardAPI`, as
    :class:`hubwire.aio.AsyncDevice` is, hub channels as a direct device's (``hub``, ``provide``...
    ``notify``; client/hub_client.py). Closing it ends this client's subscriptions and lets go of its
    hub channels; the board stays
    connected to the service."""

    def __init__(self, conn: Connection, board: Dict[str, Any], desc: Descriptor) -> None:
        self.conn = conn
        self.board = board
        self.key: str = board["key"]
        self._desc = desc
        self._cbs: Dict[str, List[Callable[..., Any]]] = {"link_lost": [], "link_restored": [], "reconnect": []}
        self._subs: List[int] = []
        self._sessions: Any = board.get("sessions")  # the service's count of device sessions
        self._since: Optional[int] = None  # the service's last event id when this client connected
        self._delivered: Dict[str, int] = {}  # per event channel: the newest id a listener here had
        self._closed = False
        self._loop = asyncio.get_running_loop()
        self._hub: Optional[RemoteHub] = None
        #: where hub channel handlers run (the sync face sets its dispatcher thread)
        loop = self._loop
        self.hub_dispatch: Callable[[Callable[[], None]], Any] = lambda fn: loop.call_soon_threadsafe(fn)

    # ------------------------------------------------------------------------- hub channels

    def _hub_side(self) -> Any:
        if self._hub is None:
            self._hub = RemoteHub(self, HubChannels(), self._loop)
        return self._hub

    async def provide_hub(self, hub: Optional[HubChannels]) -> None:
        """Offer ``hub`` to the board through the service (``connect(name, hub=...)``): raises as a
        direct connect for a channel the board expects otherwise, HubConflict naming both when
        another provider holds one."""
        if hub is None:
            return
        if self._hub is not None:
            self._hub.close()
        self._hub = side = RemoteHub(self, hub, self._loop)
        try:
            held = tuple(str(r.get("channel")) for r in await side.fetch_status() if r.get("by"))
            side.check_all(held)
            await side.start()
        except BaseException:
            side.close()
            raise
        await side.fetch_binding()

    async def wait_notified(self, timeout: Optional[float] = 5.0) -> None:
        """Return once every hub event given to :meth:`notify` is queued and stored at the service
        (it then reaches the board exactly once); :class:`hubwire.Timeout` after ``timeout`` s."""
        from ..errors import Timeout

        if self._hub is not None and not await self._hub.wait_notified(timeout):
            raise Timeout(f"{len(self._hub.queue)} hub events still wait for hubwire serve after {timeout} s")

    async def _watch(self) -> None:
        sub, _ = await self.conn.subscribe("boards", self._board_changed, board=self.key)
        self._subs.append(sub)

    async def _mark_events(self) -> None:
        sub, reply = await self.conn.subscribe("events", lambda _m: None, board=self.key, names=[])
        await self.conn.unsubscribe(sub)
        last = reply.get("last")
        self._since = last if isinstance(last, int) and not isinstance(last, bool) else None

    def listen(self, names: List[str], handler: Handler) -> "tuple[int, asyncio.Future[Dict[str, Any]]]":
        """Subscribe one listener to the events of ``names`` (all when empty), as a direct session
        hands them: first those since this client connected that no listener here has had yet (the
        service replays them: ``after``), then every new one. Returns the subscription and its answer."""
        extra = {} if self._since is None else {"after": self._since}
        answered: List["asyncio.Future[Dict[str, Any]]"] = []

        def push(msg: Dict[str, Any]) -> None:
            e = msg.get("event")
            ch = self._desc.by_name(str(e.get("name"))) if isinstance(e, dict) else None
            eid = e.get("id") if isinstance(e, dict) else None
            if ch is not None and isinstance(eid, int):
                had = self._delivered.get(ch.name, -1)
                if not answered[0].done() and eid <= had:
                    return  # replayed, but another listener here had it already
                self._delivered[ch.name] = max(had, eid)
            handler(msg)
        sub, fut = self.conn.subscribe_nowait("events", push, board=self.key, names=names, **extra)
        answered.append(fut)
        return sub, fut

    def _board_changed(self, msg: Dict[str, Any]) -> None:
        b = msg.get("board")
        if b is None:
            return
        was, self.board = self.board, b
        if was["state"] == "ready" and b["state"] != "ready":
            self._fire("link_lost")
        elif b["state"] == "ready" and b.get("sessions") != self._sessions:
            # a new device session (a reboot, a replug): its descriptor may be another one
            self._sessions = b.get("sessions")
            if was["state"] == "ready":
                self._fire("link_lost")  # as a direct session that had not noticed the reboot
            asyncio.get_running_loop().create_task(self._rediscovered())
        elif was["state"] != "ready" and b["state"] == "ready":
            self._fire("link_restored")

    async def _rediscovered(self) -> None:
        try:
            reply = await self.conn.request("describe", board=self.key)
            self._desc = parse_descriptor(reply["descriptor"])
        except HubwireError:
            return  # gone again: told by the next board message
        self._fire("reconnect", self._desc)

    def _fire(self, kind: str, *args: Any) -> None:
        for cb in list(self._cbs[kind]):
            res = cb(*args)
            if asyncio.iscoroutine(res):
                asyncio.get_running_loop().create_task(res)

    @property
    def descriptor(self) -> Descriptor:
        return self._desc

    @property
    def name(self) -> str:
        return self._desc.name

    @property
    def state(self) -> str:
        """``"ready"``, ``"connecting"``, ``"lost"`` (also while unplugged: ``board["state"]`` tells
        the service's own word) or ``"closed"`` once this client closed it, as on a direct session."""
        if self._closed:
            return "closed"
        state = str(self.board["state"])
        return "lost" if state == "unplugged" else state

    @property
    def url(self) -> str:
        return f"service:{self.key}"

    async def board_id(self, *, timeout: Optional[float] = None) -> Optional[str]:
        """The id the service knows the board by: its USB serial number when its port has one, else
        the board's own id (as :meth:`hubwire.aio.AsyncDevice.board_id` reads it), else None."""
        bid = self.board.get("board_id")
        return None if bid is None else str(bid)

    def health(self) -> LinkHealth:
        """The state as last heard from the service (:meth:`fetch_health` asks it for the rest)."""
        return LinkHealth(self.state, None, None, 0, None, {}, {})

    async def fetch_health(self) -> LinkHealth:
        """The link's health as the service measures it (once closed: :meth:`health`, as direct)."""
        if self._closed:
            return self.health()
        h = (await self.conn.request("health", board=self.key))["health"]
        return LinkHealth(**h) if h else self.health()

    def channel(self, name: str) -> Channel:
        return ops.channel(self._desc, name)

    async def read_raw(self, name: str, timeout: Optional[float] = None) -> bytes:
        msg = await self.conn.request("read", board=self.key, channel=name, timeout=timeout)
        return bytes.fromhex(msg["raw"])

    async def control_raw(self, ch: Channel, payload: bytes, timeout: Optional[float] = None) -> Optional[bytes]:
        """Write (``ch`` writable) or call with an encoded payload; the call's result payload or None."""
        if ch.callable:
            msg = await self.conn.request("call", board=self.key, channel=ch.name, raw=payload.hex(), timeout=timeout)
            return None if msg.get("raw") is None else bytes.fromhex(msg["raw"])
        await self.conn.request("write", board=self.key, channel=ch.name, raw=payload.hex(), timeout=timeout)
        return None

    async def read(self, name: str, *, timeout: Optional[float] = None) -> Any:
        return ops.readable(self._desc, name).codec.decode(await self.read_raw(name, timeout))

    async def write(self, name: str, value: Any, *, timeout: Optional[float] = None) -> None:
        ch, payload = ops.write_payload(self._desc, name, value)
        await self.control_raw(ch, payload, timeout)

    async def call(self, name: str, arg: Any = None, *, timeout: Optional[float] = None) -> Any:
        ch, payload = ops.call_payload(self._desc, name, arg)
        raw = await self.control_raw(ch, payload, timeout)
        return None if raw is None or ch.returns is None else ch.returns.decode(raw)

    def sample(self, ch: Channel, s: Dict[str, Any]) -> StreamSample:
        return StreamSample(ch.codec.decode(bytes.fromhex(s["raw"])), int(s["since_ms"]), int(s["seq"]),
                            int(s["lost"]), time.monotonic(), int(s["gap"]))

    def decode_event(self, e: Dict[str, Any]) -> ReceivedEvent:
        ch = self.channel(e["name"])
        return ReceivedEvent(ch.name, ch.codec.decode(bytes.fromhex(e["raw"])), int(e["seq"]), time.monotonic(), ch.id)

    def stream(self, name: str, hz: Optional[float] = None, *, interval_ms: Optional[int] = None,
               meta: bool = False, timeout: Optional[float] = None, maxlen: int = 1024) -> RemoteStream:
        ch = ops.stream_channel(self._desc, name)
        return RemoteStream(self, ch, ops.interval_for(hz, interval_ms), meta, timeout, maxlen)

    def events(self, *names: str, timeout: Optional[float] = None) -> RemoteEvents:
        for n in names:
            self.channel(n)
        return RemoteEvents(self, list(names), timeout)

    def on(self, name: str, callback: Callable[..., Any]) -> Callable[[], None]:
        """As :meth:`AsyncDevice.on`: events of ``name`` (``"*"``: every event), or ``link_lost``,
        ``link_restored`` (the board's state at the service); returns the remover."""
        if name in self._cbs:
            lst = self._cbs[name]
            lst.append(callback)
            return lambda: lst.remove(callback) if callback in lst else None
        key = ops.event_key(self._desc, name)

        def handler(msg: Dict[str, Any]) -> None:
            if "event" in msg:
                ev = self.decode_event(msg["event"])
                res = callback(ev if key is None else ev.value)
                if asyncio.iscoroutine(res):
                    asyncio.get_running_loop().create_task(res)
        sub, fut = self.listen([] if key is None else [key], handler)
        self._subs.append(sub)
        fut.add_done_callback(lambda f: None if f.result().get("ok") else self.conn._subs.pop(sub, None))
        def remove() -> None:
            asyncio.ensure_future(self.conn.unsubscribe(sub))
        return remove

    async def close(self) -> None:
        self._closed = True
        if self._hub is not None:
            self._hub.close()
        await self.conn.close()

    async def __aenter__(self) -> "AsyncRemoteDevice":
        return self

    async def __aexit__(self, *exc: Any) -> None:
        await self.close()

    def __repr__(self) -> str:
        return f"<hubwire AsyncRemoteDevice {self.key} through hubwire serve ({self.state})>"
