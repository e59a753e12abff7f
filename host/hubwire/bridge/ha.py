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
from .ha_map import MAX_STATE, NUMERIC, TEXT, is_counter, json_text, readable_name, unit_class, value_keys
from .topics import OFFLINE, ONLINE, Topics, dumps, level

__all__ = ["entity_kind", "entity_kinds", "entity_configs", "discovery_messages", "config_topic", "device", "ORIGIN"]

ORIGIN = {"name": "hubwire", "sw_version": __version__,
          "support_url": "https://github.com/hubwire/hubwire/blob/main/docs/MQTT.md"}

#: what a button sends (the bridge takes JSON null as "call without an argument")
PRESS = "null"


def _scalar(ch: Channel) -> Optional[str]:
    return ch.type.get("t") if ch.codec.kind == "scalar" else None


def _numeric_arg(ch: Channel) -> bool:
    t = _scalar(ch)
    return t in NUMERIC_TYPES and (ch.range is not None or t in INTEGER_TYPES)


def entity_kinds(ch: Channel) -> List[str]:
    """The Home Assistant platforms a channel becomes (docs/MQTT.md, "Entity mapping"); empty for
    a channel reached by commands only (a write-only float without a range, a write-only array or
    struct, an action whose argument is a bool)."""
    t = _scalar(ch)
    if ch.is_event:
        return ["event"]
    if ch.mission:
        return ["sensor"]  # its last run (the retained mission state); started by its topics
    if ch.callable:
        if ch.codec.kind == "void":
            kinds = ["button"]
        elif _numeric_arg(ch):
            kinds = ["number"]
        elif ch.codec.kind in ("str", "array", "list", "struct"):
            kinds = ["text"]
        else:
            return []
        if ch.returns is not None and ch.returns.kind != "void":
            kinds.append(value_keys(ch.returns, ch.unit, ch.name, "value_json.value")[0])
        return kinds
    if ch.writable and t == "bool":
        return ["switch"]
    if ch.writable and t in NUMERIC_TYPES and (ch.range is not None or t in INTEGER_TYPES):
        return ["number"]
    if ch.writable and ch.codec.kind == "str":
        return ["text"]
    if ch.readable:
        return [value_keys(ch.codec, ch.unit, ch.name)[0]]
    return []


def entity_kind(ch: Channel) -> Optional[str]:
    """The main platform of a channel's entities, or None."""
    kinds = entity_kinds(ch)
    return kinds[0] if kinds else None


def legacy_kind(ch: Channel) -> Optional[str]:
    """The platform versions before the entity mapping gave a channel: its retained config is
    cleared when the channel's entity moved to another platform (no stale duplicate in HA)."""
    t = _scalar(ch)
    if ch.is_event:
        return "event"
    if ch.callable:
        return "button" if ch.codec.kind == "void" else None
    if ch.writable and t == "bool":
        return "switch"
    if ch.writable and t in NUMERIC_TYPES and (ch.range is not None or t in INTEGER_TYPES):
        return "number"
    return "sensor" if ch.readable else None


def config_topic(topics: Topics, kind: str, key: str, channel: str) -> str:
    """``<discovery_prefix>/<component>/<node_id>/<object_id>/config``: node_id is the board's topic
    level (its key), object_id the channel's (both ``[A-Za-z0-9_-]``, distinct by construction)."""
    return f"{topics.discovery_prefix}/{kind}/{_node(topics, key)}/{level(channel)}/config"


def _node(topics: Topics, key: str) -> str:
    return topics.board(key).rpartition("/")[2]


def _unique(topics: Topics, key: str, channel: str) -> str:
    # levels never contain "--", so the last "--" always separates board and channel
    return f"hubwire_{_node(topics, key)}--{level(channel)}"


