"""Missions through `hubwire serve` (docs/SERVICE.md "Missions"): start, progress in order, the
result once, a second start while one runs (BUSY), cancel; the service's session owns each run, so
a client that goes away mid-run loses nothing for the others. On a scripted device (exact counts)
and on the missions emulator (examples/Missions, the real device library)."""
from __future__ import annotations

import asyncio
import json
import os
import signal
import subprocess
import sys
from typing import Any, Iterator, List

import pytest

import hubwire
import hubwire.aio
from hubwire import MissionCancelled, NakError
from hubwire.wire.messages import NakCode

from conftest import Emulator
from missiondevice import DRIVE, MissionDevice, f32, wait_for

from .conftest import Serve

#: generous: progress comes every 100 ms, but the machine may be busy
DEADLINE = 60.0
MISSIONS_EMULATOR = os.path.join(os.path.dirname(os.environ.get("HUBWIRE_EMULATOR", "") or os.path.join(
    os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))), "build",
    "emulator", "x")), "hubwire-missions-emulator")


@pytest.fixture
def missions_emulator(boards_dir: str) -> Iterator[Emulator]:
    if not os.access(MISSIONS_EMULATOR, os.X_OK):
        pytest.fail(f"{MISSIONS_EMULATOR} missing: build it with `make emulator`", pytrace=False)
    emu = Emulator(MISSIONS_EMULATOR, os.path.join(boards_dir, "missions"))
    emu.start()
    yield emu
    emu.stop()


def test_start_progress_result_on_a_scripted_device(serve: Serve, boards_dir: str) -> None:
    with MissionDevice() as dev:
        os.symlink(dev.path, os.path.join(boards_dir, "rover"))
        serve.wait_state("rover", "ready")
        with hubwire.connect("rover") as rover:
            assert rover.url == "service:rover"
            with pytest.raises(hubwire.HubwireError, match="not a mission"):
                rover.start("beep", 1)
            job = rover.start("drive", 2.0)
            assert (job.mission, job.run, job.status) == ("drive", 1, "running")
            with pytest.raises(NakError) as busy:  # one run of a mission at a time
                rover.start("drive", 1.0)
            assert busy.value.code == NakCode.BUSY
            for v in (0.5, 1.0, 1.5):
                assert dev.progress(DRIVE, f32(v)) and wait_for(dev.idle, 15)
            assert dev.finish(DRIVE, f32(1.75))
            assert list(job.feedback(timeout=DEADLINE)) == [0.5, 1.0, 1.5]
            assert job.result(timeout=DEADLINE) == 1.75
            assert job.status == "succeeded" and job.cancel() is False
        assert dev.missions[DRIVE].starts == [f32(2.0)]  # the refused second start started nothing


def test_on_the_missions_emulator_sync_cancel_and_busy(serve: Serve, missions_emulator: Emulator) -> None:
    serve.wait_state("missions", "ready")
    with hubwire.connect("missions") as dev:
        dev.speed = 2.0
        job = dev.start("drive", 1.0)
        progress: List[float] = list(job.feedback(timeout=DEADLINE))
        assert job.result(timeout=DEADLINE) == pytest.approx(1.0)
        assert progress and progress == sorted(set(progress)) and all(0 < p < 1.0 for p in progress), progress
        dev.speed = 0.1
        job = dev.start("drive", 10.0)
        assert job.run == 2
        with pytest.raises(NakError) as e:
            dev.start("drive", 1.0)
        assert e.value.code == NakCode.BUSY
        assert next(iter(job.feedback(timeout=DEADLINE))) > 0
        assert job.cancel() is True
        with pytest.raises(MissionCancelled):
            job.result(timeout=DEADLINE)
        assert job.status == "cancelled" and job.cancel() is False


