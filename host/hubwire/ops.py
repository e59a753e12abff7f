"""Channel operations shared by the synchronous and the asyncio device: checks before sending,
payloads, decoding answers. Nothing here does I/O."""
from __future__ import annotations

from typing import Any, Optional

from .descriptor import Channel, Descriptor
from .diagnose import access_words
from .errors import HubwireError, NakError, NotCallable, NotReadable, NotWritable
from .text import clip, clip_list, show
from .wire import messages as m
from .wire.frame import Frame

__all__ = ["channel", "readable", "write_payload", "call_payload", "call_result", "stream_channel",
           "interval_for", "event_key", "cached_board_id", "remember_board_id", "UNASKED", "mission_start",
           "not_a_mission"]


def channel(desc: Optional[Descriptor], name: str) -> Channel:
    """The channel called ``name`` (KeyError listing the channels if there is none)."""
    if desc is None:
        raise HubwireError("device not discovered yet")
    ch = desc.by_name(name)
    if ch is None:
        raise KeyError(f"{show(desc.name)} has no channel {clip(name)}; channels: "
                       f"{clip_list(c.name for c in desc.channels)}")
    return ch


def _lacking(ch: Channel, verb: str) -> str:
    return f"channel {ch.name!r} cannot be {verb}: its access is {access_words(ch.access)}"


def readable(desc: Optional[Descriptor], name: str) -> Channel:
    ch = channel(desc, name)
    if not ch.readable:
        raise NotReadable(_lacking(ch, "read"))
    return ch


def write_payload(desc: Optional[Descriptor], name: str, value: Any) -> "tuple[Channel, bytes]":
    """Channel and payload of a write, type and range checked (InvalidValue)."""
    ch = channel(desc, name)
    if not ch.writable:
        raise NotWritable(_lacking(ch, "written"))
    return ch, ch.codec.encode(ch.check(value))


def not_a_mission(ch: Channel) -> HubwireError:
    """The error for using a mission as a call, a read or a write."""
    return HubwireError(f"{ch.name!r} is a mission, not an action: start it with dev.start({ch.name!r}"
                        f"{'' if ch.codec.kind == 'void' else ', goal'}) and wait with job.result()")


def _argument(ch: Channel, name: str, arg: Any) -> bytes:
    if ch.codec.kind == "void":
        if arg is not None:
            raise HubwireError(f"{name}() takes no argument")
        return b""
    if arg is None:
        raise HubwireError(f"{name}() needs an argument of type {ch.codec.name}")
    return ch.codec.encode(ch.check(arg))


def mission_start(desc: Optional[Descriptor], name: str, goal: Any) -> "tuple[Channel, bytes]":
    """Channel and ``C`` payload that start mission ``name`` with ``goal`` (None for no goal)."""
    from .wire.missions import start_payload

    ch = channel(desc, name)
    if not ch.mission:
        hint = f"; call an action with dev.call({name!r}, ...)" if ch.callable else ""
        raise HubwireError(f"channel {name!r} is not a mission (its access is {access_words(ch.access)}): "
                           f"dev.start starts missions only{hint}")
    return ch, start_payload(_argument(ch, name, goal))


def call_payload(desc: Optional[Descriptor], name: str, arg: Any) -> "tuple[Channel, bytes]":
    """Channel and payload of a call with ``arg`` (None for no argument)."""
    ch = channel(desc, name)
    if ch.mission:
        raise not_a_mission(ch)
    if not ch.callable:
        raise NotCallable(_lacking(ch, "called"))
    return ch, _argument(ch, name, arg)


def call_result(ch: Channel, answer: Frame) -> Any:
    if answer.type == m.ACK:
        return None
    assert ch.returns is not None
    return ch.returns.decode(answer.payload)


def stream_channel(desc: Optional[Descriptor], name: str) -> Channel:
    ch = channel(desc, name)
    if not ch.streamable:
        raise HubwireError(f"channel {name!r} is not streamable (access {ch.access!r})")
    return ch


def interval_for(hz: Optional[float], interval_ms: Optional[int]) -> int:
    """Subscription interval in ms from ``hz`` or ``interval_ms`` (default 10 Hz)."""
    if interval_ms is None:
        interval_ms = 100 if hz is None else max(1, int(round(1000.0 / hz)))
    if not 1 <= interval_ms <= 0xFFFF:
        raise ValueError("interval must be 1..65535 ms")
    return interval_ms


def event_key(desc: Optional[Descriptor], name: str) -> Optional[str]:
    """Callback key of ``name``: None for ``"*"`` (every event), else the event channel's name."""
    if name == "*":
        return None
    ch = channel(desc, name)
    if not ch.is_event:
        raise HubwireError(f"channel {name!r} is not an event (access {ch.access!r})")
    return name


UNASKED = object()  # cached_board_id(): not asked yet in this device session


def cached_board_id(core: Any) -> Any:
    """The board id read earlier from this boot of the device, or ``UNASKED`` when it must be read."""
    if core.board_id is not None and core.board_id[0] == core.descriptor_nonce:
        return core.board_id[1]
    return UNASKED


def remember_board_id(core: Any, answer: Optional[Frame], nak: Optional[NakError] = None) -> Optional[str]:
    """Decode the answer to ``R`` id 0 (PROTOCOL 3.4): the id in hex, or None for a device that
    has none (it answers NAK UNKNOWN_CHANNEL, as every device predating board ids does)."""
    if nak is not None and nak.code != m.NakCode.UNKNOWN_CHANNEL:
        raise nak
    value = answer.payload.hex() if answer is not None and answer.type == m.RESPONSE and answer.payload else None
    core.board_id = (core.descriptor_nonce, value)
    return value
