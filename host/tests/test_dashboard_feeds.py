"""The dashboard's feeds against a registry shaped like the service's (FLEET shape), with a board
that is unplugged (no device) and plugged again (a new device object); and DeviceFleet's keys."""
from __future__ import annotations

import asyncio
import time
from typing import Any, AsyncIterator, Callable, List

from conftest import Emulator

from hubwire import aio
from hubwire.dashboard.feed import Feeds
from hubwire.dashboard.fleet import Board, DeviceFleet

#: generous deadline for a busy machine: many heartbeat intervals (250 ms) and stream periods
DEADLINE = 20.0


class StandInFleet:
    """The registry shape `hubwire serve` provides, driven by the test."""

    def __init__(self, boards: List[Board]) -> None:
        self._boards = {b.key: b for b in boards}
        self._queues: List["asyncio.Queue[Board]"] = []

    def boards(self) -> List[Board]:
        return list(self._boards.values())

    def get(self, key: str) -> Board:
        return self._boards[key]

    async def changes(self) -> AsyncIterator[Board]:
        q: "asyncio.Queue[Board]" = asyncio.Queue()
        self._queues.append(q)
        while True:
            yield await q.get()

    def changed(self, b: Board) -> None:
        for q in self._queues:
            q.put_nowait(b)


async def until(pred: Callable[[], Any], what: str) -> None:
    end = time.monotonic() + DEADLINE
    while not pred():
        assert time.monotonic() < end, f"timed out waiting for {what}"
        await asyncio.sleep(0.02)


def test_a_board_unplugged_ends_its_feed_and_plugged_again_gets_a_new_one(emulator: Emulator,
                                                                           cache_dir: str) -> None:
    async def scenario() -> None:
        dev = await aio.connect(emulator.link, cache_dir=cache_dir)
        board = Board("rover", "rover", None, emulator.link, "ready", dev)
        fleet = StandInFleet([board])
        feeds = Feeds(fleet, stream_hz=50.0)
        await feeds.start()
        first = feeds.feeds["rover"]
        await until(lambda: first.records["imu"].count >= 2, "imu samples")
        assert first.records["failsafes"].read == "read"  # not streamable: read instead

        await dev.close()
        board.device, board.state, board.port = None, "unplugged", None
        fleet.changed(board)
        # its feed ends, and keeps the last values for the page to show as such (not a blank card)
        await until(lambda: getattr(feeds.feeds.get("rover"), "ended", False), "the feed of the unplugged board to end")
        assert feeds.feeds["rover"] is first and first.records["imu"].value is not None
        await until(lambda: all(t.done() for t in list(first._streams.values()) + first._tasks), "its tasks to end")

        dev2 = await aio.connect(emulator.link, cache_dir=cache_dir)
        board.device, board.state, board.port = dev2, "ready", emulator.link
        fleet.changed(board)
        await until(lambda: feeds.feeds["rover"] is not first, "a feed for the board plugged again")
        second = feeds.feeds["rover"]
        assert second is not first and second.dev is dev2 and second.generation > first.generation
        await until(lambda: second.records["imu"].count >= 2, "imu samples from the new session")
        emulator.bump()
        await until(lambda: second.event_count == 1, "the bumper event")
        assert [(e.n, e.name, e.value) for e in second.events] == [(1, "bumper", True)]
        ok, msg, code = await second.write_coded(dev2.channel("left"), 2.0)
        assert (ok, code) == (False, "OUT_OF_RANGE") and msg == "not sent: left: 2.0 is outside the declared range -1..1"
        ok, msg = await second.call(dev2.channel("selftest"), 2)
        assert (ok, msg) == (True, "2")
        await feeds.stop()
        await dev2.close()

    asyncio.run(scenario())


def test_device_fleet_keys_boards_by_name_and_tells_their_state(emulator_path: str, tmp_path: Any,
                                                               cache_dir: str) -> None:
    a, b = Emulator(emulator_path, str(tmp_path / "a")), Emulator(emulator_path, str(tmp_path / "b"))
    a.start()
    b.start()

    async def scenario() -> None:
        async with DeviceFleet([a.link, b.link, str(tmp_path / "absent")], cache_dir=cache_dir) as fleet:
            told: List[Any] = []

            async def follow() -> None:
                async for x in fleet.changes():
                    told.append((x.port, x.state))  # a snapshot as it is told

            follower = asyncio.ensure_future(follow())
            await until(lambda: len(fleet.boards()) == 2, "both boards")
            keys = sorted(x.key for x in fleet.boards())
            assert keys == ["rover", "rover---2"], keys  # same name, no id: numbered
            assert list(fleet.pending) == [str(tmp_path / "absent")]
            board = next(x for x in fleet.boards() if x.port == a.link)
            assert fleet.get(board.key) == board and board.state == "ready"
            a.pause()  # silent: the link is declared lost
            await until(lambda: (a.link, "lost") in told, "the board told lost")
            a.resume()
            await until(lambda: told[-1] == (a.link, "ready") if told else False, "the board told back")
            mine = [st for port, st in told if port == a.link]
            assert mine[0] == "ready" and "lost" in mine and mine[-1] == "ready", mine
            assert all(x != y for x, y in zip(mine, mine[1:])), mine  # each change told once
            follower.cancel()
        try:
            fleet.get("nope")
        except KeyError as e:
            assert "rover" in str(e)
        else:
            raise AssertionError("no KeyError")

    try:
        asyncio.run(scenario())
    finally:
        a.stop()
        b.stop()


def test_a_stream_the_board_cannot_grant_is_read_and_says_so_plainly(emulator: Emulator, cache_dir: str) -> None:
    """The Rover streams four channels at once (HUBWIRE_MAX_STREAMS) and has five: one is read
    instead, and its row says why without the protocol's word for it (it said "stream refused: BUSY")."""
    async def scenario() -> None:
        dev = await aio.connect(emulator.link, cache_dir=cache_dir)
        feeds = Feeds(StandInFleet([Board("rover", "rover", None, emulator.link, "ready", dev)]), stream_hz=10.0)
        await feeds.start()
        try:
            recs = feeds.feeds["rover"].records.values()
            await until(lambda: any(r.read not in ("", "read") for r in recs), "a stream refused")
            notes = [r.read for r in recs if r.read not in ("", "read")]
            assert notes == ["read 10 times a second (the board has no stream free for it)"], notes
        finally:
            await feeds.stop()
            await dev.close()

    asyncio.run(scenario())
