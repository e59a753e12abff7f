"""The dashboard as one more client of `hubwire serve --http`: every board the service owns, by its
key, in Debian's chromium driven by Playwright; a board unplugged shows so and comes back on another
port; a write from another client shows on the page."""
from __future__ import annotations

import re
import sys
from typing import Any, Callable

import pytest

from conftest import Emulator

from .conftest import make_serve

if sys.version_info < (3, 10):
    pytest.skip("NiceGUI 3 and Playwright need Python 3.10+", allow_module_level=True)

from test_dashboard_browser import _free_port, need_chromium, opened, sel, wait_text  # noqa: E402


def test_the_dashboard_shows_every_board_the_service_owns(boards_dir: str, tmp_path: Any,
                                                          emulators: Callable[..., Emulator],
                                                          monkeypatch: pytest.MonkeyPatch) -> None:
    need_chromium()
    http = _free_port()
    serve = make_serve(boards_dir, tmp_path, monkeypatch, ["--http", str(http)])
    emulators("a", "--board-id", "aa01")
    serve.start()
    try:
        serve.wait_state("rover--aa01", "ready")
        b = emulators("b", "--board-id", "bb02")
        serve.wait_state("rover--bb02", "ready")
        with opened(serve.dashboard_url(http)) as page:
            wait_text(page, sel("state", "rover--aa01"), "^ready$")
            wait_text(page, sel("state", "rover--bb02"), "^ready$")
            # another client of the service writes; the page shows the board's value
            serve.cli("set", "rover--bb02", "left", "0.25")
            wait_text(page, sel("value", "rover--bb02.left"), r"^0\.25 m/s$")
            wait_text(page, sel("value", "rover--aa01.left"), r"^0 m/s$")
            # unplugged, then back on another port: the same key, ready again
            b.stop()
            wait_text(page, sel("state", "rover--bb02"), "^unplugged$")
            emulators("c", "--board-id", "bb02")
            wait_text(page, sel("state", "rover--bb02"), "^ready$")
            wait_text(page, sel("state", "rover--aa01"), "^ready$")
    finally:
        status = serve.stop()
    assert status == 0, serve.log_text()
    assert re.search(r"dashboard at http://localhost:\d+/", serve.log_text())

