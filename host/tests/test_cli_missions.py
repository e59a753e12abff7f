"""``hubwire call`` on a mission and ``hubwire info`` listing missions, as subprocesses against a
scripted device: the progress bar, one line per value, the result, a failure, Ctrl-C cancelling."""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
from typing import List

from missiondevice import DRIVE, HOME, MissionDevice, f32, wait_for


def start(*args: str) -> subprocess.Popen:
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    return subprocess.Popen([sys.executable, "-m", "hubwire", *args, "--no-cache"], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=env)


def play(dev: MissionDevice, cid: int, values: List[float], result: bytes) -> None:
    """The sketch: once started, report each value (each acked before the next) and finish."""
    assert wait_for(lambda: dev.missions[cid].running, 15)
    for v in values:
        assert dev.progress(cid, f32(v)) and wait_for(dev.idle)
    assert dev.finish(cid, result)


def test_info_lists_missions() -> None:
    with MissionDevice() as dev:
        p = start("info", dev.path)
        out, err = p.communicate(timeout=30)
        assert p.returncode == 0, err
        row = next(line for line in out.splitlines() if line.split()[:2] == ["7", "drive"])
        assert "(f32) -> f32, progress f32" in row and "mission" in row and "0..10" in row
        p = start("info", dev.path, "--json")
        out, err = p.communicate(timeout=30)
        drive = json.loads(out)["channels"][2]
        assert drive == {"id": 7, "name": "drive", "access": "m", "type": "(f32) -> f32, progress f32", "unit": "m",
                         "min": 0, "max": 10, "progress_max": 2, "description": "drive straight"}


def test_call_draws_a_bar_against_pmax_and_prints_the_result() -> None:
    with MissionDevice() as dev:
        p = start("call", dev.path, "drive", "2.0")
        play(dev, DRIVE, [0.5, 1.0, 2.0], f32(1.75))
        out, err = p.communicate(timeout=30)
        assert p.returncode == 0, err
        assert out.strip() == "1.75"
        assert "drive run 1 started" in err
        assert "drive run 1:  25%" in err and "0.5/2 m" in err and "100%" in err and "2/2 m" in err
        assert dev.missions[DRIVE].starts == [f32(2.0)]


def test_the_bar_is_whole_when_the_run_succeeds_short_of_pmax() -> None:
    with MissionDevice() as dev:  # a 1 m drive against pmax 2: the run's success fills the bar
        p = start("call", dev.path, "drive", "1.0")
        play(dev, DRIVE, [0.5], f32(1.0))
        out, err = p.communicate(timeout=30)
        assert p.returncode == 0, err
        assert out.strip() == "1"
        assert "drive run 1:  25%" in err and "100%" in err and "2/2 m" in err


def test_call_prints_a_line_per_value_without_pmax() -> None:
    desc = (b'{"p":1,"n":"rover","ch":[{"id":7,"n":"drive","a":"m","t":"f32","rt":"f32","pt":"f32"}]}')
    with MissionDevice(desc) as dev:
        p = start("call", dev.path, "drive", "3")
        play(dev, DRIVE, [0.5, 1.5], f32(3.0))
        out, err = p.communicate(timeout=30)
        assert p.returncode == 0, err
        assert out.splitlines() == ["drive run 1: 0.5", "drive run 1: 1.5", "3"]


def test_call_reports_a_failure() -> None:
    with MissionDevice() as dev:
        p = start("call", dev.path, "drive", "2", "--json")
        assert wait_for(lambda: dev.missions[DRIVE].running, 15)
        dev.fail(DRIVE, 4)
        out, err = p.communicate(timeout=30)
        assert p.returncode == 1
        assert json.loads(out.splitlines()[-1]) == {"error": "MissionFailed",
                                                    "message": "mission 'drive' run 1 failed with code 4"}


def test_ctrl_c_cancels_the_run() -> None:
    with MissionDevice() as dev:
        p = start("call", dev.path, "drive", "1", "--json")
        assert wait_for(lambda: dev.missions[DRIVE].running, 15)
        dev.progress(DRIVE, f32(0.25))
        assert p.stdout is not None
        first = json.loads(p.stdout.readline())
        assert first == {"mission": "drive", "run": 1, "progress": 0.25}
        p.send_signal(signal.SIGINT)
        out, err = p.communicate(timeout=30)
        assert p.returncode == 130, err
        last = json.loads(out.splitlines()[-1])
        if last["status"] != "cancelled":  # a machine too busy for the confirmation within the Ctrl-C promise
            assert last["message"].startswith("drive run 1: cancel sent; the board did not confirm it"), last
            last.update(status="cancelled", message="drive run 1: cancelled on the board")
        assert last == {"mission": "drive", "run": 1, "status": "cancelled", "cancelled": True,
                        "message": "drive run 1: cancelled on the board"}
        assert wait_for(lambda: dev.missions[DRIVE].cancels == 1, 10)


def test_ctrl_c_says_so_in_text() -> None:
    with MissionDevice() as dev:
        p = start("call", dev.path, "home")
        assert p.stderr is not None
        assert "home run 1 started (Ctrl-C cancels it)" in p.stderr.readline()
        p.send_signal(signal.SIGINT)
        out, err = p.communicate(timeout=30)
        assert p.returncode == 130
        # confirmed by the board, or (on a machine too busy for it within the 2 s Ctrl-C promise) sent
        assert ("hubwire: home run 1: cancelled on the board" in err
                or "hubwire: home run 1: cancel sent; the board did not confirm it within" in err), err
        assert wait_for(lambda: dev.missions[HOME].cancels == 1, 10) and dev.missions[DRIVE].cancels == 0
