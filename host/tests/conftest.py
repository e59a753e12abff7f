"""Fixtures: the C++ device emulator on a pty (build/emulator/hubwire-emulator, or $HUBWIRE_EMULATOR)."""
from __future__ import annotations

import os
import selectors
import signal
import subprocess
import time
from typing import Iterator, Optional, Sequence

import pytest

from hubwire.testing import emulator_binary, tapped



class Emulator:
    """One emulator process playing the Rover on a pty linked at ``link``; restartable."""

    def __init__(self, binary: str, link: str, args: Sequence[str] = ()) -> None:
        self.binary = binary
        self.link = link
        self.args = list(args)  # more emulator options, e.g. ["--board-id", "0a1b"]
        self.proc: Optional[subprocess.Popen] = None
        self.starts = 0

    def start(self, timeout: float = 10.0) -> None:
        assert self.proc is None, "emulator already running"
        self.proc = subprocess.Popen([self.binary, "--link", self.link, *self.args], stdout=subprocess.PIPE,
                                     stderr=subprocess.PIPE, stdin=subprocess.DEVNULL)
        sel = selectors.DefaultSelector()
        assert self.proc.stdout is not None
        sel.register(self.proc.stdout, selectors.EVENT_READ)
        if not sel.select(timeout):
            self.kill()
            raise RuntimeError(f"emulator did not print READY within {timeout} s")
        line = self.proc.stdout.readline().decode().strip()
        sel.close()
        if line != f"READY {self.link}":
            err = self.proc.stderr.read().decode() if self.proc.poll() is not None and self.proc.stderr else ""
            self.kill()
            raise RuntimeError(f"emulator said {line!r} instead of 'READY {self.link}' {err}")
        self.starts += 1

    def signal(self, sig: int) -> None:
        assert self.proc is not None
        self.proc.send_signal(sig)

    def pause(self) -> None:
        self.signal(signal.SIGSTOP)

    def resume(self) -> None:
        self.signal(signal.SIGCONT)

    def bump(self) -> None:
        """Press or release the Rover's bumper (SIGUSR2): one bumper event."""
        self.signal(signal.SIGUSR2)

    def stop(self) -> int:
        """SIGTERM and wait; returns the exit code."""
        if self.proc is None:
            return 0
        p, self.proc = self.proc, None
        if p.poll() is None:
            p.send_signal(signal.SIGCONT)
            p.terminate()
            try:
                return p.wait(5)
            except subprocess.TimeoutExpired:
                p.kill()
                return p.wait(5)
        return p.returncode

    def kill(self) -> None:
        if self.proc is not None:
            p, self.proc = self.proc, None
            p.kill()
            p.wait(5)


@pytest.fixture
def emulator_path() -> str:
    path = emulator_binary()
    if not os.access(path, os.X_OK):
        pytest.fail(f"device emulator not found at {path}: build it with `make emulator` "
                    "(or point HUBWIRE_EMULATOR at the binary)", pytrace=False)
    return path


@pytest.fixture
def emulator(emulator_path: str, tmp_path) -> Iterator[Emulator]:  # type: ignore[no-untyped-def]
    emu = Emulator(emulator_path, str(tmp_path / "rover"))
    emu.start()
    yield emu
    emu.stop()


@pytest.fixture
def cache_dir(tmp_path) -> str:  # type: ignore[no-untyped-def]
    d = tmp_path / "cache"
    d.mkdir()
    return str(d)


@pytest.fixture
def rover(emulator: Emulator, cache_dir: str):  # type: ignore[no-untyped-def]
    import hubwire

    dev = hubwire.connect(transport=tapped(emulator.link), cache_dir=cache_dir)
    yield dev
    dev.close()


def wait_until(predicate, timeout: float = 5.0, what: str = "condition",  # type: ignore[no-untyped-def]
               interval: float = 0.01):
    """Poll ``predicate`` (for state we cannot subscribe to, e.g. another process) until it returns
    something truthy, which is returned; AssertionError after ``timeout``."""
    deadline = time.monotonic() + timeout
    while True:
        v = predicate()
        if v:
            return v
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out after {timeout} s waiting for {what}")
        time.sleep(interval)
