"""The client ops for hub channels (docs/SERVICE.md "Hub channels"): ``provide`` (a client holds
hub channels of a board and answers the board's requests on them), ``hub_answer`` (its answer to
one request) and ``hub`` (who provides what, and the binding).

A client's requests to answer come on its ``provide`` subscription::

    {"sub":5,"hub":{"req":12,"channel":"setpoint","do":"read"}}
    {"sub":5,"hub":{"req":13,"channel":"report","do":"write","raw":"e400"}}

and it answers each with ``{"op":"hub_answer","sub":5,"req":12,"raw":"0000b041"}`` (or
``"error":"REJECTED"``). Unsubscribing, or closing the connection, lets go of the channels: the
board is sent a bind report without them (its unbound path).
"""
from __future__ import annotations

import asyncio
import socket
import struct
from typing import Any, Dict, List, Optional

from ..errors import HubwireError
from ..text import clip
from .hub_providers import HubProviders, Provider
from ..client.protocol import Usage, board_json

__all__ = ["ClientProvider", "provide", "hub_answer", "hub_status", "peer_label", "MAX_HUB_REQUESTS"]

#: requests of the board waiting for one client's answers; beyond it the board is told REJECTED
MAX_HUB_REQUESTS = 32
#: a client's name for itself, as shown in errors and in `hubwire info` (longer is clipped)
MAX_LABEL = 60


def peer_label(writer: Any, name: Any) -> str:
    """``client 'NAME' (pid N)``: the pid from the socket's peer credentials (Linux), the name the
    client gave (untrusted text: clipped, shown quoted)."""
    pid: Optional[int] = None
    sock = writer.get_extra_info("socket")
    try:
        if sock is not None and hasattr(socket, "SO_PEERCRED"):
            creds = sock.getsockopt(socket.SOL_SOCKET, socket.SO_PEERCRED, struct.calcsize("3i"))
            pid = struct.unpack("3i", creds)[0]
    except OSError:
        pid = None
    shown = f" {clip(name, MAX_LABEL)}" if isinstance(name, str) and name else ""  # quoted, escaped
    return f"client{shown}" + (f" (pid {pid})" if pid else "")


class ClientProvider(Provider):
    """A client of the socket that provides hub channels: the board's requests go to it as pushed
    messages on its subscription ``sub``, its ``hub_answer`` requests settle them."""

    kind = "client"

    def __init__(self, client: Any, sub: Any, label: str) -> None:
        super().__init__(label)
        self.client = client
        self.sub = sub
        self._next = 0
        self._pending: Dict[int, "asyncio.Future[Dict[str, Any]]"] = {}

    async def _ask(self, key: str, name: str, do: str, raw: Optional[bytes] = None) -> Dict[str, Any]:
        if len(self._pending) >= MAX_HUB_REQUESTS:
            raise HubwireError(f"{MAX_HUB_REQUESTS} requests already wait for {self.label}")
        self._next += 1
        req = self._next
        fut: "asyncio.Future[Dict[str, Any]]" = asyncio.get_running_loop().create_future()
        self._pending[req] = fut
        msg: Dict[str, Any] = {"req": req, "board": key, "channel": name, "do": do}
        if raw is not None:
            msg["raw"] = raw.hex()
        try:
            self.client.send({"sub": self.sub, "hub": msg})
            answer = await fut
        finally:
            self._pending.pop(req, None)
        if answer.get("error") is not None:
            raise HubwireError(f"{self.label} refused: {clip(str(answer.get('error')), 80)}")
        return answer

    def _exp(self, key: str, name: str) -> Any:
        return next(c for c in self.client.fleet.descriptor(key).hub if c.name == name)

    async def read(self, key: str, name: str) -> Any:
        a = await self._ask(key, name, "read")
        return self._exp(key, name).codec.decode(bytes.fromhex(str(a.get("raw", ""))))

    async def write(self, key: str, name: str, value: Any) -> Any:
        try:
            await self._ask(key, name, "write", self._exp(key, name).codec.encode(value))
        except HubwireError:
            return False
        return True

    async def call(self, key: str, name: str, arg: Any) -> Any:
        exp = self._exp(key, name)
        a = await self._ask(key, name, "call", b"" if exp.codec.kind == "void" else exp.codec.encode(arg))
        raw = a.get("raw")
        if exp.returns is None or exp.returns.kind == "void":
            return None
        return exp.returns.decode(bytes.fromhex(str(raw or "")))

    def answered(self, req: Any, msg: Dict[str, Any]) -> bool:
        fut = self._pending.get(req) if isinstance(req, int) else None
        if fut is None or fut.done():
            return False
        fut.set_result(msg)
        return True

    def close(self) -> None:
        for fut in self._pending.values():
            if not fut.done():
                fut.set_result({"error": "the client went away"})


def _providers(client: Any) -> Dict[Any, ClientProvider]:
    return client.__dict__.setdefault("hub_providers", {})  # type: ignore[no-any-return]


def _entries(msg: Dict[str, Any]) -> List[Dict[str, Any]]:
    chs = msg.get("channels")
    if not isinstance(chs, list) or len(chs) > 255 or not all(isinstance(c, dict) and isinstance(c.get("n"), str)
                                                              for c in chs):
        raise Usage("channels is a list of at most 255 hub channel declarations ({\"n\": name, \"a\": ..., \"t\": ...})")
    return chs


def provide(client: Any, msg: Dict[str, Any]) -> Dict[str, Any]:
    """Hold the hub channels ``channels`` of ``board`` for this client (subscription ``sub``); the
    same ``sub`` again replaces the set it holds. Answer: ``hub`` (the board's bind status)."""
    registry: HubProviders = client.fleet.hub
    key = client.fleet.resolve(str(msg.get("board", ""))).key
    entries = _entries(msg)
    sub = msg.get("sub")
    mine = _providers(client)
    p = mine.get(sub)
    if p is not None:
        registry.claim(key, p, entries)
        registry.release(p, key, keep=tuple(str(e["n"]) for e in entries))
        return {"hub": registry.status(key)}
    client._check_sub(msg)
    p = ClientProvider(client, sub, peer_label(client.writer, msg.get("name")))
    registry.claim(key, p, entries)
    mine[sub] = p
    remove_watch = registry.watch(lambda k: k == key and client.send({"sub": sub, "binding": registry.status(key)}))

    def gone(_t: Any) -> None:
        remove_watch()
        mine.pop(sub, None)
        p.close()
        registry.release(p)
    try:
        client._subscribe(msg, asyncio.Event().wait())  # until unsubscribe or the client goes
    except BaseException:
        gone(None)
        raise
    client.subs[sub].add_done_callback(gone)
    return {"hub": registry.status(key)}


def hub_answer(client: Any, msg: Dict[str, Any]) -> Dict[str, Any]:
    """The client's answer to request ``req`` of its subscription ``sub``: ``raw`` (the value or the
    result, hex), nothing (a write or a call without result done), or ``error`` (REJECTED)."""
    p = _providers(client).get(msg.get("sub"))
    if p is None:
        raise Usage("no provide subscription with this sub")
    if "raw" in msg:
        bytes.fromhex(str(msg["raw"]))  # ValueError: Usage
    p.answered(msg.get("req"), msg)  # a late answer (the board was told already) is dropped
    return {}


def hub_status(client: Any, msg: Dict[str, Any]) -> Dict[str, Any]:
    """Who provides each hub channel of ``board``, and its binding."""
    b = client.fleet.resolve(str(msg.get("board", "")))
    return {"board": board_json(b), "hub": client.fleet.hub.status(b.key)}
