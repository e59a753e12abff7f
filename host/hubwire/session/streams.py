"""Streams (PROTOCOL.md §3.7): subscriptions, several consumers per channel, seq gaps, and riding
through link losses.

The device keeps one subscription per channel; the hub lets several consumers share it, asking the
device for the smallest interval any of them wants and cancelling it when the last one leaves.
Each consumer gets every sample in a bounded queue (the oldest dropped and counted when full) and
the number of samples lost before each one, from gaps in the device's sample counter.

A link loss or a device reboot does not end the consumers: the device ends its subscriptions
(PROTOCOL.md §4.3), so once the session is READY again the hub subscribes every open channel anew
by itself (:meth:`Streams.resume`) and the first sample after it carries ``gap`` (the outages since
the previous sample). After a reboot a consumer whose channel is gone or changed type ends with
:class:`StreamEnded`.
"""
from __future__ import annotations

import asyncio
import logging
import threading
from collections import deque
from typing import Any, Deque, Dict, List, Optional

from ..errors import HubwireError, InvalidValue, LinkLost, NakError, StreamEnded
from ..text import clip
from ..wire import messages as m
from ..wire.frame import Frame
from .records import StreamSample

__all__ = ["Subscription", "ThreadSubscription", "AsyncSubscription", "Streams", "granted_interval"]

log = logging.getLogger("hubwire")

#: seconds before a resubscription that timed out is tried again
RESUBSCRIBE_RETRY = 1.0


def granted_interval(answer: Frame, asked: int) -> int:
    """The interval the device granted in its answer to a subscribe."""
    if answer.type != m.ACK:
        raise HubwireError(f"unexpected answer type 0x{answer.type:02x} to a subscribe")
    return m.SubscribeAck.unpack(answer.payload).granted_ms if len(answer.payload) >= 2 else asked


class Subscription:
    """Hub-side record of one stream consumer; subclasses say how a waiting consumer is woken."""

    def __init__(self, channel_id: int, interval_ms: int, maxlen: int) -> None:
        self.channel_id = channel_id
        self.interval_ms = interval_ms
        self.granted_ms = 0
        self.queue: Deque[StreamSample] = deque(maxlen=maxlen)
        self.ended: Optional[BaseException] = None
        self.last_seq: Optional[int] = None
        self.dropped = 0
        #: the channel's name and type when subscribed (checked again after a reboot)
        self.name = ""
        self.type_name = ""
        #: link outages since the last sample (reported on the next one)
        self.gap = 0

    def push(self, item: StreamSample) -> None:
        if len(self.queue) == self.queue.maxlen:
            self.dropped += 1
        self.queue.append(item)
        self._wake()

    def end(self, exc: BaseException) -> None:
        if self.ended is None:
            self.ended = exc
        self._wake()

    def _wake(self) -> None:
        raise NotImplementedError


class ThreadSubscription(Subscription):
    """A consumer in another thread (the synchronous API): waits on a condition variable."""

    def __init__(self, channel_id: int, interval_ms: int, maxlen: int) -> None:
        super().__init__(channel_id, interval_ms, maxlen)
        self.cv = threading.Condition()

    def push(self, item: StreamSample) -> None:
        with self.cv:
            super().push(item)

    def end(self, exc: BaseException) -> None:
        with self.cv:
            super().end(exc)

    def _wake(self) -> None:
        self.cv.notify_all()

    def drain(self) -> List[StreamSample]:
        """Every sample waiting, at once."""
        with self.cv:
            out = list(self.queue)
            self.queue.clear()
        return out


class AsyncSubscription(Subscription):
    """A consumer on the session's own loop (the asyncio API): waits on an asyncio event."""

    def __init__(self, channel_id: int, interval_ms: int, maxlen: int) -> None:
        super().__init__(channel_id, interval_ms, maxlen)
        self.ready = asyncio.Event()

    def _wake(self) -> None:
        self.ready.set()


