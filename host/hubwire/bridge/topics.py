"""The MQTT topic layout of the bridge (docs/MQTT.md), its settings, and JSON forms of values.

Everything here is pure: names and payloads, no I/O, so tests and other clients can build the same
topics the bridge uses.
"""
from __future__ import annotations

import json
import math
import re
import socket
import struct
from dataclasses import dataclass, field
from typing import Any, Dict, Optional, Tuple

from ..daemon.keys import board_key, level, safe_id
from ..descriptor import Channel

__all__ = ["BridgeConfig", "Topics", "OPS", "ONLINE", "OFFLINE", "BadPayload", "to_json", "codec_json", "dumps",
           "parse_value", "safe_id", "level", "board_key"]

ONLINE = "online"
OFFLINE = "offline"
#: command verbs: ``<prefix>/<board>/<op>/<channel>``
OPS = ("set", "call", "read", "subscribe", "unsubscribe")

_F32 = struct.Struct("<f")


@dataclass
class BridgeConfig:
    """Settings of :func:`hubwire.bridge.mqtt.run_bridge` (all optional)."""

    prefix: str = "hubwire"
    #: Home Assistant's discovery prefix; None turns discovery off
    discovery_prefix: Optional[str] = "homeassistant"
    #: names this service's status topic (two services on one broker need two ids)
    service_id: str = field(default_factory=lambda: safe_id(socket.gethostname()))
    #: how often a streamable channel's retained state is refreshed (it follows a stream at this rate)
    state_hz: float = 1.0
    #: how often a readable, not streamable channel is read for its retained state, seconds
    poll_s: float = 5.0
    #: ceiling for stream rates: ``{"battery": 5, "rover/imu": 50}`` (channel, or board/channel)
    max_rate_hz: Dict[str, float] = field(default_factory=dict)
    #: ceiling for channels not named in ``max_rate_hz``
    default_max_rate_hz: float = 100.0
    #: streams published from the start, without a ``subscribe`` command: ``{"rover/imu": 50}``
    streams: Dict[str, float] = field(default_factory=dict)
    #: a ``subscribe`` command holds its stream this long unless renewed, seconds
    lease_s: float = 60.0
    #: events kept while the broker is away (the oldest are dropped beyond it, and counted)
    event_backlog: int = 10000
    #: seconds between attempts to reach the broker
    reconnect_s: float = 1.0
    #: MQTT keepalive, seconds
    keepalive: int = 30

    def ceiling(self, board: str, channel: str) -> float:
        """The highest stream rate allowed for ``channel`` of ``board``, Hz."""
        for key in (f"{board}/{channel}", channel):
            if key in self.max_rate_hz:
                return float(self.max_rate_hz[key])
        return self.default_max_rate_hz


_KEY = re.compile(r"[A-Za-z0-9_]+(?:-[A-Za-z0-9_]+)*(?:--[A-Za-z0-9_]+(?:-[A-Za-z0-9_]+)*)?(?:---[0-9]+)?\Z")