def device(topics: Topics, key: str, desc: Descriptor, board_id: Optional[str]) -> Dict[str, Any]:
    """The board's Home Assistant device, the same in every config that names it (its hub
    channels' too): Home Assistant takes the device's name from whichever config came last."""
    # "rover--A1B2" shows as "Rover A1B2" (entity names follow: "Rover Battery")
    shown = key.replace("---", " ").replace("--", " ")
    dev: Dict[str, Any] = {"identifiers": [f"hubwire_{_node(topics, key)}"], "name": shown[:1].upper() + shown[1:],
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


def _base(topics: Topics, service_id: str, key: str, desc: Descriptor, board_id: Optional[str],
          ch: Channel, name: str, unique_suffix: str = "") -> Dict[str, Any]:
    return {
        "name": name,
        "unique_id": _unique(topics, key, ch.name) + unique_suffix,
        "device": device(topics, key, desc, board_id),
        "origin": ORIGIN,
        "availability": [
            {"topic": topics.service_status(service_id), "payload_available": ONLINE,
             "payload_not_available": OFFLINE},
            {"topic": topics.status(key), "payload_available": ONLINE, "payload_not_available": OFFLINE},
        ],
        "availability_mode": "all",
    }


def _number(ch: Channel, cfg: Dict[str, Any]) -> None:
    lo, hi = _range(ch)
    cfg.update(min=lo, max=hi, step=1 if _scalar(ch) in INTEGER_TYPES else max(0.001, round((hi - lo) / 100, 3)))
    cls, unit = unit_class(ch.unit, ch.name)
    if unit:
        cfg["unit_of_measurement"] = unit
    if cls:
        cfg["device_class"] = cls


def _text_max(ch: Channel) -> int:
    """A string's capacity (its bytes bound its characters); JSON text (an array or struct
    argument) up to what a state may hold (a list's capacity counts elements, not characters)."""
    cap = getattr(ch.codec, "capacity", None) if ch.codec.kind == "str" else None
    return min(MAX_STATE, int(cap)) if isinstance(cap, int) else MAX_STATE


def entity_configs(topics: Topics, service_id: str, key: str, desc: Descriptor, board_id: Optional[str],
                   ch: Channel) -> List[Tuple[str, Dict[str, Any]]]:
    """``(platform, config)`` of each entity of one channel (docs/MQTT.md, "Entity mapping")."""
    kinds = entity_kinds(ch)
    if not kinds:
        return []
    name = readable_name(ch.name, ch.unit)
    cfg = _base(topics, service_id, key, desc, board_id, ch, name)
    kind = kinds[0]
    state = topics.state(key, ch.name)
    out: List[Tuple[str, Dict[str, Any]]] = [(kind, cfg)]
    if kind == "event":
        cfg.update(state_topic=topics.event(key, ch.name), event_types=[ch.name], qos=1)
    elif ch.callable:
        # an action: a button without an argument, else a number or text whose value is the argument
        # (set = call); the result topic holds the last call's argument and result, so HA shows
        # only what the board accepted, and a sensor shows the result
        result = topics.result(key, ch.name)
        cfg["command_topic"] = topics.command(key, "call", ch.name)
        if kind == "button":
            cfg["payload_press"] = PRESS
        elif kind == "number":
            _number(ch, cfg)
            cfg.update(state_topic=result, value_template="{{ value_json.arg }}", mode="box")
        else:
            plain_text = ch.codec.kind == "str"
            cfg.update(state_topic=result, max=_text_max(ch),
                       command_template="{{ value | to_json }}" if plain_text else "{{ value }}",
                       value_template="{{ value_json.arg }}" if plain_text else json_text("value_json.arg"))
        if len(kinds) > 1:
            assert ch.returns is not None
            rkind, keys = value_keys(ch.returns, ch.unit, ch.name, "value_json.value")
            rcfg = _base(topics, service_id, key, desc, board_id, ch, f"{name} result", "--result")
            rcfg.update(state_topic=result, **keys)
            if "json_attributes_template" in keys:
                rcfg["json_attributes_topic"] = result
            out.append((rkind, rcfg))
    elif ch.mission:
        # the retained state of the mission's last run: its status as the state, the run (run id,
        # progress, result) as attributes; no unit or state class: the status is text
        run = topics.board(key, "mission", level(ch.name), "state")
        cfg.update(state_topic=run, value_template="{{ value_json.status }}", json_attributes_topic=run)
    elif kind == "switch":
        # a write-only one too: the bridge publishes the value the board accepted on its state topic
        cfg.update(command_topic=topics.command(key, "set", ch.name), payload_on="true", payload_off="false",
                   state_topic=state, state_on="true", state_off="false")
    elif kind == "number":
        cfg.update(command_topic=topics.command(key, "set", ch.name), state_topic=state, value_template=NUMERIC)
        _number(ch, cfg)
    elif kind == "text":
        cfg.update(command_topic=topics.command(key, "set", ch.name), state_topic=state, max=_text_max(ch),
                   command_template="{{ value | to_json }}", value_template=TEXT)
    else:
        counter = is_counter(ch.access, ch.codec, ch.unit)
        cfg["state_topic"] = state
        cfg.update(value_keys(ch.codec, ch.unit, ch.name, counter=counter)[1])
        if "json_attributes_template" in cfg:
            cfg["json_attributes_topic"] = state
        if counter:
            cfg["entity_category"] = "diagnostic"
    return out


def entity_config(topics: Topics, service_id: str, key: str, desc: Descriptor, board_id: Optional[str],
                  ch: Channel) -> Optional[Tuple[str, Dict[str, Any]]]:
    """``(platform, config)`` of one channel's main entity, or None."""
    got = entity_configs(topics, service_id, key, desc, board_id, ch)
    return got[0] if got else None


def discovery_messages(topics: Topics, service_id: str, key: str, desc: Descriptor,
                       board_id: Optional[str]) -> List[Tuple[str, str]]:
    """``(config topic, JSON payload)`` for every entity of a board (retained by the bridge), and
    ``(config topic, "")`` for a config an earlier version retained on another platform."""
    out: List[Tuple[str, str]] = []
    for ch in desc.channels:
        got = entity_configs(topics, service_id, key, desc, board_id, ch)
        for kind, cfg in got:
            out.append((config_topic(topics, kind, key, ch.name), dumps(cfg)))
        old = legacy_kind(ch)
        if old is not None and old not in [k for k, _ in got]:
            out.append((config_topic(topics, old, key, ch.name), ""))
    return out
