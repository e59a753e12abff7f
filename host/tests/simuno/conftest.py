"""Fixtures: the examples (Rover, and the others through `examples`) built for the Uno, running in
simavr (build/simuno/simuno) on a pty.

Nothing is built here: `make simuno uno-firmware` builds them (`make test-python` does it first).
Override the paths with $HUBWIRE_SIMUNO and $HUBWIRE_UNO_ROVER_ELF, the bootloader time with
$HUBWIRE_SIMUNO_BOOT_DELAY_MS.
"""
from __future__ import annotations

import os
import selectors
import signal
import subprocess
import time
from typing import Any, Iterator, List, Optional

import pytest

from conftest import wait_until  # noqa: F401  (the simulated-Uno tests take it from here)
from hubwire.testing import tapped
from hubwire.testing.faultlink import stop_process

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", ".."))
BUILD_HINT = "build them with `make simuno uno-firmware`"

#: Like an Uno's bootloader after the DTR reset: the sketch starts ~1 s after the port is opened
#: (Optiboot waits 1 s for an upload; PROTOCOL.md 4.2 allows up to ~2 s).
BOOT_DELAY_MS = int(os.environ.get("HUBWIRE_SIMUNO_BOOT_DELAY_MS", "1000"))


def simuno_binary() -> str:
    return os.environ.get("HUBWIRE_SIMUNO") or os.path.join(REPO, "build", "simuno", "simuno")


def rover_elf() -> str:
    return os.environ.get("HUBWIRE_UNO_ROVER_ELF") or os.path.join(REPO, "build", "uno", "Rover", "Rover.ino.elf")


class Simuno:
    """One simuno process running the Rover firmware, its UART on a pty linked at ``link``.

    stderr (libsimavr's chatter and simuno's `simuno: reset` lines) goes to ``log`` so that a full
    pipe never blocks the simulation and a failing test can show it.
    """

    def __init__(self, binary: str, elf: str, link: str, log: str, boot_delay_ms: int = BOOT_DELAY_MS,
                 reset_on_open: bool = True) -> None:
        self.binary = binary
        self.elf = elf
        self.link = link
        self.log = log
        self.boot_delay_ms = boot_delay_ms
        self.reset_on_open = reset_on_open
        self.proc: Optional[subprocess.Popen] = None
        self.starts = 0

    @property
    def argv(self) -> list:
        args = [self.binary, self.elf, "--link", self.link, "--boot-delay", str(self.boot_delay_ms)]
        if self.reset_on_open:
            args.append("--reset-on-open")
        return args

    def press(self) -> None:
        """Press or release the button on pin 2 (Rover's bumper): simuno toggles it on SIGUSR2."""
        assert self.proc is not None, "simuno is not running"
        self.proc.send_signal(signal.SIGUSR2)

    def start(self, timeout: float = 10.0) -> None:
        assert self.proc is None, "simuno already running"
        with open(self.log, "ab") as err:
            self.proc = subprocess.Popen(self.argv, stdout=subprocess.PIPE, stderr=err, stdin=subprocess.DEVNULL)
        assert self.proc.stdout is not None
        sel = selectors.DefaultSelector()
        sel.register(self.proc.stdout, selectors.EVENT_READ)
        ready = sel.select(timeout)
        sel.close()
        line = self.proc.stdout.readline().decode(errors="replace").strip() if ready else ""
        if line != f"READY {self.link}":
            self.kill()
            raise RuntimeError(f"simuno did not print 'READY {self.link}' within {timeout} s "
                               f"(got {line!r}); its log:\n{self.log_text()}")
        self.starts += 1

    def reset(self) -> None:
        """SIGUSR1: reset the MCU (the bootloader delay follows), like pressing the reset button."""
        assert self.proc is not None and self.proc.poll() is None, "simuno is not running"
        self.proc.send_signal(signal.SIGUSR1)

    def resets(self) -> int:
        """How many MCU resets simuno logged so far (opens with --reset-on-open, SIGUSR1)."""
        return self.log_text().count("simuno: reset\n")

    def log_text(self) -> str:
        try:
            with open(self.log, encoding="utf-8", errors="replace") as fh:
                return fh.read()
        except OSError:
            return ""

    def stop(self) -> int:
        """SIGTERM and wait (simuno removes the link and exits 0); returns the exit status."""
        if self.proc is None:
            return 0
        p, self.proc = self.proc, None
        stop_process(p)
        if p.stdout is not None:
            p.stdout.close()
        return p.returncode

    def kill(self) -> None:
        if self.proc is not None:
            p, self.proc = self.proc, None
            if p.poll() is None:
                p.kill()
            p.wait(5)
            if p.stdout is not None:
                p.stdout.close()


@pytest.fixture(scope="session")
def simuno_build() -> tuple:
    """(simuno binary, Rover .elf): fails the test with the build command if either is missing."""
    binary, elf = simuno_binary(), rover_elf()
    missing = [p for p, ok in ((binary, os.access(binary, os.X_OK)), (elf, os.path.isfile(elf))) if not ok]
    if missing:
        pytest.fail(f"simulated Uno not built: missing {' and '.join(missing)}; {BUILD_HINT} "
                    "(or set HUBWIRE_SIMUNO / HUBWIRE_UNO_ROVER_ELF)", pytrace=False)
    return binary, elf


