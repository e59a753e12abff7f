"""The hub's writes on a fast line (session/pacer.py): the fragments of a large message go out one
frame at a time, in order, with nothing else between them; slower lines and single frames are not
paced. Order and grouping are asserted, never the length of a pause."""
from __future__ import annotations

import asyncio
from typing import List

from hubwire.session.fragments import encode_message
from hubwire.session.pacer import PACE_ABOVE_BAUD, Pacer, split_frames
from hubwire.wire import messages as m
from hubwire.wire.frame import encode_frame


class Line:
    def __init__(self, baudrate: int) -> None:
        self.baudrate = baudrate
        self.writes: List[bytes] = []

    def write(self, data: bytes) -> None:
        self.writes.append(data)


BIG = encode_message(m.CONTROL, 5, 1, bytes(range(200)), 32)  # 8 fragments for a 32-byte device
HEARTBEAT = encode_frame(m.HEARTBEAT, 1, 0, bytes(10))


def run(baud: int, *writes: bytes) -> List[bytes]:
    async def go() -> List[bytes]:
        line = Line(baud)
        pacer = Pacer(line, asyncio.get_running_loop())
        for w in writes:
            pacer.write(w)
        for _ in range(2000):  # until the last byte is written (each pause is a few µs at these rates)
            if b"".join(line.writes) == b"".join(writes):
                break
            await asyncio.sleep(0.001)
        return line.writes
    return asyncio.run(go())


def test_fragments_on_a_fast_line_go_one_frame_at_a_time_and_others_wait_behind() -> None:
    frames = split_frames(BIG)
    assert len(frames) == 8 and b"".join(frames) == BIG
    got = run(1_000_000, BIG, HEARTBEAT)
    assert got == frames + [HEARTBEAT]  # each fragment its own write, the heartbeat after the last


def test_slow_lines_unknown_rates_and_single_frames_are_not_paced() -> None:
    assert run(115200, BIG, HEARTBEAT) == [BIG, HEARTBEAT]
    assert run(0, BIG) == [BIG]
    assert run(PACE_ABOVE_BAUD, BIG) == [BIG]
    assert run(1_000_000, HEARTBEAT, HEARTBEAT) == [HEARTBEAT, HEARTBEAT]


def test_a_paced_burst_takes_twice_the_line_time() -> None:
    p = Pacer(Line(1_000_000), asyncio.new_event_loop())
    assert p.burst_time(BIG) == len(BIG) * 10.0 / 1_000_000 * 2
    assert p.burst_time(HEARTBEAT) == len(HEARTBEAT) * 10.0 / 1_000_000
    p.loop.close()
