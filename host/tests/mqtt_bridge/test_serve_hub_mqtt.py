"""Hub channels from MQTT, as a user runs it: examples/Thermostat on a simulated Uno served by
`hubwire serve --mqtt ... --mqtt-hub 'thermostat/*'`, a private mosquitto and its own command-line
clients (docs/MQTT.md "Hub channels"). The setpoint set from MQTT is what the board uses, its report
appears on MQTT, the mode is an event sent from MQTT, Home Assistant gets an entity for each, and a
Python client that wants the same channels is refused with both providers named."""
from __future__ import annotations

import json
import os
import time
import shutil
import subprocess
from typing import Any, Callable, Dict, Iterator, List

import pytest

import hubwire
from hubwire.errors import HubwireError
from service.conftest import Serve, make_serve, wait_for
from simuno.conftest import start_example

from .conftest import Broker


@pytest.fixture
def thermostat_served(broker: Broker, tmp_path: Any, monkeypatch: pytest.MonkeyPatch,
                      request: pytest.FixtureRequest) -> Iterator[Serve]:
    """The Thermostat served with ``--mqtt-hub`` for the patterns given as the fixture's parameter
    (default ``thermostat/*``)."""
    patterns = list(getattr(request, "param", ["thermostat/*"]))
    if shutil.which("mosquitto_sub") is None:
        pytest.fail("mosquitto_sub missing: run tools/setup.sh (apt-get install mosquitto-clients)", pytrace=False)
    boards = tmp_path / "boards"
    boards.mkdir()
    sim = start_example("Thermostat", str(boards / "uno"), str(tmp_path / "simuno.log"))
    serve = make_serve(str(boards), tmp_path, monkeypatch,
                       ["--mqtt", f"127.0.0.1:{broker.port}"] + [a for p in patterns for a in ("--mqtt-hub", p)])
    try:
        serve.start()
        yield serve
    finally:  # (the simulated Uno is stopped also when the service did not start)
        status = serve.stop()
        assert sim.stop() == 0, sim.log_text()
        assert status == 0, serve.log_text()


def test_the_thermostat_runs_on_hub_channels_from_mqtt(thermostat_served: Serve, broker: Broker, tmp_path: Any) -> None:
    serve = thermostat_served
    out = open(tmp_path / "sub.txt", "w+")
    sub = subprocess.Popen(["mosquitto_sub", "-h", "127.0.0.1", "-p", str(broker.port), "-v",
                            "-t", "hubwire/thermostat/hub/#", "-t", "hubwire/thermostat/hub",
                            "-t", "homeassistant/#"], stdout=out, stderr=subprocess.STDOUT)
    lines: Callable[[], List[str]] = lambda: open(tmp_path / "sub.txt").read().splitlines()  # noqa: E731

    def topic(t: str) -> List[str]:
        return [ln.split(" ", 1)[1] for ln in lines() if ln.split(" ", 1)[0] == t]

    def pub(t: str, payload: str) -> None:
        subprocess.run(["mosquitto_pub", "-h", "127.0.0.1", "-p", str(broker.port), "-q", "1", "-t", t,
                        "-m", payload], check=True, timeout=30)

    def status() -> Dict[str, Any]:
        got = topic("hubwire/thermostat/hub")
        return {r["channel"]: r for r in json.loads(got[-1])["channels"]} if got else {}

    def get(name: str) -> str:
        return str(serve.cli("get", "thermostat", name).stdout.strip())
    try:
        serve.wait_state("thermostat", "ready")
        # before any setpoint: MQTT holds the channels, the setpoint waits for its first value
        wait_for(lambda: status().get("setpoint", {}).get("status") == "waiting", 60, what="setpoint waiting")
        st = status()
        assert st["report"]["kind"] == st["alarm"]["kind"] == "mqtt" and st["mode"]["kind"] == "service", st
        # Home Assistant: the setpoint a number, the report a sensor, the mode a number (an event
        # sent with number.set_value), the alarm an event entity
        for kind, name in (("number", "setpoint"), ("sensor", "report"), ("number", "mode"), ("event", "alarm")):
            wait_for(lambda k=kind, n=name: topic(f"homeassistant/{k}/thermostat/hub-{n}/config"), 60, what=f"HA {name}")
        setpoint_cfg = json.loads(topic("homeassistant/number/thermostat/hub-setpoint/config")[-1])
        assert setpoint_cfg["command_topic"] == "hubwire/thermostat/hub/setpoint/set"
        assert setpoint_cfg["state_topic"] == "hubwire/thermostat/hub/setpoint"
        assert (setpoint_cfg["unit_of_measurement"], setpoint_cfg["device_class"]) == ("°C", "temperature")

        # the setpoint from MQTT: the board binds, reads it, and heats toward it once mode is 1
        pub("hubwire/thermostat/hub/setpoint/set", "25")
        wait_for(lambda: all(r["status"] == "ok" for r in status().values()), 60, what="every hub channel bound")
        wait_for(lambda: int(get("setpoints")) >= 2, 60, what="the board read the setpoint")
        assert topic("hubwire/thermostat/hub/setpoint")[-1] == "25.0"
        pub("hubwire/thermostat/hub/mode/set", "1")
        wait_for(lambda: int(get("modes")) == 1, 60, what="mode event applied")
        wait_for(lambda: get("heating") == "True", 60, what="heating below the MQTT setpoint")
        # its report (tenths of a degree) is published, retained
        wait_for(lambda: len(topic("hubwire/thermostat/hub/report")) >= 2, 60, what="reports on MQTT")
        assert all(150 <= int(v) <= 400 for v in topic("hubwire/thermostat/hub/report"))
        # a setpoint far below the temperature: heating stops, and the board calls the alarm
        pub("hubwire/thermostat/hub/setpoint/set", "5")
        wait_for(lambda: get("heating") == "False", 60, what="heating off above the new setpoint")
        wait_for(lambda: topic("hubwire/thermostat/hub/alarm/call"), 60, what="an alarm call on MQTT")
        call = json.loads(topic("hubwire/thermostat/hub/alarm/call")[-1])
        assert call["event_type"] == "alarm" and call["arg"] > 10
        wait_for(lambda: int(get("alarms")) >= 1, 60, what="the alarm answered true")

        # a Python client that wants the same channels: refused, both providers named
        hub = hubwire.HubChannels()
        hub.provide("setpoint", 21.5, type="f32")
        hub.accept("report", lambda v: None, type="u16")
        hub.action("alarm", lambda t: True, type="f32", returns="bool")
        hub.event("mode", type="u8")
        with pytest.raises(HubwireError) as e:
            hubwire.connect("thermostat", hub=hub)
        assert "MQTT" in str(e.value) and f"pid {os.getpid()}" in str(e.value), str(e.value)
        info = serve.cli("info", "thermostat").stdout
        assert "MQTT" in info[info.index("provided through hubwire serve"):], info
        # no request refused; one may time out (240: kHubTimeout) on a loaded machine
        assert int(get("last_failure")) in (0, 240)
    finally:
        sub.terminate()
        sub.wait(10)
        out.close()