class Topics:
    """Topic names under ``prefix`` (default ``hubwire``)."""

    def __init__(self, prefix: str = "hubwire", discovery_prefix: Optional[str] = "homeassistant") -> None:
        self.prefix = prefix.rstrip("/")
        self.discovery_prefix = discovery_prefix

    def service_status(self, service_id: str) -> str:
        return f"{self.prefix}/_service/{service_id}/status"

    def board(self, key: str, *rest: str) -> str:
        """``<prefix>/<key>/<rest>...``: the key as it is when it is a key :func:`board_key` makes,
        else (a key from some other fleet) as one :func:`level`."""
        return "/".join((self.prefix, key if _KEY.match(key) else level(key)) + rest)

    def descriptor(self, key: str) -> str:
        return self.board(key, "descriptor")

    def status(self, key: str) -> str:
        return self.board(key, "status")

    def state(self, key: str, channel: str) -> str:
        return self.board(key, "state", level(channel))

    def stream(self, key: str, channel: str) -> str:
        return self.board(key, "stream", level(channel))

    def result(self, key: str, channel: str) -> str:
        """The last call of an action: ``{"arg": ..., "value": ...}`` (retained)."""
        return self.board(key, "result", level(channel))

    def event(self, key: str, channel: str) -> str:
        return self.board(key, "event", level(channel))

    def command(self, key: str, op: str, channel: str) -> str:
        return self.board(key, op, level(channel))

    @staticmethod
    def channel(desc: Any, channel_level: str) -> Any:
        """The channel of ``desc`` whose topic level is ``channel_level``, or None."""
        for ch in desc.channels:
            if level(ch.name) == channel_level:
                return ch
        return None

    def rpc(self, key: str) -> str:
        return self.board(key, "rpc")

    def rpc_reply(self, key: str) -> str:
        return self.board(key, "rpc", "reply")

    def errors(self, key: str) -> str:
        return self.board(key, "error")

    def descriptor_filter(self) -> str:
        """What the bridge subscribes to for every board's descriptor (its own and other services')."""
        return f"{self.prefix}/+/descriptor"

    def command_filters(self) -> Tuple[str, ...]:
        """What the bridge subscribes to for commands."""
        return tuple(f"{self.prefix}/+/{op}/+" for op in OPS) + (f"{self.prefix}/+/rpc",)

    def parse_command(self, topic: str) -> Optional[Tuple[str, str, Optional[str]]]:
        """``(board, op, channel)`` of a command topic (op ``rpc`` has channel None), else None."""
        head = self.prefix + "/"
        if not topic.startswith(head):
            return None
        parts = topic[len(head):].split("/")
        if len(parts) == 2 and parts[1] == "rpc":
            return parts[0], "rpc", None
        if len(parts) == 3 and parts[1] in OPS:
            return parts[0], parts[1], parts[2]
        return None


# ------------------------------------------------------------------------------- values as JSON

def to_json(ch: Optional[Channel], value: Any, returns: bool = False) -> Any:
    """JSON form of a value of ``ch`` (its return value when ``returns``): structs become objects,
    arrays lists; NaN and infinities become None (JSON has no such numbers); an f32 is its
    shortest decimal (0.1, not the double 0.10000000149011612 it reads back as)."""
    return codec_json((ch.returns if returns else ch.codec) if ch is not None else None, value)


def codec_json(codec: Any, value: Any) -> Any:
    """As :func:`to_json`, for a value of ``codec`` (a mission's progress, say); None: as it is."""
    v = codec.to_json(value) if codec is not None else value
    return _finite(_short_f32(codec, v) if codec is not None else v)


def _f32(x: Any) -> Any:
    if not isinstance(x, float) or not math.isfinite(x):
        return x
    packed = _F32.pack(x)
    for digits in range(6, 10):  # 9 significant digits always give the same f32 back
        short = float(f"{x:.{digits}g}")
        if _F32.pack(short) == packed:
            return short
    return x


def _short_f32(codec: Any, v: Any) -> Any:
    kind = getattr(codec, "kind", "")
    if kind == "scalar" or kind in ("array", "list"):
        if getattr(codec, "scalar", None) != "f32":
            return v
        return [_f32(x) for x in v] if isinstance(v, list) else _f32(v)
    if kind == "struct" and isinstance(v, dict):
        subs = dict(zip(codec.fields, codec.field_codecs))
        return {k: _short_f32(subs.get(k), x) for k, x in v.items()}
    return v


def _finite(v: Any) -> Any:
    if isinstance(v, float) and not math.isfinite(v):
        return None
    if isinstance(v, dict):
        return {k: _finite(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [_finite(x) for x in v]
    return v


def dumps(obj: Any) -> str:
    """Compact JSON, as every payload of the bridge is."""
    return json.dumps(obj, separators=(",", ":"), ensure_ascii=False, allow_nan=False)


class BadPayload(ValueError):
    """A command payload that is not what the command takes (nothing is sent to the board)."""


def parse_value(payload: bytes, *, empty_is_none: bool = False) -> Any:
    """The JSON value in a command payload; an empty payload is None when ``empty_is_none``."""
    try:
        text = payload.decode("utf-8")
    except UnicodeDecodeError:
        raise BadPayload("payload is not UTF-8 text: give the value as JSON") from None
    if not text.strip():
        if empty_is_none:
            return None
        raise BadPayload("empty payload: give the value as JSON (0.5, true, \"text\", [1,2], {\"ax\":1})")
    try:
        return json.loads(text, parse_constant=_reject_constant)
    except ValueError as e:
        raise BadPayload(f"payload is not JSON ({e}): give the value as JSON, e.g. 0.5, true, \"text\"") from None


def _reject_constant(name: str) -> Any:
    raise ValueError(f"{name} is not JSON")
