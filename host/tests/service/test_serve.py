"""`hubwire serve` against emulated boards: the CLI and Python reach boards by name through it, the
board stays linked between commands, unplug and replug on a new port, two clients at once, and what
a client hears when the board or the service is not there."""
from __future__ import annotations

import asyncio
import json
import os
import socket
from typing import Any, Callable

import pytest

import hubwire
import hubwire.aio
from conftest import Emulator

from .conftest import Serve, wait_for

#: the Rover's heartbeat is 250 ms and a side declares the link lost after 4 silent intervals; a
#: board that lost its hub would have run its failsafe well within this long
LOSS_WINDOW = 4 * 0.25 * 3


def test_cli_set_then_get_holds_the_value_no_failsafe(serve: Serve, emulators: Callable[[str], Emulator]) -> None:
    emulators("a")
    serve.wait_state("rover", "ready")
    serve.cli("set", "rover", "led", "true")
    assert serve.cli("get", "rover", "led").stdout.strip() == "True"
    r = serve.cli("set", "rover", "left", "0.5")
    assert "failsafe" not in r.stderr  # no warning: the service holds the link after the command
    import time

    time.sleep(LOSS_WINDOW)  # long enough for the board to notice a hub that went away
    assert serve.cli("get", "rover", "left").stdout.strip() == "0.5"
    out = json.loads(serve.cli("get", "rover", "failsafes", "--json").stdout)
    assert out == {"channel": "failsafes", "value": 0}
    assert serve.cli("call", "rover", "beep", "200").stdout.strip() == "True"
    info = serve.cli("info", "rover").stdout
    assert info.startswith("rover ") and "service:rover" in info


def test_python_connect_by_name_and_by_the_port_the_service_owns(serve: Serve,
                                                                  emulators: Callable[[str], Emulator]) -> None:
    emu = emulators("a")
    serve.wait_state("rover", "ready")
    with hubwire.connect("rover") as rover:
        assert rover.session.board["key"] == "rover"  # type: ignore[attr-defined]
        rover.left = 0.25
        assert rover.left == 0.25
        assert rover.beep(100) is True
        assert rover.imu.az > 9  # a struct, decoded as a direct connection decodes it
        assert "battery" in rover.table()
    # the port itself: the service owns it, so the hub goes through the service instead of opening it
    with hubwire.connect(emu.link) as same:
        assert same.url == "service:rover"
        assert same.left == 0.25
    with hubwire.connect() as auto:  # no port: the one board the service has
        assert auto.url == "service:rover"
    assert serve.board("rover")["attached"] == 1  # type: ignore[index]


def test_aio_connect_by_name(serve: Serve, emulators: Callable[[str], Emulator]) -> None:
    emulators("a")
    serve.wait_state("rover", "ready")

    async def main() -> Any:
        async with hubwire.aio.connect("rover") as rover:
            await rover.write("right", -0.5)
            got = [await rover.read("right"), await rover.call("beep", 50)]
            async with rover.stream("left", hz=50) as st:
                got.append(await st.__anext__())
            evs = rover.events("bumper")
            await rover.call("selftest", 3)
            got.append([(await evs.__anext__()).value for _ in range(3)])
            evs.close()
            return got
    assert asyncio.run(main()) == [-0.5, True, 0.0, [True, False, True]]


def test_two_clients_each_see_every_event_once(serve: Serve, emulators: Callable[[str], Emulator]) -> None:
    emulators("a")
    serve.wait_state("rover", "ready")
    with hubwire.connect("rover") as one, hubwire.connect("rover") as two:
        with one.events("bumper") as e1, two.events("bumper") as e2:
            got_cb = []
            one.on("bumper", got_cb.append)
            assert two.selftest(4) == 4  # the Rover's event queue holds 4
            a = [e1.get(10) for _ in range(4)]
            b = [e2.get(10) for _ in range(4)]
            assert None not in a and None not in b
            assert [e.seq for e in a] == [e.seq for e in b]
            assert [e.value for e in a] == [True, False, True, False]
            assert len({e.seq for e in a}) == 4
            assert e1.get(0.5) is None and e2.get(0.5) is None  # once each, nothing more
            wait_for(lambda: len(got_cb) == 4, what="4 callbacks")
            assert got_cb == [True, False, True, False]
        # one client's write is what the other reads: one board, shared
        one.led = True
        assert two.led is True
        one.led = False
        assert two.led is False