@pytest.mark.parametrize("thermostat_served", [["thermostat/setpoint"]], indirect=True)
def test_a_client_beside_mqtt_and_the_status_topic_when_it_leaves(thermostat_served: Serve, broker: Broker,
                                                                  tmp_path: Any) -> None:
    """MQTT backs the setpoint only; a Python client provides the report and the alarm. The status
    topic names each provider, and says unbound once the client has gone; the board stops."""
    serve = thermostat_served
    out = open(tmp_path / "sub.txt", "w+")
    sub = subprocess.Popen(["mosquitto_sub", "-h", "127.0.0.1", "-p", str(broker.port), "-v",
                            "-t", "hubwire/thermostat/hub"], stdout=out, stderr=subprocess.STDOUT)

    def status() -> Dict[str, Any]:
        got = [ln.split(" ", 1)[1] for ln in open(tmp_path / "sub.txt").read().splitlines()]
        return {r["channel"]: r for r in json.loads(got[-1])["channels"]} if got else {}
    try:
        serve.wait_state("thermostat", "ready")
        subprocess.run(["mosquitto_pub", "-h", "127.0.0.1", "-p", str(broker.port), "-q", "1", "-r",
                        "-t", "hubwire/thermostat/hub/setpoint/set", "-m", "22.5"], check=True, timeout=30)
        wait_for(lambda: status().get("setpoint", {}).get("status") == "ok", 60, what="setpoint from MQTT")
        reports: List[int] = []
        hub = hubwire.HubChannels()
        hub.accept("report", reports.append, type="u16")
        hub.action("alarm", lambda t: True, type="f32", returns="bool")
        # the setpoint (MQTT's) and the mode events (the service's) are held elsewhere: not needed here
        with hubwire.connect("thermostat", hub=hub) as dev:
            wait_for(lambda: all(r["status"] == "ok" for r in status().values()), 60, what="every channel bound")
            st = status()
            assert st["setpoint"]["kind"] == "mqtt" and st["report"]["kind"] == "client", st
            assert f"pid {os.getpid()}" in st["report"]["by"] and f"pid {os.getpid()}" in st["alarm"]["by"]
            wait_for(lambda: len(reports) >= 2, 60, what="reports at the client")
            wait_for(lambda: dev.setpoints >= 2, 60, what="the MQTT setpoint read")
        wait_for(lambda: status()["report"]["status"] == "unbound" and status()["report"]["by"] is None, 60,
                 what="the status topic says unbound")
        assert status()["setpoint"]["kind"] == "mqtt"

        def stopped() -> bool:  # the board is unbound: it asks for no setpoint any more
            before = int(serve.cli("get", "thermostat", "setpoints").stdout)
            time.sleep(2.5)
            return int(serve.cli("get", "thermostat", "setpoints").stdout) == before
        wait_for(stopped, 60, what="the board stopped")
    finally:
        sub.terminate()
        sub.wait(10)
        out.close()
