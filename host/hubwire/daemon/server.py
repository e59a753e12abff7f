"""The service's side of the client protocol (docs/SERVICE.md): one task per connected client,
requests answered in any order, streams and events pushed as they come.

A client's streams and event subscriptions outlive the board's outages: when a board is unplugged
and comes back (a new session, perhaps on another port) they carry on with the new device, the
next sample marked with a gap, as a direct connection rides through a link loss.
"""
from __future__ import annotations

import asyncio
import logging
import os
import stat
from typing import Any, Awaitable, Callable, Dict, Optional

from .. import __version__
from ..errors import HubwireError, InvalidValue, LinkLost, StreamEnded
from ..wire.messages import NakCode
from . import durable_ops, hub_ops, mission_ops
from .fleet import Fleet
from ..client.protocol import MAX_LINE, PROTOCOL, Busy, Usage, board_json, encode, error_json, jsonable
from ..client.sockdir import ensure_dir

__all__ = ["Server", "MAX_SUBSCRIPTIONS", "MAX_PENDING", "MAX_BACKLOG"]

log = logging.getLogger("hubwire.service")

# Per client (docs/SERVICE.md "Limits"): one client cannot make the service hold more than this.
#: streams, event and board subscriptions at once; one more is answered ``Busy``
MAX_SUBSCRIPTIONS = 64
#: requests in flight; the service reads no further request of this client until one is answered
#: (the client's writes wait), so one client's burst cannot queue ahead of everyone else's
MAX_PENDING = 32
#: bytes of answers and pushed samples waiting for a client that does not read: beyond it the
#: client is sent ``{"error": "Overflow", ...}`` and disconnected
MAX_BACKLOG = 1 << 20
#: how long a client disconnected for an overflow has to read what was sent before it is cut off
OVERFLOW_GRACE_S = 10.0


