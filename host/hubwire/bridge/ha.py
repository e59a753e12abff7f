"""Home Assistant MQTT discovery for the boards the bridge serves (docs/MQTT.md, "Home Assistant").

Each board is one Home Assistant device; each channel one entity of the kind its descriptor implies.
Payloads use only keys Home Assistant documents for the platform (the tests check every key against
the documentation's lists); the full key names are used, not the abbreviations.
"""
from __future__ import annotations

from typing import Any, Dict, List, Optional, Tuple

from .. import __version__
from ..descriptor import Channel, Descriptor
from ..wire.scalars import INTEGER_TYPES, NUMERIC_TYPES, SCALARS
from .topics import OFFLINE, ONLINE, Topics, dumps, level

__all__ = ["entity_kind", "discovery_messages", "config_topic", "ORIGIN"]

ORIGIN = {"name": "hubwire", "sw_version": __version__,
          "support_url": "https://github.com/hubwire/hubwire/blob/main/docs/MQTT.md"}

#: what a button sends (the bridge takes JSON null as "call without an argument")
PRESS = "null"


def _scalar(ch: Channel) -> Optional[str]:
    return ch.type.get("t") if ch.codec.kind == "scalar" else None


def entity_kind(ch: Channel) -> Optional[str]:
    """The Home Assistant platform a channel becomes, or None (no entity: a callable that takes an
    argument, a writable string, array or struct without a read side is reached by commands only)."""
    t = _scalar(ch)
    if ch.is_event:
        return "event"
    if ch.callable:
        return "button" if ch.codec.kind == "void" else None
    if ch.writable and t == "bool":
        return "switch"
    if ch.writable and t in NUMERIC_TYPES and (ch.range is not None or t in INTEGER_TYPES):
        return "number"
    if ch.readable:
        return "sensor"
    return None


def config_topic(topics: Topics, kind: str, key: str, channel: str) -> str:
    """``<discovery_prefix>/<component>/<node_id>/<object_id>/config``: node_id is the board's topic
    level (its key), object_id the channel's (both ``[A-Za-z0-9_-]``, distinct by construction)."""
    return f"{topics.discovery_prefix}/{kind}/{_node(topics, key)}/{level(channel)}/config"


def _node(topics: Topics, key: str) -> str:
    return topics.board(key).rpartition("/")[2]


def _unique(topics: Topics, key: str, channel: str) -> str:
    # levels never contain "--", so the last "--" always separates board and channel
    return f"hubwire_{_node(topics, key)}--{level(channel)}"


def _device(topics: Topics, key: str, desc: Descriptor, board_id: Optional[str]) -> Dict[str, Any]:
    dev: Dict[str, Any] = {"identifiers": [f"hubwire_{_node(topics, key)}"], "name": key,
                           "manufacturer": "Hubwire", "model": desc.name}
    if desc.firmware:
        dev["sw_version"] = desc.firmware
    if board_id:
        dev["serial_number"] = board_id
    return dev


def _range(ch: Channel) -> Tuple[float, float]:
    t = _scalar(ch) or "i32"
    lo, hi = (ch.min, ch.max)
    if t in INTEGER_TYPES:
        tlo, thi = SCALARS[t][2], SCALARS[t][3]
        lo = tlo if lo is None else lo
        hi = thi if hi is None else hi
    return float(lo if lo is not None else 0), float(hi if hi is not None else 0)


def entity_config(topics: Topics, service_id: str, key: str, desc: Descriptor, board_id: Optional[str],
                  ch: Channel) -> Optional[Tuple[str, Dict[str, Any]]]:
    """``(platform, config)`` of one channel's entity, or None."""
    kind = entity_kind(ch)
    if kind is None:
        return None
    cfg: Dict[str, Any] = {
        "name": ch.name,
        "unique_id": _unique(topics, key, ch.name),
        "device": _device(topics, key, desc, board_id),
        "origin": ORIGIN,
        "availability": [
            {"topic": topics.service_status(service_id), "payload_available": ONLINE,
             "payload_not_available": OFFLINE},
            {"topic": topics.status(key), "payload_available": ONLINE, "payload_not_available": OFFLINE},
        ],
        "availability_mode": "all",
    }
    state = topics.state(key, ch.name)
    if kind == "event":
        cfg.update(state_topic=topics.event(key, ch.name), event_types=[ch.name], qos=1)
    elif kind == "button":
        cfg.update(command_topic=topics.command(key, "call", ch.name), payload_press=PRESS)
    elif kind == "switch":
        cfg.update(command_topic=topics.command(key, "set", ch.name), payload_on="true", payload_off="false")
        if ch.readable:
            cfg.update(state_topic=state, state_on="true", state_off="false")
    elif kind == "number":
        lo, hi = _range(ch)
        cfg.update(command_topic=topics.command(key, "set", ch.name), min=lo, max=hi,
                   step=1 if _scalar(ch) in INTEGER_TYPES else max(0.001, round((hi - lo) / 100, 3)))
        if ch.readable:
            cfg["state_topic"] = state
    else:
        cfg["state_topic"] = state
        if _scalar(ch) in NUMERIC_TYPES:
            cfg["state_class"] = "measurement"
        elif ch.codec.kind == "str":
            cfg["value_template"] = "{{ value_json }}"  # the text, without JSON's quotes
    if ch.unit and kind in ("sensor", "number"):
        cfg["unit_of_measurement"] = ch.unit
    return kind, cfg


def discovery_messages(topics: Topics, service_id: str, key: str, desc: Descriptor,
                       board_id: Optional[str]) -> List[Tuple[str, str]]:
    """``(config topic, JSON payload)`` for every entity of a board (retained by the bridge)."""
    out: List[Tuple[str, str]] = []
    for ch in desc.channels:
        got = entity_config(topics, service_id, key, desc, board_id, ch)
        if got is not None:
            kind, cfg = got
            out.append((config_topic(topics, kind, key, ch.name), dumps(cfg)))
    return out
