"""How a channel's type and unit become Home Assistant entity settings (docs/MQTT.md, "Entity
mapping"): names, device classes, state classes, categories and the templates that turn the
bridge's JSON states into states Home Assistant accepts.

Device classes come from the unit alone, never from a channel's name, except the two documented
cases of ``%`` (a name with ``humid`` is humidity, one with ``batt`` a battery level): a wrong
device class is worse than none (Home Assistant converts and graphs by it). Every unit here is one
Home Assistant accepts for the device class it maps to.
"""
from __future__ import annotations

from typing import Any, Dict, Optional, Tuple

from ..wire.scalars import FLOAT_TYPES, INTEGER_TYPES, NUMERIC_TYPES
from ..wire.values import Codec

__all__ = ["UNITS", "unit_class", "readable_name", "value_keys", "json_text", "MAX_STATE"]

#: a unit as a sketch may write it -> (device class, the unit as Home Assistant spells it)
UNITS: Dict[str, Tuple[str, str]] = {
    "V": ("voltage", "V"), "mV": ("voltage", "mV"),
    "A": ("current", "A"), "mA": ("current", "mA"),
    "W": ("power", "W"), "kW": ("power", "kW"),
    "C": ("temperature", "°C"), "°C": ("temperature", "°C"), "degC": ("temperature", "°C"),
    "F": ("temperature", "°F"), "°F": ("temperature", "°F"), "K": ("temperature", "K"),
    "Pa": ("pressure", "Pa"), "hPa": ("pressure", "hPa"), "kPa": ("pressure", "kPa"),
    "bar": ("pressure", "bar"), "mbar": ("pressure", "mbar"),
    "lx": ("illuminance", "lx"),
    "Hz": ("frequency", "Hz"), "kHz": ("frequency", "kHz"),
    "mm": ("distance", "mm"), "cm": ("distance", "cm"), "m": ("distance", "m"), "km": ("distance", "km"),
    "m/s": ("speed", "m/s"), "km/h": ("speed", "km/h"),
    "ms": ("duration", "ms"), "s": ("duration", "s"), "min": ("duration", "min"), "h": ("duration", "h"),
    "g": ("weight", "g"), "kg": ("weight", "kg"),
    "dBm": ("signal_strength", "dBm"),
}

#: the longest state Home Assistant keeps (a longer one becomes ``unknown`` with an error)
MAX_STATE = 255

#: a numeric state: JSON ``null`` (a NaN or infinity the board sent) renders ``None``, which Home
#: Assistant's MQTT sensor and number take as "no value" (state ``unknown``), not as an error
NUMERIC = "{{ value_json }}"
#: a string's text without JSON's quotes (a bounded string holds at most 254 bytes: it always fits)
TEXT = "{{ value_json }}"
#: an array's or struct's JSON text as the state, cut; the whole value is in the attributes
JSON_TEXT = "{{ value if value | length <= 255 else value[:252] ~ '...' }}"


def json_text(path: str) -> str:
    """A template: the JSON text of ``path`` in the payload, cut to what Home Assistant keeps."""
    return "{% set s = " + path + " | to_json %}{{ s if s | length <= 255 else s[:252] ~ '...' }}"


def unit_class(unit: Optional[str], name: str) -> Tuple[Optional[str], Optional[str]]:
    """``(device_class, unit)`` for a channel's unit: the class None when the unit implies none."""
    if not unit:
        return None, None
    if unit in UNITS:
        return UNITS[unit]
    if unit == "%":
        low = name.lower()
        if "humid" in low:
            return "humidity", "%"
        if "batt" in low:
            return "battery", "%"
    return None, unit


def readable_name(name: str, unit: Optional[str] = None) -> str:
    """``uptime_ms`` -> ``Uptime`` (a trailing unit dropped: the unit is shown anyway),
    ``left_motor`` -> ``Left motor``."""
    words = [w for w in name.split("_") if w]
    if len(words) > 1 and unit and words[-1].lower() == unit.lower():
        words = words[:-1]
    text = " ".join(words) or name
    return text[:1].upper() + text[1:]


def _scalar(codec: Optional[Codec]) -> Optional[str]:
    return getattr(codec, "scalar", None) if codec is not None and codec.kind == "scalar" else None


def is_counter(access: str, codec: Codec, unit: Optional[str]) -> bool:
    """A read-only, not streamed unsigned integer without a unit counts something (failsafes,
    writes): ``total_increasing`` (a reboot's reset is taken as a reset), shown as diagnostic."""
    t = _scalar(codec)
    return access == "r" and t in INTEGER_TYPES and t is not None and t.startswith("u") and not unit


def value_keys(codec: Optional[Codec], unit: Optional[str], name: str, path: str = "value_json",
               counter: bool = False) -> Tuple[str, Dict[str, Any]]:
    """``(platform, keys)`` showing a JSON value read from a state topic: ``binary_sensor`` for a
    bool, else ``sensor``. ``path`` is the JSON in the topic's payload that holds the value
    (``value_json.value`` for a call's result)."""
    t = _scalar(codec)
    plain = path == "value_json"
    if t == "bool":
        if plain:
            return "binary_sensor", {"payload_on": "true", "payload_off": "false"}
        return "binary_sensor", {"value_template": f"{{{{ 'ON' if {path} else 'OFF' }}}}"}
    keys: Dict[str, Any] = {}
    if t in NUMERIC_TYPES:
        cls, shown = unit_class(unit, name)
        keys["value_template"] = NUMERIC.replace("value_json", path)
        if cls:
            keys["device_class"] = cls
        if shown:
            keys["unit_of_measurement"] = shown
        if counter:
            keys["state_class"] = "total_increasing"
        else:
            keys["state_class"] = "measurement"
        if t in FLOAT_TYPES:
            keys["suggested_display_precision"] = 2
    elif codec is not None and codec.kind == "str":
        keys["value_template"] = TEXT.replace("value_json", path)
    elif codec is not None and codec.kind in ("array", "list", "struct"):
        # not a number: no unit, no state class (HA would refuse every update); the value's JSON
        # is the state (cut to 255) and, whole, the entity's attributes
        keys["value_template"] = JSON_TEXT if plain else json_text(path)
        if codec.kind == "struct":
            keys["json_attributes_template"] = "{{ %s | to_json }}" % path
        else:
            keys["json_attributes_template"] = "{{ {'values': %s} | to_json }}" % path
    else:
        keys["value_template"] = "{{ %s | to_json }}" % path
    return "sensor", keys
