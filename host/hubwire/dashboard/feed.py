"""The dashboard's side of each board: one stream per streamable channel, periodic reads of the
other readable channels, every event, and writes and calls from the page, shared by every open tab.

Feeds live on the fleet's event loop. A board whose session object or descriptor changes gets a
new feed (``generation`` counts them, and the page redraws that board)."""
from __future__ import annotations

import asyncio
import contextlib
import logging
import time
from collections import deque
from typing import Any, Deque, Dict, List, Mapping, Optional, Tuple

from .. import aio
from ..descriptor import Channel, Descriptor
from ..errors import HubwireError, NakError
from .fleet import FleetLike
from .model import ChannelRecord, EventRecord, LinkRecord
from .words import outcome, outcome_text

__all__ = ["BoardFeed", "Feeds", "outcome_text"]

log = logging.getLogger("hubwire.dashboard")

#: events kept per board for the page's log
EVENT_LOG = 500
#: default read rate of readable channels that cannot stream, Hz
POLL_HZ = 2.0
#: most reads a second of one channel (each is a round trip; streams are for fast values)
READ_MAX_HZ = 10.0


class BoardFeed:
    """Live records of one board's device (one session object, one descriptor)."""

    def __init__(self, key: str, dev: aio.AsyncDevice, generation: int, stream_hz: float,
                 rates: Optional[Mapping[str, float]] = None) -> None:
        self.key = key
        self.dev = dev
        self.generation = generation
        self.descriptor: Descriptor = dev.descriptor
        #: Unix time of monotonic 0, fixed so that arrival times keep their order
        self.epoch = time.time() - time.monotonic()
        self.records: Dict[str, ChannelRecord] = {}
        rates = rates or {}
        for ch in self.descriptor.channels:
            hz = rates.get(f"{key}.{ch.name}", rates.get(ch.name))
            if ch.streamable:
                self.records[ch.name] = ChannelRecord(ch, hz or stream_hz)
            elif ch.readable and not ch.callable and not ch.is_event:
                self.records[ch.name] = ChannelRecord(ch, min(hz or min(POLL_HZ, stream_hz), READ_MAX_HZ), read="read")
        self.events: Deque[EventRecord] = deque(maxlen=EVENT_LOG)
        self.event_count = 0
        self._streams: Dict[str, "asyncio.Task[None]"] = {}
        self._tasks: List["asyncio.Task[None]"] = []
        #: the service's hub providers (``fleet.hub``, daemon/hub_providers.py), None without a service
        self.providers: Any = None
        #: True once stopped: its records are the last values the board sent
        self.ended = False

    def hub_providers(self) -> Dict[str, str]:
        """Who provides each hub channel the board uses, through the service ("" when nobody)."""
        if self.providers is None:
            return {}
        return {str(r["channel"]): str(r.get("by") or "") for r in self.providers.status(self.key)}

    def start(self) -> None:
        for name, rec in self.records.items():
            if rec.channel.streamable:
                self._streams[name] = asyncio.ensure_future(self._stream(rec))
        self._tasks = [asyncio.ensure_future(self._poll()), asyncio.ensure_future(self._events())]

    async def stop(self) -> None:
        self.ended = True
        tasks = list(self._streams.values()) + self._tasks
        for t in tasks:
            t.cancel()
        for t in tasks:
            with contextlib.suppress(asyncio.CancelledError, Exception):
                await t

    def set_rate(self, name: str, hz: float) -> None:
        """Ask for ``hz`` samples per second of ``name`` (a new subscription for a streamed channel)."""
        rec = self.records[name]
        rec.rate = float(hz) if not rec.read else min(float(hz), READ_MAX_HZ)
        if rec.read and rec.read != "read":
            rec.read = f"read {rec.rate:g} times a second (the board has no stream free for it)"
        if name in self._streams:
            self._streams[name].cancel()
            self._streams[name] = asyncio.ensure_future(self._stream(rec))

    async def _stream(self, rec: ChannelRecord) -> None:
        ch = rec.channel
        while True:
            try:
                async with self.dev.stream(ch.name, hz=rec.rate, meta=True) as s:
                    async for sample in s:
                        rec.add(ch.codec.to_json(sample.value), self.epoch + sample.time)
                return
            except asyncio.CancelledError:
                raise
            except NakError as e:  # e.g. BUSY: the device streams as many channels as it can
                if not ch.readable:
                    rec.error = outcome_text(e)
                    return
                rec.rate = min(rec.rate, READ_MAX_HZ)
                why = "the board has no stream free for it" if e.error == "BUSY" else outcome_text(e)
                rec.read = f"read {rec.rate:g} times a second ({why})"
                self._streams.pop(ch.name, None)
                return
            except HubwireError as e:  # not subscribed yet (link down while opening): try again
                rec.error = str(e)
                if self.dev.state == "closed":
                    return
                await asyncio.sleep(1.0)

    async def _poll(self) -> None:
        due: Dict[str, float] = {}
        while True:
            polled = [r for r in self.records.values() if r.read]
            now = time.monotonic()
            for rec in polled:
                if self.dev.state != "ready" or due.get(rec.channel.name, 0.0) > now:
                    continue
                due[rec.channel.name] = now + 1.0 / rec.rate
                try:
                    v = await self.dev.read(rec.channel.name)
                except HubwireError as e:
                    rec.error = outcome_text(e)
                    continue
                rec.add(rec.channel.codec.to_json(v), self.epoch + time.monotonic())
            await asyncio.sleep(min([0.05] + [1.0 / r.rate for r in polled]))

    async def _events(self) -> None:
        async for ev in self.dev.events():
            self.event_count += 1
            ch = self.descriptor.by_name(ev.name)
            value = ch.codec.to_json(ev.value) if ch is not None else ev.value
            self.events.append(EventRecord(self.event_count, self.epoch + ev.time, ev.name, value))

    # ------------------------------------------------------------------------- from the page

    async def write(self, ch: Channel, value: Any) -> Tuple[bool, str]:
        """Write through the device API (its type and range checks), ``(acked, what happened)``."""
        ok, text, _ = await self.write_coded(ch, value)
        return ok, text

    async def write_coded(self, ch: Channel, value: Any) -> Tuple[bool, str, Optional[str]]:
        """:meth:`write`, with the protocol's name of the reason when refused."""
        try:
            await self.dev.write(ch.name, value)
        except (HubwireError, ValueError, TypeError) as e:
            return (False, *outcome(e))
        rec = self.records.get(ch.name)
        if rec is not None and rec.read:
            rec.add(ch.codec.to_json(ch.check(value)), self.epoch + time.monotonic())  # the device holds it now
        return True, "acked", None

    async def call(self, ch: Channel, arg: Any) -> Tuple[bool, str]:
        """Call an action, ``(ok, its result or why it failed)``."""
        ok, text, _ = await self.call_coded(ch, arg)
        return ok, text

    async def call_coded(self, ch: Channel, arg: Any) -> Tuple[bool, str, Optional[str]]:
        """:meth:`call`, with the protocol's name of the reason when refused."""
        try:
            result = await self.dev.call(ch.name, arg)
        except (HubwireError, ValueError, TypeError) as e:
            return (False, *outcome(e))
        from .model import fmt_value

        returns = ch.returns
        return True, fmt_value(returns.to_json(result) if returns is not None and result is not None else result), None


