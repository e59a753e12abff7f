"""Missions on MQTT as a Node-RED flow or a Home Assistant automation would use them
(docs/MQTT.md "Missions"): `hubwire serve --mqtt` with examples/Missions on the missions emulator
and on the simulated Uno (real AVR firmware in simavr), a private mosquitto, and mosquitto_pub / mosquitto_sub. A goal in, progress in order and the result
once per run id out, a repeated start that starts nothing, BUSY as a refused result, a cancel, and
malformed run ids and payloads refused before anything reaches the board."""
from __future__ import annotations

import json
import os
import shutil
import subprocess
from typing import Any, Dict, Iterator, List, Tuple

import pytest

from conftest import Emulator
from service.conftest import HOST, Serve, wait_for
from simuno.conftest import start_example

from .conftest import Broker
from .helpers import f32_shortest

MISSIONS_EMULATOR = os.path.join(HOST, "..", "build", "emulator", "hubwire-missions-emulator")
DEADLINE = 60.0
BASE = "hubwire/missions/mission/drive"


@pytest.fixture(params=["emulator", "uno"])
def served(request: pytest.FixtureRequest, broker: Broker, tmp_path: Any) -> Iterator[Tuple[Serve, Broker, Any]]:
    if shutil.which("mosquitto_sub") is None:
        pytest.fail("mosquitto_sub missing: run tools/setup.sh (apt-get install mosquitto-clients)", pytrace=False)
    boards = tmp_path / "boards"
    boards.mkdir()
    emu: Any
    if request.param == "uno":
        emu = start_example("Missions", str(boards / "missions"), str(tmp_path / "simuno.log"))
    else:
        if not os.access(MISSIONS_EMULATOR, os.X_OK):
            pytest.fail(f"{MISSIONS_EMULATOR} missing: build it with `make emulator`", pytrace=False)
        emu = Emulator(MISSIONS_EMULATOR, str(boards / "missions"))
        emu.start()
    serve = Serve.own(str(boards), tmp_path, ["--mqtt", f"127.0.0.1:{broker.port}"])
    out = open(tmp_path / "sub.txt", "w+")
    sub = subprocess.Popen(["mosquitto_sub", "-h", "127.0.0.1", "-p", str(broker.port), "-v", "-q", "1",
                            "-t", f"{BASE}/#", "-t", "hubwire/missions/error"], stdout=out, stderr=subprocess.STDOUT)
    serve.start()
    try:
        serve.wait_state("missions", "ready")
        yield serve, broker, tmp_path / "sub.txt"
    finally:
        status = serve.stop()
        sub.terminate()
        sub.wait(10)
        out.close()
        emu.stop()
    assert status == 0, serve.log_text()


def pub(broker: Broker, topic: str, payload: str) -> None:
    subprocess.run(["mosquitto_pub", "-h", "127.0.0.1", "-p", str(broker.port), "-q", "1", "-t", topic, "-m", payload],
                   check=True, timeout=30)


def on(path: Any, topic: str) -> List[Dict[str, Any]]:
    out = []
    for line in open(path).read().splitlines():
        t, _, payload = line.partition(" ")
        if t == topic:
            out.append(json.loads(payload))
    return out


def results(path: Any, run_id: str) -> List[Dict[str, Any]]:
    return [r for r in on(path, f"{BASE}/result") if r["run_id"] == run_id]


