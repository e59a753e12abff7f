"""Ties a board's session to the service's :class:`~.store.Store` (docs/SERVICE.md, "What survives a
restart"): its events are stored before they are acknowledged, its hub events are kept from
``notify`` until the device answers them, and the hub session on its port (nonce, the seqs of its
events) is kept so that the first session after a restart of the service resumes it
(session/resume.py): the device's duplicate memory makes hub events exactly once across it.
"""
from __future__ import annotations

import logging
from typing import Any, Optional

from ..session.events import EventSink
from ..session.link import new_nonce
from ..session.records import ReceivedEvent
from ..session.resume import HubSession
from ..text import clip
from .store import Store

__all__ = ["attach", "offer_hub_events", "hub_session"]

log = logging.getLogger("hubwire.service")


class _HubKeeper:
    """The persistence hook of a session's hub event queue (``HubSide.keeper``)."""

    def __init__(self, store: Store, key: str, port: Optional[str]) -> None:
        self.store, self.key, self.port = store, key, port

    def add(self, name: str, payload: bytes) -> int:
        return self.store.hub_add(self.key, name, payload)

    def sent(self, token: Any, seq: int, id: int) -> None:
        if self.port is not None:  # (raises when it cannot: the event then waits)
            self.store.hub_sent(self.port, int(token), seq, id)

    def done(self, token: Any, acked: Optional[int]) -> None:
        self.store.hub_done(int(token), self.port, acked)

    def nonce(self, nonce: int) -> None:
        if self.port is None:
            return
        try:
            self.store.hub_session_new(self.port, nonce, fresh=False)
        except Exception as e:  # noqa: BLE001 - the port opens all the same (at least once after a restart)
            log.error("hubwire serve: hub nonce for %s not stored: %s", self.key, clip(str(e), 200))


class _EventLog(EventSink):
    """Stores each event of one session as it arrives (before it is acknowledged to the device)."""

    limit = 1 << 30  # nothing waits here: each event goes to the store at once

    def __init__(self, store: Store, key: str, dev: Any) -> None:
        self.store, self.key, self.dev = store, key, dev

    def put(self, ev: ReceivedEvent) -> None:
        core = self.dev.core
        hello = core.link.device_hello
        try:
            ch = core.descriptor.by_id(ev.channel_id)
            raw = ch.codec.encode(ev.value)
            self.store.event_add(self.key, ev.name, raw, ev.seq, None if hello is None else hello.nonce)
        except Exception as e:  # noqa: BLE001 - a full disk must not stop the link
            log.error("hubwire serve: event %s of %s not stored: %s", clip(ev.name), self.key, clip(str(e), 200))

    def close(self) -> None:
        pass


def offer_hub_events(dev: Any) -> None:
    """Declare, on the service's session, every hub event the device takes (access ``e`` in its
    ``hub`` list) with the device's own type, so clients can ``notify`` it through the service."""
    channels = dev.core.hub.channels
    for exp in dev.descriptor.hub:
        if "e" in exp.access and exp.name not in channels:
            try:
                channels.event(exp.name, type=exp.codec.type_obj)
            except Exception as e:  # noqa: BLE001 - a declaration the hub cannot make is skipped
                log.warning("hubwire serve: hub event %s of %s not offered: %s", clip(exp.name), dev.name,
                            clip(str(e), 200))


def hub_session(store: Optional[Store], port: str, resume: bool) -> Optional[HubSession]:
    """The hub session to open ``port`` with: with ``resume`` the one kept for it (the service's
    first session on the port since it started), else a new nonce; kept before the first hello."""
    if store is None:
        return None
    row = store.hub_session(port) if resume else None
    if row is not None:
        return HubSession(row.nonce, True, row.acked, row.head)
    nonce = new_nonce()
    store.hub_session_new(port, nonce)
    return HubSession(nonce)


def attach(store: Optional[Store], key: str, dev: Any, port: Optional[str] = None) -> None:
    """A board's new session (on ``port``, opened with :func:`hub_session`): offer its hub events,
    send the stored ones first, store its events."""
    offer_hub_events(dev)
    if store is None:
        return
    side = dev.core.hub
    side.keeper = _HubKeeper(store, key, port)
    if port is not None:  # the link may have drawn a new nonce while connecting (a port opened again)
        store.hub_session_new(port, dev.core.link.nonce, fresh=False)
    side.restore(store.hub_pending(key))
    dev.core.events.add_sink(_EventLog(store, key, dev))
