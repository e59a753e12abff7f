"""An Uno has no unique id of its own: a build with HUBWIRE_BOARD_ID_EEPROM keeps one in EEPROM,
drawn on the first boot and the same after every reset (PROTOCOL.md 3.4). Minimal built that way by
`make uno-firmware`, on the simulated Uno."""
from __future__ import annotations

import os
from typing import Any

import pytest

import hubwire
from hubwire.testing import tapped

from .conftest import REPO, Simuno, wait_until


def test_an_eeprom_board_id_is_drawn_once_and_survives_resets(simuno_build: tuple, tmp_path: Any) -> None:
    elf = os.path.join(REPO, "build", "uno", "MinimalBoardId", "Minimal.ino.elf")
    if not os.path.isfile(elf):
        pytest.fail(f"{elf} missing; build it with `make uno-firmware`", pytrace=False)
    sim = Simuno(simuno_build[0], elf, str(tmp_path / "uno"), str(tmp_path / "uno.log"))
    sim.start()
    ids = []
    try:
        for _ in range(2):  # each open resets the board, as on a real Uno
            with hubwire.connect(transport=tapped(sim.link)) as dev:
                ids.append(dev.board_id())
        wait_until(lambda: sim.resets() >= 2, what="two resets")
    finally:
        assert sim.stop() == 0, sim.log_text()
    assert ids[0] is not None and len(ids[0]) == 8, ids
    assert ids[0] not in ("ffffffff", "00000000")  # a blank EEPROM reads all ones: the id was drawn and written
    assert ids[1] == ids[0]


def test_a_plain_uno_build_has_no_board_id(examples: Any) -> None:
    dev = examples.start("Minimal")
    assert dev.board_id() is None
