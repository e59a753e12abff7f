"""The client ops that use the service's store (docs/SERVICE.md): ``notify`` (a hub event for a
board, kept until the device answers it) and ``events`` with ids and a resume point (``after``).
"""
from __future__ import annotations

import asyncio
from typing import Any, Dict, List

from ..client.protocol import jsonable
from ..errors import HubwireError, LinkLost
from .store import StoredEvent

__all__ = ["notify", "events", "event_json"]


class _UnknownChannel(HubwireError, KeyError):
    kind = "UnknownChannel"

    def __str__(self) -> str:
        return str(self.args[0]) if self.args else ""


def notify(fleet: Any, msg: Dict[str, Any]) -> Dict[str, Any]:
    """Queue hub event ``channel`` for the board (``value``, or ``raw``: its payload in hex); with a
    store, also while the board is unplugged (its next session sends it)."""
    b = fleet.resolve(str(msg.get("board", "")))
    name = str(msg.get("channel"))
    desc = fleet.descriptor(b.key)
    exp = next((c for c in desc.hub if c.name == name and "e" in c.access), None)
    if exp is None:
        takes = sorted(c.name for c in desc.hub if "e" in c.access)
        raise _UnknownChannel(f"{desc.name} takes no hub event {name!r}; it takes: {', '.join(takes) or 'none'}")
    value = exp.codec.decode(bytes.fromhex(str(msg["raw"]))) if "raw" in msg else msg.get("value")
    if b.device is not None:
        b.device.notify(name, value)  # checked, queued and (with a store) on disk when this returns
    elif fleet.store is not None:
        fleet.store.hub_add(b.key, name, exp.codec.encode(exp.check(value)))
    else:
        raise LinkLost(f"board {b.key} is unplugged (last seen on {b.last_port})")
    return {}


def event_json(desc: Any, ev: StoredEvent) -> Dict[str, Any]:
    """An event as the client protocol pushes it (``value`` None when today's descriptor cannot
    decode what an earlier firmware sent)."""
    value = None
    ch = desc.by_name(ev.name) if desc is not None else None
    if ch is not None:
        try:
            value = jsonable(ch.codec.decode(ev.raw))
        except Exception:  # noqa: BLE001 - the bytes still go out as they came
            value = None
    return {"name": ev.name, "value": value, "raw": ev.raw.hex(), "seq": ev.seq, "id": ev.id}


def events(client: Any, msg: Dict[str, Any]) -> Dict[str, Any]:
    """Subscribe ``client`` to a board's events: every event stored from now on, and with
    ``after`` first the stored ones after that id. Answer: ``last`` (the newest id when it
    subscribed), with ``after`` also ``missed`` (events after it no longer kept) and ``reset``
    (``after`` is beyond every id this store handed out: everything kept is sent)."""
    fleet, store = client.fleet, client.fleet.store
    key = fleet.resolve(str(msg.get("board", ""))).key
    names: List[str] = [str(n) for n in msg.get("names") or []]
    desc = fleet.descriptor(key)
    for n in names:
        ch = desc.by_name(n)
        if ch is None or not ch.is_event:
            raise _UnknownChannel(f"{desc.name} has no event {n!r}")
    after = msg.get("after")
    if after is not None and (isinstance(after, bool) or not isinstance(after, int) or after < 0):
        raise HubwireError("after: the id of the last event seen (an integer, 0 for every event kept)")
    sub = msg.get("sub")

    def push(ev: StoredEvent) -> None:
        if not names or ev.name in names:
            client.send({"sub": sub, "event": event_json(fleet.descriptor(key), ev)})

    client._subscribe(msg, asyncio.Event().wait())  # until unsubscribe or the client goes
    remove = store.listen(key, push)  # nothing is stored between this and the replay below
    client.subs[sub].add_done_callback(lambda _t: remove())
    out: Dict[str, Any] = {"last": store.last_id(key)}
    if after is not None:
        if after > out["last"]:
            after, out["reset"] = 0, True
        rows, out["missed"], out["last"] = store.events_after(key, after, names)
        for ev in rows:
            push(ev)
    return out
