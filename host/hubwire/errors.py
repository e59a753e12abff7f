"""Exceptions raised by hubwire. Every one derives from :class:`HubwireError`."""
from __future__ import annotations

from typing import Optional


class HubwireError(Exception):
    """Base class of every error hubwire raises on purpose."""


class Timeout(HubwireError, TimeoutError):
    """The device did not answer in time (after all retries)."""


class LinkLost(HubwireError, ConnectionError):
    """The link to the device is down; calls fail fast until it is restored."""


class StreamEnded(HubwireError):
    """A stream could not go on after the link came back: the rebooted device no longer has its
    channel (or not streamable, or of another type), or refused to subscribe it again."""


class ProtocolVersionError(HubwireError):
    """The device speaks a protocol version this hub does not."""

    def __init__(self, device_version: int, hub_version: int) -> None:
        super().__init__(
            f"device speaks Hubwire protocol version {device_version}, this hub speaks version "
            f"{hub_version}; update the {'hub (pip install -U ./host from a newer Hubwire checkout)' if device_version > hub_version else 'Hubwire library on the board'}"
        )
        self.device_version = device_version
        self.hub_version = hub_version


class NoDeviceFound(HubwireError):
    """No serial port (or more than one) matched a known microcontroller USB id."""


class DescriptorError(HubwireError, ValueError):
    """The device's descriptor is not valid JSON or does not match the descriptor schema."""


class HubChannelError(HubwireError, ValueError):
    """A hub channel declaration is invalid, or does not match what the connected device expects
    (a name it uses that the hub does not offer, another type or access)."""


class InvalidValue(HubwireError, ValueError):
    """A value does not fit a channel's type (encoding) or a payload does not decode.

    ``code`` is the :class:`hubwire.wire.messages.NakCode` a device would answer with
    (``BAD_LENGTH``, ``BAD_VALUE`` or ``OUT_OF_RANGE``).
    """

    def __init__(self, message: str, code: "int") -> None:
        super().__init__(message)
        self.code = code

    @property
    def error(self) -> str:
        """Name of :attr:`code` (``"BAD_VALUE"``, ...)."""
        from .wire.messages import nak_name

        return nak_name(self.code)


class AccessError(HubwireError):
    """The channel does not allow what was asked: the base of :class:`NotReadable`,
    :class:`NotWritable` and :class:`NotCallable` (the ``--json`` error types of the same names)."""


class NotReadable(AccessError):
    """A read of a channel that cannot be read (an action, an event)."""


class NotWritable(AccessError):
    """A write to a channel that cannot be written (``rover.battery = 5`` on a read-only channel)."""


class NotCallable(AccessError):
    """A call of a channel that is not an action."""


class NakError(HubwireError):
    """The device refused a request with a NAK; ``code`` and ``error`` (its name) tell why."""

    def __init__(self, code: int, channel: Optional[str] = None, what: str = "") -> None:
        from .wire.messages import nak_name

        self.code = code
        self.error = nak_name(code)
        self.channel = channel
        where = f" for channel {channel!r}" if channel else ""
        super().__init__(f"device answered NAK {self.error} ({code}){where}{': ' + what if what else ''}")


class MissionError(HubwireError):
    """A mission did not succeed: the base of :class:`MissionFailed`, :class:`MissionCancelled` and
    :class:`MissionLost`. ``mission`` is the channel's name, ``run`` the device's run number."""

    def __init__(self, message: str, mission: str = "", run: int = 0) -> None:
        super().__init__(message)
        self.mission = mission
        self.run = run


class MissionFailed(MissionError):
    """The sketch ended the run with a failure; ``code`` is the error code it chose (1..255)."""

    def __init__(self, mission: str, run: int, code: int) -> None:
        super().__init__(f"mission {mission!r} run {run} failed with code {code}", mission, run)
        self.code = code


class MissionCancelled(MissionError):
    """The run ended as cancelled (by :meth:`Job.cancel`, or by the sketch)."""

    def __init__(self, mission: str, run: int) -> None:
        super().__init__(f"mission {mission!r} run {run} was cancelled", mission, run)


class MissionLost(MissionError):
    """The run's outcome can never arrive: the board rebooted while it ran (or the session closed)."""
