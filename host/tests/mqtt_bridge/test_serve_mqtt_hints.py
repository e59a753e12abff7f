"""What `hubwire serve --mqtt` says about its broker: one hint saying what to do when there is none
(not a line a second), and with -v the connection and the Home Assistant discovery it publishes."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from typing import Any, List

from conftest import Emulator
from hubwire.testing import emulator_binary
from service.conftest import HOST, Serve, wait_for

from .conftest import Broker, free_port

RETRIES = 4  # broker connection attempts the service makes (one a second) while the test watches


def serve_stderr(tmp_path: Any, *args: str) -> List[str]:
    env = dict(os.environ, HUBWIRE_STATE_DIR=str(tmp_path / "state"),
               PYTHONPATH=HOST + os.pathsep + os.environ.get("PYTHONPATH", ""))
    p = subprocess.Popen([sys.executable, "-m", "hubwire", "serve", "--no-usb", "--socket", str(tmp_path / "s.sock"),
                          *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    assert p.stdout is not None and p.stdout.readline().startswith("READY"), p.communicate(timeout=10)
    time.sleep(RETRIES)
    p.send_signal(signal.SIGINT)
    _, err = p.communicate(timeout=30)
    return err.splitlines()


def test_no_broker_gives_one_hint_saying_what_to_do(tmp_path: Any) -> None:
    where = f"127.0.0.1:{free_port()}"  # nothing listens there
    for verbose in ([], ["-v"]):
        lines = [ln for ln in serve_stderr(tmp_path, "--mqtt", where, *verbose) if "MQTT" in ln]
        assert len(lines) == 1, lines  # not one per retry: the next one a minute later
        assert "hubwire serve: hubwire serve:" not in lines[0]
        assert f"no MQTT broker answers at {where}" in lines[0]
        assert "mosquitto" in lines[0] and "--mqtt HOST:PORT" in lines[0], lines[0]


def test_verbose_logs_the_broker_connection_and_discovery(broker: Broker, tmp_path: Any) -> None:
    boards = tmp_path / "boards"
    boards.mkdir()
    emu = Emulator(emulator_binary(), str(boards / "a"), [])
    emu.start()
    serve = Serve.own(str(boards), tmp_path, ["--mqtt", f"127.0.0.1:{broker.port}"])
    serve.start()
    try:
        wait_for(lambda: f"MQTT: connected to the broker at 127.0.0.1:{broker.port}" in serve.log_text(),
                 what="the connection logged")
        wait_for(lambda: "MQTT: Home Assistant discovery for" in serve.log_text(), what="discovery logged")
    finally:
        serve.stop()
        emu.stop()
    line = next(ln for ln in serve.log_text().splitlines() if "Home Assistant discovery" in ln)
    assert "entities under homeassistant/" in line, line