class Server:
    """Listens on ``path`` (a Unix socket, mode 0660, in a directory only this user may write to:
    :mod:`hubwire.client.sockdir`) and serves ``fleet`` to every client."""

    def __init__(self, fleet: Fleet, path: str) -> None:
        self.fleet = fleet
        self.path = path
        self._server: Optional[asyncio.AbstractServer] = None
        self._clients: "set[_Client]" = set()

    async def start(self) -> None:
        ensure_dir(self.path)  # ours, 0700: never a directory another user made first
        if os.path.exists(self.path) and stat.S_ISSOCK(os.stat(self.path).st_mode):
            os.unlink(self.path)  # left by a service that did not stop cleanly
        self._server = await asyncio.start_unix_server(self._client, self.path, limit=MAX_LINE)
        os.chmod(self.path, 0o660)

    async def close(self) -> None:
        if self._server is not None:
            self._server.close()
        for c in list(self._clients):
            c.close()
        try:
            os.unlink(self.path)
        except OSError:
            pass

    async def _client(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        c = _Client(self.fleet, writer)
        self._clients.add(c)
        try:
            await c.run(reader)
        finally:
            self._clients.discard(c)
            c.close()


class _Client:
    def __init__(self, fleet: Fleet, writer: asyncio.StreamWriter) -> None:
        self.fleet = fleet
        self.writer = writer
        self.subs: Dict[Any, "asyncio.Task[None]"] = {}
        self.tasks: "set[asyncio.Task[None]]" = set()
        self._slot = asyncio.Event()  # set when a request in flight finished

    def send(self, obj: Dict[str, Any]) -> None:
        if self.writer.is_closing():
            return
        waiting = self.writer.transport.get_write_buffer_size()
        if waiting > MAX_BACKLOG:
            # a client that stopped reading would make the service hold every sample for it
            log.warning("hubwire serve: a client stopped reading (%d bytes waiting); disconnecting it", waiting)
            self.writer.write(encode({"ok": False, "error": "Overflow", "message": (
                f"more than {MAX_BACKLOG} bytes waited for this client to read them; disconnected")}))
            self.close()
            asyncio.get_running_loop().call_later(OVERFLOW_GRACE_S, self.writer.transport.abort)
            return
        self.writer.write(encode(obj))

    def close(self) -> None:
        for t in list(self.subs.values()) + list(self.tasks):
            t.cancel()
        self.writer.close()

    async def run(self, reader: asyncio.StreamReader) -> None:
        import json

        self.send({"service": "hubwire", "protocol": PROTOCOL, "version": __version__})
        while True:
            try:
                line = await reader.readline()
            except (ValueError, ConnectionError):  # a line over the limit, or the client went away
                return
            if not line:
                return
            try:
                msg = json.loads(line)
                if not isinstance(msg, dict):
                    raise ValueError("a request is a JSON object")
            except (ValueError, RecursionError) as e:
                self.send({"ok": False, "error": "Usage", "message": f"not a request: {e}"})
                continue
            while len(self.tasks) >= MAX_PENDING:
                self._slot.clear()
                await self._slot.wait()
            t = asyncio.get_running_loop().create_task(self._answer(msg))
            self.tasks.add(t)
            t.add_done_callback(self._done)

    def _done(self, t: "asyncio.Task[None]") -> None:
        self.tasks.discard(t)
        self._slot.set()

    async def _answer(self, msg: Dict[str, Any]) -> None:
        rid = msg.get("id")
        op = msg.get("op")
        fn: Optional[Callable[[Dict[str, Any]], Awaitable[Dict[str, Any]]]] = getattr(self, f"op_{op}", None)
        try:
            if fn is None or not isinstance(op, str):
                raise HubwireError(f"unknown op {op!r}; ops: {', '.join(sorted(_OPS))}")
            out = await fn(msg)
            self.send({"id": rid, "ok": True, **out})
        except asyncio.CancelledError:
            raise
        except (HubwireError, KeyError) as e:  # documented types (an unknown channel is a KeyError)
            self.send({"id": rid, **error_json(e)})
        except (ValueError, TypeError, RecursionError) as e:
            # what a request's fields did not allow for (the documented errors have classes)
            self.send({"id": rid, **error_json(Usage(f"{type(e).__name__}: {e}"))})
        except Exception as e:  # noqa: BLE001 - every error goes back to the client that asked
            self.send({"id": rid, **error_json(e)})
        try:
            await self.writer.drain()
        except ConnectionError:
            pass

    # ----------------------------------------------------------------------------------- ops

    def _device(self, msg: Dict[str, Any]) -> Any:
        b = self.fleet.resolve(str(msg.get("board", "")))
        if b.device is None:
            raise LinkLost(f"board {b.key} is unplugged (last seen on {b.last_port})")
        return b.device

    async def op_list(self, msg: Dict[str, Any]) -> Dict[str, Any]:
        return {"boards": [board_json(b) for b in self.fleet.boards()]}

    async def op_describe(self, msg: Dict[str, Any]) -> Dict[str, Any]:
        b = self.fleet.resolve(str(msg.get("board", "")))
        return {"board": board_json(b), "descriptor": self.fleet.descriptor(b.key).raw.decode("utf-8")}

    async def op_read(self, msg: Dict[str, Any]) -> Dict[str, Any]:
        dev = self._device(msg)
        ch = dev.channel(str(msg.get("channel")))
        v = await dev.read(ch.name, timeout=_timeout(msg))
        return {"value": jsonable(v), "raw": ch.codec.encode(v).hex()}

    def _arg(self, dev: Any, msg: Dict[str, Any], key: str) -> Any:
        if "raw" in msg:  # exactly the bytes a client encoded (and checked again when written)
            try:
                raw = bytes.fromhex(str(msg["raw"]))
            except ValueError:
                raise InvalidValue(f"raw must be hex digits, not {str(msg['raw'])[:40]!r}", NakCode.BAD_VALUE) from None
            return dev.channel(str(msg.get("channel"))).codec.decode(raw)
        return msg.get(key)

    async def op_write(self, msg: Dict[str, Any]) -> Dict[str, Any]:
        dev = self._device(msg)
        await dev.write(str(msg.get("channel")), self._arg(dev, msg, "value"), timeout=_timeout(msg))
        return {}

    async def op_call(self, msg: Dict[str, Any]) -> Dict[str, Any]:
        dev = self._device(msg)
        ch = dev.channel(str(msg.get("channel")))
        arg = None if ch.codec.kind == "void" else self._arg(dev, msg, "arg")
        r = await dev.call(ch.name, arg, timeout=_timeout(msg))
        raw = ch.returns.encode(r).hex() if r is not None and ch.returns is not None else None
        return {"value": jsonable(r), "raw": raw}

    async def op_health(self, msg: Dict[str, Any]) -> Dict[str, Any]:
        import dataclasses

        b = self.fleet.resolve(str(msg.get("board", "")))
        h = dataclasses.asdict(b.device.health()) if b.device is not None else None
        return {"board": board_json(b), "health": h}

    async def op_unsubscribe(self, msg: Dict[str, Any]) -> Dict[str, Any]:
        t = self.subs.pop(msg.get("sub"), None)
        if t is not None:
            t.cancel()
        return {}

    def _check_sub(self, msg: Dict[str, Any]) -> None:
        """Before a subscription is made: a ``sub`` id of its own, and room for it."""
        sub = msg.get("sub")
        if not isinstance(sub, (str, int)) or isinstance(sub, bool) or sub in self.subs:
            raise Usage("a subscription needs a \"sub\" id of its own (a string or an integer)")
        if len(self.subs) >= MAX_SUBSCRIPTIONS:
            raise Busy(f"this client has {MAX_SUBSCRIPTIONS} subscriptions, the most one client may hold; "
                       "unsubscribe one first")

    def _subscribe(self, msg: Dict[str, Any], coro: Awaitable[None]) -> None:
        sub = msg.get("sub")
        if not isinstance(sub, (str, int)) or sub in self.subs or len(self.subs) >= MAX_SUBSCRIPTIONS:
            getattr(coro, "close", lambda: None)()  # checked before; still, never one too many
            raise Busy("no room for this subscription")
        t: "asyncio.Task[None]" = asyncio.ensure_future(coro)
        self.subs[sub] = t

        def done(_t: "asyncio.Task[None]") -> None:
            if self.subs.get(sub) is t:
                del self.subs[sub]
        t.add_done_callback(done)

    async def op_boards(self, msg: Dict[str, Any]) -> Dict[str, Any]:
        self._check_sub(msg)
        sub = msg.get("sub")
        only = msg.get("board")
        key = self.fleet.resolve(str(only)).key if only is not None else None

        async def push() -> None:
            async for b in self.fleet.changes():
                if key is None or b.key == key:
                    self.send({"sub": sub, "board": board_json(b)})
        self._subscribe(msg, push())
        return {"boards": [board_json(b) for b in self.fleet.boards() if key is None or b.key == key]}

    async def op_stream(self, msg: Dict[str, Any]) -> Dict[str, Any]:
        self._check_sub(msg)
        dev = self._device(msg)
        key = self.fleet.resolve(str(msg.get("board"))).key
        interval = msg.get("interval_ms", 100)
        if not isinstance(interval, (int, float)) or isinstance(interval, bool) or not 0 < interval <= 3_600_000:
            raise Usage(f"interval_ms is a number of milliseconds, not {interval!r}")
        interval = int(interval)
        st = dev.stream(str(msg.get("channel")), interval_ms=interval, meta=True)
        await st.open()  # errors (not streamable, refused) go back as the answer
        try:
            self._subscribe(msg, self._samples(msg.get("sub"), key, st, interval))
        except HubwireError:  # another request took the last place meanwhile
            await st.aclose()
            raise
        return {"granted_ms": st.granted_ms}

    async def _samples(self, sub: Any, key: str, st: Any, interval: int) -> None:
        gap = 0
        try:
            while True:
                ch = st.channel
                try:
                    async for s in st:
                        self.send({"sub": sub, "sample": {
                            "value": jsonable(s.value), "raw": ch.codec.encode(s.value).hex(), "seq": s.seq,
                            "lost": s.lost, "gap": s.gap + gap, "since_ms": s.since_ms}})
                        gap = 0
                except LinkLost:
                    pass  # the board was unplugged: carry on with its next session
                await st.aclose()
                gap += 1
                dev = await self.fleet.wait_device(key)
                st = dev.stream(ch.name, interval_ms=interval, meta=True)
        except StreamEnded as e:
            self.send({"sub": sub, "end": "StreamEnded", "message": str(e)})
        finally:
            await st.aclose()

    async def op_notify(self, msg: Dict[str, Any]) -> Dict[str, Any]:
        """A hub event for the board (PROTOCOL.md 10.3): answered once queued (and stored)."""
        return durable_ops.notify(self.fleet, msg)

    # ----------------------------------------------------------- hub channels (hub_ops.py)

    async def op_provide(self, msg: Dict[str, Any]) -> Dict[str, Any]:
        return hub_ops.provide(self, msg)

    async def op_hub_answer(self, msg: Dict[str, Any]) -> Dict[str, Any]:
        return hub_ops.hub_answer(self, msg)

    async def op_hub(self, msg: Dict[str, Any]) -> Dict[str, Any]:
        return hub_ops.hub_status(self, msg)

    async def op_events(self, msg: Dict[str, Any]) -> Dict[str, Any]:
        self._check_sub(msg)
        if self.fleet.store is not None:  # events with ids, and a resume point (``after``)
            return durable_ops.events(self, msg)
        dev = self._device(msg)
        key = self.fleet.resolve(str(msg.get("board"))).key
        names = msg.get("names") or []
        if not isinstance(names, list) or not all(isinstance(n, str) for n in names):
            raise Usage("names is a list of event channel names")
        evs = dev.events(*names)  # listening from now on, before the answer goes out
        self._subscribe(msg, self._events(msg.get("sub"), key, dev, evs, names))
        return {}

    async def _events(self, sub: Any, key: str, dev: Any, evs: Any, names: Any) -> None:
        try:
            while True:
                async for ev in evs:
                    raw = dev.channel(ev.name).codec.encode(ev.value).hex()
                    self.send({"sub": sub, "event": {"name": ev.name, "value": jsonable(ev.value), "raw": raw,
                                                     "seq": ev.seq}})
                evs.close()  # the session closed: the board was unplugged
                dev = await self.fleet.wait_device(key)
                evs = dev.events(*names)
        finally:
            evs.close()

    # ------------------------------------------------------------- missions (mission_ops.py)

    async def op_start(self, msg: Dict[str, Any]) -> Dict[str, Any]:
        return await mission_ops.start(self, msg)

    async def op_mission(self, msg: Dict[str, Any]) -> Dict[str, Any]:
        return await mission_ops.follow(self, msg)

    async def op_cancel(self, msg: Dict[str, Any]) -> Dict[str, Any]:
        return await mission_ops.cancel(self, msg)

    async def op_runs(self, msg: Dict[str, Any]) -> Dict[str, Any]:
        return await mission_ops.runs(self, msg)


_OPS = [n[3:] for n in dir(_Client) if n.startswith("op_")]


def _timeout(msg: Dict[str, Any]) -> Optional[float]:
    t = msg.get("timeout")
    return float(t) if isinstance(t, (int, float)) else None
