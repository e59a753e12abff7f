"""The service's table of mission runs (hubwire.daemon.mission_runs) on stand-in boards: run ids
checked, a repeated start answered from the table, a refusal remembered, and the bound: the oldest
ended run forgotten when full, ``Busy`` when every run still goes."""
from __future__ import annotations

import asyncio
import types
from typing import Any, List

import pytest

from hubwire import NakError
from hubwire.errors import LinkLost
from hubwire.daemon.mission_runs import MissionRuns, UnknownRun
from hubwire.client.protocol import Busy, Usage
from hubwire.wire.messages import NakCode


class _Job:
    def __init__(self, run: int) -> None:
        self.run = run
        self.ended = False

    def done(self) -> bool:
        return self.ended

    @property
    def status(self) -> str:
        return "succeeded" if self.ended else "running"


class _Dev:
    def __init__(self) -> None:
        self.starts: List[Any] = []
        self.refuse = False
        self.lose = False

    async def start(self, name: str, goal: Any, timeout: Any = None) -> _Job:
        await asyncio.sleep(0.01)  # a round trip: a repeat arrives while the start is out
        if self.lose:
            raise LinkLost("gone")
        if self.refuse:
            raise NakError(NakCode.BUSY, name)
        self.starts.append(goal)
        return _Job(len(self.starts))


def _fleet(dev: _Dev) -> Any:
    return types.SimpleNamespace(get=lambda key: types.SimpleNamespace(device=dev))


def test_run_ids_repeats_and_refusals() -> None:
    async def main() -> None:
        dev = _Dev()
        fleet, runs = _fleet(dev), MissionRuns()
        for bad in ("", "a/b", "x" * 65, "+", 7):
            with pytest.raises(Usage):
                await runs.start(fleet, "rover", "drive", 1.0, bad)  # type: ignore[arg-type]
        a, b = await asyncio.gather(runs.start(fleet, "rover", "drive", 1.0, "r1"),
                                    runs.start(fleet, "rover", "drive", 1.0, "r1"))
        assert a is b and dev.starts == [1.0]  # started once, though asked twice at once
        with pytest.raises(Usage, match="is mission 'drive' of board rover"):
            await runs.start(fleet, "rover", "home", None, "r1")
        dev.refuse = True
        for _ in range(2):
            with pytest.raises(NakError):
                await runs.start(fleet, "rover", "drive", 2.0, "r2")
        dev.refuse = False
        with pytest.raises(NakError):  # the refusal is remembered under its id: not asked again
            await runs.start(fleet, "rover", "drive", 2.0, "r2")
        assert runs.get("r2").status == "refused" and dev.starts == [1.0]
        dev.lose = True
        with pytest.raises(LinkLost):
            await runs.start(fleet, "rover", "drive", 3.0, "r3")
        dev.lose = False
        assert (await runs.start(fleet, "rover", "drive", 3.0, "r3")).job.run == 2  # a lost start leaves its id free
        made = await runs.start(fleet, "rover", "drive", 4.0)
        assert len(made.run_id) == 16 and made.run_id != "r3"
        with pytest.raises(UnknownRun):
            runs.get("nope")
    asyncio.run(main())


def test_a_full_table_forgets_the_oldest_ended_run_then_refuses() -> None:
    async def main() -> None:
        dev = _Dev()
        fleet, runs = _fleet(dev), MissionRuns(limit=3)
        seen: List[str] = []
        runs.listeners.append(lambda e: seen.append(e.run_id))
        for rid in ("a", "b", "c"):
            await runs.start(fleet, "rover", "drive", 1.0, rid)
        runs.get("b").job.ended = True
        runs.get("c").job.ended = True
        await runs.start(fleet, "rover", "drive", 1.0, "d")  # full: "b", the oldest that ended, goes
        assert [e.run_id for e in runs.of_board("rover")] == ["a", "c", "d"]
        with pytest.raises(UnknownRun):
            runs.get("b")
        await runs.start(fleet, "rover", "drive", 1.0, "e")  # then "c"
        with pytest.raises(Busy, match="3 mission runs are going"):  # a, d, e all going
            await runs.start(fleet, "rover", "drive", 1.0, "f")
        assert [e.run_id for e in runs.of_board()] == ["a", "d", "e"] and seen == ["a", "b", "c", "d", "e"]
    asyncio.run(main())
