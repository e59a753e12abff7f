"""What the hub says about hub channels a board uses but the program does not offer: nothing from
a program that offers none (every `hubwire` command), once (not at every reconnect) from one that
offers some but not these, and a status line in `hubwire info`."""
from __future__ import annotations

import logging
import os
import subprocess
import sys
from typing import Any, Iterator, List

import pytest

from hubdevice import HubDevice, connect, full_hub, wait_for

NOTE = "uses hub channels the hub does not offer as it expects"


@pytest.fixture
def dev() -> Iterator[HubDevice]:
    d = HubDevice()
    d.start()
    yield d
    d.close()


def notes(caplog: Any) -> List[str]:
    return [r.getMessage() for r in caplog.records if NOTE in r.getMessage() and r.levelno >= logging.WARNING]


def test_a_program_offering_no_hub_channels_is_not_warned(dev: HubDevice, caplog: Any) -> None:
    caplog.set_level(logging.INFO, logger="hubwire")
    with connect(dev) as board:
        wait_for(lambda: len(dev.binds) >= 1)
        dev.reboot()  # a reconnect reports the binding again
        wait_for(lambda: len(dev.binds) >= 2)
        board.health()
    assert notes(caplog) == []


def test_a_program_offering_other_hub_channels_is_warned_once(dev: HubDevice, caplog: Any) -> None:
    caplog.set_level(logging.INFO, logger="hubwire")
    with connect(dev, hub=full_hub([])) as board:
        wait_for(lambda: len(dev.binds) >= 1)
        board.hub.remove("dock")  # the program takes one back: the board no longer has it
        wait_for(lambda: len(dev.binds) >= 2)
        dev.reboot()
        wait_for(lambda: len(dev.binds) >= 3)
    assert len(notes(caplog)) == 1, notes(caplog)
    assert "dock: UNKNOWN_CHANNEL" in notes(caplog)[0]


def test_info_says_which_program_offers_hub_channels(dev: HubDevice) -> None:
    r = subprocess.run([sys.executable, "-m", "hubwire", "info", dev.path, "--no-cache"], capture_output=True,
                       text=True, timeout=30, env=dict(os.environ, HUBWIRE_NO_SERVICE="1"))
    assert r.returncode == 0, r.stderr
    assert NOTE not in r.stderr
    assert "hubwire commands offer none of them" in r.stdout, r.stdout
