"""The rig of the real Home Assistant test (test_ha_real.py): Home Assistant with its MQTT
integration on a private mosquitto, `hubwire serve --mqtt --mqtt-hub 'thermostat/*'` owning five
emulated boards and examples/Thermostat on a simulated Uno, and mosquitto's own clients to watch
and publish beside Home Assistant."""
from __future__ import annotations

import os
import select
import subprocess
import time
from typing import Any, Dict, Iterator, List, Optional

import pytest

from conftest import Emulator
from hubwire.testing import emulator_binary
from service.conftest import HOST, Serve
from simuno.conftest import Simuno, example_elf, simuno_binary

from .conftest import MOSQUITTO, Broker
from .real_ha import STATE_S, HomeAssistant, setup_ha

#: the emulated boards: key -> emulator (build/emulator)
EMULATORS = {"rover": "hubwire-emulator", "actions": "hubwire-actions-emulator",
             "large": "hubwire-largevalues-emulator", "large1k": "hubwire-large-emulator",
             "missions": "hubwire-missions-emulator"}


class Rig:
    def __init__(self, ha: HomeAssistant, broker: Broker, serve: Serve, emus: Dict[str, Emulator],
                 uno: Simuno) -> None:
        self.ha, self.broker, self.serve, self.emus, self.uno = ha, broker, serve, emus, uno

    def mqtt_one(self, topic: str, action: Any) -> str:
        """The next message on ``topic`` after ``action()``."""
        return self.mqtt_until(topic, action, lambda got: len(got) >= 1)[0]

    def mqtt_until(self, topic: str, action: Any, done: Any) -> List[str]:
        """The payloads on ``topic`` from before ``action()`` until ``done(payloads)`` (mosquitto's
        own client, which is known to be subscribed once a probe of ours reached it)."""
        probe = f"test/probe/{os.getpid()}"
        sub = subprocess.Popen(["mosquitto_sub", "-h", "127.0.0.1", "-p", str(self.broker.port), "-v",
                                "-t", topic, "-t", probe], stdout=subprocess.PIPE, bufsize=0)
        assert sub.stdout is not None
        fd, buf = sub.stdout.fileno(), b""

        def until(pred: Any, what: str) -> List[str]:
            nonlocal buf
            deadline = time.monotonic() + STATE_S
            while True:
                got = [ln for ln in buf.decode(errors="replace").splitlines() if ln.startswith(what + " ")]
                if pred(got):
                    return [ln[len(what) + 1:].strip() for ln in got]
                assert time.monotonic() < deadline, f"timed out waiting for {what}: {got}"
                if select.select([fd], [], [], 0.5)[0]:
                    buf += os.read(fd, 65536)
                elif what == probe:
                    self.publish(probe, "x")
        try:
            until(bool, probe)
            buf = b""
            action()
            return until(lambda got: done([ln[len(topic) + 1:].strip() for ln in got]), topic)
        finally:
            sub.kill()
            sub.wait()

    def publish(self, topic: str, payload: str) -> None:
        subprocess.run(["mosquitto_pub", "-h", "127.0.0.1", "-p", str(self.broker.port), "-q", "1",
                        "-t", topic, "-m", payload], check=True, timeout=30)


@pytest.fixture(scope="module", name="rig")
def rig_fixture(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Rig]:
    if MOSQUITTO is None:
        pytest.fail("mosquitto is not installed: run tools/setup.sh", pytrace=False)
    sim_binary, thermostat = simuno_binary(), example_elf("Thermostat")
    if not (os.access(sim_binary, os.X_OK) and os.path.isfile(thermostat)):
        pytest.fail("simulated Uno or Thermostat firmware not built: `make simuno uno-firmware`", pytrace=False)
    tmp = tmp_path_factory.mktemp("ha")
    venv = setup_ha()
    (tmp / "broker").mkdir()
    broker = Broker(MOSQUITTO, str(tmp / "broker"), False)
    broker.start()
    ha = HomeAssistant(venv, str(tmp / "config"))
    emus: Dict[str, Emulator] = {}
    uno: Optional[Simuno] = None
    serve: Optional[Serve] = None
    try:
        ha.start()
        ha.onboard()
        ha.add_mqtt(broker.port)
        boards = tmp / "boards"
        boards.mkdir()
        bin_dir = os.path.dirname(emulator_binary())
        for name, binary in EMULATORS.items():
            emus[name] = Emulator(os.path.join(bin_dir, binary), str(boards / name))
            emus[name].start()
        uno = Simuno(sim_binary, thermostat, str(boards / "thermostat"), str(tmp / "simuno.log"))
        uno.start()
        sock = str(tmp / "run" / "hubwire.sock")
        (tmp / "cache").mkdir()
        env = dict(os.environ, HUBWIRE_SOCKET=sock, HUBWIRE_CACHE_DIR=str(tmp / "cache"),
                   PYTHONPATH=HOST + os.pathsep + os.environ.get("PYTHONPATH", ""))
        serve = Serve(str(boards), sock, env, str(tmp / "serve.log"),
                      ["--mqtt", f"127.0.0.1:{broker.port}", "--mqtt-id", "test", "--mqtt-hub", "thermostat/*"])
        serve.start()
        yield Rig(ha, broker, serve, emus, uno)
    finally:
        if serve is not None:
            serve.stop()
        for e in emus.values():
            if e.proc is not None:
                e.stop()
        if uno is not None:
            uno.stop()
        ha.stop()
        broker.stop()
