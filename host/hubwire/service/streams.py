"""Async iterators over what the service pushes to a client: :class:`RemoteStream` (samples, as
:class:`hubwire.aio.AsyncStream`) and :class:`RemoteEvents` (events, as ``AsyncEventStream``)."""
from __future__ import annotations

import asyncio
from collections import deque
from typing import TYPE_CHECKING, Any, Deque, Dict, List, Optional

from ..aio import EventIterator
from ..descriptor import Channel
from ..errors import LinkLost, StreamEnded, Timeout
from ..session import ReceivedEvent, StreamSample

if TYPE_CHECKING:
    from .client import AsyncRemoteDevice

__all__ = ["RemoteStream", "RemoteEvents", "ended"]


def ended(msg: Dict[str, Any]) -> BaseException:
    """The exception a subscription's end message stands for."""
    kind, text = msg.get("end"), str(msg.get("message", ""))
    return StreamEnded(text) if kind == "StreamEnded" else LinkLost(text)


class _Closed(Exception):
    """The subscription ended (the service went away)."""


class _Queue:
    """Pushed items for ``async for``: a bounded deque, an event to wait on, the end."""

    def __init__(self, maxlen: int) -> None:
        self.q: Deque[Any] = deque(maxlen=maxlen)
        self.ready = asyncio.Event()
        self.end: Optional[BaseException] = None

    async def next(self, timeout: Optional[float], what: str) -> Any:
        while not self.q:
            if self.end is not None:
                raise self.end
            self.ready.clear()
            try:
                await asyncio.wait_for(self.ready.wait(), timeout)
            except asyncio.TimeoutError:
                raise Timeout(what) from None
        return self.q.popleft()


class RemoteStream:
    """``async for`` over a stream through the service (as :class:`hubwire.aio.AsyncStream`)."""

    def __init__(self, dev: AsyncRemoteDevice, ch: Channel, interval_ms: int, meta: bool,
                 timeout: Optional[float], maxlen: int) -> None:
        self.dev, self.channel, self.interval_ms = dev, ch, interval_ms
        self.meta, self.timeout = meta, timeout
        self._q = _Queue(maxlen)
        self._sub: Optional[int] = None
        self.granted_ms = 0
        self.lost = 0
        self.gaps = 0

    def _push(self, msg: Dict[str, Any]) -> None:
        if "sample" in msg:
            self._q.q.append(self.dev.sample(self.channel, msg["sample"]))
        elif "end" in msg:
            self._q.end = ended(msg)
        self._q.ready.set()

    async def open(self) -> "RemoteStream":
        if self._sub is None:
            self._sub, reply = await self.dev.conn.subscribe("stream", self._push, board=self.dev.key,
                                                              channel=self.channel.name, interval_ms=self.interval_ms)
            self.granted_ms = int(reply["granted_ms"])
        return self

    def __aiter__(self) -> "RemoteStream":
        return self

    async def __anext__(self) -> Any:
        await self.open()
        s: StreamSample = await self._q.next(self.timeout, f"no sample of {self.channel.name} within {self.timeout} s")
        self.lost += s.lost
        self.gaps += s.gap
        return s if self.meta else s.value

    async def aclose(self) -> None:
        sub, self._sub = self._sub, None
        if sub is not None:
            await self.dev.conn.unsubscribe(sub)

    async def __aenter__(self) -> "RemoteStream":
        return await self.open()

    async def __aexit__(self, *exc: Any) -> None:
        await self.aclose()


class RemoteEvents(EventIterator):
    """``async for ev in dev.events(...)`` through the service: every event from its creation on."""

    def __init__(self, dev: AsyncRemoteDevice, names: List[str], timeout: Optional[float]) -> None:
        self.dev, self.timeout = dev, timeout
        self._q = _Queue(4096)
        self._fut: "Optional[asyncio.Future[Dict[str, Any]]]"
        self._sub, self._fut = dev.conn.subscribe_nowait("events", self._push, board=dev.key, names=names)

    def _push(self, msg: Dict[str, Any]) -> None:
        if "event" in msg:
            self._q.q.append(self.dev.decode_event(msg["event"]))
        elif "end" in msg:
            self._q.end = _Closed()
        self._q.ready.set()

    async def get(self, timeout: Optional[float] = None) -> Optional[ReceivedEvent]:
        if self._fut is not None:
            fut, self._fut = self._fut, None
            await self.dev.conn.confirm(self._sub, fut)
        try:
            ev: ReceivedEvent = await self._q.next(timeout, "")
            return ev
        except (Timeout, _Closed):
            return None

    def close(self) -> None:
        asyncio.ensure_future(self.dev.conn.unsubscribe(self._sub))
