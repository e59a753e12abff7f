"""Streams (PROTOCOL.md §3.7): subscriptions, several consumers per channel, seq gaps.

The device keeps one subscription per channel; the hub lets several consumers share it, asking the
device for the smallest interval any of them wants and cancelling it when the last one leaves.
Each consumer gets every sample in a bounded queue (the oldest dropped and counted when full) and
the number of samples lost before each one, from gaps in the device's sample counter.
"""
from __future__ import annotations

import asyncio
import threading
from collections import deque
from typing import Any, Deque, Dict, List, Optional

from ..errors import HubwireError, InvalidValue
from ..wire import messages as m
from ..wire.frame import Frame
from .records import StreamSample

__all__ = ["Subscription", "ThreadSubscription", "AsyncSubscription", "Streams", "granted_interval"]


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
    """Subscriptions of one session. ``core`` provides ``tx`` (Transactions), ``link``, ``stats``,
    ``decoder_drop()``, ``is_ready()`` and ``descriptor``."""

    def __init__(self, core: Any) -> None:
        self.core = core
        self.subs: Dict[int, List[Subscription]] = {}

    async def subscribe(self, id: int, interval_ms: int, *, timeout: Optional[float] = None, what: str = "") -> int:
        """``S``: (re)subscribe or cancel (0); returns the granted interval."""
        a = await self.core.tx.transact(m.SUBSCRIBE, id, m.Subscribe(interval_ms).pack(), timeout=timeout, what=what)
        return granted_interval(a, interval_ms)

    def attach(self, sub: Subscription) -> int:
        """Add a consumer; the interval to ask the device for: the smallest its channel's consumers want."""
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

    def send_subscribe(self, id: int, interval: int) -> None:
        self.core.link.send_frame(m.SUBSCRIBE, self.core.tx.next_seq(), id, m.Subscribe(interval).pack())

    def end_all(self, exc: BaseException) -> None:
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
            sub.push(StreamSample(value, s.since_ms, f.seq, lost, now))