@pytest.fixture(autouse=True)
def hub_cache_dir(tmp_path: Any, monkeypatch: pytest.MonkeyPatch) -> str:
    """A fresh descriptor cache per test: HUBWIRE_CACHE_DIR points at it, so the hub's default
    (``cache_dir=None``) and the CLI use it too. A test that needs a shared cache reuses this path."""
    d = tmp_path / "hubwire-cache"
    d.mkdir()
    monkeypatch.setenv("HUBWIRE_CACHE_DIR", str(d))
    return str(d)


@pytest.fixture
def uno(simuno_build: tuple, tmp_path: Any, request: pytest.FixtureRequest) -> Iterator[Simuno]:
    """A simulated Uno running Rover on ``uno.link`` (reset-on-open, bootloader delay)."""
    binary, elf = simuno_build
    sim = Simuno(binary, elf, str(tmp_path / "uno"), str(tmp_path / "simuno.log"))
    sim.start()
    yield sim
    status = sim.stop()
    assert not os.path.lexists(sim.link), "simuno left its link behind"
    if status != 0:
        pytest.fail(f"simuno exited with status {status}; its log:\n{sim.log_text()}", pytrace=False)


@pytest.fixture
def rover(uno: Simuno) -> Iterator[Any]:
    """The real hub connected to the simulated Rover (default cache: this test's HUBWIRE_CACHE_DIR)."""
    import hubwire

    dev = hubwire.connect(transport=tapped(uno.link))
    try:
        yield dev
    finally:
        dev.close()


def drain_events(evs: Any, quiet: float = 0.4) -> List[Any]:
    """Events (or stream samples) until none arrived for ``quiet`` seconds; 0: those already here."""
    got = []
    while True:
        ev = evs.get(quiet)
        if ev is None:
            return got
        got.append(ev)


def take(stream: Any, n: int, deadline: float) -> List[Any]:
    """``n`` samples (or events) from ``stream``, waiting at most ``deadline`` seconds in all (a
    simulated Uno on a busy machine runs slower than real time; what counts is what it sends)."""
    got: List[Any] = []
    end = time.monotonic() + deadline
    while len(got) < n:
        left = end - time.monotonic()
        x = stream.get(left) if left > 0 else None
        if x is None:
            break
        got.append(x)
    return got


def example_elf(name: str) -> str:
    """examples/<name> built for the Uno by `make uno-firmware`."""
    return os.path.join(REPO, "build", "uno", name, f"{name}.ino.elf")


def start_example(name: str, link: str, log: str, elf: Optional[str] = None) -> Simuno:
    """examples/<name> (or the firmware ``elf``) started on a simulated Uno linked at ``link``;
    fails the test with the build command when simuno or the firmware is missing. The caller stops it."""
    binary, elf = simuno_binary(), elf or example_elf(name)
    if not (os.access(binary, os.X_OK) and os.path.isfile(elf)):
        pytest.fail(f"simulated Uno or {name} firmware not built: missing {binary} or {elf}; {BUILD_HINT}",
                    pytrace=False)
    sim = Simuno(binary, elf, link, log)
    sim.start()
    return sim


class Examples:
    """Starts example sketches on simulated Unos: ``examples.start("Failsafe")`` returns the
    connected hub device, ``examples.sim("Failsafe")`` its simulator."""

    def __init__(self, binary: str, tmp_path: Any) -> None:
        self.binary = binary
        self.tmp_path = tmp_path
        self.sims: dict = {}
        self.devices: List[Any] = []

    def start(self, name: str, **connect: Any) -> Any:
        """Run examples/<name> on a simulated Uno and connect to it (``connect``: to hubwire.connect,
        e.g. ``hub=`` the hub channels the sketch uses)."""
        import hubwire

        elf = example_elf(name)
        if not os.path.isfile(elf):
            pytest.fail(f"{elf} missing; {BUILD_HINT}", pytrace=False)
        sim = Simuno(self.binary, elf, str(self.tmp_path / name), str(self.tmp_path / f"{name}.log"))
        sim.start()
        self.sims[name] = sim
        # simavr keeps to wall-clock time only when it gets the CPU: on a busy machine the board's
        # bootloader wait and start-up take several times longer than the 5 s default deadline
        connect.setdefault("timeout", 30.0)
        dev = hubwire.connect(transport=tapped(sim.link), **connect)
        self.devices.append(dev)
        return dev

    def sim(self, name: str) -> Simuno:
        return self.sims[name]


@pytest.fixture
def examples(simuno_build: tuple, tmp_path: Any) -> Iterator[Examples]:
    """Example sketches on simulated Unos (see :class:`Examples`), all closed and stopped after the test."""
    ex = Examples(simuno_build[0], tmp_path)
    yield ex
    for dev in ex.devices:
        dev.close()
    for sim in ex.sims.values():
        status = sim.stop()
        assert status == 0, f"simuno exited with status {status}; its log:\n{sim.log_text()}"
