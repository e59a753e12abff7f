"""Hub channels on a board reached through ``hubwire serve`` (:class:`hubwire.board.BoardAPI` on the
routed road): hub events go through the service's ``notify`` op (checked here first, as a direct
connection checks them); hub channels a client declares are not routed yet and raise
:class:`hubwire.NotRoutedYet` saying what to do."""
from __future__ import annotations

import asyncio
from typing import TYPE_CHECKING, Any, Dict, List, NoReturn, Optional, Set

from ..descriptor import Descriptor
from ..errors import NotRoutedYet, Timeout
from ..hub import HubChannel, HubChannels
from ..hub_face import expected_hub_event

if TYPE_CHECKING:
    from .connection import Connection

__all__ = ["hub_not_routed", "RoutedHubChannels", "hub_event_payload", "AsyncRoutedHub"]


def hub_not_routed() -> NotRoutedYet:
    return NotRoutedYet("hub channels a client declares (provide, accept, action, event, hub_binding)",
                        "declare them in a program that opens the board's port itself (with the service not "
                        "serving that board); hub events (notify) do go through the service")


class RoutedHubChannels(HubChannels):
    """``dev.hub`` of a routed board: empty, and every declaration raises :class:`NotRoutedYet`."""

    def _refuse(self, *args: Any, **kwargs: Any) -> NoReturn:
        raise hub_not_routed()

    def provide(self, *args: Any, **kwargs: Any) -> HubChannel:
        self._refuse()

    def accept(self, *args: Any, **kwargs: Any) -> Any:
        self._refuse()

    def action(self, *args: Any, **kwargs: Any) -> Any:
        self._refuse()

    def event(self, *args: Any, **kwargs: Any) -> HubChannel:
        self._refuse()


def hub_event_payload(desc: Descriptor, name: str, value: Any) -> bytes:
    """The payload of hub event ``name`` with ``value``, checked by the device's own type (the
    errors a direct ``notify`` raises)."""
    exp = expected_hub_event(desc, name)
    return exp.codec.encode(exp.check(value))


class AsyncRoutedHub:
    """The hub-channel members of :class:`hubwire.board.AsyncBoardAPI` on the routed
    ``AsyncRemoteDevice`` (``conn``: its service connection, ``key``, ``_desc``)."""

    conn: "Connection"
    key: str
    _desc: Descriptor

    def __init__(self) -> None:
        self._hub = RoutedHubChannels()
        self._notifying: Set["asyncio.Task[Dict[str, Any]]"] = set()  # notify requests not answered yet
        self._notify_errors: List[BaseException] = []

    @property
    def hub(self) -> HubChannels:
        """Empty: hub channels a client declares are not routed yet (declaring raises NotRoutedYet)."""
        return self._hub

    def provide(self, name: str, source: Any, **kwargs: Any) -> HubChannel:
        return self._hub.provide(name, source, **kwargs)

    def accept(self, name: str, on_write: Any = None, **kwargs: Any) -> Any:
        return self._hub.accept(name, on_write, **kwargs)

    def action(self, name: str, fn: Any = None, **kwargs: Any) -> Any:
        return self._hub.action(name, fn, **kwargs)

    def event(self, name: str, **kwargs: Any) -> HubChannel:
        return self._hub.event(name, **kwargs)

    def hub_binding(self) -> Dict[str, str]:
        raise hub_not_routed()

    def notify(self, name: str, value: Any) -> None:
        """Hand hub event ``name`` to the service (checked here first, as a direct ``notify``): it
        stores it and sends it exactly once, in order, also after its own restart. Returns at once;
        :meth:`wait_notified` waits until the service has stored every one."""
        raw = hub_event_payload(self._desc, name, value)
        task = asyncio.get_running_loop().create_task(
            self.conn.request("notify", board=self.key, channel=name, raw=raw.hex()))
        self._notifying.add(task)
        task.add_done_callback(self._notified)

    def _notified(self, task: "asyncio.Task[Dict[str, Any]]") -> None:
        self._notifying.discard(task)
        if not task.cancelled() and task.exception() is not None:
            self._notify_errors.append(task.exception())  # type: ignore[arg-type]

    @property
    def notifications_pending(self) -> int:
        """Hub events handed to :meth:`notify` that the service has not stored yet."""
        return len(self._notifying)

    async def wait_notified(self, timeout: Optional[float] = 5.0) -> None:
        """Return once the service has stored every hub event :meth:`notify` handed it (it then
        delivers each exactly once); raises the first refusal, :class:`Timeout` after ``timeout`` s."""
        if self._notifying:
            _, late = await asyncio.wait(set(self._notifying), timeout=timeout)
            if late:
                raise Timeout(f"{len(late)} hub events still wait for hubwire serve after {timeout} s")
        if self._notify_errors:
            err, self._notify_errors = self._notify_errors[0], []
            raise err
