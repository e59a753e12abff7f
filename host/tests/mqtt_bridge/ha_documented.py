"""The configuration keys Home Assistant documents for MQTT discovery, per platform, written down
from its documentation (home-assistant.io, source/_integrations/<platform>.mqtt.markdown, the
``{% configuration %}`` blocks; the discovery topic and ``origin`` from mqtt.markdown). The tests
check every key the bridge sends against these lists, and the documented required keys."""
from __future__ import annotations

import re
from typing import Dict, FrozenSet

#: ``<discovery_prefix>/<component>/[<node_id>/]<object_id>/config``; ids from [a-zA-Z0-9_-]
TOPIC = re.compile(r"(?P<prefix>[^/]+)/(?P<component>[a-z_]+)/(?:(?P<node>[a-zA-Z0-9_-]+)/)?(?P<obj>[a-zA-Z0-9_-]+)/config\Z")

_COMMON = frozenset({
    "availability", "availability_mode", "availability_template", "availability_topic", "device",
    "enabled_by_default", "encoding", "entity_category", "entity_picture", "icon",
    "json_attributes_template", "json_attributes_topic", "name", "object_id", "platform", "qos",
    "unique_id", "origin",
})

KEYS: Dict[str, FrozenSet[str]] = {
    "sensor": _COMMON | {"device_class", "expire_after", "force_update", "last_reset_value_template",
                         "options", "payload_available", "payload_not_available",
                         "suggested_display_precision", "state_class", "state_topic",
                         "unit_of_measurement", "value_template"},
    "number": _COMMON | {"command_template", "command_topic", "device_class", "min", "max", "mode",
                         "optimistic", "payload_reset", "retain", "state_topic", "step",
                         "unit_of_measurement", "value_template"},
    "switch": _COMMON | {"command_template", "command_topic", "device_class", "optimistic",
                         "payload_available", "payload_not_available", "payload_off", "payload_on",
                         "retain", "state_off", "state_on", "state_topic", "value_template"},
    "button": _COMMON | {"command_template", "command_topic", "device_class", "payload_available",
                         "payload_not_available", "payload_press", "retain"},
    "event": _COMMON | {"device_class", "event_types", "payload_available", "payload_not_available",
                        "state_topic", "value_template"},
    "binary_sensor": _COMMON | {"device_class", "expire_after", "force_update", "off_delay",
                                "payload_available", "payload_not_available", "payload_off",
                                "payload_on", "state_topic", "value_template"},
    "text": _COMMON | {"command_template", "command_topic", "max", "min", "mode", "pattern",
                       "retain", "state_topic", "value_template"},
    "select": _COMMON | {"command_template", "command_topic", "optimistic", "options", "retain",
                         "state_topic", "value_template"},
}

#: required keys (``platform`` only in device-based discovery, which the bridge does not use)
REQUIRED: Dict[str, FrozenSet[str]] = {
    "sensor": frozenset({"state_topic"}),
    "number": frozenset({"command_topic"}),
    "switch": frozenset({"command_topic"}),
    "button": frozenset({"command_topic"}),
    "event": frozenset({"state_topic", "event_types"}),
    "binary_sensor": frozenset({"state_topic"}),
    "text": frozenset({"command_topic"}),
    "select": frozenset({"command_topic", "options"}),
}

DEVICE_KEYS = frozenset({"configuration_url", "connections", "hw_version", "identifiers", "manufacturer",
                         "model", "model_id", "name", "serial_number", "suggested_area", "sw_version",
                         "via_device"})
AVAILABILITY_KEYS = frozenset({"payload_available", "payload_not_available", "topic", "value_template"})
AVAILABILITY_MODES = frozenset({"all", "any", "latest"})
ORIGIN_KEYS = frozenset({"name", "sw_version", "support_url"})
