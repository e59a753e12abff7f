"""Large values and lists against a scripted device that accepts 32-byte payloads (largedevice.py):
1 KB and 200-byte structs written, read and passed to actions in fragments; lists checked on both
sides; a lossy link never delivers a torn or repeated value and applies a large write exactly once."""
from __future__ import annotations

import pathlib
from typing import Any, Dict, Iterator, Tuple

import pytest

import hubwire
from hubwire.errors import InvalidValue
from hubwire.testing.faultlink import Faults, FaultyTransport
from hubwire.transport import SerialTransport
from hubwire.wire.messages import NakCode

from conftest import wait_until
from largedevice import LargeDevice


def big_value(n: int) -> Dict[str, Any]:
    data = [(n * 31 + i * 7) % 256 for i in range(1016)]
    return {"seq": n, "data": data, "check": sum(data) + n}


def mid_value(n: int) -> Dict[str, Any]:
    return {"seq": n, "samples": [((n + 1) * (i - 49) * 13) % 60000 - 30000 for i in range(99)]}


def as_json(value: Any) -> Dict[str, Any]:
    return {k: (list(v) if isinstance(v, tuple) else v) for k, v in value._asdict().items()}


@pytest.fixture
def pair(tmp_path: pathlib.Path) -> Iterator[Tuple[LargeDevice, Any]]:
    with LargeDevice() as fake, hubwire.connect(fake.path, cache_dir=tmp_path) as dev:
        yield fake, dev


