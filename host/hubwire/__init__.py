"""Hubwire hub: talk to a microcontroller running the Hubwire library over a serial line.

``hubwire.connect(url)`` returns a synchronous :class:`Device`; ``hubwire.aio.connect(url)`` is the
asyncio flavour. Both run on the same session core (:mod:`hubwire.session`).
"""
from __future__ import annotations

from .errors import (DescriptorError, HubChannelError, HubwireError, InvalidValue, LinkLost, MissionCancelled,
                     MissionError, MissionFailed, MissionLost, NakError, NoDeviceFound,
                     ProtocolVersionError, StreamEnded, Timeout, UnknownBoard)

__version__ = "0.1.0"

__all__ = [
    "HubwireError", "Timeout", "NakError", "DescriptorError", "LinkLost", "ProtocolVersionError",
    "NoDeviceFound", "InvalidValue", "StreamEnded", "HubChannelError", "MissionError", "MissionFailed",
    "MissionCancelled", "MissionLost", "UnknownBoard", "__version__",
]

from .descriptor import Channel, Descriptor, parse_descriptor  # noqa: E402
from .hub import HubChannel, HubChannels  # noqa: E402
from .device import Device, EventStream, Stream, connect, find_port  # noqa: E402
from .job import Job  # noqa: E402
from .board import AsyncBoardAPI, BoardAPI  # noqa: E402
from .session import LinkHealth, ReceivedEvent, Session, State, Stats, StreamSample  # noqa: E402
from .transport import SerialTransport, Transport  # noqa: E402
from . import aio  # noqa: E402
from . import roads  # noqa: E402
from .client import route as _route  # noqa: E402

roads.install(_route)  # connect() reaches boards through hubwire serve where that applies

__all__ += ["connect", "find_port", "Device", "Stream", "EventStream", "Session", "State", "ReceivedEvent",
            "StreamSample", "LinkHealth", "Stats", "Channel", "Descriptor", "parse_descriptor", "Transport",
            "SerialTransport", "aio", "HubChannels", "HubChannel", "Job", "BoardAPI", "AsyncBoardAPI"]
