"""Streams, event iterators and event callbacks ride through a link loss (the device falls silent
longer than the loss timeout) and a device reboot: the hub subscribes again by itself, iteration
goes on, and the first sample after the outage reports it in ``gap``. Deadlines come from the
configured heartbeat intervals, never from a few milliseconds of wall clock."""
from __future__ import annotations

import asyncio
import threading
from typing import Any, List

import pytest

import hubwire
import hubwire.aio
from hubwire.errors import StreamEnded
from hubwire.session.link import LOSS_HEARTBEATS, REOPEN_MAX
from hubwire.testing import tapped
from hubwire.wire import messages as m


from .conftest import HostileDevice, wait_until

HEARTBEAT_MS = 250
#: silence after which the hub declares the link lost (the device announces 250 ms heartbeats)
LOSS = LOSS_HEARTBEATS * HEARTBEAT_MS / 1000.0
CONNECT = 5.0
#: how long a relink may take on a busy machine: the port re-opened with backoff, a handshake and
#: a discovery, with room to spare
BACK = REOPEN_MAX + CONNECT + 20 * LOSS


def samples_until_gap(st: Any, limit: int = 10_000) -> List[Any]:
    """Samples up to and including the first one reporting an outage, then two more."""
    got: List[Any] = []
    for s in st:
        got.append(s)
        if s.gap or len(got) >= limit:
            break
    got += [next(st), next(st)]
    return got


def check_gap(got: List[Any], st: Any) -> None:
    """The outage is reported on one sample, and samples flow on after it. (A busy machine may add
    a loss of its own, starving heartbeats: also ridden through and reported, so counts are >= 1.)"""
    gaps = [s.gap for s in got]
    assert gaps[-3] >= 1 and gaps[-2:] == [0, 0], gaps
    assert st.gaps == sum(gaps) >= 1
    after = got[-3:]
    assert after[0].lost == 0  # the new subscription counts afresh: no bogus loss across the outage
    assert [s.time for s in after] == sorted(s.time for s in after)


def outage(emulator: Any, lost: threading.Event, reboot: bool) -> None:
    """SIGSTOP the emulator until the hub declared the link lost, then SIGCONT it; or kill it and
    start a new one (a reboot on the same port)."""
    lost.clear()  # a loss of the busy machine's own before this one does not count
    if reboot:
        emulator.kill()
        assert lost.wait(BACK), "the hub did not notice the device died"
        emulator.start()
        return
    emulator.pause()
    try:
        assert lost.wait(10 * LOSS), "the hub did not declare the link lost"
    finally:
        emulator.resume()


@pytest.mark.parametrize("reboot", [False, True], ids=["stopped", "rebooted"])
def test_stream_loop_rides_through_an_outage(emulator: Any, cache_dir: str, reboot: bool) -> None:
    with hubwire.connect(transport=tapped(emulator.link), cache_dir=cache_dir, heartbeat_ms=HEARTBEAT_MS,
                         timeout=CONNECT) as dev:
        lost = threading.Event()
        dev.on("link_lost", lost.set)
        with dev.stream("battery", hz=20, meta=True, timeout=BACK) as st:
            first = [next(st) for _ in range(3)]
            outage(emulator, lost, reboot)
            got = samples_until_gap(st)
        check_gap(first + got, st)
        assert dev.session.stats.reboots == int(reboot)
        assert dev.session.stats.link_lost >= 1
        assert dev.session.stats.resubscribes >= 1
        assert dev.session.subscriptions == {}  # closed at the end as usual


def test_stream_timeout_still_raises_during_an_outage(emulator: Any, cache_dir: str) -> None:
    with hubwire.connect(transport=tapped(emulator.link), cache_dir=cache_dir, heartbeat_ms=HEARTBEAT_MS) as dev:
        lost = threading.Event()
        dev.on("link_lost", lost.set)
        with dev.stream("battery", hz=20, timeout=LOSS) as st:
            next(st)
            emulator.pause()
            try:
                assert lost.wait(10 * LOSS)
                with pytest.raises(hubwire.Timeout):
                    while True:
                        next(st)
            finally:
                emulator.resume()
            st.timeout = BACK
            assert isinstance(next(st), int)  # and goes on once the link is back


