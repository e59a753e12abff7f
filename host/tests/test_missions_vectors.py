"""The golden vectors of missions (test/vectors/missions/frames.json): every frame encodes and
decodes as pinned, the scenarios name existing frames, and the hub's payload builders and parsers
agree with the vectors byte for byte."""
from __future__ import annotations

import json
import pathlib
from typing import Any, Dict

import pytest

from hubwire.descriptor import parse_descriptor
from hubwire.wire import messages as m
from hubwire.wire.frame import FrameDecoder, encode_frame
from hubwire.wire.missions import MissionKind, MissionState, MissionUpdate, cancel_payload, start_payload

VECTORS = pathlib.Path(__file__).resolve().parents[2] / "test" / "vectors" / "missions" / "frames.json"
DOC = json.loads(VECTORS.read_text())
BY_NAME: Dict[str, Dict[str, Any]] = {v["name"]: v for v in DOC["vectors"]}


@pytest.mark.parametrize("v", DOC["vectors"], ids=[v["name"] for v in DOC["vectors"]])
def test_frame_codec(v: Dict[str, Any]) -> None:
    payload = bytes.fromhex(v["payload"])
    wire = encode_frame(v["type"], v["seq"], v["id"], payload)
    assert wire.hex() == v["wire"]
    (f,) = FrameDecoder(255).feed(wire)
    assert (f.type, f.seq, f.id, f.payload) == (v["type"], v["seq"], v["id"], payload)
    assert m.describe(f, v["message"]["kind"]) == v["message"]


def test_payload_builders_match() -> None:
    desc = parse_descriptor(DOC["descriptor"])
    drive = desc.by_name("drive")
    assert drive is not None and drive.mission
    start = BY_NAME["hub starts drive: goal f32 2.0"]
    assert start_payload(drive.codec.encode(drive.check(2.0))).hex() == start["payload"]
    assert cancel_payload(1).hex() == BY_NAME["hub cancels drive run 1"]["payload"]
    u = MissionUpdate.unpack(bytes.fromhex(BY_NAME["drive run 1 succeeded: f32 2.0"]["payload"]))
    assert (u.run, u.kind, drive.returns.decode(u.data) if drive.returns else None) == (1, MissionKind.SUCCEEDED, 2.0)
    assert MissionState.unpack(bytes.fromhex(BY_NAME["device: run 1 running"]["payload"])) == MissionState(1, True)


@pytest.mark.parametrize("payload", ["01", "0105", "0100", "0103", "01030102", "010401"])
def test_malformed_updates_are_refused(payload: str) -> None:
    with pytest.raises(m.PayloadError):
        MissionUpdate.unpack(bytes.fromhex(payload))


def test_scenarios_name_frames_that_alternate_sensibly() -> None:
    for sc in DOC["scenarios"]:
        frames = [BY_NAME[s] for s in sc["steps"]]
        # every hub question is followed by the device's answer with its seq and id, and every M by the hub's ACK
        for ask, ans in zip(frames[::2], frames[1::2]):
            assert (ask["seq"], ask["id"]) == (ans["seq"], ans["id"]), sc["name"]
            assert ask["direction"] != ans["direction"], sc["name"]
