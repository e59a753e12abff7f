"""Iterators of the synchronous API: :class:`Stream` (samples) and :class:`EventStream` (events)."""
from __future__ import annotations

import queue
import time
from typing import Any, Iterator, Optional, Sequence

from .descriptor import Channel
from .errors import HubwireError, Timeout
from .session import ReceivedEvent, Session, StreamSample, ThreadSubscription

__all__ = ["Stream", "EventStream"]


class Stream:
    """A subscription to a streamable channel: iterate to get values (or :class:`StreamSample` with
    ``meta=True``). Ends the subscription on :meth:`close` / leaving the ``with`` block.

    The stream rides through link losses and device reboots: once the link is back the hub
    subscribes again by itself and iteration goes on; the first sample after an outage has
    ``gap`` >= 1 (see :class:`StreamSample`; :attr:`gaps` counts them). Iteration raises
    :class:`Timeout` if no sample arrives within ``timeout`` seconds (when given; an outage longer
    than that included), :class:`StreamEnded` if a rebooted device no longer has the channel, and
    :class:`LinkLost` once the session is closed.
    """

    def __init__(self, session: Session, channel: Channel, interval_ms: int, *, meta: bool = False,
                 timeout: Optional[float] = None, maxlen: int = 1024) -> None:
        self._session = session
        self.channel = channel
        self.meta = meta
        self.timeout = timeout
        self._sub: Optional[ThreadSubscription] = session.open_stream(channel.id, interval_ms, maxlen, what=channel.name)
        #: interval the device granted, ms
        self.granted_ms = self._sub.granted_ms
        #: samples lost (gaps in the device's sample counter)
        self.lost = 0
        #: link outages ridden through (each reported on the next sample's ``gap``)
        self.gaps = 0

    def __iter__(self) -> "Stream":
        return self

    def __next__(self) -> Any:
        sub = self._sub
        if sub is None:
            raise StopIteration
        deadline = None if self.timeout is None else time.monotonic() + self.timeout
        with sub.cv:
            while not sub.queue:
                if sub.ended is not None:
                    if isinstance(sub.ended, StopIteration):
                        raise StopIteration
                    raise sub.ended
                left = None if deadline is None else deadline - time.monotonic()
                if left is not None and left <= 0:
                    raise Timeout(f"no sample of {self.channel.name} within {self.timeout:g} s")
                sub.cv.wait(left)
            s: StreamSample = sub.queue.popleft()
        self.lost += s.lost
        self.gaps += s.gap
        return s if self.meta else s.value

    def get(self, timeout: Optional[float] = None) -> Optional[Any]:
        """Next sample within ``timeout`` s, or None."""
        old = self.timeout
        self.timeout = timeout
        try:
            return next(self)
        except (Timeout, StopIteration):
            return None
        finally:
            self.timeout = old

    def close(self, wait: bool = True) -> None:
        """End the subscription (cancelled on the device when this was its last consumer)."""
        sub, self._sub = self._sub, None
        if sub is not None:
            try:
                self._session.close_stream(sub, wait=wait)
            except HubwireError:
                pass

    def __enter__(self) -> "Stream":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

    def __del__(self) -> None:
        try:
            if self._sub is not None:
                self.close(wait=False)
        except Exception:  # noqa: BLE001 - interpreter shutdown
            pass

    def __repr__(self) -> str:
        return f"<Stream {self.channel.name} every {self.granted_ms} ms{' (closed)' if self._sub is None else ''}>"


class EventStream:
    """Iterator over events (all, or those of the given channel names), from its creation on.

    Yields :class:`hubwire.ReceivedEvent` objects (``.name``, ``.value``, ``.seq``, ``.time``).
    ``timeout`` (s) makes iteration stop after that long without an event; :meth:`get` polls.
    It rides through link losses and device reboots (events the device kept meanwhile arrive once
    the link is back, each delivered once); it ends when the session closes.
    """

    def __init__(self, session: Session, names: Optional[Sequence[str]] = None, timeout: Optional[float] = None) -> None:
        self._session = session
        self._names = set(names) if names else None
        self.timeout = timeout
        self._sink = session.event_queue(self._names)
        self._q: Optional["queue.Queue[Optional[ReceivedEvent]]"] = self._sink.q

    def get(self, timeout: Optional[float] = None) -> Optional[ReceivedEvent]:
        """Next event within ``timeout`` seconds (None: wait forever), or None."""
        q = self._q
        if q is None:
            return None
        try:
            ev = q.get(timeout=timeout) if timeout is None or timeout > 0 else q.get_nowait()
        except queue.Empty:
            return None
        if ev is None:  # session closed
            self.close()
        return ev

    def __iter__(self) -> Iterator[ReceivedEvent]:
        while self._q is not None:
            ev = self.get(self.timeout)
            if ev is None:
                return
            yield ev

    def close(self) -> None:
        q, self._q = self._q, None
        if q is not None:
            self._session.drop_event_queue(self._sink)

    def __enter__(self) -> "EventStream":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()
