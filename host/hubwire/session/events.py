"""Events (PROTOCOL.md §4.5): acknowledged, deduplicated by seq, decoded and delivered to callbacks
and event queues; events that arrive before anyone listens are kept for the first listener.

Flow control: when the application's callbacks lag behind (``DISPATCH_LIMIT`` waiting), new events
are not acknowledged, so the device keeps them and retries later instead of the hub piling them up.
Each queue is bounded (``EVENT_QUEUE_LIMIT``): beyond it the oldest event is dropped, counted and
a warning logged (see :class:`EventSink`).
"""
from __future__ import annotations

import logging
import queue
from collections import deque
from typing import Any, Callable, Deque, Dict, FrozenSet, List, Optional

from ..errors import InvalidValue
from ..text import clip
from ..wire import messages as m
from ..wire.frame import Frame
from .records import ReceivedEvent, Stats

__all__ = ["Events", "EventSink", "QueueSink", "EVENT_QUEUE_LIMIT", "DISPATCH_LIMIT", "BACKLOG_LIMIT"]

log = logging.getLogger("hubwire")

#: events waiting in one event queue; beyond it the oldest is dropped (and counted)
EVENT_QUEUE_LIMIT = 4096
#: callbacks waiting on the dispatcher; beyond it new events are not acked (the device retries them)
DISPATCH_LIMIT = 1024
#: events kept while nobody listens
BACKLOG_LIMIT = 1024


class EventSink:
    """Where a listener's events go: ``put`` (never blocks) and ``close`` (no more events).

    A full queue drops its oldest event for each new one: counted in ``Stats.events_dropped``, and
    a warning logged when it starts dropping (once, and once more each time it drops again after
    its reader caught up to half the limit)."""

    names: Optional[FrozenSet[str]] = None
    limit = EVENT_QUEUE_LIMIT
    _dropping = False

    def put(self, ev: ReceivedEvent) -> None:
        raise NotImplementedError

    def note_size(self, size: int) -> None:
        """Before adding to a queue of ``size`` items: recovered once it drained to half the limit."""
        if self._dropping and size <= self.limit // 2:
            self._dropping = False

    def note_dropped(self, stats: Stats) -> None:
        """The oldest event was dropped to make room."""
        stats.events_dropped += 1
        if not self._dropping:
            self._dropping = True
            log.warning("hubwire: an event queue is full (%d events): its reader falls behind, so the oldest "
                        "events are dropped from now on (counted in stats.events_dropped)", self.limit)

    def close(self) -> None:
        raise NotImplementedError


class QueueSink(EventSink):
    """A thread-safe bounded queue for the synchronous API; ``None`` in it means closed."""

    def __init__(self, stats: Stats, names: Optional[FrozenSet[str]] = None, limit: int = EVENT_QUEUE_LIMIT) -> None:
        self.q: "queue.Queue[Optional[ReceivedEvent]]" = queue.Queue(limit)
        self.stats = stats
        self.names = names
        self.limit = limit

    def _put(self, item: Optional[ReceivedEvent]) -> None:
        self.note_size(self.q.qsize())
        while True:
            try:
                self.q.put_nowait(item)
                return
            except queue.Full:
                try:
                    self.q.get_nowait()
                    self.note_dropped(self.stats)
                except queue.Empty:
                    pass

    def put(self, ev: ReceivedEvent) -> None:
        self._put(ev)

    def close(self) -> None:
        self._put(None)


class Events:
    """Event delivery of one session. ``core`` provides ``link``, ``stats``, ``dispatch(fn, *args)``,
    ``dispatch_pending()`` and ``decodable()`` (the descriptor, once it matches the device session)."""

    def __init__(self, core: Any) -> None:
        self.core = core
        self.last_seq: Optional[int] = None
        self.callbacks: Dict[Optional[str], List[Callable[[Any], Any]]] = {}
        self.sinks: List[EventSink] = []
        self.backlog: Deque[ReceivedEvent] = deque(maxlen=BACKLOG_LIMIT)

    def on_event(self, f: Frame, now: float) -> None:
        core = self.core
        desc = core.decodable()
        if desc is None:
            return  # not acked: the device retries, we deliver it once we can decode it
        if core.dispatch_pending() >= DISPATCH_LIMIT:
            # callbacks lag behind: not acked, so the device keeps it and retries (flow control)
            core.stats.events_deferred += 1
            return
        try:
            self._take(f, now, desc)
        finally:
            # acknowledged once handed on: a sink that stores events (hubwire serve) has it on disk
            core.link.send_frame(m.ACK, f.seq, f.id)

    def _take(self, f: Frame, now: float, desc: Any) -> None:
        core = self.core
        if self.last_seq == f.seq:
            core.stats.duplicate_events += 1
            return
        self.last_seq = f.seq
        core.stats.events += 1
        ch = desc.by_id(f.id)
        if ch is None or not ch.is_event:
            log.warning("hubwire: event for unknown channel id %d", f.id)
            return
        try:
            value = ch.codec.decode(f.payload)
        except InvalidValue as e:
            log.warning("hubwire: malformed event %s: %s", clip(ch.name), clip(str(e), 160))
            return
        self.deliver(ReceivedEvent(ch.name, value, f.seq, now, f.id))

    def deliver(self, ev: ReceivedEvent) -> None:
        named = self.callbacks.get(ev.name, ())
        every = self.callbacks.get(None, ())
        dispatch = self.core.dispatch
        for cb in named:
            dispatch(cb, ev.value)
        for cb in every:
            dispatch(cb, ev)
        for sink in self.sinks:
            if sink.names is None or ev.name in sink.names:
                sink.put(ev)
        if not named and not every and not self.sinks:
            self.backlog.append(ev)

    def add_callback(self, name: Optional[str], cb: Callable[[Any], Any]) -> None:
        """Call ``cb(value)`` (``cb(event)`` when ``name`` is None: every event); events kept while
        nobody listened are handed to it first."""
        self.callbacks.setdefault(name, []).append(cb)
        for ev in self._take_backlog(None if name is None else frozenset((name,))):
            self.core.dispatch(cb, ev if name is None else ev.value)

    def remove_callback(self, name: Optional[str], cb: Callable[[Any], Any]) -> None:
        cbs = self.callbacks.get(name, [])
        if cb in cbs:
            cbs.remove(cb)

    def add_sink(self, sink: EventSink) -> None:
        """Feed ``sink`` every event from now on (of ``sink.names``, or all), the backlog first."""
        self.sinks.append(sink)
        for ev in self._take_backlog(sink.names):
            sink.put(ev)

    def remove_sink(self, sink: EventSink) -> None:
        if sink in self.sinks:
            self.sinks.remove(sink)

    def _take_backlog(self, names: Optional[FrozenSet[str]]) -> List[ReceivedEvent]:
        taken = [ev for ev in self.backlog if names is None or ev.name in names]
        if taken:
            keep = [ev for ev in self.backlog if not (names is None or ev.name in names)]
            self.backlog = deque(keep, maxlen=BACKLOG_LIMIT)
        return taken

    def close(self) -> None:
        for sink in self.sinks:
            sink.close()
