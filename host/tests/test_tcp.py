"""The hub over TCP (``socket://host:port``), as to a board serving the protocol on WiFi: the C++
emulator with Serial on a TCP connection (``--tcp``), taking the next hub after one hangs up."""
from __future__ import annotations

import selectors
import signal
import subprocess
from typing import Iterator, List

import pytest

import hubwire

from conftest import wait_until


@pytest.fixture
def tcp_rover(emulator_path: str) -> Iterator[subprocess.Popen]:  # type: ignore[type-arg]
    proc = subprocess.Popen([emulator_path, "--tcp", "0"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            stdin=subprocess.DEVNULL)
    yield proc
    proc.terminate()
    try:
        proc.wait(5)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait(5)


def ready_url(proc: subprocess.Popen) -> str:  # type: ignore[type-arg]
    sel = selectors.DefaultSelector()
    assert proc.stdout is not None
    sel.register(proc.stdout, selectors.EVENT_READ)
    assert sel.select(10), "emulator did not print READY"
    line = proc.stdout.readline().decode().strip()
    sel.close()
    assert line.startswith("READY socket://127.0.0.1:"), line
    return line.split(" ", 1)[1]


def test_discovery_and_writes_over_tcp(tcp_rover: subprocess.Popen, cache_dir: str) -> None:  # type: ignore[type-arg]
    url = ready_url(tcp_rover)
    with hubwire.connect(url, cache_dir=cache_dir) as dev:
        assert dev.descriptor.name == "rover"
        dev.left = 0.5
        assert dev.left == 0.5
    # the board takes the next hub once this one has hung up
    with hubwire.connect(url, cache_dir=cache_dir) as dev:
        assert dev.session.stats.cache_hits == 1
        assert dev.left == 0.5


def test_the_hub_reconnects_after_the_connection_drops(tcp_rover: subprocess.Popen,  # type: ignore[type-arg]
                                                       cache_dir: str) -> None:
    url = ready_url(tcp_rover)
    lost: List[str] = []
    restored: List[str] = []
    with hubwire.connect(url, cache_dir=cache_dir, on_link_lost=lambda *a: lost.append("lost"),
                         on_link_restored=lambda *a: restored.append("restored")) as dev:
        dev.right = 0.25
        reopens = dev.session.stats.port_reopens
        tcp_rover.send_signal(signal.SIGHUP)  # the board drops the connection, as a WiFi link that fails
        wait_until(lambda: dev.session.stats.port_reopens > reopens and bool(restored), timeout=15,
                   what="the hub to open the connection again and link")
        assert lost, "the drop was noticed"
        dev.right = -0.5  # the same board, talking again over the new connection
        assert dev.right == -0.5