class Streams:
    """Subscriptions of one session. ``core`` provides ``loop``, ``tx`` (Transactions), ``link``, ``stats``,
    ``decoder_drop()``, ``is_ready()`` and ``descriptor``."""

    def __init__(self, core: Any) -> None:
        self.core = core
        self.subs: Dict[int, List[Subscription]] = {}
        self._interrupted = False
        self._resuming: Optional["asyncio.Task[None]"] = None
        self._retry: Optional[asyncio.TimerHandle] = None

    async def subscribe(self, id: int, interval_ms: int, *, timeout: Optional[float] = None, what: str = "") -> int:
        """``S``: (re)subscribe or cancel (0); returns the granted interval."""
        a = await self.core.tx.transact(m.SUBSCRIBE, id, m.Subscribe(interval_ms).pack(), timeout=timeout, what=what)
        return granted_interval(a, interval_ms)

    def attach(self, sub: Subscription) -> int:
        """Add a consumer; the interval to ask the device for: the smallest its channel's consumers want."""
        ch = self.core.descriptor.by_id(sub.channel_id) if self.core.descriptor is not None else None
        if ch is not None:
            sub.name, sub.type_name = ch.name, ch.type_name
        others = self.subs.setdefault(sub.channel_id, [])
        interval = min([s.interval_ms for s in others] + [sub.interval_ms])
        others.append(sub)
        return interval

    def forget(self, sub: Subscription) -> None:
        """Undo :meth:`attach` (the subscribe failed)."""
        self._remove(sub)

    async def open(self, sub: Subscription, what: str = "") -> Subscription:
        """Add a consumer and (re)subscribe at the smallest interval its channel's consumers want."""
        interval = self.attach(sub)
        try:
            sub.granted_ms = await self.subscribe(sub.channel_id, interval, what=what)
        except BaseException:
            self._remove(sub)
            raise
        return sub

    def _remove(self, sub: Subscription) -> List[Subscription]:
        lst = self.subs.get(sub.channel_id, [])
        if sub in lst:
            lst.remove(sub)
        if not lst:
            self.subs.pop(sub.channel_id, None)
        return list(lst)

    def detach(self, sub: Subscription) -> Optional[int]:
        """Forget a consumer; the interval to ask the device for now (0 cancels), None if not linked."""
        remaining = self._remove(sub)
        sub.end(StopIteration())
        if not self.core.is_ready():
            return None
        return min(s.interval_ms for s in remaining) if remaining else 0

    async def close(self, sub: Subscription) -> None:
        """End a consumer; cancels the subscription on the device when it was the channel's last."""
        interval = self.detach(sub)
        if interval is not None:
            try:
                await self.subscribe(sub.channel_id, interval)
            except HubwireError:
                pass

    def close_nowait(self, sub: Subscription) -> None:
        """Like :meth:`close` without waiting for the device's answer (one ``S``, not retried)."""
        interval = self.detach(sub)
        if interval is not None:
            self.send_subscribe(sub.channel_id, interval)

    def send_subscribe(self, id: int, interval: int, *, closing: bool = False) -> None:
        """One ``S``, not retried; it waits while a control is out (an ``S`` between the tries of a
        ``C`` would end the device's memory of it, PROTOCOL.md 4.1), unless the session closes."""
        if self.core.tx.control_owner is not None and not closing:
            self.core.loop.call_later(self.core.retry_timeout, self.send_subscribe, id, interval)
            return
        self.core.link.send_frame(m.SUBSCRIBE, self.core.tx.next_seq(m.SUBSCRIBE, id), id, m.Subscribe(interval).pack())

    def end_all(self, exc: BaseException) -> None:
        """End every consumer with ``exc`` (the session closed, or cannot go on)."""
        for t in (self._resuming, self._retry):
            if t is not None:
                t.cancel()
        subs = [s for lst in self.subs.values() for s in lst]
        self.subs.clear()
        for s in subs:
            s.end(exc)

    def on_sample(self, f: Frame, now: float) -> None:
        core = self.core
        core.stats.samples += 1
        subs = self.subs.get(f.id)
        desc = core.descriptor
        if not subs or desc is None:
            return
        ch = desc.by_id(f.id)
        if ch is None:
            return
        try:
            s = m.Sample.unpack(f.payload)
            value = ch.codec.decode(s.value)
        except (m.PayloadError, InvalidValue):
            core.link.decoder.dropped += 1
            return
        for sub in subs:
            lost = 0 if sub.last_seq is None else (f.seq - sub.last_seq - 1) & 0xFF
            sub.last_seq = f.seq
            gap, sub.gap = sub.gap, 0
            sub.push(StreamSample(value, s.since_ms, f.seq, lost, now, gap))

    # ------------------------------------------------------------------------ ride-through

    def interrupt(self) -> None:
        """The link is down or the device rebooted: its subscriptions ended; keep the consumers,
        mark the outage on their next sample (once per outage) and resubscribe at :meth:`resume`."""
        if self._interrupted:
            return
        self._interrupted = True
        if self._resuming is not None:
            self._resuming.cancel()
            self._resuming = None
        for lst in self.subs.values():
            for sub in lst:
                sub.gap += 1
                sub.last_seq = None  # a new subscription counts its samples afresh

    def resume(self) -> None:
        """The session is READY again: resubscribe every open channel (a task on the loop)."""
        self._interrupted = False
        if self._retry is not None:
            self._retry.cancel()
            self._retry = None
        if self.subs and self._resuming is None:
            self._resuming = self.core.loop.create_task(self._resubscribe())

    async def _resubscribe(self) -> None:
        try:
            self._check_channels()
            for cid in list(self.subs):
                if not await self._resubscribe_one(cid):
                    break
        finally:
            if self._resuming is asyncio.current_task():
                self._resuming = None

    async def _resubscribe_one(self, cid: int) -> bool:
        """Subscribe ``cid`` again; False when the rest must wait (the link went down, or a retry)."""
        lst = self.subs.get(cid)
        if not lst:
            return True
        interval = min(s.interval_ms for s in lst)
        try:
            granted = await self.subscribe(cid, interval, what=lst[0].name)
        except LinkLost:
            return False  # down again: resume() runs once it is back
        except NakError as e:
            self._end_channel(cid, StreamEnded(f"stream of {clip(lst[0].name)} ended: the device refused to "
                                               f"subscribe it again after the link came back ({e})"))
            return True
        except HubwireError as e:
            log.warning("hubwire: resubscribing %s failed (%s); trying again in %g s",
                        clip(lst[0].name), e, RESUBSCRIBE_RETRY)
            self._retry = self.core.loop.call_later(RESUBSCRIBE_RETRY, self.resume)
            return False
        self.core.stats.resubscribes += 1
        remaining = self.subs.get(cid)
        if not remaining:
            self.send_subscribe(cid, 0)  # its consumers left meanwhile
        for sub in remaining or ():
            sub.granted_ms = granted
        return True

    def _check_channels(self) -> None:
        """After a reboot the descriptor may differ: follow a channel that moved to another id, end
        the consumers of one that is gone, no longer streamable or of another type."""
        desc = self.core.descriptor
        for cid, lst in list(self.subs.items()):
            sub = lst[0]
            ch = desc.by_name(sub.name) if desc is not None and sub.name else None
            if ch is not None and ch.streamable and ch.type_name == sub.type_name:
                if ch.id != cid and ch.id not in self.subs:
                    self.subs[ch.id] = self.subs.pop(cid)
                    for s in lst:
                        s.channel_id = ch.id
                continue
            what = "has no such channel" if ch is None else (
                "cannot stream it any more" if not ch.streamable else f"changed its type to {ch.type_name}")
            self._end_channel(cid, StreamEnded(
                f"stream of {clip(sub.name)} ({sub.type_name}) ended: the rebooted device {what}"))

    def _end_channel(self, cid: int, exc: BaseException) -> None:
        for sub in self.subs.pop(cid, []):
            sub.end(exc)
