"""The dashboard's mission controls in Debian's chromium (Playwright), on `hubwire serve --http` with
the missions emulator (examples/Missions): the start form takes the goal of the declared type and
range, the progress bar fills, a second start while one runs shows BUSY, cancel ends the run, and a
run started by another client (`hubwire call`) shows on the page too."""
from __future__ import annotations

import os
import sys
from typing import Any

import pytest

from conftest import Emulator

from .conftest import HOST, make_serve

if sys.version_info < (3, 10):
    pytest.skip("NiceGUI 3 and Playwright need Python 3.10+", allow_module_level=True)

from test_dashboard_browser import _free_port, field, need_chromium, opened, sel, wait_text  # noqa: E402

MISSIONS_EMULATOR = os.path.join(HOST, "..", "build", "emulator", "hubwire-missions-emulator")
M = "missions.drive"


def test_start_progress_cancel_and_result_in_the_browser(boards_dir: str, tmp_path: Any,
                                                          monkeypatch: pytest.MonkeyPatch) -> None:
    need_chromium()
    if not os.access(MISSIONS_EMULATOR, os.X_OK):
        pytest.fail(f"{MISSIONS_EMULATOR} missing: build it with `make emulator`", pytrace=False)
    http = _free_port()
    serve = make_serve(boards_dir, tmp_path, monkeypatch, ["--http", str(http)])
    emu = Emulator(MISSIONS_EMULATOR, os.path.join(boards_dir, "missions"))
    emu.start()
    serve.start()
    try:
        serve.wait_state("missions", "ready")
        with opened(serve.dashboard_url(http)) as page:
            wait_text(page, sel("state", "missions"), "^ready$")
            wait_text(page, sel("run", M), "^no run yet$")
            # a goal outside the declared range is refused by the hub; nothing starts
            serve.cli("set", "missions", "speed", "2")
            goal = field(page, "goal", M)
            goal.fill("20")
            goal.press("Tab")  # the field loses focus first, as when the user moves to the button
            page.locator(sel("start", M)).click()
            wait_text(page, sel("mission-error", M), r"outside the declared range")
            assert goal.input_value() == "20"  # what was typed stays (never clamped to the range)
            # a drive of 1 m: the bar fills, the result shows
            field(page, "goal", M).fill("1")
            page.locator(sel("start", M)).click()
            wait_text(page, sel("run", M), r"^run 1 \([0-9a-f]{16}\): succeeded$")
            wait_text(page, sel("mission-result", M), r"^-> 1 m$")
            assert page.locator(sel("progress", M)).get_attribute("data-hw-fraction") == "1"
            assert page.locator(sel("mission-error", M)).inner_text() == ""
            # a slow drive: progress shows, a second start is BUSY, cancel ends it
            serve.cli("set", "missions", "speed", "0.1")
            field(page, "goal", M).fill("10")
            page.locator(sel("start", M)).click()
            wait_text(page, sel("run", M), r"^run 2 .*: running$")
            wait_text(page, sel("progress-value", M), r"^0\.\d+ m$")
            page.wait_for_function(f"Number(document.querySelector('{sel('progress', M)}')"
                                   ".getAttribute('data-hw-fraction')) > 0")
            page.locator(sel("start", M)).click()
            wait_text(page, sel("mission-error", M), r"^refused by the board: the board is busy")
            wait_text(page, sel("run", M), r"^run 2 .*: running$")  # the run that goes is still shown
            page.locator(sel("cancel", M)).click()
            wait_text(page, sel("run", M), r"^run 2 .*: cancelled$")
            wait_text(page, sel("mission-result", M), r"run 2 was cancelled")
            # a run another client starts shows here too
            serve.cli("set", "missions", "speed", "2")
            serve.cli("call", "missions", "drive", "0.5")
            wait_text(page, sel("run", M), r"^run 3 .*: succeeded$")
            wait_text(page, sel("mission-result", M), r"^-> 0\.5 m$")
    finally:
        status = serve.stop()
        emu.stop()
    assert status == 0, serve.log_text()
