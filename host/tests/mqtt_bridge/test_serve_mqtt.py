"""The whole path as a user runs it: `hubwire serve --mqtt` owning two emulated boards running one
sketch (told apart by their board ids), a private mosquitto, and mosquitto's own command-line
clients: retained states and Home Assistant configs for both boards, commands that reach the board,
and events delivered once each."""
from __future__ import annotations

import os
import shutil
import select
import subprocess
from typing import Any, Callable, List

import pytest

from conftest import Emulator
from hubwire.testing import emulator_binary
from service.conftest import Serve, wait_for

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
    serve = Serve.own(str(boards), tmp_path, ["--mqtt", f"127.0.0.1:{broker.port}"])
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


def test_two_services_on_one_broker_one_client_commands_both(broker: Broker, tmp_path: Any) -> None:
    """Two hubs (two `hubwire serve --mqtt` processes with ids of their own, each owning its board) on
    one broker: a plain MQTT 5 client commands a board of each and gets one reply from each; each
    service answers for its own board only (commands for the other's are left to it)."""
    if shutil.which("mosquitto_rr") is None:
        pytest.fail("mosquitto_rr missing: run tools/setup.sh (apt-get install mosquitto-clients)", pytrace=False)
    actions = os.path.join(os.path.dirname(emulator_binary()), "hubwire-actions-emulator")
    services: List[Serve] = []
    emus: List[Emulator] = []
    try:
        for name, binary, key in (("one", emulator_binary(), "rover"), ("two", actions, "actions")):
            boards = tmp_path / name
            boards.mkdir()
            emus.append(Emulator(binary, str(boards / "board")))
            emus[-1].start()
            services.append(Serve.own(str(boards), tmp_path / f"serve-{name}",  # (outside what it watches)
                                      ["--mqtt", f"127.0.0.1:{broker.port}", "--mqtt-id", f"hub-{name}",
                                       "--mqtt-reply-prefix", "replies/"]))
            services[-1].start()
            services[-1].wait_state(key, "ready")

        def replies(topic: str, value: str, n: int) -> List[str]:
            """The replies to one MQTT 5 command (response topic set), once ``n`` have come and the
            broker has then delivered a later message of ours (a fence: a second answer would be
            before it)."""
            back = f"replies/{topic}"
            sub = subprocess.Popen(["mosquitto_sub", "-h", "127.0.0.1", "-p", str(broker.port), "-V", "5", "-v",
                                    "-t", back, "-t", "fence/" + topic], stdout=subprocess.PIPE, text=True)
            assert sub.stdout is not None

            def fence() -> List[str]:
                """Publish to the fence topic until it comes back: every reply sent before it is read."""
                lines: List[str] = []
                while True:
                    subprocess.run(["mosquitto_pub", "-h", "127.0.0.1", "-p", str(broker.port),
                                    "-t", "fence/" + topic, "-m", "f"], check=True, timeout=30)
                    while select.select([sub.stdout], [], [], 0.2)[0]:
                        line = sub.stdout.readline().strip()  # type: ignore[union-attr]
                        if line.startswith("fence/"):
                            return lines
                        lines.append(line)
            try:
                fence()  # subscribed: the command's replies cannot be missed
                subprocess.run(["mosquitto_pub", "-h", "127.0.0.1", "-p", str(broker.port), "-V", "5", "-q", "1",
                                "-t", topic, "-m", value, "-D", "publish", "response-topic", back],
                               check=True, timeout=30)
                got: List[str] = []
                while len(got) < n:
                    got += fence()
                # both services have handled the command by now (each answered a request of the local
                # socket since): a second reply would come before one more fence
                for s in services:
                    s.cli("get", *(["rover", "left"] if s is services[0] else ["actions", "calls"]))
                return got + fence()
            finally:
                sub.terminate()
                sub.wait(10)

        for topic, value in (("hubwire/rover/set/left", "0.25"), ("hubwire/actions/set/blink", "3")):
            got = replies(topic, value, 1)
            assert len(got) == 1 and '"ok": true' in got[0].replace('"ok":true', '"ok": true'), got
        assert float(services[0].cli("get", "rover", "left").stdout) == 0.25
        assert int(services[1].cli("get", "actions", "calls").stdout) >= 1
        assert [b["key"] for b in services[0].boards()] == ["rover"]
        assert [b["key"] for b in services[1].boards()] == ["actions"]
    finally:
        for s in services:
            s.stop()
        for e in emus:
            e.stop()
