"""The published JSON Schema (docs/descriptor.schema.json) accepts what the hub writes and reads:
a device descriptor with a "hub" list, and the hub's own descriptor in every kind of channel."""
from __future__ import annotations

import json
import pathlib

import jsonschema
import pytest

from hubwire import HubChannels
from hubwire.descriptor import parse_descriptor

from hubdevice import DESCRIPTOR

SCHEMA = json.loads((pathlib.Path(__file__).resolve().parents[2] / "docs" / "descriptor.schema.json").read_text())
VALIDATOR = jsonschema.Draft202012Validator(SCHEMA)


def every_kind() -> HubChannels:
    hub = HubChannels("home")
    hub.provide("setpoint", 21.5, unit="C", min=5, max=30, doc="target")
    hub.provide("clock", lambda: 0, type="u32", writable=True)
    hub.provide("name", "kitchen", type="str[12]")
    hub.accept("report", type="struct", fields={"temp": "f32", "gyro": "i16[3]"})
    hub.action("dock", lambda speed: True, type="f32", returns="bool")
    hub.action("stamp", lambda: (1, 2), type="void", returns="u16[2]")
    hub.event("mode", type="u8")
    return hub


def test_the_hub_descriptor_matches_the_schema_and_the_parser() -> None:
    raw = every_kind().descriptor()
    VALIDATOR.validate(json.loads(raw))
    assert [c.name for c in parse_descriptor(raw).channels] == ["setpoint", "clock", "name", "report", "dock",
                                                              "stamp", "mode"]


def test_a_device_descriptor_with_a_hub_list_matches_the_schema() -> None:
    VALIDATOR.validate(json.loads(DESCRIPTOR))
    assert len(parse_descriptor(DESCRIPTOR).hub) == 5


@pytest.mark.parametrize("bad", [
    {"hub": {}},                                                   # not a list
    {"hub": [{"id": 1, "n": "x", "a": "r"}]},                      # no type
    {"hub": [{"id": 1, "n": "x", "a": "r", "t": "f32", "z": 1}]},  # unknown key
    {"hubs": []},                                                  # unknown top-level key
])
def test_the_schema_and_the_parser_refuse_a_bad_hub_list(bad: dict) -> None:
    doc = dict(json.loads(DESCRIPTOR), **bad)
    if "hubs" in bad:
        del doc["hub"]
    assert not VALIDATOR.is_valid(doc)
    with pytest.raises(ValueError):
        parse_descriptor(json.dumps(doc))


LISTS = {"p": 1, "n": "d", "ch": [{"id": 1, "n": "path", "a": "rw", "t": "i16", "vc": 8},
                                  {"id": 2, "n": "blob", "a": "rws", "t": "u8", "c": 1024},
                                  {"id": 3, "n": "pick", "a": "c", "t": "u8", "vc": 3, "rt": "bool", "rvc": 2}]}


def test_variable_length_arrays_and_large_arrays_match_the_schema() -> None:
    VALIDATOR.validate(LISTS)
    assert len(parse_descriptor(json.dumps(LISTS)).channels) == 3


@pytest.mark.parametrize("change", [
    {"vc": 0}, {"vc": 256}, {"vc": 4, "c": 4}, {"t": "str", "vc": 4}, {"rvc": 2},
])
def test_the_schema_and_the_parser_refuse_a_bad_variable_length_array(change: dict) -> None:
    doc = json.loads(json.dumps(LISTS))
    doc["ch"][0].update(change)
    assert not VALIDATOR.is_valid(doc)
    with pytest.raises(ValueError):
        parse_descriptor(json.dumps(doc))
