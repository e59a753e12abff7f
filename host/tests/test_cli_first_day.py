"""What a newcomer meets on the first day: install advice that works from a clone, command-line
advice on the command line, column headers, a Python error per refused access, and values that say
"not measured yet" rather than 0."""
from __future__ import annotations

import os
import subprocess
import sys
from typing import Any, Optional

import pytest
from conftest import Emulator

import hubwire
from hubwire.diagnose import ERROR_TYPES

CLI = [sys.executable, "-m", "hubwire"]


def run(*args: str, cache: Optional[str] = None, timeout: float = 30, **env: str) -> subprocess.CompletedProcess:
    return subprocess.run([*CLI, *args], capture_output=True, text=True, timeout=timeout,
                          env=dict(os.environ, HUBWIRE_CACHE_DIR=cache or os.devnull, **env))


# ------------------------------------------------------------------------------- install advice

def test_install_advice_names_the_clone_not_the_package_index() -> None:
    """The package is not on the package index: `pip install 'hubwire[...]'` fails there."""
    text = " ".join((run("--help").stdout + run("dashboard", "--help").stdout + run("serve", "--help").stdout).split())
    assert "hubwire[" not in text.replace("./host[", "")
    assert "pip install './host[dashboard]'" in text
    from hubwire.diagnose import install_hint

    assert install_hint("mqtt") == "pip install './host[mqtt]' in your Hubwire clone (it is not on PyPI)"


def test_serve_without_the_mqtt_libraries_says_how_to_install_them(monkeypatch: pytest.MonkeyPatch) -> None:
    from hubwire.cli import serve as main

    monkeypatch.setitem(sys.modules, "hubwire.bridge.mqtt", None)  # as if aiomqtt were missing
    with pytest.raises(SystemExit) as e:
        main.mqtt_bridge()
    assert "pip install './host[mqtt]'" in str(e.value) and "hubwire[" not in str(e.value)


def test_auto_without_a_board_gives_command_line_advice() -> None:
    # no board on this machine's USB: what `auto` says is about the command line, not Python
    r = run("get", "auto", "battery", HUBWIRE_NO_SERVICE="1")
    assert r.returncode == 1 and "no microcontroller board found" in r.stderr, r.stderr
    assert "connect(" not in r.stderr
    assert "hubwire get /dev/ttyACM0 battery" in r.stderr
    with pytest.raises(hubwire.NoDeviceFound, match=r"connect\('/dev/ttyACM0'\)"):
        hubwire.find_port()  # Python keeps its own advice


# ------------------------------------------------------------------------------- column headers

def test_ports_prints_column_headers() -> None:
    r = run("ports")
    assert r.returncode == 0
    first = r.stdout.splitlines()[0]
    assert first.split() == ["PORT", "USB", "ID", "DESCRIPTION"] or first == "no serial ports found", r.stdout


def test_ports_lines_up_under_its_headers(monkeypatch: pytest.MonkeyPatch, capsys: Any) -> None:
    from types import SimpleNamespace

    from serial.tools import list_ports

    from hubwire import cli

    fake = [SimpleNamespace(device="/dev/ttyACM0", vid=0x2341, pid=0x43, description="Arduino Uno", serial_number="1"),
            SimpleNamespace(device="/dev/ttyS0", vid=None, pid=None, description="n/a", serial_number=None)]
    monkeypatch.setattr(list_ports, "comports", lambda: fake)
    assert cli.main(["ports"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].split() == ["PORT", "USB", "ID", "DESCRIPTION"]
    assert lines[1].split() == ["/dev/ttyACM0", "2341:0043", "Arduino", "Uno", "[Arduino]"]
    assert lines[2].split() == ["/dev/ttyS0", "-", "n/a"]
    assert lines[1].index("2341") == lines[0].index("USB")


def test_list_prints_column_headers(monkeypatch: pytest.MonkeyPatch, capsys: Any) -> None:
    from hubwire.cli import serve as main
    from hubwire.client import connection as client

    rows = [{"key": "rover", "name": "rover", "board_id": None, "state": "ready", "port": "/dev/ttyACM0"}]

    class Conn:
        @classmethod
        async def open(cls, *a: Any) -> "Conn":
            return cls()

        async def request(self, what: str) -> Any:
            return {"boards": rows}

        async def close(self) -> None:
            pass

    monkeypatch.setattr(client, "Connection", Conn)
    assert main.cmd_list(main.argparse.Namespace(json=False)) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].split() == ["BOARD", "NAME", "BOARD", "ID", "STATE", "PORT"]
    assert lines[1].split() == ["rover", "rover", "-", "ready", "/dev/ttyACM0"]


# ------------------------------------------------------------------------- the Python interface

def test_writing_a_read_only_channel_raises_not_writable(emulator: Emulator, cache_dir: str) -> None:
    assert issubclass(hubwire.NotWritable, hubwire.HubwireError)
    assert {hubwire.NotReadable.__name__, hubwire.NotWritable.__name__, hubwire.NotCallable.__name__} <= set(ERROR_TYPES)
    with hubwire.connect(emulator.link, cache_dir=cache_dir) as rover:
        with pytest.raises(hubwire.NotWritable, match="'battery' cannot be written"):
            rover.battery = 5
        with pytest.raises(hubwire.NotCallable):
            rover.call("battery")
    from hubwire import diagnose

    assert diagnose.error_type(hubwire.NotWritable("x")) == "NotWritable"


def test_measured_heartbeat_is_none_until_measured() -> None:
    from hubwire.session import LinkHealth  # noqa: F401  (the field documented there)
    from hubwire.session.core import measured_ms

    assert measured_ms(None) is None
    assert measured_ms(0) is None  # the first heartbeat after a start has no previous one
    assert measured_ms(250) == 250


def test_times_are_documented_as_monotonic_seconds() -> None:
    for cls in (hubwire.ReceivedEvent, hubwire.StreamSample):
        assert "seconds of ``time.monotonic()``" in (cls.__doc__ or ""), cls