def test_unplug_and_replug_on_a_new_port(serve: Serve, emulators: Callable[[str], Emulator], boards_dir: str) -> None:
    first = emulators("a")
    serve.wait_state("rover", "ready", first.link)
    with hubwire.connect("rover") as rover:
        lost: list = []
        restored: list = []
        rover.on("link_lost", lambda: lost.append(1))
        rover.on("link_restored", lambda: restored.append(1))
        rover.on("reconnect", lambda desc: restored.append(desc.name))  # a new device session
        samples = rover.stream("left", hz=20, meta=True)
        assert samples.get(10) is not None
        first.stop()  # unplugged ...
        assert serve.wait_state("rover", "unplugged")["port"] is None
        with hubwire.connect("rover") as meanwhile:  # known while away, its calls fail fast
            assert meanwhile.session.board["state"] == "unplugged"  # type: ignore[attr-defined]
            with pytest.raises(hubwire.LinkLost, match="unplugged"):
                meanwhile.read("left")
        second = emulators("b")  # ... and back on another port
        back = serve.wait_state("rover", "ready", second.link)
        assert back["attached"] == 2 and back["key"] == "rover"
        assert rover.left == 0.0  # the same client object reaches the board on its new port
        rover.left = 0.75
        assert rover.left == 0.75
        wait_for(lambda: (lost, restored) == ([1], ["rover"]), what="link lost, then reconnect, once each")
        s = samples.get(10)  # the stream rode through, its first sample marked with the outage
        while s is not None and s.value != 0.75 and s.gap == 0:
            s = samples.get(10)
        assert s is not None and samples.gaps >= 1
        samples.close()
    assert [b["key"] for b in serve.boards()] == ["rover"]


def test_boards_with_one_name_get_keys_of_their_own(serve: Serve, emulators: Callable[[str], Emulator]) -> None:
    emulators("a")
    serve.wait_state("rover", "ready")
    emulators("b")
    serve.wait_state("rover---2", "ready")
    with hubwire.connect("rover") as r1, hubwire.connect("rover---2") as r2:
        r1.left = 0.5
        r2.left = -0.5
        assert (r1.left, r2.left) == (0.5, -0.5)
    r = serve.cli("get", "nosuch", "left", "--json", check=False)
    err = json.loads(r.stdout)
    assert r.returncode == 1 and err["error"] == "UnknownBoard"
    assert "rover (ready)" in err["message"] and "rover---2 (ready)" in err["message"]


def test_service_not_running(emulators: Callable[[str], Emulator], tmp_path: Any,
                             monkeypatch: Any) -> None:
    monkeypatch.setenv("HUBWIRE_SOCKET", str(tmp_path / "nobody.sock"))
    emu = emulators("a")
    import subprocess
    import sys

    r = subprocess.run([sys.executable, "-m", "hubwire", "get", "rover", "battery", "--json"], capture_output=True,
                       text=True, timeout=60)
    err = json.loads(r.stdout)
    assert r.returncode == 1 and err["error"] == "ServiceNotRunning"
    assert "hubwire serve" in err["message"] and "start it" in err["message"]
    # a port still opens directly, as without a service
    with hubwire.connect(emu.link) as rover:
        assert rover.url == emu.link and rover.battery > 0


def test_protocol_errors_are_answered(serve: Serve, emulators: Callable[[str], Emulator]) -> None:
    emulators("a")
    serve.wait_state("rover", "ready")
    with socket.socket(socket.AF_UNIX) as s:
        s.connect(serve.socket)
        f = s.makefile("rwb")
        hello = json.loads(f.readline())
        assert hello["service"] == "hubwire" and hello["protocol"] == 1
        for line in (b"not json\n", b'{"id": 1, "op": "fly"}\n', b'{"id": 2, "op": "write", "board": "rover", '
                     b'"channel": "left", "value": 7}\n', b'{"id": 3, "op": "read", "board": "rover", '
                     b'"channel": "left"}\n', b'{"id": 4, "op": "read", "board": "rover", "channel": "wings"}\n'):
            f.write(line)
            f.flush()
        answers = [json.loads(f.readline()) for _ in range(5)]
    by_id = {a.get("id"): a for a in answers}
    assert by_id[None]["error"] == "Usage"
    assert not by_id[1]["ok"] and "read" in by_id[1]["message"]
    assert by_id[2]["error"] == "InvalidValue"  # out of range: refused before it reaches the board
    assert by_id[3] == {"id": 3, "ok": True, "value": 0.0, "raw": "00000000"}
    assert by_id[4]["error"] == "UnknownChannel" and by_id[4]["message"].startswith("rover has no channel 'wings'")
    assert os.path.exists(serve.socket)


