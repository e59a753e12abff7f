"""Fixtures for the MQTT bridge: a private mosquitto on a free loopback port, emulated boards, and a
stand-in for the service's fleet (``hubwire.daemon.fleet`` has the real one)."""
from __future__ import annotations

import getpass
import os
import shutil
import signal
import socket
import subprocess
import time
from typing import Iterator, Optional

import pytest

MOSQUITTO = shutil.which("mosquitto") or ("/usr/sbin/mosquitto" if os.access("/usr/sbin/mosquitto", os.X_OK) else None)


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


class Broker:
    """A mosquitto of our own: ``start``, ``stop`` (SIGTERM: it saves its store), ``kill`` (SIGKILL)."""

    def __init__(self, binary: str, workdir: str, persistence: bool) -> None:
        self.binary = binary
        self.port = free_port()
        self.dir = workdir
        self.conf = os.path.join(workdir, "mosquitto.conf")
        self.log = os.path.join(workdir, "mosquitto.log")
        with open(self.conf, "w") as f:
            f.write(f"listener {self.port} 127.0.0.1\nallow_anonymous true\n"
                    f"persistence {'true' if persistence else 'false'}\npersistence_location {workdir}/\n"
                    "max_queued_messages 100000\nset_tcp_nodelay true\nlog_dest stderr\nlog_type error\nlog_type warning\n"
                    # run as root, mosquitto would switch to its own user, who cannot write here
                    f"user {getpass.getuser()}\n")
        self.proc: Optional[subprocess.Popen] = None  # type: ignore[type-arg]

    def start(self, timeout: float = 10.0) -> None:
        assert self.proc is None
        with open(self.log, "a") as log:
            self.proc = subprocess.Popen([self.binary, "-c", self.conf], stdout=log, stderr=log,
                                         stdin=subprocess.DEVNULL)
        deadline = time.monotonic() + timeout
        while True:
            try:
                socket.create_connection(("127.0.0.1", self.port), 0.2).close()
                return
            except OSError:
                if self.proc.poll() is not None or time.monotonic() > deadline:
                    raise RuntimeError(f"mosquitto did not start: {open(self.log).read()[-800:]}")
                time.sleep(0.05)

    def _end(self, sig: int) -> None:
        p, self.proc = self.proc, None
        if p is not None and p.poll() is None:
            p.send_signal(sig)
            p.wait(10)

    def stop(self) -> None:
        self._end(signal.SIGTERM)

    def kill(self) -> None:
        self._end(signal.SIGKILL)


def _broker(tmp_path, persistence: bool) -> Iterator[Broker]:  # type: ignore[no-untyped-def]
    if MOSQUITTO is None:
        pytest.fail("mosquitto is not installed: run tools/setup.sh (or apt-get install mosquitto)", pytrace=False)
    d = tmp_path / ("broker-p" if persistence else "broker")
    d.mkdir()
    b = Broker(MOSQUITTO, str(d), persistence)
    b.start()
    yield b
    b.stop()


@pytest.fixture
def broker(tmp_path) -> Iterator[Broker]:  # type: ignore[no-untyped-def]
    """A mosquitto without persistence: a restart forgets everything retained."""
    yield from _broker(tmp_path, False)


@pytest.fixture
def persistent_broker(tmp_path) -> Iterator[Broker]:  # type: ignore[no-untyped-def]
    """A mosquitto that keeps sessions and queued messages across a stop and start."""
    yield from _broker(tmp_path, True)


@pytest.fixture
def emulators(emulator_path: str, tmp_path):  # type: ignore[no-untyped-def]
    """``emulators(n)``: n Rover emulators on their own ptys (stopped at the end)."""
    from conftest import Emulator

    started = []

    def make(n: int, tag: str = "r") -> list:  # type: ignore[type-arg]
        out = []
        for i in range(n):
            emu = Emulator(emulator_path, str(tmp_path / f"{tag}{len(started)}"))
            emu.start()
            started.append(emu)
            out.append(emu)
        return out

    yield make
    for emu in started:
        emu.stop()
