"""Golden vectors (test/vectors/*.json): every file must be consumed by a checker below."""
from __future__ import annotations

import glob
import json
import os
import subprocess
import sys
from typing import Any, Callable, Dict

import pytest
from cobs import cobs

from hubwire.errors import InvalidValue
from hubwire.wire.frame import Frame, FrameDecoder, crc16, encode_frame
from hubwire.wire.messages import NakCode, describe
from hubwire.wire.values import codec_for

VECTORS = os.path.join(os.path.dirname(__file__), "..", "..", "test", "vectors")


def load(name: str) -> Dict[str, Any]:
    with open(os.path.join(VECTORS, name)) as fh:
        doc = json.load(fh)
    assert set(doc) == {"description", "vectors"}, name
    assert doc["vectors"], f"{name} has no vectors"
    names = [v["name"] for v in doc["vectors"]]
    assert len(names) == len(set(names)), f"{name}: duplicate vector names"
    return doc


def check_crc(v: Dict[str, Any]) -> None:
    assert crc16(bytes.fromhex(v["data"])) == v["crc"]


def check_cobs(v: Dict[str, Any]) -> None:
    dec, enc = bytes.fromhex(v["decoded"]), bytes.fromhex(v["encoded"])
    assert b"\x00" not in enc
    assert cobs.encode(dec) == enc
    assert cobs.decode(enc) == dec


def check_frame(v: Dict[str, Any]) -> None:
    payload = bytes.fromhex(v["payload"])
    wire = bytes.fromhex(v["wire"])
    assert encode_frame(v["type"], v["seq"], v["id"], payload) == wire
    assert wire.endswith(b"\x00") and wire.count(b"\x00") == 1
    d = FrameDecoder(255)
    assert d.feed(wire) == [Frame(v["type"], v["seq"], v["id"], payload)]
    assert d.counters() == {"crc": 0, "overflow": 0, "dropped": 0}
    msg = v["message"]
    assert describe(Frame(v["type"], v["seq"], v["id"], payload), msg["kind"]) == msg


def check_stream(v: Dict[str, Any]) -> None:
    data = bytes.fromhex(v["input"])
    expect = [Frame(f["type"], f["seq"], f["id"], bytes.fromhex(f["payload"])) for f in v["frames"]]
    d = FrameDecoder(v["max_payload"])
    got = []
    for i in range(len(data)):
        got.extend(d.feed(data[i:i + 1]))
    assert got == expect
    assert d.counters() == v["counters"]
    # the hot path feeds whole reads; it must agree with byte-by-byte feeding
    d2 = FrameDecoder(v["max_payload"])
    assert d2.feed(data) == expect
    assert d2.counters() == v["counters"]


def check_value(v: Dict[str, Any]) -> None:
    c = codec_for(v["type"])
    raw = bytes.fromhex(v["hex"])
    assert c.encode(c.from_json(v["value"])) == raw
    assert c.to_json(c.decode(raw)) == v["value"]


def check_invalid(v: Dict[str, Any]) -> None:
    c = codec_for(v["type"])
    with pytest.raises(InvalidValue) as ei:
        c.decode(bytes.fromhex(v["hex"]))
    assert ei.value.code == NakCode[v["error"]]
    assert ei.value.error == v["error"]


KNOWN: Dict[str, Callable[[Dict[str, Any]], None]] = {
    "crc.json": check_crc,
    "cobs.json": check_cobs,
    "frames.json": check_frame,
    "streams.json": check_stream,
    "values.json": check_value,
    "values_invalid.json": check_invalid,
}


def test_every_vector_file_is_known() -> None:
    present = {os.path.basename(p) for p in glob.glob(os.path.join(VECTORS, "*.json"))}
    unknown = present - set(KNOWN)
    assert not unknown, f"vector files this suite does not consume: {sorted(unknown)}"
    missing = set(KNOWN) - present
    assert not missing, f"vector files missing: {sorted(missing)}"


def _cases():  # type: ignore[no-untyped-def]
    for name in sorted(KNOWN):
        path = os.path.join(VECTORS, name)
        if not os.path.exists(path):
            continue
        for v in load(name)["vectors"]:
            yield pytest.param(name, v, id=f"{name}:{v['name']}")


@pytest.mark.parametrize("name,vector", list(_cases()))
def test_vector(name: str, vector: Dict[str, Any]) -> None:
    KNOWN[name](vector)


def test_published_references_present() -> None:
    crc = {v["data"]: v["crc"] for v in load("crc.json")["vectors"]}
    assert crc[b"123456789".hex()] == 0x29B1
    cobs_v = {v["decoded"]: v["encoded"] for v in load("cobs.json")["vectors"]}
    assert cobs_v["00"] == "0101"
    assert cobs_v["0000"] == "010101"
    assert cobs_v["11220033"] == "0311220233"


def test_frames_cover_every_message_kind() -> None:
    kinds = {v["message"]["kind"] for v in load("frames.json")["vectors"]}
    assert kinds == {"hello", "heartbeat", "chunk_request", "chunk", "request", "response", "control",
                     "ack", "nak", "event", "subscribe", "sample"}
    acks = [v["message"] for v in load("frames.json")["vectors"] if v["message"]["kind"] == "ack"]
    assert any("granted_ms" in a for a in acks) and any("granted_ms" not in a for a in acks)
    sizes = {len(v["payload"]) // 2 for v in load("frames.json")["vectors"]}
    assert {0, 249, 250, 253, 254, 255} <= sizes


def test_generator_is_deterministic_and_files_up_to_date() -> None:
    gen = os.path.join(VECTORS, "generate.py")
    r = subprocess.run([sys.executable, gen, "--check"], capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr
