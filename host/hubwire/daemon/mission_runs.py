"""The mission runs of ``hubwire serve`` (docs/SERVICE.md "Missions"): one table per fleet, shared
by socket clients, the MQTT bridge and the dashboard, so a run started on one road can be followed
and cancelled on another.

The service's session of the board owns each run (an :class:`hubwire.job.AsyncJob`), not the client
that started it: a client that goes away leaves the run going, and its progress and outcome stay
here for whoever follows it by its run id. A run id is the client's own (a retried start with the
same id starts nothing: it gets the same run, or the same refusal) or made up by the service.
"""
from __future__ import annotations

import asyncio
import re
import secrets
import weakref
from collections import OrderedDict
from dataclasses import dataclass
from typing import Any, Callable, Dict, List, Optional

from ..errors import HubwireError, LinkLost, Timeout
from ..client.protocol import Busy, Usage

__all__ = ["MissionRuns", "RunEntry", "runs_of", "check_run_id", "MAX_RUNS", "UnknownRun", "Usage"]

#: runs (going, ended or refused) the table keeps; when full the one that ended longest ago is
#: forgotten; when every one is still going a new start is refused ``Busy``
MAX_RUNS = 1024
#: what a run id may be: one MQTT topic level and a JSON string without escapes
RUN_ID = re.compile(r"[A-Za-z0-9_.:-]{1,64}\Z")


class UnknownRun(HubwireError):
    """No run of that id is known (never started here, or forgotten: see :data:`MAX_RUNS`)."""

    kind = "UnknownRun"


def check_run_id(run_id: Any) -> str:
    """``run_id`` when it is a valid run id, else :class:`Usage`."""
    if not isinstance(run_id, str) or not RUN_ID.match(run_id):
        shown = repr(run_id)[:80]
        raise Usage(f"a run id is 1 to 64 of A-Z a-z 0-9 _ . : - (not {shown})")
    return run_id


@dataclass
class RunEntry:
    """One start: ``job`` once the board answered with a run number, or the ``refused`` error."""

    run_id: str
    key: str
    mission: str
    job: Any = None
    refused: Optional[BaseException] = None

    @property
    def done(self) -> bool:
        return self.refused is not None or (self.job is not None and self.job.done())

    @property
    def status(self) -> str:
        return "refused" if self.refused is not None else str(self.job.status)


class MissionRuns:
    """The table: run id -> :class:`RunEntry`, at most ``limit`` of them, in the order started."""

    def __init__(self, limit: int = MAX_RUNS) -> None:
        self.limit = limit
        self._runs: "OrderedDict[str, RunEntry]" = OrderedDict()
        self._starting: Dict[str, "asyncio.Future[RunEntry]"] = {}
        #: called with each new entry (a run started or refused) on the loop: the MQTT bridge and
        #: the dashboard follow runs whoever started them
        self.listeners: List[Callable[[RunEntry], None]] = []

    def get(self, run_id: Any) -> RunEntry:
        e = self._runs.get(check_run_id(run_id))
        if e is None:
            raise UnknownRun(f"no mission run {run_id!r} is known to the service (it keeps the last {self.limit})")
        return e

    def of_board(self, key: Optional[str] = None) -> List[RunEntry]:
        return [e for e in self._runs.values() if key is None or e.key == key]

    def _room(self) -> None:
        while len(self._runs) + len(self._starting) >= self.limit:
            old = next((k for k, e in self._runs.items() if e.done), None)
            if old is None:
                raise Busy(f"{self.limit} mission runs are going on this service already")
            del self._runs[old]

    async def start(self, fleet: Any, key: str, mission: str, goal: Any, run_id: Optional[str] = None,
                    timeout: Optional[float] = None) -> RunEntry:
        """Start ``mission`` on board ``key`` (exactly once per run id), or the run already
        started under ``run_id``; raises what the start raised (the same again for a repeat)."""
        if run_id is None:
            run_id = secrets.token_hex(8)
            while run_id in self._runs:
                run_id = secrets.token_hex(8)
        check_run_id(run_id)
        if run_id in self._starting:
            entry = await asyncio.shield(self._starting[run_id])
        else:
            entry = self._runs.get(run_id) or await self._start(fleet, key, mission, goal, run_id, timeout)
        if (entry.key, entry.mission) != (key, mission):
            raise Usage(f"run id {run_id!r} is mission {entry.mission!r} of board {entry.key}")
        if entry.refused is not None:
            raise entry.refused
        return entry

    async def _start(self, fleet: Any, key: str, mission: str, goal: Any, run_id: str,
                     timeout: Optional[float]) -> RunEntry:
        self._room()
        fut: "asyncio.Future[RunEntry]" = asyncio.get_running_loop().create_future()
        self._starting[run_id] = fut
        entry = RunEntry(run_id, key, mission)
        try:
            dev = fleet.get(key).device
            if dev is None:
                raise LinkLost(f"board {key} is unplugged: nothing was sent")
            try:
                entry.job = await dev.start(mission, goal, timeout=timeout)
            except (LinkLost, Timeout):
                raise  # the start may or may not have reached the board: the id stays free for a retry
            except HubwireError as e:  # refused (BUSY, REJECTED, a bad goal): the same for a repeat
                entry.refused = e
            self._runs[run_id] = entry
            fut.set_result(entry)
            for cb in list(self.listeners):
                cb(entry)
            return entry
        except BaseException as e:
            fut.set_exception(e)
            fut.exception()  # retrieved: nobody else may be waiting
            raise
        finally:
            del self._starting[run_id]


_tables: "weakref.WeakKeyDictionary[Any, MissionRuns]" = weakref.WeakKeyDictionary()


def runs_of(fleet: Any) -> MissionRuns:
    """The table of ``fleet`` (made on first use)."""
    t = _tables.get(fleet)
    if t is None:
        t = _tables[fleet] = MissionRuns()
    return t
