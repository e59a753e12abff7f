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
from ..cli_support import jsonable
from ..errors import HubwireError, LinkLost, StreamEnded
from . import durable_ops
from .fleet import Fleet
from .protocol import MAX_LINE, PROTOCOL, board_json, encode, error_json
from .sockdir import ensure_dir

__all__ = ["Server"]

log = logging.getLogger("hubwire.service")

#: bytes waiting for a client before it is taken for gone and disconnected
MAX_BACKLOG = 4 << 20


class Server:
    """Listens on ``path`` (a Unix socket, mode 0660, in a directory only this user may write to:
    :mod:`hubwire.service.sockdir`) and serves ``fleet`` to every client."""

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

    def send(self, obj: Dict[str, Any]) -> None:
        if self.writer.is_closing():
            return
        if self.writer.transport.get_write_buffer_size() > MAX_BACKLOG:
            # a client that stopped reading would make the service hold every sample for it
            log.warning("hubwire serve: a client stopped reading (%d bytes waiting); disconnecting it",
                        self.writer.transport.get_write_buffer_size())
            self.close()
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
            except ValueError as e:
                self.send({"ok": False, "error": "Usage", "message": f"not a request: {e}"})
                continue
            t = asyncio.get_running_loop().create_task(self._answer(msg))
            self.tasks.add(t)
            t.add_done_callback(self.tasks.discard)

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
            return dev.channel(str(msg.get("channel"))).codec.decode(bytes.fromhex(str(msg["raw"])))
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

    def _subscribe(self, msg: Dict[str, Any], coro: Awaitable[None]) -> None:
        sub = msg.get("sub")
        if sub is None or sub in self.subs:
            raise HubwireError("a subscription needs a \"sub\" id of its own")
        t: "asyncio.Task[None]" = asyncio.ensure_future(coro)
        self.subs[sub] = t

        def done(_t: "asyncio.Task[None]") -> None:
            if self.subs.get(sub) is t:
                del self.subs[sub]
        t.add_done_callback(done)

    async def op_boards(self, msg: Dict[str, Any]) -> Dict[str, Any]:
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
        dev = self._device(msg)
        key = self.fleet.resolve(str(msg.get("board"))).key
        interval = int(msg.get("interval_ms", 100))
        st = dev.stream(str(msg.get("channel")), interval_ms=interval, meta=True)
        await st.open()  # errors (not streamable, refused) go back as the answer
        self._subscribe(msg, self._samples(msg.get("sub"), key, st, interval))
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

    async def op_events(self, msg: Dict[str, Any]) -> Dict[str, Any]:
        if self.fleet.store is not None:  # events with ids, and a resume point (``after``)
            return durable_ops.events(self, msg)
        dev = self._device(msg)
        key = self.fleet.resolve(str(msg.get("board"))).key
        names = [str(n) for n in msg.get("names") or []]
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


_OPS = [n[3:] for n in dir(_Client) if n.startswith("op_")]


def _timeout(msg: Dict[str, Any]) -> Optional[float]:
    t = msg.get("timeout")
    return float(t) if isinstance(t, (int, float)) else None
