"""Exceptions raised by hubwire. Every one derives from :class:`HubwireError`."""
from __future__ import annotations

from typing import Any, Dict, Optional


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


class UnknownBoard(HubwireError, KeyError):
    """``hubwire serve`` has no board of that key, name, board id or port (the message lists the
    known ones)."""

    kind = "UnknownBoard"

    def __str__(self) -> str:
        return str(self.args[0]) if self.args else ""


class ServiceNotRunning(HubwireError):
    """No ``hubwire serve`` answers on the socket."""

    kind = "ServiceNotRunning"


class ServiceError(HubwireError):
    """An error ``hubwire serve`` reported that has no class of its own here (``kind`` is its type)."""

    def __init__(self, kind: str, message: str) -> None:
        super().__init__(message)
        self.kind = kind


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


# ------------------------------------------------------------------- errors as types and back

#: Every error type the command line, the service's socket and the MQTT bridge report
#: (``{"error": TYPE, "message": TEXT}``), and why.
ERROR_TYPES: Dict[str, str] = {
    "UnknownChannel": "the device has no channel of that name",
    "NotReadable": "the channel cannot be read",
    "NotWritable": "the channel cannot be written",
    "NotCallable": "the channel is not an action",
    "InvalidValue": "the value does not parse, or does not fit the channel's type or range",
    "Nak": "the device refused the request (its reason is in the \"nak\" field)",
    "Timeout": "the device stopped answering a request",
    "LinkLost": "the link to the device went down (board unplugged, reset or silent)",
    "ConnectTimeout": "no Hubwire device answered on the port in time (silent, or another sketch)",
    "NoDeviceFound": "'auto' found no board, or more than one",
    "NoSuchPort": "the port does not exist",
    "PermissionDenied": "no permission to open the port",
    "PortBusy": "another program has the port open",
    "PortError": "the port could not be opened for another reason",
    "DescriptorError": "the device's descriptor is not valid",
    "ProtocolVersionError": "the device speaks another Hubwire protocol version",
    "UnknownBoard": "hubwire serve has no board of that name (the message lists the boards it has)",
    "ServiceNotRunning": "a board was named but hubwire serve is not running (the message says how to start it)",
    "Busy": "a per-client limit of hubwire serve was reached",
    "UnknownRun": "hubwire serve keeps no mission run of that id",
    "Conflict": "another client (or MQTT) already provides that hub channel (the message names both)",
    "MissionFailed": "the mission ended with a failure (its code is in the \"code\" field)",
    "MissionCancelled": "the mission was cancelled on the board",
    "MissionLost": "the board rebooted while the mission ran",
    "Usage": "the command line (or a request to the service) is not valid (exit status 2)",
    "Error": "any other error",
}


def error_type(exc: BaseException) -> str:
    """The stable type (a key of :data:`ERROR_TYPES`) of an error; errors that carry their own
    ``kind`` (a port that cannot be opened, the command line's, the service's) give it."""
    kind = getattr(exc, "kind", None)
    if kind in ERROR_TYPES:
        return str(kind)
    if isinstance(exc, NakError):
        return "Nak"
    for cls in (InvalidValue, Timeout, LinkLost, NoDeviceFound, DescriptorError, ProtocolVersionError,
                MissionFailed, MissionCancelled, MissionLost):
        if isinstance(exc, cls):
            return cls.__name__
    if isinstance(exc, KeyError):
        return "UnknownChannel"  # a channel name a face does not know
    return "Error"


def error_json(exc: BaseException) -> Dict[str, Any]:
    """An error as the command line (``--json``) and the service's socket report it: ``error`` (its
    type), ``message``, and for a NAK ``nak``, ``code`` and ``channel``, for an invalid value ``code``."""
    text = str(exc.args[0]) if isinstance(exc, KeyError) and exc.args else str(exc)
    out: Dict[str, Any] = {"error": error_type(exc), "message": text}
    if isinstance(exc, NakError):
        out.update(nak=exc.error, code=exc.code, channel=exc.channel)
    elif isinstance(exc, InvalidValue):
        out.update(code=exc.code)
    return out


def error_from(msg: Dict[str, Any]) -> HubwireError:
    """The exception an :func:`error_json` reply stands for (the class a direct connection raises;
    :class:`ServiceError` naming the type for the others)."""
    kind, text = str(msg.get("error", "Error")), str(msg.get("message", ""))
    if kind == "Nak":
        e: HubwireError = NakError(int(msg.get("code", 0)), msg.get("channel"))
        e.args = (text,)
        return e
    if kind == "InvalidValue":
        return InvalidValue(text, int(msg.get("code", 0)))
    if kind == "Timeout":
        return Timeout(text)
    if kind == "LinkLost":
        return LinkLost(text)
    if kind == "UnknownBoard":
        return UnknownBoard(text)
    return ServiceError(kind, text)
