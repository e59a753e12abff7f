"""The golden vectors of both directions (test/vectors/both/frames.json): every frame encodes and
decodes as pinned, and the hub's session answers the device frames of the vectors with exactly the
hub frames of the vectors (a scripted device sends them with their seq)."""
from __future__ import annotations

import struct
import time
from typing import Any, Dict, List

import pytest

import hubwire
from hubwire import HubChannels
from hubwire.wire import messages as m
from hubwire.wire.frame import encode_frame

from hubdevice import HubDevice
from framevectors import check_frame, load

DOC, BY_NAME = load("both")
DEVICE = (b'{"p":1,"n":"thermo","ch":[],"hub":[{"id":1,"n":"setpoint","a":"r","t":"f32"},'
          b'{"id":2,"n":"report","a":"w","t":"u16"},{"id":3,"n":"dock","a":"c","t":"f32","rt":"bool"},'
          b'{"id":4,"n":"mode","a":"e","t":"u8"}]}')


@pytest.mark.parametrize("v", DOC["vectors"], ids=[v["name"] for v in DOC["vectors"]])
def test_frame_codec(v: Dict[str, Any]) -> None:
    check_frame(v, kind=v["message"]["kind"])


def vector_hub(refuse: List[int]) -> HubChannels:
    """The hub of the vectors: its descriptor is byte for byte the one the chunks read."""
    hub = HubChannels("hub")
    hub.provide("setpoint", 21.5, unit="C")
    hub.accept("report", lambda v: v not in refuse, type="u16")
    hub.action("dock", lambda speed: speed > 0, type="f32", returns="bool")
    hub.event("mode", type="u8")
    return hub


def test_hub_descriptor_and_hello() -> None:
    hub = vector_hub([])
    assert hub.descriptor() == DOC["hub_descriptor"].encode()
    v = BY_NAME["hub hello with its descriptor hash and length"]
    hello = m.Hello(1, 0, 0x0BADCAFE, 255, 250, hub.descriptor_hash(), len(hub.descriptor()))
    assert hello.pack().hex() == v["payload"]


def frame(name: str) -> Any:
    v = BY_NAME[name]
    return v["type"], v["seq"], v["id"], bytes.fromhex(v["payload"])


# (the device's frame: a vector, or (type, seq, id, payload) for one the vectors only answer), the answer
READS = [
    ("device reads hub id 1", "hub answers the read: f32 21.5"),
    ((m.REQUEST, 6, 2, b""), "hub refuses a read of a value the device may not read"),
    ((m.REQUEST, 7, 9, b""), "hub refuses an unknown hub id"),
    ("device calls hub id 3 with f32 0.25", "hub returns the action's value: bool true"),
    ("device asks for the hub descriptor from 0, up to 28 bytes", "hub answers the first chunk of its descriptor"),
    ((m.CHUNK, 16, 0, m.ChunkRequest(191, 28).pack()), "hub answers the last chunk of its descriptor"),
    ((m.CHUNK, 17, 0, m.ChunkRequest(202, 28).pack()), "hub refuses an offset past its descriptor"),
]
# after "report" is declared again with a range (the descriptor changes, so after the chunks)
WRITES = [
    ("device writes hub id 2: u16 1234", "hub acknowledges the write"),
    ((m.CONTROL, 9, 2, struct.pack("<H", 2000)), "hub refuses the write: out of range"),
    ((m.CONTROL, 10, 2, struct.pack("<H", 13)), "hub refuses the write: its handler refused"),
    ((m.CONTROL, 11, 1, struct.pack("<f", 1.0)), "hub refuses a write of a value the device may not write"),
    ((m.CONTROL, 12, 2, b"\x01"), "hub refuses the write: wrong length"),
]


def exchange(dev: HubDevice, pairs: List[Any]) -> None:
    for ask, answer in pairs:
        t, seq, cid, payload = frame(ask) if isinstance(ask, str) else ask
        a = dev.ask(t, cid, payload, seq=seq)
        assert a is not None, ask
        assert encode_frame(a.type, a.seq, a.id, a.payload).hex() == BY_NAME[answer]["wire"], answer


def test_hub_answers_as_the_vectors() -> None:
    with HubDevice(DEVICE) as dev, hubwire.connect(dev.path, timeout=5, cache_dir=False, hub=vector_hub([])) as d:
        end = time.monotonic() + 5
        while not dev.binds and time.monotonic() < end:
            time.sleep(0.01)
        assert dev.binds == [bytes.fromhex(BY_NAME["bind report, all bound"]["payload"])]
        exchange(dev, READS)
        d.accept("report", lambda v: v != 13, type="u16", max=1500)
        exchange(dev, WRITES)
        d.notify("mode", 2)
        end = time.monotonic() + 5
        while not dev.events and time.monotonic() < end:
            time.sleep(0.01)
        ev = BY_NAME["hub event: hub id 4, u8 2"]
        assert dev.events == [(ev["id"], bytes.fromhex(ev["payload"]))]
        assert d.hub["report"].value == 1234
