"""The board interface: what a program may do with one board, declared once and implemented on both
roads to it, as python-can's ``BusABC`` is for its buses.

- :class:`BoardAPI` (synchronous) is implemented by :class:`hubwire.Device`, which is what
  ``hubwire.connect()`` returns on both roads: a direct connection (over a
  :class:`hubwire.session.Session`) and one routed through ``hubwire serve``
  (:class:`hubwire.client.remote.RemoteDevice`, over a ``RemoteSession``).
- :class:`AsyncBoardAPI` (asyncio) is implemented by :class:`hubwire.aio.AsyncDevice` (direct) and
  :class:`hubwire.client.connection.AsyncRemoteDevice` (routed).

Every implementation names the protocol as a base class, so mypy checks its signatures against this
one and refuses to instantiate one that lacks a member; ``isinstance(dev, BoardAPI)`` holds at run
time too. Nothing is missing on either road (host/tests/roads/ runs one behaviour suite on both).
The members both declare alike are written once, in a private base protocol.
"""
from __future__ import annotations

from typing import Any, Callable, Dict, Optional, Protocol, Tuple, runtime_checkable

from .descriptor import Channel, Descriptor
from .hub import HubChannel, HubChannels
from .session import LinkHealth

__all__ = ["BoardAPI", "AsyncBoardAPI", "BOARD_METHODS"]

#: the members both protocols have (the async one's I/O methods are coroutines)
BOARD_METHODS: Tuple[str, ...] = (
    "name", "descriptor", "url", "state", "channel", "health", "board_id", "read", "write", "call", "start",
    "on", "events", "stream", "hub", "provide", "accept", "action", "event", "notify", "wait_notified",
    "notifications_pending", "hub_binding", "close")


class _BothRoads(Protocol):
    """The members :class:`BoardAPI` and :class:`AsyncBoardAPI` declare alike: what is known without
    a round trip, callbacks, and the hub's own channels (PROTOCOL.md 10)."""

    @property
    def name(self) -> str:
        """The board's name from its descriptor."""
        ...

    @property
    def descriptor(self) -> Descriptor:
        ...

    @property
    def url(self) -> str:
        """The port, or ``service:<key>`` for a board reached through ``hubwire serve``."""
        ...

    @property
    def state(self) -> str:
        """``"ready"``, ``"connecting"``, ``"lost"`` or ``"closed"``."""
        ...

    def channel(self, name: str) -> Channel:
        ...

    def health(self) -> LinkHealth:
        ...

    def on(self, name: str, callback: Callable[..., Any]) -> Callable[[], None]:
        ...

    @property
    def hub(self) -> HubChannels:
        ...

    def provide(self, name: str, source: Any, **kwargs: Any) -> HubChannel:
        ...

    def accept(self, name: str, on_write: Any = None, **kwargs: Any) -> Any:
        ...

    def action(self, name: str, fn: Any = None, **kwargs: Any) -> Any:
        ...

    def event(self, name: str, **kwargs: Any) -> HubChannel:
        ...

    def notify(self, name: str, value: Any) -> None:
        """Send hub event ``name``: checked at once, queued, delivered exactly once and in order."""
        ...

    @property
    def notifications_pending(self) -> int:
        ...

    def hub_binding(self) -> Dict[str, str]:
        ...


@runtime_checkable
class BoardAPI(_BothRoads, Protocol):
    """One board, synchronously: values, writes, actions, missions, events, streams, hub channels.

    Values are checked against the channel's type and range before anything is sent
    (:class:`hubwire.InvalidValue`); the board's refusals raise :class:`hubwire.NakError`; an unknown
    name raises KeyError listing the channels."""

    def board_id(self, *, timeout: Optional[float] = None) -> Optional[str]:
        ...

    def read(self, name: str, *, timeout: Optional[float] = None) -> Any:
        ...

    def write(self, name: str, value: Any, *, timeout: Optional[float] = None) -> None:
        ...

    def call(self, name: str, arg: Any = None, *, timeout: Optional[float] = None) -> Any:
        ...

    def start(self, name: str, goal: Any = None, *, timeout: Optional[float] = None) -> Any:
        """Start a mission: a :class:`hubwire.Job`."""
        ...

    def events(self, *names: str, timeout: Optional[float] = None) -> Any:
        """An iterator of :class:`hubwire.ReceivedEvent` (:class:`hubwire.EventStream`)."""
        ...

    def stream(self, name: str, hz: Optional[float] = None, *, interval_ms: Optional[int] = None,
               meta: bool = False, timeout: Optional[float] = None, maxlen: int = 1024) -> Any:
        """An iterator of samples (:class:`hubwire.Stream`)."""
        ...

    def wait_notified(self, timeout: Optional[float] = 5.0) -> None:
        ...

    def close(self) -> None:
        ...

    def table(self) -> str:
        ...

    def __getitem__(self, name: str) -> Any:
        ...

    def __setitem__(self, name: str, value: Any) -> None:
        ...

    def __contains__(self, name: str) -> bool:
        ...


@runtime_checkable
class AsyncBoardAPI(_BothRoads, Protocol):
    """One board for asyncio code: :class:`BoardAPI` with its round trips as coroutines
    (``read``, ``write``, ``call``, ``start``, ``board_id``, ``wait_notified``, ``close``,
    ``fetch_health``); ``stream`` and ``events`` return async iterators, ``on`` callbacks run on
    the loop. ``health()`` is what is known without asking (through the service: the board's state
    only); ``await fetch_health()`` asks."""

    async def fetch_health(self) -> LinkHealth:
        ...

    async def board_id(self, *, timeout: Optional[float] = None) -> Optional[str]:
        ...

    async def read(self, name: str, *, timeout: Optional[float] = None) -> Any:
        ...

    async def write(self, name: str, value: Any, *, timeout: Optional[float] = None) -> None:
        ...

    async def call(self, name: str, arg: Any = None, *, timeout: Optional[float] = None) -> Any:
        ...

    async def start(self, name: str, goal: Any = None, *, timeout: Optional[float] = None) -> Any:
        """Start a mission: a :class:`hubwire.job.AsyncJob`."""
        ...

    def events(self, *names: str, timeout: Optional[float] = None) -> Any:
        """An async iterator of :class:`hubwire.ReceivedEvent`."""
        ...

    def stream(self, name: str, hz: Optional[float] = None, *, interval_ms: Optional[int] = None,
               meta: bool = False, timeout: Optional[float] = None, maxlen: int = 1024) -> Any:
        """An async iterator of samples (subscribed on first use; ``async with`` ends it)."""
        ...

    async def wait_notified(self, timeout: Optional[float] = 5.0) -> None:
        ...

    async def close(self) -> None:
        ...
