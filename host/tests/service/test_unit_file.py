"""The systemd unit agrees with the code: it listens where clients look and caches where it may write."""
from __future__ import annotations

import configparser
import os
import shlex

from hubwire.client.protocol import SYSTEM_SOCKET
from hubwire.daemon.store import SYSTEM_STATE_DIR

UNIT = os.path.join(os.path.dirname(__file__), "..", "..", "hubwire", "daemon", "hubwire.service")


def _unit() -> configparser.ConfigParser:
    unit = configparser.ConfigParser(strict=False, interpolation=None)
    unit.optionxform = str  # type: ignore[assignment,method-assign]
    with open(UNIT) as fh:
        unit.read_file(fh)
    return unit


def test_unit_serves_on_the_socket_clients_try_and_caches_in_its_cache_directory() -> None:
    unit = _unit()
    svc = unit["Service"]
    argv = shlex.split(svc["ExecStart"])
    assert argv[0].endswith("/bin/hubwire") and argv[1] == "serve"
    assert argv[argv.index("--socket") + 1] == SYSTEM_SOCKET
    assert SYSTEM_SOCKET == f"/run/{svc['RuntimeDirectory']}/hubwire.sock"
    assert svc["Environment"] == f"HUBWIRE_CACHE_DIR=/var/cache/{svc['CacheDirectory']}"
    assert svc["Group"] == "dialout" and unit["Install"]["WantedBy"] == "multi-user.target"


def test_unit_makes_the_socket_directory_for_its_group_only() -> None:
    """/run/hubwire: the service's user writes, its group (dialout) may enter, other users not at all."""
    unit = _unit()
    svc = unit["Service"]
    assert int(svc["RuntimeDirectoryMode"], 8) == 0o750
    assert svc["Group"] and svc["User"] != "root"


def test_unit_keeps_its_state_in_a_private_state_directory() -> None:
    unit = _unit()
    svc = unit["Service"]
    argv = shlex.split(svc["ExecStart"])
    assert argv[argv.index("--state") + 1] == f"/var/lib/{svc['StateDirectory']}" == SYSTEM_STATE_DIR
    assert svc["StateDirectoryMode"] == "0700"