class Feeds:
    """A feed for every ready board of ``fleet``, kept current as boards come, go and change."""

    def __init__(self, fleet: FleetLike, stream_hz: float = 10.0, rates: Optional[Mapping[str, float]] = None) -> None:
        self.fleet = fleet
        self.stream_hz = stream_hz
        self.rates = dict(rates or {})
        self.feeds: Dict[str, BoardFeed] = {}
        #: each board's losses and returns as seen here, by key (kept across its feeds)
        self.links: Dict[str, LinkRecord] = {}
        self._generation = 0
        self._task: Optional["asyncio.Task[None]"] = None
        self._watch: Optional["asyncio.Task[None]"] = None

    async def start(self) -> None:
        for b in self.fleet.boards():
            self.update(b)
        self._task = asyncio.ensure_future(self._follow())
        self._watch = asyncio.ensure_future(self._check_descriptors())

    async def stop(self) -> None:
        for t in (self._task, self._watch):
            if t is not None:
                t.cancel()
                with contextlib.suppress(asyncio.CancelledError, Exception):
                    await t
        for f in list(self.feeds.values()):
            await f.stop()
        self.feeds.clear()

    def boards(self) -> List[Any]:
        return sorted(self.fleet.boards(), key=lambda b: b.key)

    def update(self, board: Any) -> None:
        """A feed for ``board`` if it has a discovered device it has none for yet. While it has no
        device its feed is stopped and kept: the page shows its last values as such."""
        dev: Optional[aio.AsyncDevice] = board.device
        self.links.setdefault(board.key, LinkRecord()).observe(board.state)
        old = self.feeds.get(board.key)
        if dev is None and old is not None:  # unplugged: its session is gone, its last values stay
            if not old.ended:
                old.ended = True
                asyncio.ensure_future(old.stop())
            return
        if dev is None or dev.core.descriptor is None:
            return
        if old is not None and old.dev is dev and old.descriptor is dev.core.descriptor:
            return
        if old is not None:
            asyncio.ensure_future(old.stop())
        self._generation += 1
        feed = BoardFeed(board.key, dev, self._generation, self.stream_hz, self.rates)
        feed.providers = getattr(self.fleet, "hub", None)
        self.feeds[board.key] = feed
        feed.start()

    async def _follow(self) -> None:
        async for b in self.fleet.changes():
            self.update(b)

    async def _check_descriptors(self) -> None:
        # a rebooted device may come back with other channels (no state change tells it): look
        while True:
            await asyncio.sleep(0.5)
            for b in self.fleet.boards():
                self.update(b)
