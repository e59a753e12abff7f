"""Fixtures: `hubwire serve` as its own process, watching a directory where emulated boards and
simulated Unos put their pty links (a board "unplugged" is a process stopped, "replugged" one
started again on a new link in the same directory)."""
from __future__ import annotations

import json
import os
import re
import selectors
import signal
import subprocess
import sys
from typing import Any, Callable, Dict, Iterator, List, Optional, Sequence

import pytest

from conftest import Emulator, wait_until
from hubwire.testing import emulator_binary
from simuno.conftest import Simuno, start_example

HERE = os.path.dirname(os.path.abspath(__file__))
HOST = os.path.dirname(os.path.dirname(HERE))


def wait_for(predicate: Callable[[], Any], timeout: float = 15.0, what: str = "condition") -> Any:
    """:func:`conftest.wait_until` with the longer deadline a service's processes need."""
    return wait_until(predicate, timeout, what, 0.05)


class Serve:
    """One `hubwire serve` process serving every port that appears in ``boards_dir``."""

    def __init__(self, boards_dir: str, socket: str, env: Dict[str, str], log: str, args: Sequence[str] = ()) -> None:
        self.boards_dir = boards_dir
        self.args = list(args)  # more `hubwire serve` options, e.g. ["--mqtt", "127.0.0.1:1883"]
        self.socket = socket
        # what the service keeps across restarts: next to its log, never the user's own state
        self.env = env if "HUBWIRE_STATE_DIR" in env else dict(env, HUBWIRE_STATE_DIR=os.path.splitext(log)[0] + "-state")
        self.log = log
        self.proc: Optional[subprocess.Popen] = None

    @classmethod
    def own(cls, boards_dir: str, tmp_path: Any, args: Sequence[str] = (),
            extra_env: Optional[Dict[str, str]] = None) -> "Serve":
        """`hubwire serve ARGS` (not started yet) with a socket, descriptor cache and log of the
        test's own under ``tmp_path``; routing to the service is on in the commands it runs."""
        sock = str(tmp_path / "run" / "hubwire.sock")
        cache = os.path.join(str(tmp_path), "cache")
        os.makedirs(cache, exist_ok=True)
        env = dict(os.environ, HUBWIRE_SOCKET=sock, HUBWIRE_CACHE_DIR=cache,
                   PYTHONPATH=HOST + os.pathsep + os.environ.get("PYTHONPATH", ""), **(extra_env or {}))
        env.pop("HUBWIRE_NO_SERVICE", None)
        return cls(boards_dir, sock, env, str(tmp_path / "serve.log"), args)

    def start(self, timeout: float = 20.0) -> None:
        argv = [sys.executable, "-m", "hubwire", "serve", "--no-usb", "--watch", os.path.join(self.boards_dir, "*"),
                "--socket", self.socket, "--poll", "0.2", "-v", *self.args]
        with open(self.log, "ab") as err:
            self.proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=err, stdin=subprocess.DEVNULL,
                                         env=self.env)
        sel = selectors.DefaultSelector()
        assert self.proc.stdout is not None
        sel.register(self.proc.stdout, selectors.EVENT_READ)
        ready = sel.select(timeout)
        sel.close()
        line = self.proc.stdout.readline().decode().strip() if ready else ""
        assert line == f"READY {self.socket}", f"hubwire serve said {line!r}; its log:\n{self.log_text()}"

    def stop(self) -> int:
        p, self.proc = self.proc, None
        if p is None:
            return 0
        p.send_signal(signal.SIGTERM)
        try:
            return p.wait(10)
        except subprocess.TimeoutExpired:
            p.kill()
            p.wait(5)
            return -9

    def log_text(self) -> str:
        try:
            with open(self.log, encoding="utf-8", errors="replace") as fh:
                return fh.read()
        except OSError:
            return ""

    def cli(self, *args: str, check: bool = True) -> subprocess.CompletedProcess:
        """`hubwire ARGS` as a user runs it, with this service's socket."""
        r = subprocess.run([sys.executable, "-m", "hubwire", *args], env=self.env, capture_output=True,
                           text=True, timeout=60)
        if check:
            assert r.returncode == 0, f"hubwire {' '.join(args)}: {r.returncode}\n{r.stdout}\n{r.stderr}"
        return r

    def boards(self) -> List[Dict[str, Any]]:
        return json.loads(self.cli("list", "--json").stdout)  # type: ignore[no-any-return]

    def board(self, key: str) -> Optional[Dict[str, Any]]:
        return next((b for b in self.boards() if b["key"] == key), None)

    def dashboard_url(self, http: int) -> str:
        """The dashboard's address with its token, once the service started with ``--http HTTP`` logged it."""
        return str(wait_for(lambda: re.search(r"dashboard at (http://localhost:%d/\?token=\S+)" % http, self.log_text()),
                            what="the dashboard")[1])

    def wait_state(self, key: str, state: str, port: Optional[str] = None) -> Dict[str, Any]:
        def ok() -> Optional[Dict[str, Any]]:
            b = self.board(key)
            return b if b is not None and b["state"] == state and (port is None or b["port"] == port) else None
        return wait_for(ok, what=f"board {key} {state}{' on ' + port if port else ''}")  # type: ignore[no-any-return]


