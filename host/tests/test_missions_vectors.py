"""The golden vectors of missions (test/vectors/missions/frames.json): every frame encodes and
decodes as pinned, the scenarios name existing frames, and the hub's payload builders and parsers
agree with the vectors byte for byte."""
from __future__ import annotations

from typing import Any, Dict

import pytest

import hubwire

from hubwire.descriptor import parse_descriptor
from hubwire.wire import messages as m
from hubwire.wire.frame import encode_frame
from hubwire.wire.missions import MissionKind, MissionState, MissionUpdate, cancel_payload, start_payload

from missiondevice import MissionDevice, f32, wait_for
from framevectors import check_frame, load

DOC, BY_NAME = load("missions")


@pytest.mark.parametrize("v", DOC["vectors"], ids=[v["name"] for v in DOC["vectors"]])
def test_frame_codec(v: Dict[str, Any]) -> None:
    check_frame(v, kind=v["message"]["kind"])


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


def wire(f: Any) -> str:
    return encode_frame(f.type, f.seq, f.id, f.payload).hex()


def test_the_hub_plays_the_scenarios() -> None:
    """The hub's start and cancel payloads are the vectors'; it acks the device's updates with the
    vectors' ACKs, a repeated one too, delivering it once, and acks an unknown run's update."""
    with MissionDevice(DOC["descriptor"].encode()) as dev, \
            hubwire.connect(dev.path, timeout=5, cache_dir=False) as d:
        job = d.start("drive", 2.0)
        start = BY_NAME["hub starts drive: goal f32 2.0"]
        sent = [f for f in dev.received if f.type == m.CONTROL]
        assert [(f.id, f.payload.hex()) for f in sent] == [(start["id"], start["payload"])]
        assert job.run == 1
        sc = {s["name"]: s for s in DOC["scenarios"]}["a run reports progress and succeeds; a retried M is acked again and delivered once"]
        for name in sc["steps"][2:]:
            v = BY_NAME[name]
            if v["direction"] == "device":
                n = len(dev.received)
                dev.send(v["type"], v["seq"], v["id"], bytes.fromhex(v["payload"]))
                assert wait_for(lambda: len(dev.received) > n)
            else:
                assert wire(dev.received[-1]) == v["wire"], name
        assert list(job.feedback(timeout=5)) == [0.5, 1.25]
        assert job.result(timeout=5) == 2.0
        assert d.session.stats.duplicate_mission_updates == 1
        unknown = BY_NAME["drive run 9 progress f32 0.5 (a run the hub does not know)"]
        dev.send(unknown["type"], unknown["seq"], unknown["id"], bytes.fromhex(unknown["payload"]))
        ack = BY_NAME["hub acknowledges: " + unknown["name"]]
        assert wait_for(lambda: wire(dev.received[-1]) == ack["wire"])
        assert d.session.stats.unknown_mission_updates == 1
        with dev.lock2:
            dev.missions[7].running = False  # the sketch's run ended with the vectors' updates
        job2 = d.start("drive", 1.5)
        assert job2.cancel() is True
        cancel = BY_NAME["hub cancels drive run 1"]
        last_c = [f for f in dev.received if f.type == m.CONTROL][-1]  # (the hub's ACK of the final may follow)
        assert last_c.payload == cancel_payload(2) and bytes.fromhex(cancel["payload"]) == cancel_payload(1)
        assert f32(1.5) == dev.missions[7].starts[-1]
