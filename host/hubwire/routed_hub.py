"""Hub channels on a board reached through ``hubwire serve`` (:class:`hubwire.board.BoardAPI` on the
routed road): hub events go through the service's ``notify`` op (checked here first, as a direct
connection checks them); hub channels a client declares are not routed yet and raise
:class:`hubwire.NotRoutedYet` saying what to do."""
from __future__ import annotations

from typing import Any, NoReturn

from .descriptor import Descriptor
from .errors import NotRoutedYet
from .hub import HubChannel, HubChannels
from .hub_face import expected_hub_event

__all__ = ["hub_not_routed", "RoutedHubChannels", "hub_event_payload"]


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
