"""The golden vectors of large values and lists (test/vectors/large/frames.json): every frame encodes
and decodes as pinned, the hub fragments a large message into exactly the pinned frames, and its
reassembler puts the pinned fragments back together (or drops them) as the exchanges say."""
from __future__ import annotations

import json
from typing import Any, Dict, List

import pytest

from hubwire.descriptor import parse_descriptor
from hubwire.errors import InvalidValue
from hubwire.session.fragments import Reassembler, encode_message
from hubwire.session.windows import WindowAssembly, window_request
from hubwire.wire import messages as m
from hubwire.wire.frame import FrameDecoder, encode_frame
from framevectors import check_frame, load

DOC, BY_NAME = load("large")
BIG = bytes.fromhex(DOC["big"])
LIMIT = DOC["max_payload"]


class Counters:
    dropped = 0


def wires(names: List[str]) -> bytes:
    return b"".join(bytes.fromhex(BY_NAME[n]["wire"]) for n in names)


def starting(prefix: str) -> List[str]:
    return [n for n in BY_NAME if n.startswith(prefix)]


@pytest.mark.parametrize("v", DOC["vectors"], ids=[v["name"] for v in DOC["vectors"]])
def test_frame_codec(v: Dict[str, Any]) -> None:
    check_frame(v, LIMIT)


@pytest.mark.parametrize("prefix,type,seq,payload", [
    ("hub writes big (200 bytes, seq 0x10), fragment", m.CONTROL, 0x10, BIG),
    ("device answers the read of big (seq 0x11), fragment", m.RESPONSE, 0x11, BIG),
    ("device streams a sample of big", m.SAMPLE, 0, b"\x00\x00" + BIG),
])
def test_a_large_message_is_split_into_the_pinned_fragments(prefix: str, type: int, seq: int, payload: bytes) -> None:
    names = starting(prefix)
    assert len(names) == 8
    assert encode_message(type, seq, 1, payload, LIMIT) == wires(names)
    # and a message that fits is one plain frame
    assert encode_message(type, seq, 1, payload[:LIMIT], LIMIT) == encode_frame(type, seq, 1, payload[:LIMIT])


def test_the_pinned_fragments_reassemble_into_the_message() -> None:
    r = Reassembler(Counters())
    got = [r.feed(f) for f in FrameDecoder(LIMIT).feed(wires(starting("device answers the read of big")))]
    assert got[:-1] == [None] * 7
    assert got[-1] == (m.RESPONSE, 0x11, 1, BIG)


@pytest.mark.parametrize("e", DOC["exchanges"], ids=[e["name"] for e in DOC["exchanges"]])
def test_exchange_through_a_reassembler(e: Dict[str, Any]) -> None:
    """What the device's reassembly gives (whole messages, dropped count) is what the hub's gives;
    only a total over the device's capacity differs (the hub holds any total)."""
    counters = Counters()
    r = Reassembler(counters)
    whole = []
    for f in FrameDecoder(LIMIT).feed(wires(e["send"])):
        if f.type == m.FRAGMENT:
            f = r.feed(f)  # type: ignore[assignment]
        if f is not None:
            whole.append(f)
    assert all(len(w.payload) <= LIMIT or w.type == m.CONTROL for w in whole)
    if "over the channel's size" in e["name"]:
        assert (len(whole), counters.dropped) == (1, 0)  # 201 bytes: the hub would take them
        assert len(whole[0].payload) == 201
        return
    assert counters.dropped == e["dropped"]
    # every message the device handles gets exactly one answer (whole), with its seq and id
    answers = Reassembler(Counters())
    got = [a for a in FrameDecoder(LIMIT).feed(wires(e["answer"]))
           if a.type != m.FRAGMENT or answers.feed(a) is not None]
    assert [(w.seq, w.id) for w in whole] == [(a.seq, a.id) for a in got]


def test_the_window_vector_is_what_the_hub_asks_and_assembles() -> None:
    ask = BY_NAME["hub asks for a window of big: 100 bytes from offset 50 (seq 0x12)"]
    assert bytes.fromhex(ask["payload"]) == window_request(50, 100)
    answer = bytes.fromhex(BY_NAME[starting("device answers the window: offset 50")[0]]["payload"])
    asm = WindowAssembly()
    assert asm.add(50, answer) is None
    assert (asm.total, asm.hash, asm.next_offset()) == (200, m.fnv1a32(BIG), 0)
    assert answer[8:] == BIG[50:74]


def test_lists_on_the_channel_of_the_vectors() -> None:
    desc = parse_descriptor(json.dumps({"p": 1, "n": "large", "ch": DOC["channels"]}))
    path = desc.by_name("path")
    assert path is not None
    ok = BY_NAME["hub writes path = [1, -2, 1000] (seq 0x20)"]
    assert path.codec.encode(path.check([1, -2, 1000])).hex() == ok["payload"]
    assert path.codec.decode(bytes.fromhex(ok["payload"])) == [1, -2, 1000]
    for e in DOC["exchanges"]:
        if not e["name"].startswith("path: "):
            continue
        sent = BY_NAME[e["send"][1]]
        code = m.NakCode[BY_NAME[e["answer"][1]]["message"]["error"]]
        with pytest.raises(InvalidValue) as ex:
            path.check(path.codec.decode(bytes.fromhex(sent["payload"])))
        assert ex.value.code == code, e["name"]
