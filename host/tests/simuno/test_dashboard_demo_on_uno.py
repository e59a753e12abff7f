"""`make dashboard-demo` (tools/demo.sh --dashboard): the page shows the simulated Uno running
examples/Rover, live, in Debian's chromium; Ctrl-C on the dashboard ends the demo cleanly."""
from __future__ import annotations

import os
import re
import signal
import socket
import subprocess
import sys
import time
from typing import Any, Optional

import pytest

from .conftest import BOOT_DELAY_MS, BUILD_HINT, REPO, rover_elf, simuno_binary

if sys.version_info < (3, 10):
    pytest.skip("NiceGUI 3 and Playwright need Python 3.10+", allow_module_level=True)
import playwright.sync_api as playwright_api  # noqa: E402  (after the version check)

#: the Uno's boot delay, discovery of a descriptor at 115200 baud and a few page refreshes, with a
#: wide margin for a busy machine
WAIT_S = 20 * (BOOT_DELAY_MS / 1000 + 1.0)


def _child_of(pid: int, word: str) -> Optional[int]:
    for d in os.listdir("/proc"):
        if not d.isdigit():
            continue
        try:
            stat = open(f"/proc/{d}/stat").read()
            cmd = open(f"/proc/{d}/cmdline", "rb").read().replace(b"\0", b" ").decode()
        except OSError:
            continue
        if int(stat.rsplit(")", 1)[1].split()[1]) == pid and word in cmd:
            return int(d)
    return None


def test_the_dashboard_demo_shows_the_simulated_uno(tmp_path: Any) -> None:
    for path in (simuno_binary(), rover_elf()):
        if not os.path.exists(path):
            pytest.fail(f"{path} not found: {BUILD_HINT}", pytrace=False)
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    env = dict(os.environ, DASHBOARD_PORT=str(port), DEMO_BOOT_DELAY_MS=str(BOOT_DELAY_MS), TMPDIR=str(tmp_path))
    env.pop("DEMO_DURATION", None)
    demo = subprocess.Popen(["bash", os.path.join(REPO, "tools", "demo.sh"), "--dashboard"], stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL, env=env, text=True)
    dash: Optional[int] = None
    try:
        assert demo.stdout is not None
        out = ""
        deadline = time.monotonic() + WAIT_S
        while "hubwire dashboard: http" not in out and time.monotonic() < deadline and demo.poll() is None:
            out += demo.stdout.readline()
        url = re.search(r"hubwire dashboard: (http://\S+)", out)
        # the dashboard asks for a token even on loopback: the URL it prints carries one it made up
        assert url and re.fullmatch(rf"http://localhost:{port}/\?token=[\w-]{{16,}}", url.group(1)), out
        with playwright_api.sync_playwright() as p:
            browser = p.chromium.launch(executable_path="/usr/bin/chromium", args=["--no-sandbox"])
            page = browser.new_page()
            page.goto(url.group(1))
            playwright_api.expect(page.locator('[data-hw-state="rover"]')).to_have_text("ready", timeout=WAIT_S * 1000)
            playwright_api.expect(page.locator('[data-hw-value="rover.imu"]')).to_have_text(
                re.compile(r"az: 9\.81"), timeout=WAIT_S * 1000)
            assert "simulated Arduino Uno" in out
            browser.close()
        dash = _child_of(demo.pid, "-m hubwire dashboard")
        assert dash is not None
        os.kill(dash, signal.SIGINT)  # Ctrl-C reaches the dashboard, the one command in the foreground
        rest, _ = demo.communicate(timeout=WAIT_S)
        assert demo.returncode == 0, out + rest
        assert "demo: done (simulator stopped)." in rest
    finally:
        if demo.poll() is None:
            dash = dash or _child_of(demo.pid, "-m hubwire dashboard")
            if dash is not None:
                os.kill(dash, signal.SIGTERM)  # in a process group of its own (the script's job control)
            demo.terminate()  # its trap stops the simulator
            try:
                demo.wait(WAIT_S)
            except subprocess.TimeoutExpired:
                demo.kill()
                demo.wait()
