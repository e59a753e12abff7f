"""Missions in the descriptor (access "m", progress "pt"/"pc"/"pmax"): the parser and the published
schema accept the same missions and refuse the same mistakes; old descriptors stay valid."""
from __future__ import annotations

import json
import pathlib
from typing import Any, Dict

import jsonschema
import pytest

from hubwire.descriptor import parse_descriptor
from hubwire.device import channel_table
from hubwire.errors import DescriptorError

SCHEMA = json.loads((pathlib.Path(__file__).resolve().parents[2] / "docs" / "descriptor.schema.json").read_text())
VALIDATOR = jsonschema.Draft202012Validator(SCHEMA)
DRIVE: Dict[str, Any] = {"id": 7, "n": "drive", "a": "m", "t": "f32", "rt": "f32", "pt": "f32", "u": "m",
                         "min": 0, "max": 10, "pmax": 2, "d": "drive straight"}


def doc(*channels: Dict[str, Any]) -> Dict[str, Any]:
    return {"p": 1, "n": "rover", "ch": list(channels)}


def test_a_mission_parses_with_goal_result_and_progress() -> None:
    d = doc(DRIVE, {"id": 8, "n": "home", "a": "m", "t": "void"},
            {"id": 9, "n": "scan", "a": "m", "t": "u8", "rt": "u16", "rc": 2, "pt": "i16", "pc": 3})
    VALIDATOR.validate(d)
    desc = parse_descriptor(json.dumps(d))
    drive, home, scan = desc.channels
    assert drive.mission and not drive.callable and not drive.readable
    assert (drive.codec.name, drive.returns.name if drive.returns else None,
            drive.progress.name if drive.progress else None, drive.progress_max) == ("f32", "f32", "f32", 2)
    assert (home.codec.kind, home.returns.kind if home.returns else None, home.progress.kind if home.progress else None,
            home.progress_max) == ("void", "void", "void", None)
    assert scan.type_name == "(u8) -> u16[2], progress i16[3]"
    assert "mission" in channel_table(desc).splitlines()[2]


@pytest.mark.parametrize("change, message", [
    ({"a": "mr"}, "mission 'm' stands alone"),
    ({"a": "mm"}, "repeated access letter"),
    ({"fs": 1}, "failsafe"),
    ({"rt": "str", "rc": 4}, "not allowed here"),
    ({"pt": "str", "pc": 4}, "not allowed here"),
    ({"pt": "struct"}, "not allowed here"),
    ({"pmax": "two"}, "'pmax' must be a number"),
    ({"pt": None, "pc": 2}, "'pc' given without a progress type"),
    ({"pt": "u8", "pc": 254}, "does not fit a mission update"),
    ({"t": "u8", "c": 255, "min": None, "max": None}, "does not fit a start"),
])
def test_the_parser_and_the_schema_refuse_a_bad_mission(change: Dict[str, Any], message: str) -> None:
    ch = {k: v for k, v in dict(DRIVE, **change).items() if v is not None}
    with pytest.raises(DescriptorError, match=message):
        parse_descriptor(json.dumps(doc(ch)))
    if message != "does not fit a mission update" and message != "does not fit a start":  # sizes: the parser's
        assert not VALIDATOR.is_valid(doc(ch))


@pytest.mark.parametrize("ch", [
    {"id": 1, "n": "x", "a": "c", "t": "u8", "pt": "u8"},
    {"id": 1, "n": "x", "a": "rw", "t": "u8", "pmax": 3},
    {"id": 1, "n": "x", "a": "e", "t": "u8", "pc": 2},
])
def test_progress_keys_are_only_for_missions(ch: Dict[str, Any]) -> None:
    with pytest.raises(DescriptorError, match="only for missions"):
        parse_descriptor(json.dumps(doc(ch)))
    assert not VALIDATOR.is_valid(doc(ch))


def test_a_hub_channel_is_never_a_mission() -> None:
    d = dict(doc(), hub=[{"id": 1, "n": "drive", "a": "m", "t": "f32"}])
    with pytest.raises(DescriptorError, match="not a mission"):
        parse_descriptor(json.dumps(d))