def test_goal_progress_result_busy_and_cancel_over_mqtt(served: Tuple[Serve, Broker, Any]) -> None:
    serve, broker, log = served
    serve.cli("set", "missions", "speed", "2")
    odometer = float(serve.cli("get", "missions", "odometer").stdout)
    pub(broker, f"{BASE}/start", '{"run_id": "nr-1", "goal": 1.0}')
    wait_for(lambda: results(log, "nr-1"), DEADLINE, "the result of nr-1")
    assert results(log, "nr-1") == [{"run_id": "nr-1", "run": 1, "status": "succeeded", "value": 1.0}]
    progress = [p for p in on(log, f"{BASE}/progress") if p["run_id"] == "nr-1"]
    assert [p["index"] for p in progress] == list(range(len(progress))) and progress
    values = [p["value"] for p in progress]
    assert values == sorted(set(values)) and all(0 < v < 1.0 for v in values) and {p["run"] for p in progress} == {1}
    # f32 progress as its shortest decimal (0.45, not the double 0.4500000178813934 it reads back as)
    assert all(v == f32_shortest(v) for v in values), values

    # the same start again (a QoS 1 redelivery, a flow retrying) starts nothing
    pub(broker, f"{BASE}/start", '{"run_id": "nr-1", "goal": 1.0}')
    # a goal outside the declared range and malformed run ids: refused, nothing sent
    pub(broker, f"{BASE}/start", '{"run_id": "nr-x", "goal": 20}')
    pub(broker, f"{BASE}/start", '{"run_id": "a/b", "goal": 1}')
    pub(broker, f"{BASE}/start", '{"run_id": "' + "x" * 65 + '", "goal": 1}')
    pub(broker, f"{BASE}/start", "[" * 100000)
    errors = lambda: on(log, "hubwire/missions/error")  # noqa: E731
    wait_for(lambda: len(errors()) >= 4, DEADLINE, "four errors")
    assert [e["error"] for e in errors()] == ["InvalidValue"] * 4
    assert "outside the declared range" in errors()[0]["message"] and "run id" in errors()[1]["message"]
    assert "run id" in errors()[2]["message"] and "at most 8192 bytes" in errors()[3]["message"]
    # a start refused before it was sent still ends its run id: one result, "refused"
    assert [(r["status"], r["error"]) for r in results(log, "nr-x")] == [("refused", "InvalidValue")]
    assert float(serve.cli("get", "missions", "odometer").stdout) == pytest.approx(odometer + 1.0)

    # one run at a time: a second start while one goes is refused, its result says so
    serve.cli("set", "missions", "speed", "0.1")
    pub(broker, f"{BASE}/start", '{"run_id": "nr-2", "goal": 10}')
    wait_for(lambda: [p for p in on(log, f"{BASE}/progress") if p["run_id"] == "nr-2"], DEADLINE, "nr-2 driving")
    pub(broker, f"{BASE}/start", '{"run_id": "nr-3", "goal": 1}')
    wait_for(lambda: results(log, "nr-3"), DEADLINE, "nr-3 refused")
    r3 = results(log, "nr-3")[0]
    assert (r3["status"], r3["error"], r3["nak"], r3["run"]) == ("refused", "Nak", "BUSY", None)
    pub(broker, f"{BASE}/cancel", '{"run_id": "nr-2"}')
    wait_for(lambda: results(log, "nr-2"), DEADLINE, "nr-2 cancelled")
    # the refused start did not take the retained state from the run that went on
    assert [st["run_id"] for st in on(log, f"{BASE}/state") if st["run_id"] in ("nr-2", "nr-3")][-1:] == ["nr-2"]
    assert not [st for st in on(log, f"{BASE}/state") if st["run_id"] == "nr-3"]
    assert results(log, "nr-2") == [{"run_id": "nr-2", "run": 2, "status": "cancelled", "error": "MissionCancelled",
                                     "message": "mission 'drive' run 2 was cancelled"}]
    # a start without run id: the bridge names the run; the retained state shows the latest run
    serve.cli("set", "missions", "speed", "2")
    pub(broker, f"{BASE}/start", "0.5")
    wait_for(lambda: [r for r in on(log, f"{BASE}/result") if r["run"] == 3], DEADLINE, "run 3 ended")
    made = [r for r in on(log, f"{BASE}/result") if r["run"] == 3][0]
    assert len(made["run_id"]) == 16 and made["status"] == "succeeded"
    state = subprocess.run(["mosquitto_sub", "-h", "127.0.0.1", "-p", str(broker.port), "-C", "1", "-W", "10",
                            "-t", f"{BASE}/state"], capture_output=True, text=True, timeout=30).stdout
    got = json.loads(state)
    assert (got["run_id"], got["run"], got["status"], got["value"]) == (made["run_id"], 3, "succeeded", 0.5)
    # every run id had exactly one result, and the redelivered start none of its own
    ids = [r["run_id"] for r in on(log, f"{BASE}/result")]
    assert sorted(ids) == sorted(["nr-1", "nr-x", "nr-2", "nr-3", made["run_id"]])