def test_a_1k_struct_is_written_in_fragments_and_read_back(pair: Tuple[LargeDevice, Any]) -> None:
    fake, dev = pair
    v = big_value(3)
    dev.big = v
    assert fake.applied["big"] == 1
    assert fake.values[1] == dev.descriptor.by_name("big").codec.encode(v)
    assert fake.fragments_in == -(-1024 // 27)  # 27 bytes of value per 32-byte fragment
    assert fake.largest_frame_in <= 32  # nothing longer than the device accepts
    assert as_json(dev.big) == v  # the device's answer came back in 1024 / 27 fragments
    assert fake.dropped == 0


def test_a_200_byte_struct_round_trips_and_each_write_is_applied_once(pair: Tuple[LargeDevice, Any]) -> None:
    fake, dev = pair
    for n in range(5):
        dev.mid = mid_value(n)
        assert as_json(dev.mid) == mid_value(n)
    assert fake.applied["mid"] == 5
    assert fake.largest_frame_in <= 32


def test_a_retried_large_write_is_reassembled_again_and_applied_once(pair: Tuple[LargeDevice, Any]) -> None:
    fake, dev = pair
    fake.lose_answers = 1  # the ACK of the first try is lost: the hub sends every fragment again
    dev.mid = mid_value(4)
    assert (fake.applied["mid"], fake.duplicates) == (1, 1)
    assert fake.fragments_in == 2 * -(-200 // 27)
    assert dev.session.stats.retries == 1
    assert as_json(dev.mid) == mid_value(4)


def test_the_hub_waits_for_a_large_answer_that_keeps_coming(tmp_path: pathlib.Path) -> None:
    """A read whose answer takes longer than the retry timeout on the line is not asked again while
    its fragments keep arriving (PROTOCOL.md 12.6)."""
    with LargeDevice() as fake, hubwire.connect(fake.path, cache_dir=tmp_path, retry_timeout=0.3, tries=2) as dev:
        dev.mid = mid_value(2)
        fake.fragment_gap = 0.1  # 8 fragments: about 0.8 s, more than both tries' 0.6 s
        assert as_json(dev.mid) == mid_value(2)
        assert dev.session.stats.retries == 0
        fake.fragment_gap = 0.0
        before = dev.session.core.link.reassembler.completed
        assert as_json(dev.mid) == mid_value(2)
        assert dev.session.core.link.reassembler.completed == before + 1


def test_large_arguments_and_results_of_actions(pair: Tuple[LargeDevice, Any]) -> None:
    fake, dev = pair
    v = mid_value(9)
    assert dev.call("digest", v) == sum(v["samples"]) & 0xFFFFFFFF
    echo = [(i * 5) % 256 for i in range(300)]
    assert list(dev.call("echo", echo)) == echo  # 300 bytes each way
    assert [name for name, _ in fake.calls] == ["digest", "echo"]
    assert fake.largest_frame_in <= 32


def test_a_large_sample_arrives_whole(pair: Tuple[LargeDevice, Any]) -> None:
    fake, dev = pair
    dev.big = big_value(5)
    with dev.stream("big", interval_ms=1000, timeout=5) as s:
        wait_until(lambda: fake.subscribes, what="the subscription")
        fake.sample(1, 0)
        sample = next(iter(s))
    assert as_json(sample) == big_value(5)


def test_lists_round_trip(pair: Tuple[LargeDevice, Any]) -> None:
    fake, dev = pair
    for value in ([1, -2, 1000], [], [-1000] * 8):
        dev.path = value
        assert dev.path == value
        assert isinstance(dev.path, list)
    dev.flags = [True, False, True]
    assert dev.flags == [True, False, True]
    assert dev.call("pick", [1, 2, 3, 4, 5]) == [2, 4, 6]
    assert dev.call("pick", []) == []
    assert fake.applied["path"] == 3


@pytest.mark.parametrize("value,code", [
    ([0] * 9, NakCode.BAD_VALUE),         # more than the capacity, whatever the elements
    ([0] * 9 + ["x"], NakCode.BAD_VALUE),
    ([1, 1001], NakCode.OUT_OF_RANGE),    # every element within min..max
    ([-1001], NakCode.OUT_OF_RANGE),
    ([1, "a"], NakCode.BAD_VALUE),
    ([40000], NakCode.OUT_OF_RANGE),      # outside i16
    ("12", NakCode.BAD_VALUE),            # not a list
    (5, NakCode.BAD_VALUE),
])
def test_an_invalid_list_is_refused_before_sending(pair: Tuple[LargeDevice, Any], value: Any, code: int) -> None:
    fake, dev = pair
    dev.path = [7]
    with pytest.raises(InvalidValue) as e:
        dev.path = value
    assert e.value.code == code
    assert fake.applied["path"] == 1 and dev.path == [7]


@pytest.mark.parametrize("payload,code", [
    (bytes((9,)) + bytes(18), NakCode.BAD_VALUE),    # count over the capacity
    (bytes((9,)) + bytes(2), NakCode.BAD_VALUE),     # ... whatever the length
    (bytes((2,)) + bytes(2), NakCode.BAD_LENGTH),
    (b"", NakCode.BAD_LENGTH),
])
def test_a_malformed_list_from_the_device_raises_its_code(pair: Tuple[LargeDevice, Any], payload: bytes,
                                                          code: int) -> None:
    fake, dev = pair
    fake.values[3] = payload
    with pytest.raises(InvalidValue) as e:
        dev.path
    assert e.value.code == code


def test_a_lossy_link_never_tears_or_repeats_a_large_value(tmp_path: pathlib.Path) -> None:
    faults = Faults(drop=0.001, dup=0.01, ber=1e-5)  # per byte, per frame, per bit
    with LargeDevice() as fake:
        fl = FaultyTransport(SerialTransport(fake.path), seed=22, both=faults)
        with hubwire.connect(transport=fl, cache_dir=tmp_path, tries=40, timeout=20) as dev:
            writes = 0
            for n in range(20):
                dev.mid = mid_value(n)
                writes += 1
                assert fake.applied["mid"] == writes  # exactly once, however often it was sent
                assert fake.values[2] == dev.descriptor.by_name("mid").codec.encode(mid_value(n))
                assert as_json(dev.mid) == mid_value(n)  # never torn, never an older value
            big = big_value(1)
            dev.big = big
            assert as_json(dev.big) == big
            assert fake.applied["big"] == 1
            stats = fl.stats()
            hub_refused = dev.session.core.link.reassembler.refused
    # the link really was lossy: fragments were lost or repeated on the way, in both directions
    assert stats["h2d"]["bytes_dropped"] + stats["h2d"]["frames_duplicated"] > 0
    assert stats["d2h"]["bytes_dropped"] + stats["d2h"]["frames_duplicated"] > 0
    assert fake.dropped > 0  # the device abandoned reassemblies, and its retried writes were answered again
    assert hub_refused > 0  # and so did the hub with the device's answers


def test_the_cli_parses_and_formats_lists() -> None:
    from hubwire.cli.support import fmt_value, jsonable
    from hubwire.wire.values import codec_for

    c = codec_for({"t": "i16", "vc": 4})
    assert c.parse_text("10,-20, 30") == [10, -20, 30]
    assert c.parse_text("[1, 2]") == [1, 2]
    assert c.parse_text("") == [] and c.parse_text("[]") == []
    assert codec_for({"t": "bool", "vc": 3}).parse_text("true,0,on") == [True, False, True]
    for text, code in (("1,2,3,4,5", NakCode.BAD_VALUE), ("1,x", NakCode.BAD_VALUE), ("[1,", NakCode.BAD_VALUE),
                       ("40000", NakCode.OUT_OF_RANGE)):
        with pytest.raises(InvalidValue) as e:
            c.parse_text(text)
        assert e.value.code == code, text
    assert fmt_value([1.5, -2.0]) == "[1.5, -2]" and fmt_value([]) == "[]"
    assert jsonable([1, 2]) == [1, 2]


def test_large_values_and_lists_through_asyncio(tmp_path: pathlib.Path) -> None:
    import asyncio

    import hubwire.aio

    async def main(path: str) -> Tuple[Any, Any, Any]:
        async with hubwire.aio.connect(path, cache_dir=tmp_path) as dev:
            await dev.write("big", big_value(11))
            await dev.write("path", [5, -5])
            return await dev.read("big"), await dev.read("path"), await dev.call("pick", [4, 5])

    with LargeDevice() as fake:
        got_big, got_path, picked = asyncio.run(asyncio.wait_for(main(fake.path), 30))
        assert (fake.applied["big"], fake.applied["path"]) == (1, 1)
    assert as_json(got_big) == big_value(11)
    assert (got_path, picked) == ([5, -5], [8, 10])