@pytest.fixture
def boards_dir(tmp_path: Any) -> str:
    d = tmp_path / "boards"
    d.mkdir()
    return str(d)


def make_serve(boards_dir: str, tmp_path: Any, monkeypatch: pytest.MonkeyPatch, args: Sequence[str] = ()) -> Serve:
    """:meth:`Serve.own`, and HUBWIRE_SOCKET points this process at it too (routing on)."""
    s = Serve.own(boards_dir, tmp_path, args)
    monkeypatch.setenv("HUBWIRE_SOCKET", s.socket)
    monkeypatch.delenv("HUBWIRE_NO_SERVICE", raising=False)
    return s


@pytest.fixture
def serve(boards_dir: str, tmp_path: Any, monkeypatch: pytest.MonkeyPatch) -> Iterator[Serve]:
    """`hubwire serve` on a socket of this test's own; HUBWIRE_SOCKET points this process at it too."""
    s = make_serve(boards_dir, tmp_path, monkeypatch)
    s.start()
    yield s
    status = s.stop()
    assert status == 0, f"hubwire serve exited with {status}; its log:\n{s.log_text()}"
    assert not os.path.exists(s.socket), "hubwire serve left its socket behind"


@pytest.fixture
def served_uno(boards_dir: str, tmp_path: Any) -> Iterator[Callable[..., Simuno]]:
    """``start(example, elf=None)``: examples/<example> (or ``elf``) on a simulated Uno linked at
    ``boards_dir/uno``, reset on every open as a real one; after the test simuno must exit cleanly."""
    started: List[Simuno] = []

    def start(name: str, elf: Optional[str] = None) -> Simuno:
        started.append(start_example(name, os.path.join(boards_dir, "uno"), str(tmp_path / "simuno.log"), elf))
        return started[-1]
    yield start
    for sim in started:
        assert sim.stop() == 0, sim.log_text()


@pytest.fixture
def emulators(boards_dir: str) -> Iterator[Callable[..., Emulator]]:
    """``start(name, *options)``: an emulated Rover on ``boards_dir/name`` (options such as
    ``"--board-id", "0a1b"``); every one stopped after the test."""
    path = emulator_binary()
    if not os.access(path, os.X_OK):
        pytest.fail(f"device emulator not found at {path}: build it with `make emulator`", pytrace=False)
    started: List[Emulator] = []

    def start(name: str, *args: str) -> Emulator:
        emu = Emulator(path, os.path.join(boards_dir, name), args)
        emu.start()
        started.append(emu)
        return emu
    yield start
    for emu in started:
        emu.stop()
