"""The hub's fragmenter and reassembler (hubwire.session.fragments, PROTOCOL.md 12) on their own."""
from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hubwire.session.fragments import MAX_TOTAL, Reassembler, accepted, encode_message, fragments
from hubwire.wire import messages as m
from hubwire.wire.frame import Frame, FrameDecoder


class Counters:
    dropped = 0


def frames(t: int, seq: int, cid: int, payload: bytes, limit: int) -> "list[Frame]":
    return FrameDecoder(255).feed(encode_message(t, seq, cid, payload, limit))


def test_accepted_payload_is_clamped_as_a_hello_says() -> None:
    assert (accepted(None), accepted(8), accepted(32), accepted(1000)) == (255, 16, 32, 255)


@pytest.mark.parametrize("size,limit,count", [(32, 32, 1), (33, 32, 2), (54, 32, 2), (55, 32, 3), (1024, 32, 38),
                                              (256, 255, 2), (1024, 16, 94)])
def test_split_sizes(size: int, limit: int, count: int) -> None:
    payload = (bytes(range(256)) * 4)[:size]
    fs = frames(m.CONTROL, 1, 2, payload, limit)
    assert len(fs) == count
    assert all(len(f.payload) <= limit for f in fs)
    if count > 1:
        assert all(f.type == m.FRAGMENT and (f.seq, f.id) == (1, 2) for f in fs)
        assert Reassembler(Counters()).feed(fs[0]) is None
        r = Reassembler(Counters())
        assert [r.feed(f) for f in fs][-1] == (m.CONTROL, 1, 2, payload)
    else:
        assert fs == [(m.CONTROL, 1, 2, payload)]


def test_too_large_to_carry() -> None:
    with pytest.raises(ValueError):
        fragments(m.CONTROL, bytes(MAX_TOTAL + 1), 32)


def test_reassembly_rules() -> None:
    c = Counters()
    r = Reassembler(c)
    payload = bytes(range(100))
    fs = frames(m.RESPONSE, 7, 3, payload, 32)
    assert len(fs) == 4
    # complete, in order
    assert [r.feed(f) for f in fs][-1] == (m.RESPONSE, 7, 3, payload)
    # a repeated fragment abandons the value; the rest of it is dropped too
    got = [r.feed(f) for f in (fs[0], fs[1], fs[1], fs[2], fs[3])]
    assert got == [None] * 5 and c.dropped == 3
    # a new offset 0 restarts: the first attempt's tail never joins the second
    got = [r.feed(f) for f in (fs[0], fs[1], fs[0], fs[1], fs[2], fs[3])]
    assert got[-1] == (m.RESPONSE, 7, 3, payload) and c.dropped == 3
    # another seq, id or total in the middle abandons it
    other = frames(m.RESPONSE, 8, 3, payload, 32)
    assert [r.feed(f) for f in (fs[0], other[1], fs[1])] == [None] * 3 and c.dropped == 5
    # malformed: no data, total 0, data past the total, a fragment of a fragment
    for bad in (m.Fragment(m.RESPONSE, 0, 4, b"").pack()[:5], m.Fragment(m.RESPONSE, 0, 0, b"x").pack(),
                m.Fragment(m.RESPONSE, 0, 2, b"xyz").pack(), m.Fragment(m.FRAGMENT, 0, 1, b"x").pack()):
        assert r.feed(Frame(m.FRAGMENT, 1, 1, bad)) is None
    assert c.dropped == 9 and r.completed == 2
    # a single fragment holding the whole payload completes at once
    assert r.feed(Frame(m.FRAGMENT, 1, 1, m.Fragment(m.EVENT, 0, 2, b"ab").pack())) == (m.EVENT, 1, 1, b"ab")


@settings(max_examples=200, deadline=None)
@given(st.binary(min_size=0, max_size=3000), st.integers(16, 255), st.integers(0, 255), st.integers(0, 255),
       st.sampled_from([m.CONTROL, m.RESPONSE, m.SAMPLE, m.EVENT]))
def test_any_message_comes_back_whole(payload: bytes, limit: int, seq: int, cid: int, t: int) -> None:
    fs = frames(t, seq, cid, payload, limit)
    assert all(len(f.payload) <= limit for f in fs)
    r = Reassembler(Counters())
    got = [f if f.type != m.FRAGMENT else r.feed(f) for f in fs]
    assert got[-1] == (t, seq, cid, payload) and all(g is None for g in got[:-1])
    # without any one fragment, nothing is delivered
    if len(fs) > 1:
        for skip in range(len(fs)):
            r2 = Reassembler(Counters())
            assert all(r2.feed(f) is None for i, f in enumerate(fs) if i != skip)
