"""The dashboard lists the hub channels a board uses (examples/Thermostat on the simulated Uno: a
value it reads from the hub, one it writes, an action it calls, events it hears), each with its
binding as the dashboard's own hub sees it: `hubwire dashboard` declares no hub channels, so none is
bound there, and the page says why."""
from __future__ import annotations

import os
import re
import subprocess
import sys
import time
from typing import Any

import pytest

from .conftest import BOOT_DELAY_MS, Simuno, example_elf, simuno_binary

if sys.version_info < (3, 10):
    pytest.skip("NiceGUI 3 and Playwright need Python 3.10+", allow_module_level=True)
import playwright.sync_api as playwright_api  # noqa: E402  (after the version check)

WAIT_S = 20 * (BOOT_DELAY_MS / 1000 + 1.0)


def test_the_page_lists_the_hub_channels_a_board_uses(tmp_path: Any) -> None:
    elf = example_elf("Thermostat")
    if not os.path.isfile(elf):
        pytest.fail(f"{elf} missing; build it with `make uno-firmware`", pytrace=False)
    sim = Simuno(simuno_binary(), elf, str(tmp_path / "uno"), str(tmp_path / "uno.log"))
    sim.start()
    from test_dashboard_browser import _free_port

    port = _free_port()
    dash = subprocess.Popen([sys.executable, "-m", "hubwire", "dashboard", sim.link, "--http", str(port),
                             "--no-cache"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        assert dash.stdout is not None
        out, deadline = "", time.monotonic() + WAIT_S
        while "hubwire dashboard: http" not in out and time.monotonic() < deadline and dash.poll() is None:
            out += dash.stdout.readline()
        url = re.search(r"hubwire dashboard: (http://\S+)", out)
        assert url, out
        with playwright_api.sync_playwright() as p:
            browser = p.chromium.launch(executable_path="/usr/bin/chromium", args=["--no-sandbox"])
            page = browser.new_page(viewport={"width": 1400, "height": 1000})
            page.goto(url.group(1))
            expect = playwright_api.expect
            expect(page.locator('[data-hw-state="thermostat"]')).to_have_text("ready", timeout=WAIT_S * 1000)
            for name in ("setpoint", "report", "alarm"):  # nobody provides them
                row = page.locator(f'[data-hw-hub="thermostat.{name}"]')
                expect(row).to_have_text("not bound here: UNKNOWN_CHANNEL", timeout=WAIT_S * 1000)
            # a hub event is offered by the fleet itself (any client may send one), as by hubwire serve
            expect(page.locator('[data-hw-hub="thermostat.mode"]')).to_have_text("bound here", timeout=WAIT_S * 1000)
            assert page.locator('[data-hw-hub^="thermostat."]').count() == 4
            browser.close()
    finally:
        dash.terminate()
        dash.wait(15)
        assert sim.stop() == 0, sim.log_text()
