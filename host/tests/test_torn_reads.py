"""A large read retried while the value changes is never handed back torn (PROTOCOL.md 4.1, 12.4): the
answer to the retry must not complete what arrived of the answer to the first try.

The device double answers the first try of a read of ``mid`` (200 bytes, 8 fragments of 32-byte
frames) with its first fragment only (the rest lost on the line), and the second try, the value
having changed meanwhile, with every fragment but the first (that one lost). A hub that retried
with the same seq would glue the first fragment of the old value to the rest of the new one. It predates window reads
(PROTOCOL.md 12.8: NAK BAD_LENGTH), so the hub's retries are whole reads."""
from __future__ import annotations

import pathlib
from typing import Any, Dict, List

import hubwire
from hubwire.wire import messages as m
from hubwire.wire.frame import Frame
from hubwire.session.fragments import encode_message

from largedevice import LargeDevice


def snapshot(n: int) -> Dict[str, Any]:
    return {"seq": n, "samples": [n * 100 + i for i in range(99)]}


class ChangingDevice(LargeDevice):
    """Answers reads of ``mid`` (id 2) as described above; ``tries`` lists the seq of each R."""

    def __init__(self) -> None:
        super().__init__()
        self.tries: List[int] = []
        self.codec = self.desc.by_name("mid").codec  # type: ignore[union-attr]

    def handle(self, f: Frame) -> None:
        if f.type != m.REQUEST or f.id != 2:
            return super().handle(f)
        if f.payload:  # a device that predates windows (PROTOCOL.md 12.8): the hub reads it whole
            self.send(m.NAK, f.seq, f.id, bytes((m.NakCode.BAD_LENGTH,)))
            return
        self.tries.append(f.seq)
        n = len(self.tries)
        value = self.codec.encode(snapshot(min(n, 2)))
        frames = encode_message(m.RESPONSE, f.seq, f.id, value, self.max_payload).split(b"\x00")[:-1]
        assert len(frames) > 2
        keep = frames[:1] if n == 1 else frames[1:] if n == 2 else frames
        self.write_raw(b"".join(fr + b"\x00" for fr in keep))

    def write_raw(self, data: bytes) -> None:
        import os

        with self.lock:
            os.write(self.master, data)


def test_a_retried_large_read_of_a_changing_value_is_never_torn(tmp_path: pathlib.Path) -> None:
    with ChangingDevice() as fake, hubwire.connect(fake.path, cache_dir=tmp_path, retry_timeout=0.3) as dev:
        got = dev.mid
        value = {"seq": got.seq, "samples": list(got.samples)}
        assert len(fake.tries) >= 2
        assert value in (snapshot(1), snapshot(2)), f"torn: seq {value['seq']}, samples {value['samples'][:14]}"


def _fragments(seq: int, payload: bytes) -> List[Frame]:
    from hubwire.wire.frame import FrameDecoder

    d = FrameDecoder()
    return list(d.feed(encode_message(m.RESPONSE, seq, 2, payload, 32)))


def test_a_reassembly_is_abandoned_for_a_retired_try_and_after_a_long_gap() -> None:
    from types import SimpleNamespace

    from hubwire.session.fragments import FRAGMENT_GAP, Reassembler

    counters = SimpleNamespace(dropped=0)
    r = Reassembler(counters)
    old, new = bytes(range(100)), bytes(range(100, 200))
    a, b = _fragments(7, old), _fragments(7, new)
    assert r._feed(a[0], 10.0) is None
    r.abandon(7, 2)  # the try was given up: its second half, whoever sends it, completes nothing
    assert all(r._feed(f, 10.1) is None for f in b[1:])
    # a fragment long after the one before it does not continue it (the seq may have come round)
    assert r._feed(a[0], 20.0) is None
    assert r._feed(b[1], 20.0 + FRAGMENT_GAP + 0.1) is None
    assert counters.dropped >= len(b) - 1 + 1
    # on time and in order: whole
    for f in a[:-1]:
        assert r._feed(f, 30.0) is None
    whole = r._feed(a[-1], 30.0 + FRAGMENT_GAP / 2)
    assert whole is not None and whole.payload == old
