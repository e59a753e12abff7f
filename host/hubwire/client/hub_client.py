"""Hub channels of a board reached through ``hubwire serve``, on the client's side: :class:`RemoteHub`
stands where a direct session has its ``HubSide``, so ``connect("thermostat", hub=hub)``,
``dev.hub``, ``dev.provide(...)``, ``dev.notify(...)`` and ``dev.hub_binding()`` are the same calls
as on a direct connection (docs/SERVICE.md "Hub channels").

The client holds its hub channels at the service with a ``provide`` subscription; the board's
requests come as pushed messages, the declared handlers run where this connection's callbacks run
(the dispatcher thread of a :class:`hubwire.Device`, the loop of a ``hubwire.aio`` device; a
coroutine is awaited there) and their answers go back as ``hub_answer``. Hub events go out with
``notify`` as any client's.
"""
from __future__ import annotations

import asyncio
import logging
import os
import sys
import threading
from typing import Any, Callable, Dict, List, Optional, Tuple

from ..errors import HubChannelError, HubwireError
from ..hub import HubChannel, HubChannels, bind_status
from ..session.hub_channels import mismatch
from ..session.runner import run_handler, running_loop
from ..text import clip

__all__ = ["RemoteHub", "status_lines"]

log = logging.getLogger("hubwire")

#: hub events handed to the service and not answered yet; beyond it ``notify`` raises
NOTIFY_LIMIT = 4096


def _program() -> str:
    """How this program names itself to the service: its script, or its package for ``python -m``."""
    path = sys.argv[0] if sys.argv and sys.argv[0] else ""
    name = os.path.basename(path)
    if name == "__main__.py":
        name = os.path.basename(os.path.dirname(path))
    return name or "python"


