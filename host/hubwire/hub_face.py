"""The hub-channel methods a connected device offers, shared by :class:`hubwire.Device` and
:class:`hubwire.aio.AsyncDevice` (declarations: :mod:`hubwire.hub`; session: ``session/hub_channels``)."""
from __future__ import annotations

from typing import Any, Dict

from .descriptor import Channel, Descriptor
from .errors import HubChannelError
from .hub import HubChannel, HubChannels, bind_status
from .session.hub_channels import HubSide
from .wire.messages import nak_name

__all__ = ["HubMethods", "expected_hub_event"]


def expected_hub_event(desc: Descriptor, name: str) -> Channel:
    """The hub event ``name`` the device takes (access ``e`` in its ``hub`` list), else HubChannelError."""
    exp = next((c for c in desc.hub if c.name == name and "e" in c.access), None)
    if exp is None:
        takes = sorted(c.name for c in desc.hub if "e" in c.access)
        raise HubChannelError(f"{desc.name} takes no hub event {name!r}; it takes: {', '.join(takes) or 'none'}")
    return exp


class HubMethods:
    """``dev.provide`` / ``dev.accept`` / ``dev.action`` / ``dev.event`` declare on ``dev.hub`` (a
    type the device expects otherwise raises :class:`HubChannelError` at once); ``dev.notify``
    queues an event for this device."""

    __slots__ = ()

    def _hub_side(self) -> HubSide:
        raise NotImplementedError

    @property
    def hub(self) -> HubChannels:
        """The hub channels this device is offered (given to ``connect(..., hub=...)``, or its own)."""
        return self._hub_side().channels

    def provide(self, name: str, source: Any, **kwargs: Any) -> HubChannel:
        """A value the device may read: see :meth:`HubChannels.provide`."""
        return self.hub.provide(name, source, **kwargs)

    def accept(self, name: str, on_write: Any = None, **kwargs: Any) -> Any:
        """A value the device may write: see :meth:`HubChannels.accept` (also a decorator)."""
        return self.hub.accept(name, on_write, **kwargs)

    def action(self, name: str, fn: Any = None, **kwargs: Any) -> Any:
        """An action the device may call: see :meth:`HubChannels.action` (also a decorator)."""
        return self.hub.action(name, fn, **kwargs)

    def event(self, name: str, **kwargs: Any) -> HubChannel:
        """An event the hub may send with :meth:`notify`: see :meth:`HubChannels.event`."""
        return self.hub.event(name, **kwargs)

    def notify(self, name: str, value: Any) -> None:
        """Send hub event ``name`` to the device: delivered exactly once, in order, kept across link
        losses and device reboots until the device acknowledges it. Returns at once; raises for a
        value that does not fit or a name the device does not take as an event. An event the device
        takes that was not declared is declared with the device's own type."""
        side = self._hub_side()
        desc = side.core.descriptor
        if name not in side.channels and desc is not None:
            side.channels.event(name, type=expected_hub_event(desc, name).codec.type_obj)
        side.notify(name, value)

    @property
    def notifications_pending(self) -> int:
        """Hub events queued for the device and not acknowledged yet."""
        return len(self._hub_side().queue)

    def hub_binding(self) -> Dict[str, str]:
        """For every hub channel the device uses: ``"ok"``, or why it is not bound (``"UNKNOWN_CHANNEL"``:
        the hub lacks it, ``"BAD_LENGTH"``: another type, ``"NOT_WRITABLE"``, ``"NOT_READABLE"``)."""
        side = self._hub_side()
        remote = getattr(side, "binding", None)
        if remote is not None:  # through hubwire serve: as the service binds the board
            return remote()  # type: ignore[no-any-return]
        desc = side.core.descriptor
        out: Dict[str, str] = {}
        for exp in desc.hub if desc is not None else ():
            code = bind_status(exp, side.channels.get(exp.name))
            out[exp.name] = "ok" if code == 0 else nak_name(code)
        return out
