"""The whole path as a user runs it: `hubwire serve --mqtt` owning two emulated boards running one
sketch (told apart by their board ids), a private mosquitto, and mosquitto's own command-line
clients: retained states and Home Assistant configs for both boards, commands that reach the board,
and events delivered once each."""
from __future__ import annotations

import os
import shutil
import subprocess
from typing import Any, Callable, List

import pytest

from conftest import Emulator
from hubwire.testing import emulator_binary
from service.conftest import HOST, Serve, wait_for

from .conftest import Broker


def test_serve_with_mqtt_as_a_user_sees_it(broker: Broker, tmp_path: Any) -> None:
    if shutil.which("mosquitto_sub") is None:
        pytest.fail("mosquitto_sub missing: run tools/setup.sh (apt-get install mosquitto-clients)", pytrace=False)
    boards = tmp_path / "boards"
    boards.mkdir()
    emus: List[Emulator] = []
    for name, bid in (("a", "aa01"), ("b", "bb02")):
        emus.append(Emulator(emulator_binary(), str(boards / name), ["--board-id", bid]))
        emus[-1].start()
    sock = str(tmp_path / "run" / "hubwire.sock")
    cache = tmp_path / "cache"
    cache.mkdir()
    env = dict(os.environ, HUBWIRE_SOCKET=sock, HUBWIRE_CACHE_DIR=str(cache),
               PYTHONPATH=HOST + os.pathsep + os.environ.get("PYTHONPATH", ""))
    serve = Serve(str(boards), sock, env, str(tmp_path / "serve.log"), ["--mqtt", f"127.0.0.1:{broker.port}"])
    out = open(tmp_path / "sub.txt", "w+")
    sub = subprocess.Popen(["mosquitto_sub", "-h", "127.0.0.1", "-p", str(broker.port), "-v",
                            "-t", "hubwire/#", "-t", "homeassistant/#"], stdout=out, stderr=subprocess.STDOUT)
    serve.start()
    try:
        keys = {b["board_id"]: b["key"] for b in wait_for(
            lambda: [b for b in serve.boards() if b["state"] == "ready"] if len(
                [b for b in serve.boards() if b["state"] == "ready"]) == 2 else None, what="two boards ready")}
        assert set(keys) == {"aa01", "bb02"} and len(set(keys.values())) == 2
        lines: Callable[[], List[str]] = lambda: open(tmp_path / "sub.txt").read().splitlines()  # noqa: E731

        def topic(t: str) -> List[str]:
            return [ln.split(" ", 1)[1] for ln in lines() if ln.split(" ", 1)[0] == t]

        for key in keys.values():
            wait_for(lambda k=key: "online" in topic(f"hubwire/{k}/status"), what=f"{key} online")
            wait_for(lambda k=key: topic(f"hubwire/{k}/state/battery"), what=f"{key} battery state")
            wait_for(lambda k=key: topic(f"homeassistant/sensor/{k}/battery/config"), what=f"{key} HA sensor")
            wait_for(lambda k=key: topic(f"homeassistant/number/{k}/left/config"), what=f"{key} HA number")

        # a write from a plain MQTT client reaches that board alone (read back through the service)
        other = keys["bb02"]
        subprocess.run(["mosquitto_pub", "-h", "127.0.0.1", "-p", str(broker.port), "-q", "1",
                        "-t", f"hubwire/{other}/set/left", "-m", "0.5"], check=True, timeout=30)
        wait_for(lambda: float(serve.cli("get", other, "left").stdout) == 0.5, what="the write applied")
        assert float(serve.cli("get", keys["aa01"], "left").stdout) == 0.0

        # events: the board's selftest raises 4, then 1 more as a fence; each published once
        first = keys["aa01"]
        serve.cli("call", first, "selftest", "4")
        wait_for(lambda: len(topic(f"hubwire/{first}/event/bumper")) >= 4, what="4 events")
        serve.cli("call", first, "selftest", "1")
        wait_for(lambda: len(topic(f"hubwire/{first}/event/bumper")) >= 5, what="the fence event")
        assert len(topic(f"hubwire/{first}/event/bumper")) == 5
        assert topic(f"hubwire/{other}/event/bumper") == []
    finally:
        status = serve.stop()
        sub.terminate()
        sub.wait(10)
        out.close()
        for e in emus:
            e.stop()
    assert status == 0, serve.log_text()