class RemoteHub:
    """The hub channels ``channels`` offered to the board of ``remote`` (an ``AsyncRemoteDevice``)
    through the service; handlers run through ``remote.hub_dispatch`` (where callbacks run). Also
    what the faces' ``_session.core`` stands for here (``hub``, ``descriptor``, ``sync_cv``, ``closed``)."""

    def __init__(self, remote: Any, channels: HubChannels, loop: asyncio.AbstractEventLoop) -> None:
        self.remote = remote
        self.channels = channels
        self.loop = loop
        self.sub: Optional[int] = None
        #: hub events handed to the service, not answered yet
        self.queue: List[Tuple[str, Any]] = []
        self.sync_cv = threading.Condition()
        self.closed = False
        self.last_binding: Dict[str, str] = {}
        self._update: Optional["asyncio.Task[None]"] = None
        self._updating: Optional[asyncio.Lock] = None  # one update at a time (made on the loop)
        channels.add_listener(self)

    # --------------------------------------------------------------- what the faces ask for

    @property
    def hub(self) -> "RemoteHub":
        return self

    @property
    def core(self) -> "RemoteHub":
        return self

    @property
    def descriptor(self) -> Any:
        return self.remote.descriptor

    def _expected(self) -> List[Any]:
        return [c for c in self.remote.descriptor.hub if "e" not in c.access]

    def _entries(self) -> List[Dict[str, Any]]:
        names = {c.name for c in self._expected()}
        return [dict(hc.entry) for n, hc in list(self.channels._channels.items()) if n in names]

    # ----------------------------------------------------------------------------- binding

    def check_all(self, elsewhere: Tuple[str, ...] = ()) -> None:
        """HubChannelError naming each hub channel the board uses that ``channels`` declares
        otherwise, or lacks and no other provider holds (``elsewhere``: another client, the MQTT
        bridge, the service for events), as a direct ``connect(..., hub=...)`` raises."""
        desc = self.remote.descriptor
        bad = [mismatch(exp, self.channels.get(exp.name), code, desc.name)
               for exp in desc.hub for code in (bind_status(exp, self.channels.get(exp.name)),)
               if code and not (exp.name in elsewhere and self.channels.get(exp.name) is None)]
        if bad:
            raise HubChannelError("; ".join(bad))

    async def start(self) -> None:
        """Hold every declared channel the board reads, writes or calls (HubConflict naming both
        providers when another holds one)."""
        if not self._entries():
            return
        sub, reply = await self.remote.conn.subscribe("provide", self._pushed, board=self.remote.key,
                                                      channels=self._entries(), name=_program())
        self.sub = sub
        self._note_binding(reply.get("hub") or [])

    def hub_changed(self, hc: HubChannel, removed: bool) -> None:
        """A declaration changed (any thread): refuse one the board expects otherwise, then tell
        the service the new set."""
        if not removed:
            for exp in self.remote.descriptor.hub:
                if exp.name == hc.name:
                    code = bind_status(exp, hc)
                    if code:
                        raise HubChannelError(mismatch(exp, hc, code, self.remote.descriptor.name))
        self.loop.call_soon_threadsafe(self._schedule_update)

    def _schedule_update(self) -> None:
        if self.closed or self.remote.conn.closed:
            return
        self._update = self.loop.create_task(self._send_update())

    async def _send_update(self) -> None:
        if self._updating is None:
            self._updating = asyncio.Lock()
        async with self._updating:  # several declarations in a row: each sends the set as it is then
            await self._update_now()

    async def _update_now(self) -> None:
        try:
            if self.sub is None:
                await self.start()
            else:
                reply = await self.remote.conn.request("provide", sub=self.sub, board=self.remote.key,
                                                       channels=self._entries(), name=_program())
                self._note_binding(reply.get("hub") or [])
        except HubwireError as e:
            log.error("hubwire: hub channels of %s not provided: %s", self.remote.key, clip(str(e), 300))

    def _note_binding(self, rows: List[Dict[str, Any]]) -> None:
        self.last_binding = {str(r.get("channel")): str(r.get("bind", "?")) for r in rows if isinstance(r, dict)}

    def binding(self) -> Dict[str, str]:
        """As ``hub_binding()`` of a direct device, as the service sees the board's channels."""
        if running_loop() is self.loop:  # (hubwire.aio: as last heard, pushed by the service)
            return dict(self.last_binding)
        return asyncio.run_coroutine_threadsafe(self.fetch_binding(), self.loop).result(30)

    async def fetch_binding(self) -> Dict[str, str]:
        await self.fetch_status()
        return dict(self.last_binding)

    async def fetch_status(self) -> List[Dict[str, Any]]:
        """The service's rows for the board's hub channels (op ``hub``)."""
        rows = (await self.remote.conn.request("hub", board=self.remote.key)).get("hub") or []
        self._note_binding(rows)
        return [r for r in rows if isinstance(r, dict)]

    # ----------------------------------------------------------------- the board's requests

    def _pushed(self, msg: Dict[str, Any]) -> None:
        if "hub" in msg and isinstance(msg["hub"], dict):
            self._request(msg["hub"])
        elif "binding" in msg and isinstance(msg["binding"], list):
            self._note_binding(msg["binding"])
        elif "end" in msg:  # the service went away: nothing is provided any more
            self.last_binding = {}

    def _request(self, req: Dict[str, Any]) -> None:
        hc = self.channels.get(str(req.get("channel")))
        do, rid = req.get("do"), req.get("req")
        if hc is None:
            self._answer(rid, error="UNKNOWN_CHANNEL")
            return
        try:
            raw = bytes.fromhex(str(req.get("raw", "")))
            if do == "read":
                if hc.getter is None:
                    self._answer(rid, raw=hc.channel.codec.encode(hc.value))
                else:
                    self._run(hc.getter, (), lambda v: self._answer(rid, raw=hc.channel.codec.encode(v)), rid)
            elif do == "write":
                value = hc.channel.check(hc.channel.codec.decode(raw))

                def written(result: Any) -> None:
                    if result is False:
                        self._answer(rid, error="REJECTED")
                    else:
                        hc.store(value)
                        self._answer(rid)
                if hc.on_write is None:
                    written(None)
                else:
                    self._run(hc.on_write, (value,), written, rid)
            elif do == "call" and hc.fn is not None:
                returns = hc.channel.returns
                void = hc.channel.codec.kind == "void"
                args = () if void else (hc.channel.check(hc.channel.codec.decode(raw)),)

                def called(result: Any) -> None:
                    if returns is None or returns.kind == "void":
                        self._answer(rid)
                    else:
                        self._answer(rid, raw=returns.encode(result))
                self._run(hc.fn, args, called, rid)
            else:
                self._answer(rid, error="NOT_WRITABLE")
        except Exception as e:  # noqa: BLE001 - a value that does not fit: the board is told REJECTED
            log.warning("hubwire: hub channel %s: %s", clip(hc.name), clip(str(e), 160))
            self._answer(rid, error="REJECTED")

    def _run(self, fn: Callable[..., Any], args: Tuple[Any, ...], done: Callable[[Any], None], rid: Any) -> None:
        """Run a handler where callbacks run; ``done(result)`` on the loop, REJECTED when it raises."""
        loop = self.loop

        def finish(ok: bool, result: Any) -> None:
            if not ok:
                log.warning("hubwire: hub channel handler %r raised: %s", fn, clip(repr(result), 160))
                self._answer(rid, error="REJECTED")
                return
            try:
                done(result)
            except Exception as e:  # noqa: BLE001 - a result that does not fit the declared type
                log.warning("hubwire: hub channel handler %r gave %s: %s", fn, clip(repr(result), 60), clip(str(e), 120))
                self._answer(rid, error="REJECTED")

        run_handler(loop, self.remote.hub_dispatch, fn, args, finish)

    def _answer(self, rid: Any, raw: Optional[bytes] = None, error: Optional[str] = None) -> None:
        if self.sub is None or self.remote.conn.closed:
            return
        kw: Dict[str, Any] = {"sub": self.sub, "req": rid}
        if raw is not None:
            kw["raw"] = raw.hex()
        if error is not None:
            kw["error"] = error
        fut = self.remote.conn._send("hub_answer", **kw)  # its own answer needs no wait
        fut.add_done_callback(lambda f: None)

    # ------------------------------------------------------------------------------ events

    def notify(self, name: str, value: Any) -> None:
        """Hand hub event ``name`` to the service (any thread); raises at once for a name the board
        does not take as an event or a value that does not fit. Delivered as the service's
        ``notify`` says: stored, then sent exactly once, in order."""
        if self.closed or self.remote.conn.closed:
            raise HubwireError("the connection to hubwire serve is closed: no event can reach the board")
        desc = self.remote.descriptor
        exp = next((c for c in desc.hub if c.name == name and "e" in c.access), None)
        if exp is None:
            raise HubChannelError(f"{desc.name} takes no hub event {name!r}")
        hc = self.channels.get(name)
        if hc is not None and not hc.is_event:
            raise HubChannelError(f"hub channel {name!r} is not an event (declare it with hub.event())")
        ch = hc.channel if hc is not None else exp
        payload = ch.codec.encode(ch.check(value))
        with self.sync_cv:
            if len(self.queue) >= NOTIFY_LIMIT:
                raise HubwireError(f"{NOTIFY_LIMIT} hub events wait for hubwire serve already")
            item = (name, value)
            self.queue.append(item)
        self.loop.call_soon_threadsafe(self._send_event, item, payload)

    def _send_event(self, item: Tuple[str, Any], payload: bytes) -> None:
        def done(f: "asyncio.Future[Dict[str, Any]]") -> None:
            msg = f.result() if not f.cancelled() else {"ok": False, "message": "cancelled"}
            if not msg.get("ok"):
                log.error("hubwire: hub event %s for %s not queued: %s", clip(item[0]), self.remote.key,
                          clip(str(msg.get("message")), 200))
            self._settled(item)
        try:
            fut = self.remote.conn._send("notify", board=self.remote.key, channel=item[0], raw=payload.hex())
        except HubwireError as e:
            log.error("hubwire: hub event %s not sent: %s", clip(item[0]), e)
            self._settled(item)
            return
        fut.add_done_callback(done)

    def _settled(self, item: Tuple[str, Any]) -> None:
        with self.sync_cv:
            if item in self.queue:
                self.queue.remove(item)
            self.sync_cv.notify_all()

    async def wait_notified(self, timeout: Optional[float]) -> bool:
        """Until every event handed over is queued and stored at the service (True), or timeout."""
        end = None if timeout is None else self.loop.time() + timeout
        while self.queue:
            if end is not None and self.loop.time() >= end:
                return False
            await asyncio.sleep(0.02)
        return True

    def close(self) -> None:
        self.closed = True
        self.channels.remove_listener(self)
        with self.sync_cv:
            self.sync_cv.notify_all()


def status_lines(rows: List[Dict[str, Any]]) -> str:
    """The service's hub status (op ``hub``) as a table: channel, access, status, provided by."""
    table = [("name", "access", "status", "provided by")] + [
        (str(r.get("channel")), str(r.get("access")), str(r.get("status")), str(r.get("by") or "nobody (unbound)"))
        for r in rows]
    widths = [max(len(t[i]) for t in table) for i in range(4)]
    lines = ["  ".join(v.ljust(w) for v, w in zip(t, widths)).rstrip() for t in table]
    lines.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(lines)
