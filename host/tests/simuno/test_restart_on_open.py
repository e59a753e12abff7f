"""An Uno restarts whenever a program opens its port (DTR pulses its reset line), so a value one
`hubwire set` wrote is gone when the next command opens the port. On a Linux host the kernel raises
DTR at every open, before any setting a program makes can apply (pyserial's ``dtr`` before
``open()`` only lowers it afterwards); ``stty -hupcl`` keeps DTR up after a close so that the next
open makes no new edge, but that changes the port for every program. So the command says why in one
line and what to use instead. simuno models the reset on open, not the DTR line itself."""
from __future__ import annotations

import os
import subprocess
import sys
from typing import Any

from .conftest import Simuno

NOTE = ("hubwire: note: the board restarted when this command opened its port (as an Uno does), and will "
        "again at the next command, which then reads its start-up values; `hubwire serve` keeps it running "
        "(commands go through it)\n")


def cli(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "hubwire", *args], capture_output=True, text=True, timeout=60,
                          env=dict(os.environ, HUBWIRE_NO_SERVICE="1"))


def test_set_says_the_board_restarts_at_each_command(uno: Simuno) -> None:
    r = cli("set", uno.link, "led", "true")
    assert r.returncode == 0 and r.stderr == NOTE, r.stderr
    r = cli("get", uno.link, "led")
    assert r.stdout == "False\n" and r.stderr == "", r  # what the note announced: a fresh start
    r = cli("call", uno.link, "beep", "100")
    assert r.returncode == 0 and r.stderr == NOTE, r.stderr


def test_no_note_for_a_board_that_keeps_running(simuno_build: tuple, tmp_path: Any) -> None:
    binary, elf = simuno_build
    sim = Simuno(binary, elf, str(tmp_path / "uno"), str(tmp_path / "simuno.log"), reset_on_open=False)
    sim.start()
    try:
        r = cli("set", sim.link, "led", "true")
        assert r.returncode == 0 and r.stderr == "", r.stderr
        assert cli("get", sim.link, "led").stdout == "True\n"
    finally:
        sim.stop()
