"""Home Assistant discovery for the hub channels the MQTT bridge backs (docs/MQTT.md "Hub channels"):

| the board ... | entity | state | command |
| --- | --- | --- | --- |
| reads a number (`setpoint`) | `number` (a slider within its range, else a box) | the value topic | `.../set` |
| reads a bool | `switch` | the value topic | `.../set` |
| writes a value (`report`) | `sensor` (`binary_sensor` for a bool) | the value topic | |
| calls an action (`alarm`) | `event` (each call) | `.../call` | |
| takes events (`mode`) | `number` (a box: sending one is `number.set_value`), `select` for a bool | the value topic (last sent) | `.../set` |

Entities join the board's device (``hubwire_<key>``, described as in :func:`.ha.device`) with unique
ids ``hubwire_<key>--hub-<channel>`` and object ids ``hub-<channel>``: no board channel has a ``-``
in its name, so none collides. Names and units are the board channels' (``Hub setpoint``, a unit
``C`` as ``°C`` with device class ``temperature``: :mod:`.ha_map`). Every entity is unavailable
while the service is away; what the board writes or calls also while the board is.
"""
from __future__ import annotations

from typing import Any, Dict, List, Optional, Tuple

from ..descriptor import Channel, Descriptor
from ..wire.scalars import INTEGER_TYPES, NUMERIC_TYPES, SCALARS
from .ha import ORIGIN, device
from .ha_map import NUMERIC, readable_name, unit_class
from .topics import OFFLINE, ONLINE, Topics, dumps, level

__all__ = ["hub_discovery", "entity"]


def _scalar(ch: Channel) -> Optional[str]:
    t = ch.codec.type_obj.get("t")
    return str(t) if ch.codec.kind == "scalar" else None


def _range(ch: Channel) -> Tuple[Optional[float], Optional[float]]:
    t = _scalar(ch)
    lo, hi = ch.min, ch.max
    if t in INTEGER_TYPES:
        lo = SCALARS[t][2] if lo is None else lo
        hi = SCALARS[t][3] if hi is None else hi
    return lo, hi


def entity(topics: Topics, service_id: str, key: str, desc: Descriptor, board_id: Optional[str],
           exp: Channel) -> Optional[Tuple[str, Dict[str, Any]]]:
    """``(platform, config)`` for hub channel ``exp`` of board ``key``, or None (no entity)."""
    node = topics.board(key).rpartition("/")[2]
    value = topics.board(key, "hub", level(exp.name))
    t = _scalar(exp)
    cfg: Dict[str, Any] = {
        "name": readable_name(f"hub_{exp.name}", exp.unit), "unique_id": f"hubwire_{node}--hub-{level(exp.name)}",
        "device": device(topics, key, desc, board_id),
        "origin": ORIGIN, "availability_mode": "all",
        "availability": [{"topic": topics.service_status(service_id), "payload_available": ONLINE,
                          "payload_not_available": OFFLINE}],
    }
    if "w" in exp.access or "c" in exp.access:
        # what the board writes or calls goes with the board; a value it reads, or an event for it,
        # may be set while it is away (it gets it when it is back)
        cfg["availability"].append({"topic": topics.status(key), "payload_available": ONLINE,
                                    "payload_not_available": OFFLINE})
    lo, hi = _range(exp)
    kind: Optional[str] = None
    if "c" in exp.access:
        kind = "event"
        cfg.update(state_topic=value + "/call", event_types=[exp.name])
    elif "e" in exp.access or "r" in exp.access:
        cfg["command_topic"] = value + "/set"
        cfg["state_topic"] = value
        if t == "bool":
            kind = "switch" if "r" in exp.access else "select"
            if kind == "switch":
                cfg.update(payload_on="true", payload_off="false", state_on="true", state_off="false")
            else:
                cfg["options"] = ["false", "true"]
        elif t in NUMERIC_TYPES:
            kind = "number"
            cfg["value_template"] = NUMERIC  # null (a NaN) is no value, not an error
            ranged = exp.min is not None and exp.max is not None
            low, high = float(lo if lo is not None else -1e9), float(hi if hi is not None else 1e9)
            cfg.update(min=low, max=high, mode="slider" if ranged else "box",
                       step=1 if t in INTEGER_TYPES else (max(0.001, round((high - low) / 100, 3)) if ranged else 0.1))
        elif exp.codec.kind == "str":
            kind = "text"
            cfg["value_template"] = "{{ value_json }}"
            cfg["command_template"] = "{{ value | tojson }}"
    elif "w" in exp.access:
        cfg["state_topic"] = value
        if t == "bool":
            kind = "binary_sensor"
            cfg.update(payload_on="true", payload_off="false")
        elif t in NUMERIC_TYPES or exp.codec.kind == "str":
            kind = "sensor"
            if t in NUMERIC_TYPES:
                cfg["state_class"] = "measurement"
                cfg["value_template"] = NUMERIC
            else:
                cfg["value_template"] = "{{ value_json }}"
    if kind is None:
        return None
    cls, unit = unit_class(exp.unit, exp.name)
    if unit and kind in ("sensor", "number") and t in NUMERIC_TYPES:
        cfg["unit_of_measurement"] = unit
        if cls:
            cfg["device_class"] = cls
    return kind, cfg


def hub_discovery(topics: Topics, service_id: str, key: str, desc: Descriptor, board_id: Optional[str],
                  names: List[str]) -> List[Tuple[str, str]]:
    """``(config topic, payload)`` for the hub channels ``names`` of a board (retained)."""
    out: List[Tuple[str, str]] = []
    node = topics.board(key).rpartition("/")[2]
    for exp in desc.hub:
        if exp.name not in names:
            continue
        got = entity(topics, service_id, key, desc, board_id, exp)
        if got is not None:
            kind, cfg = got
            out.append((f"{topics.discovery_prefix}/{kind}/{node}/hub-{level(exp.name)}/config", dumps(cfg)))
    return out