def test_mqtt_hook_hands_the_fleet_to_the_bridge(tmp_path: Any) -> None:
    """`serve --mqtt HOST:PORT` calls hubwire.bridge.mqtt.run_bridge(fleet, host=, port=) on the
    service's loop and cancels what it returned when the service stops."""
    from hubwire.daemon.fleet import Fleet
    from hubwire.cli.serve import serve as run_serve

    calls: list = []

    async def bridge(fleet: Fleet, *, host: str, port: int) -> None:
        calls.append((fleet, host, port))
        try:
            await asyncio.Event().wait()
        except asyncio.CancelledError:
            calls.append("cancelled")
            raise

    async def main() -> None:
        fleet = Fleet(usb=False)
        up = asyncio.Event()
        task = asyncio.ensure_future(run_serve(fleet, str(tmp_path / "s.sock"), bridge, "broker.lan:1884",
                                               ready=up.set))
        await asyncio.wait_for(up.wait(), 10)
        await asyncio.sleep(0)
        assert calls == [(fleet, "broker.lan", 1884)]
        task.cancel()
        await asyncio.gather(task, return_exceptions=True)
        assert calls[-1] == "cancelled"
        assert not os.path.exists(tmp_path / "s.sock")
    asyncio.run(main())


def test_mqtt_without_its_client_library_says_how_to_install_it(tmp_path: Any) -> None:
    import subprocess
    import sys

    # an installation without the `mqtt` extra: aiomqtt cannot be imported
    code = ("import sys; sys.modules['aiomqtt'] = None; from hubwire.cli import main; "
            f"sys.exit(main(['serve', '--no-usb', '--mqtt', 'localhost:1883', '--socket', {str(tmp_path / 's.sock')!r}]))")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert r.returncode == 1, r
    assert "pip install 'hubwire[mqtt]'" in r.stderr and "aiomqtt" in r.stderr
    assert not os.path.exists(tmp_path / "s.sock")


def test_watch_through_the_service_sees_events_another_client_caused(serve: Serve,
                                                                     emulators: Callable[[str], Emulator]) -> None:
    import subprocess
    import sys

    emulators("a")
    serve.wait_state("rover", "ready")
    watch = subprocess.Popen([sys.executable, "-m", "hubwire", "watch", "rover", "--json", "--duration", "30"],
                             env=serve.env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert watch.stdout is not None
        first = json.loads(watch.stdout.readline())  # watching: its event subscription is open
        assert first["link"]["state"] == "ready" and first["values"]["failsafes"] == 0
        assert serve.cli("call", "rover", "selftest", "2").stdout.strip() == "2"
        events = []
        while len(events) < 2:
            line = json.loads(watch.stdout.readline())
            if "event" in line:
                events.append((line["event"], line["value"]))
        assert events == [("bumper", True), ("bumper", False)]
    finally:
        watch.terminate()
        watch.wait(10)


def test_hub_channels_are_routed_through_the_service(serve: Serve, emulators: Callable[[str], Emulator]) -> None:
    """``hub=`` no longer forces a direct open (docs/SERVICE.md "Hub channels"): a board name or a
    port the service owns reach the board through the service, hub channels and all (the Rover
    uses none: nothing to provide, and no PortBusy)."""
    from hubwire import HubChannels

    emu = emulators("a")
    serve.wait_state("rover", "ready")
    hub = HubChannels()
    hub.provide("setpoint", 21.5, type="f32")
    for url in ("rover", emu.link):
        with hubwire.connect(url, hub=hub, timeout=5) as dev:
            assert dev.url == "service:rover" and dev.hub is hub
            assert dev.hub_binding() == {}
