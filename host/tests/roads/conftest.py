"""Fixtures of the behaviour suite: the same emulated boards reached on both roads, directly (the
program opens the port) and routed (through a `hubwire serve` of the module's own), so that every
test runs once per road and a difference between them is a failing test.

Each sketch runs twice: one emulator in the directory the service watches, one the direct road opens.
"""
from __future__ import annotations

import asyncio
import os
from typing import Any, Callable, Dict, Iterator, List

import pytest

import hubwire
import hubwire.aio
from conftest import Emulator
from hubwire.testing import emulator_binary
from service.conftest import HOST, Serve

#: sketch -> (emulator binary, board name in its descriptor)
SKETCHES = {"rover": ("hubwire-emulator", "rover"), "actions": ("hubwire-actions-emulator", "actions"),
            "large": ("hubwire-largevalues-emulator", "large"), "soak": ("hubwire-soak-emulator", "soak")}
ROADS = ("direct", "routed")


def _binary(name: str) -> str:
    path = os.path.join(os.path.dirname(emulator_binary()), name)
    if not os.access(path, os.X_OK):
        pytest.fail(f"device emulator not found at {path}: build it with `make emulator`", pytrace=False)
    return path


class Roads:
    """Every sketch twice (served, and for the direct road) and the service serving the first."""

    def __init__(self, root: str) -> None:
        self.served_dir = os.path.join(root, "served")
        self.direct_dir = os.path.join(root, "direct")
        os.makedirs(self.served_dir)
        os.makedirs(self.direct_dir)
        self.cache = os.path.join(root, "cache")
        os.makedirs(self.cache)
        self.emulators: List[Emulator] = []
        sock = os.path.join(root, "run", "hubwire.sock")
        env = dict(os.environ, HUBWIRE_SOCKET=sock, HUBWIRE_CACHE_DIR=self.cache,
                   PYTHONPATH=HOST + os.pathsep + os.environ.get("PYTHONPATH", ""))
        env.pop("HUBWIRE_NO_SERVICE", None)
        self.serve = Serve(self.served_dir, sock, env, os.path.join(root, "serve.log"))

    def start(self) -> None:
        for sketch, (binary, _) in SKETCHES.items():
            for folder in (self.served_dir, self.direct_dir):
                emu = Emulator(_binary(binary), os.path.join(folder, sketch))
                emu.start()
                self.emulators.append(emu)
        self.serve.start()
        for _, name in SKETCHES.values():
            self.serve.wait_state(name, "ready")

    def stop(self) -> None:
        self.serve.stop()
        for emu in self.emulators:
            emu.stop()

    def emulator(self, road: str, sketch: str) -> Emulator:
        """The emulator the board on ``road`` runs in."""
        folder = self.direct_dir if road == "direct" else self.served_dir
        return next(e for e in self.emulators if e.link == os.path.join(folder, sketch))

    def target(self, road: str, sketch: str) -> str:
        """What ``connect()`` is given on ``road``: the direct emulator's port, or the board's name."""
        return os.path.join(self.direct_dir, sketch) if road == "direct" else SKETCHES[sketch][1]


@pytest.fixture(scope="module")
def roads(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Roads]:
    r = Roads(str(tmp_path_factory.mktemp("roads")))
    mp = pytest.MonkeyPatch()
    mp.setenv("HUBWIRE_SOCKET", r.serve.socket)
    mp.delenv("HUBWIRE_NO_SERVICE", raising=False)
    try:
        r.start()
        yield r
    finally:
        r.stop()
        mp.undo()


@pytest.fixture(params=ROADS)
def road(request: pytest.FixtureRequest) -> str:
    return str(request.param)


@pytest.fixture
def board(roads: Roads, road: str) -> Iterator[Callable[..., hubwire.Device]]:
    """``board(sketch, **connect_kwargs)``: the sketch's board on this test's road (closed after it)."""
    opened: List[hubwire.Device] = []

    def open_(sketch: str, **kw: Any) -> hubwire.Device:
        kw.setdefault("cache_dir", roads.cache)
        dev = hubwire.connect(roads.target(road, sketch), timeout=10, **kw)
        opened.append(dev)
        assert dev.url.startswith("service:") == (road == "routed")
        return dev
    yield open_
    for dev in opened:
        dev.close()


@pytest.fixture
def both(roads: Roads) -> Iterator[Callable[..., Dict[str, hubwire.Device]]]:
    """``both(sketch)``: the sketch's board on each road, by road name (closed after the test)."""
    opened: List[hubwire.Device] = []

    def open_(sketch: str, **kw: Any) -> Dict[str, hubwire.Device]:
        kw.setdefault("cache_dir", roads.cache)
        devs = {road: hubwire.connect(roads.target(road, sketch), timeout=10, **kw) for road in ROADS}
        opened.extend(devs.values())
        return devs
    yield open_
    for dev in opened:
        dev.close()


def run(coro: Any) -> Any:
    """Run a coroutine of an asyncio test to its end (with a generous deadline)."""
    return asyncio.run(asyncio.wait_for(coro, 60))


def aconnect(roads: Roads, road: str, sketch: str, **kw: Any) -> Any:
    """``hubwire.aio.connect`` to the sketch's board on ``road`` (an awaitable async context manager)."""
    kw.setdefault("cache_dir", roads.cache)
    return hubwire.aio.connect(roads.target(road, sketch), timeout=10, **kw)