def test_a_client_that_leaves_mid_run_loses_nothing_for_another(serve: Serve, missions_emulator: Emulator) -> None:
    serve.wait_state("missions", "ready")

    async def main() -> None:
        first = await hubwire.aio.connect("missions")
        await first.write("speed", 2.0)
        job = await first.start("drive", 1.5)
        run_id = job.run_id
        seen = [v async for v in _take(job.feedback(timeout=DEADLINE), 1)]
        await first.close()  # gone mid-run: the run goes on, owned by the service
        async with hubwire.aio.connect("missions") as second:
            other = await second.follow(run_id)
            assert (other.mission, other.run, other.run_id) == ("drive", job.run, run_id)
            everything = [v async for v in other.feedback(timeout=DEADLINE)]
            assert await other.result(timeout=DEADLINE) == pytest.approx(1.5)
            assert everything[:1] == seen and everything == sorted(set(everything))
            again = await second.follow(run_id)  # the outcome stays with the service: told once per follower
            assert await again.result(timeout=DEADLINE) == pytest.approx(1.5) and again.status == "succeeded"
    asyncio.run(main())


async def _take(it: Any, n: int) -> Any:
    async for v in it:
        yield v
        n -= 1
        if n == 0:
            return


def test_cli_call_through_the_service_and_ctrl_c_cancels(serve: Serve, missions_emulator: Emulator) -> None:
    serve.wait_state("missions", "ready")
    serve.cli("set", "missions", "speed", "2")
    r = serve.cli("call", "missions", "drive", "0.5", "--json")
    lines = [json.loads(line) for line in r.stdout.splitlines()]
    assert lines[-1] == {"mission": "drive", "run": 1, "status": "succeeded", "result": 0.5}
    progress = [x["progress"] for x in lines[:-1]]
    assert progress == sorted(set(progress)) and all(0 < p < 0.5 for p in progress)
    serve.cli("set", "missions", "speed", "0.1")
    p = subprocess.Popen([sys.executable, "-m", "hubwire", "call", "missions", "drive", "5", "--json"],
                         env=dict(serve.env, PYTHONUNBUFFERED="1"), stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                         text=True)
    assert p.stdout is not None
    assert json.loads(p.stdout.readline())["run"] == 2  # driving
    p.send_signal(signal.SIGINT)
    out, err = p.communicate(timeout=DEADLINE)
    assert p.returncode == 130, err
    assert json.loads(out.splitlines()[-1]) == {"mission": "drive", "run": 2, "status": "cancelled",
                                                "cancelled": True, "message": "drive run 2: cancelled on the board"}


class _Line:
    """A client of the socket protocol as any language would write it: JSON lines."""

    def __init__(self, path: str) -> None:
        import socket

        self.s = socket.socket(socket.AF_UNIX)
        self.s.connect(path)
        self.s.settimeout(DEADLINE)
        self.f = self.s.makefile("rwb")
        assert json.loads(self.f.readline())["protocol"] == 1

    def send(self, **msg: Any) -> None:
        self.f.write((json.dumps(msg) + "\n").encode())
        self.f.flush()

    def next(self) -> Any:
        return json.loads(self.f.readline())

    def ask(self, **msg: Any) -> Any:
        self.send(**msg)
        while True:
            got = self.next()
            if got.get("id") == msg["id"]:
                return got

    def close(self) -> None:
        self.f.close()
        self.s.close()