def test_async_stream_rides_through_an_outage(emulator: Any, cache_dir: str) -> None:
    async def main() -> None:
        lost = asyncio.Event()
        async with hubwire.aio.connect(transport=tapped(emulator.link), cache_dir=cache_dir,
                                       heartbeat_ms=HEARTBEAT_MS) as dev:
            dev.on("link_lost", lost.set)
            got: List[Any] = []
            async with dev.stream("battery", hz=20, meta=True, timeout=BACK) as st:
                async for s in st:
                    got.append(s)
                    if len(got) == 3:
                        emulator.pause()
                        try:
                            await asyncio.wait_for(lost.wait(), 10 * LOSS)
                        finally:
                            emulator.resume()
                    if len(got) > 3 and s.gap:
                        break
                got += [await st.__anext__(), await st.__anext__()]
            check_gap(got, st)

    asyncio.run(main())


def test_event_iterator_and_callbacks_ride_through_a_reboot(emulator: Any, cache_dir: str) -> None:
    """The rebooted device numbers its events afresh: its first event may carry the seq of the last
    one before the reboot, and must still be delivered (dedup memory is per device session)."""
    with hubwire.connect(transport=tapped(emulator.link), cache_dir=cache_dir, heartbeat_ms=HEARTBEAT_MS) as dev:
        lost, back = threading.Event(), threading.Event()
        dev.on("link_lost", lost.set)
        dev.on("reconnect", lambda d: back.set())
        called: List[bool] = []
        dev.on("bumper", called.append)
        with dev.events("bumper", timeout=BACK) as evs:
            emulator.bump()
            before = next(iter(evs))
            outage(emulator, lost, reboot=True)
            assert back.wait(BACK)
            emulator.bump()
            after = next(iter(evs))
        assert (before.name, before.value, after.name, after.value) == ("bumper", True, "bumper", True)
        wait_until(lambda: len(called) == 2, BACK, "both callbacks")
        assert called == [True, True]
        # delivered once each (an ack late on a busy machine makes the device retry: re-acked, not delivered)
        assert dev.session.stats.events == 2


# ------------------------------------------------------------------- a rebooted device that changed

DESC_A = (b'{"p":1,"n":"morph","ch":[{"id":1,"n":"x","a":"rw","t":"u16"},'
          b'{"id":3,"n":"s","a":"rs","t":"u16"}]}')
CHANGED = {
    "gone": (b'{"p":1,"n":"morph","ch":[{"id":1,"n":"x","a":"rw","t":"u16"}]}', "has no such channel"),
    "type": (b'{"p":1,"n":"morph","ch":[{"id":3,"n":"s","a":"rs","t":"f32"}]}', "changed its type to f32"),
    "access": (b'{"p":1,"n":"morph","ch":[{"id":3,"n":"s","a":"r","t":"u16"}]}', "cannot stream it any more"),
}


def reboot_as(d: HostileDevice, descriptor: bytes) -> None:
    """The scripted device comes back as a new boot (new nonce) serving ``descriptor``."""
    d.descriptor, d.length, d.hash = descriptor, len(descriptor), m.fnv1a32(descriptor)
    d.nonce += 1
    d.hello(reply=False)


def sample(d: HostileDevice, cid: int, seq: int) -> None:
    d.frame(m.SAMPLE, seq, cid, m.Sample(10, b"\x01\x00").pack())


def subscribes(d: HostileDevice, cid: int) -> int:
    return sum(1 for f in list(d.received) if f.type == m.SUBSCRIBE and f.id == cid and f.payload[:2] != b"\0\0")


@pytest.mark.parametrize("case", sorted(CHANGED))
def test_stream_of_a_channel_gone_after_a_reboot_ends_clearly(case: str) -> None:
    new, words = CHANGED[case]
    with HostileDevice(DESC_A) as d, hubwire.connect(d.path, cache_dir=False, timeout=CONNECT) as dev:
        with dev.stream("s", hz=10, timeout=BACK) as st:
            reboot_as(d, new)
            with pytest.raises(StreamEnded) as e:
                next(st)
            assert words in str(e.value) and "'s'" in str(e.value)
            assert subscribes(d, 3) == 1  # not subscribed again


def test_stream_follows_its_channel_to_a_new_id_after_a_reboot() -> None:
    moved = b'{"p":1,"n":"morph","ch":[{"id":7,"n":"s","a":"rs","t":"u16"}]}'
    with HostileDevice(DESC_A) as d, hubwire.connect(d.path, cache_dir=False, timeout=CONNECT) as dev:
        with dev.stream("s", hz=10, meta=True, timeout=BACK) as st:
            sample(d, 3, 1)
            assert next(st).gap == 0
            reboot_as(d, moved)
            wait_until(lambda: subscribes(d, 7) == 1, BACK, "subscribed at the new id")
            sample(d, 7, 1)
            s = next(st)
            assert (s.value, s.gap, s.lost) == (1, 1, 0)
            assert dev.session.subscriptions.keys() == {7}

