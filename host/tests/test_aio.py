"""The asyncio API (hubwire.aio) against the C++ device library running as a process on a pty, and
the one-loop design of the synchronous API."""
from __future__ import annotations

import asyncio
import threading
from typing import Any, List

import pytest

import hubwire
import hubwire.aio
from hubwire.errors import InvalidValue, NakError

from conftest import Emulator


def run(coro: Any) -> Any:
    return asyncio.run(asyncio.wait_for(coro, 30))


def test_read_write_call(emulator: Emulator, cache_dir: str) -> None:
    async def main() -> None:
        async with hubwire.aio.connect(emulator.link, cache_dir=cache_dir) as dev:
            assert dev.state == "ready" and dev.name == "rover"
            assert await dev.read("left") == 0.0
            await dev.write("left", 0.5)
            await dev.write("name", "robbie")
            assert await dev.read("left") == 0.5 and await dev.read("name") == "robbie"
            assert await dev.read("applied") == 2  # each write applied exactly once
            assert await dev.call("beep", 200) is True
            assert await dev.call("beep", 2001) is False
            with pytest.raises(InvalidValue):
                await dev.write("left", 1.5)
            assert await dev.read("applied") == 2
        assert dev.state == "closed"
    run(main())


def test_concurrent_reads_and_writes_on_one_loop(emulator: Emulator, cache_dir: str) -> None:
    async def main() -> None:
        async with hubwire.aio.connect(emulator.link, cache_dir=cache_dir) as dev:
            reads = [dev.read("battery") for _ in range(20)]
            writes = [dev.write("left", i / 10) for i in range(5)]
            got = await asyncio.gather(*reads, *writes)
            assert all(isinstance(v, int) and v > 0 for v in got[:20])
            assert await dev.read("applied") == 5
    run(main())


def test_stream_samples_in_order_and_unsubscribe(emulator: Emulator, cache_dir: str) -> None:
    async def main() -> None:
        async with hubwire.aio.connect(emulator.link, cache_dir=cache_dir) as dev:
            samples: List[Any] = []
            async with dev.stream("imu", hz=50, meta=True, timeout=2) as st:
                assert st.granted_ms == 20
                async for s in st:
                    samples.append(s)
                    if len(samples) == 10:
                        break
            assert [x.seq for x in samples] == list(range(samples[0].seq, samples[0].seq + 10))
            assert all(len(x.value.gyro) == 3 for x in samples)
            # cancelled on the device: a read (answered after any sample already queued) then quiet
            await dev.read("battery")
            count = dev.core.stats.samples
            await asyncio.sleep(0.3)  # 15 intervals of the cancelled stream
            assert dev.core.stats.samples == count
            async for value in dev.stream("battery", hz=100, timeout=2):
                assert isinstance(value, int)
                break
    run(main())


def test_events_in_order_and_callbacks_that_await_the_device(emulator: Emulator, cache_dir: str) -> None:
    async def main() -> None:
        async with hubwire.aio.connect(emulator.link, cache_dir=cache_dir) as dev:
            seen: List[Any] = []
            done = asyncio.Event()

            async def on_bumper(value: bool) -> None:
                seen.append((value, await dev.read("battery")))  # a callback may await the device
                if len(seen) == 3:
                    done.set()

            dev.on("bumper", on_bumper)
            async with dev.events("bumper", timeout=5) as evs:
                assert await dev.call("selftest", 3) == 3
                got = []
                async for ev in evs:
                    got.append(ev)
                    if len(got) == 3:
                        break
            assert [(e.name, e.value) for e in got] == [("bumper", True), ("bumper", False), ("bumper", True)]
            assert all(isinstance(e, hubwire.ReceivedEvent) for e in got)
            assert [(b - got[0].seq) & 0xFF for b in (e.seq for e in got)] == [0, 1, 2]
            await asyncio.wait_for(done.wait(), 5)
            assert [v for v, _ in seen] == [True, False, True] and all(b > 0 for _, b in seen)
    run(main())


def test_nak_and_unknown_channel(emulator: Emulator, cache_dir: str) -> None:
    async def main() -> None:
        async with hubwire.aio.connect(emulator.link, cache_dir=cache_dir) as dev:
            with pytest.raises(KeyError):
                await dev.read("nope")
            streams = [await dev.stream(n, hz=10).open() for n in ("imu", "battery", "range", "left")]
            with pytest.raises(NakError) as e:
                await dev.stream("right", hz=10).open()
            assert e.value.error == "BUSY"
            for st in streams:
                await st.aclose()
    run(main())


def test_sync_api_runs_every_device_on_one_loop_thread(emulator_path: str, tmp_path: Any, cache_dir: str) -> None:
    emus = [Emulator(emulator_path, str(tmp_path / f"rover{i}")) for i in range(3)]
    for e in emus:
        e.start()
    devs = []
    try:
        before = {t.name for t in threading.enumerate()}
        devs = [hubwire.connect(e.link, cache_dir=cache_dir) for e in emus]
        for i, d in enumerate(devs):
            d.left = i / 4
        assert [d.left for d in devs] == [0.0, 0.25, 0.5]
        names = [t.name for t in threading.enumerate() if t.name not in before]
        # one loop for every port; one callback thread per device; nothing per port besides
        assert names.count("hubwire-loop") == (0 if "hubwire-loop" in before else 1)
        assert sorted(set(names) - {"hubwire-loop"}) == ["hubwire-dispatch"]
        assert names.count("hubwire-dispatch") == 3
    finally:
        for d in devs:
            d.close()
        for e in emus:
            e.stop()
    assert "hubwire-loop" not in {t.name for t in threading.enumerate()} or "hubwire-loop" in before
