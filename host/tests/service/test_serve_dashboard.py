"""The dashboard as one more client of `hubwire serve --http`: every board the service owns, by its
key, in Debian's chromium driven by Playwright; a board unplugged shows so and comes back on another
port; a write from another client shows on the page."""
from __future__ import annotations

import os
import re
import sys
from typing import Any, Callable

import pytest

from conftest import Emulator

from .conftest import HOST, Serve, wait_for

if sys.version_info < (3, 10):
    pytest.skip("NiceGUI 3 and Playwright need Python 3.10+", allow_module_level=True)
import playwright.sync_api as playwright_api  # noqa: E402  (after the version check)

from test_dashboard_browser import CHROMIUM, WAIT_MS, _free_port, sel, wait_text  # noqa: E402


def test_the_dashboard_shows_every_board_the_service_owns(boards_dir: str, tmp_path: Any,
                                                          emulators: Callable[..., Emulator],
                                                          monkeypatch: pytest.MonkeyPatch) -> None:
    if not os.access(CHROMIUM, os.X_OK):
        pytest.fail(f"{CHROMIUM} not found: bash tools/setup.sh installs Debian's chromium", pytrace=False)
    http = _free_port()
    sock = str(tmp_path / "run" / "hubwire.sock")
    cache = tmp_path / "cache"
    cache.mkdir()
    env = dict(os.environ, HUBWIRE_SOCKET=sock, HUBWIRE_CACHE_DIR=str(cache),
               PYTHONPATH=HOST + os.pathsep + os.environ.get("PYTHONPATH", ""))
    monkeypatch.setenv("HUBWIRE_SOCKET", sock)
    serve = Serve(boards_dir, sock, env, str(tmp_path / "serve.log"), ["--http", str(http)])
    emulators("a", "--board-id", "aa01")
    serve.start()
    try:
        serve.wait_state("rover--aa01", "ready")
        b = emulators("b", "--board-id", "bb02")
        serve.wait_state("rover--bb02", "ready")
        url = wait_for(lambda: re.search(r"dashboard at (http://localhost:%d/\?token=\S+)" % http, serve.log_text()),
                       what="the dashboard")[1]
        with playwright_api.sync_playwright() as p:
            browser = p.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox"])
            page = browser.new_page(viewport={"width": 1400, "height": 1000})
            page.set_default_timeout(WAIT_MS)
            page.goto(url)
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
            browser.close()
    finally:
        status = serve.stop()
    assert status == 0, serve.log_text()
    assert re.search(r"dashboard at http://localhost:\d+/", serve.log_text())