def test_exactly_once_on_the_socket(serve: Serve, boards_dir: str) -> None:
    with MissionDevice(refuse=lambda goal: goal == f32(9.0)) as dev:
        os.symlink(dev.path, os.path.join(boards_dir, "rover"))
        serve.wait_state("rover", "ready")
        a, b = _Line(serve.socket), _Line(serve.socket)
        bad = a.ask(id=1, op="start", board="rover", channel="drive", goal=2.0, run_id="no/slash")
        assert (bad["ok"], bad["error"]) == (False, "Usage")
        assert a.ask(id=2, op="mission", sub=1, run_id="nope")["error"] == "UnknownRun"
        notm = a.ask(id=9, op="start", board="rover", channel="beep", goal=1, run_id="k")
        assert (notm["error"], "not a mission" in notm["message"]) == ("Error", True)
        assert a.ask(id=10, op="runs")["runs"] == []  # a wrong request keeps nothing
        started = a.ask(id=3, op="start", board="rover", channel="drive", goal=2.0, run_id="kitchen-1")
        assert started["ok"] and started["run"] == {"run_id": "kitchen-1", "board": "rover", "mission": "drive",
                                                    "status": "running", "run": 1, "received": 0}
        again = b.ask(id=1, op="start", board="rover", channel="drive", goal=2.0, run_id="kitchen-1")
        assert again["run"]["run"] == 1  # the same run: a repeated start starts nothing
        assert dev.missions[DRIVE].starts == [f32(2.0)] and dev.controls == 1
        assert a.ask(id=4, op="mission", sub=7, run_id="kitchen-1")["ok"]
        for v in (0.25, 0.5, 0.75, 1.0):
            assert dev.progress(DRIVE, f32(v)) and wait_for(dev.idle, 15)
        assert b.ask(id=2, op="mission", sub=3, run_id="kitchen-1", **{"from": 2})["run"]["received"] == 4
        a.close()  # gone mid-run: nothing changes for b
        assert dev.finish(DRIVE, f32(1.0)) and wait_for(dev.idle, 15)
        pushes = [b.next() for _ in range(3)]
        assert pushes == [{"sub": 3, "progress": {"index": 2, "value": 0.75, "raw": f32(0.75).hex()}},
                          {"sub": 3, "progress": {"index": 3, "value": 1.0, "raw": f32(1.0).hex()}},
                          {"sub": 3, "result": {"status": "succeeded", "value": 1.0, "raw": f32(1.0).hex()}}]
        # a second follower after the end gets every value in order and the outcome, once
        b.send(id=3, op="mission", sub=3, run_id="kitchen-1")  # the ended subscription's id is free again
        got = [b.next() for _ in range(6)]
        assert got[0]["id"] == 3 and got[0]["run"]["status"] == "succeeded"
        assert [g["progress"]["index"] for g in got[1:5]] == [0, 1, 2, 3] and got[5]["result"]["status"] == "succeeded"
        ping = b.ask(id=4, op="runs", board="rover")  # nothing more came for sub 3 before this answer
        assert [r["run_id"] for r in ping["runs"]] == ["kitchen-1"]
        # a refused start is remembered under its run id: the repeat is refused the same, unsent
        no = b.ask(id=5, op="start", board="rover", channel="drive", goal=9.0, run_id="r2")
        assert (no["error"], no["nak"]) == ("Nak", "REJECTED")
        controls = dev.controls
        assert b.ask(id=6, op="start", board="rover", channel="drive", goal=9.0, run_id="r2")["nak"] == "REJECTED"
        assert dev.controls == controls
        # cancel by run id, from a client that did not start it
        run3 = b.ask(id=7, op="start", board="rover", channel="drive", goal=1.0)["run"]
        assert len(run3["run_id"]) == 16 and run3["run"] == 2
        assert b.ask(id=8, op="cancel", run_id=run3["run_id"]) == {"id": 8, "ok": True, "cancelled": True}
        assert dev.missions[DRIVE].cancels == 1
        b.close()


def test_a_reboot_mid_run_and_the_service_going_away(serve: Serve, boards_dir: str) -> None:
    with MissionDevice() as dev:
        os.symlink(dev.path, os.path.join(boards_dir, "rover"))
        serve.wait_state("rover", "ready")
        with hubwire.connect("rover") as rover:
            job = rover.start("drive", 2.0)
            statuses: List[str] = []
            job.on_status(statuses.append)
            dev.reboot()  # the board restarts under the service: no run of the earlier boot can end
            with pytest.raises(hubwire.MissionLost, match="rebooted"):
                job.result(timeout=DEADLINE)
            assert job.status == "lost"
            wait_for(lambda: statuses == ["lost"], 15)
            job = rover.start("drive", 1.0)  # the new boot runs it as its run 1
            assert job.run == 1
            job.on_status(statuses.append)
            dev.mute = True  # the link is lost (the board goes on): the run says so, then goes on
            wait_for(lambda: job.status == "link lost", 15)
            dev.mute = False
            wait_for(lambda: job.status == "running", 30)
            assert dev.progress(DRIVE, f32(0.5)) and wait_for(dev.idle, 15)
            assert next(iter(job.feedback(timeout=DEADLINE))) == 0.5
            wait_for(lambda: statuses == ["lost", "link lost", "running"], 15)
            serve.stop()  # the service goes away mid-run: this client's job ends, saying where the run is
            with pytest.raises(hubwire.MissionLost, match="goes on with hubwire serve"):
                job.result(timeout=DEADLINE)
        serve.start()  # (the fixture stops it again)
