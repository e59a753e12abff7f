"""Hubwire hub: talk to a microcontroller running the Hubwire library over a serial line."""
from __future__ import annotations

from .errors import (DescriptorError, HubwireError, InvalidValue, LinkLost, NakError, NoDeviceFound,
                     ProtocolVersionError, Timeout)

__version__ = "0.1.0"

__all__ = [
    "HubwireError", "Timeout", "NakError", "DescriptorError", "LinkLost", "ProtocolVersionError",
    "NoDeviceFound", "InvalidValue", "__version__",
]

from .descriptor import Channel, Descriptor, parse_descriptor  # noqa: E402
from .device import Device, EventStream, Stream, connect, find_port  # noqa: E402
from .session import Event, LinkHealth, Session, State, StreamSample  # noqa: E402

__all__ += ["connect", "find_port", "Device", "Stream", "EventStream", "Session", "State", "Event",
            "StreamSample", "LinkHealth", "Channel", "Descriptor", "parse_descriptor"]
