"""The dashboard in a real browser: Debian's chromium driven by Playwright, against emulated boards
(the Rover and examples/Actions, each the C++ library on a pty) served by `hubwire dashboard`.

Every wait is on a page condition, with a deadline derived from the configured intervals (the
device's heartbeat, the loss detection, the page's refresh), made generous for a busy machine.
Pictures at three widths, and the layout facts checked on them, are in test_dashboard_layout.py."""
from __future__ import annotations

import contextlib
import os
import re
import selectors
import socket
import subprocess
import sys
from typing import Any, Iterator, List, Tuple

import pytest

from conftest import Emulator
from hubwire.dashboard.server import PLOT_REFRESH, VALUE_REFRESH
from hubwire.session.link import LOSS_HEARTBEATS
from hubwire.testing import emulator_binary

if sys.version_info < (3, 10):
    pytest.skip("NiceGUI 3 and Playwright need Python 3.10+", allow_module_level=True)
import playwright.sync_api as playwright_api  # noqa: E402  (after the version check)

CHROMIUM = "/usr/bin/chromium"
HEARTBEAT_S = 0.25  # the hub's and the emulated Rover's heartbeat interval
#: the longest a page condition may take: a loss detected and a re-handshake, several page
#: refreshes and a plot redraw, times a margin for a loaded 2-core machine
WAIT_MS = int(1000 * 20 * (LOSS_HEARTBEATS * HEARTBEAT_S + 2 * VALUE_REFRESH + PLOT_REFRESH))


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


class Dashboard:
    """`hubwire dashboard` as a user starts it, in its own process."""

    def __init__(self, ports: Tuple[str, ...], *options: str) -> None:
        self.port = _free_port()
        env = dict(os.environ, PYTHONUNBUFFERED="1")
        self.proc = subprocess.Popen([sys.executable, "-m", "hubwire", "dashboard", *ports, "--http", str(self.port),
                                      "--no-cache", *options], stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env)
        sel = selectors.DefaultSelector()
        assert self.proc.stdout is not None
        sel.register(self.proc.stdout, selectors.EVENT_READ)
        ready = sel.select(WAIT_MS / 1000)
        sel.close()
        line = self.proc.stdout.readline().decode() if ready else ""
        m = re.search(r"(http://\S+)", line)
        if not m:
            self.stop()
            raise RuntimeError(f"dashboard did not start: {line!r}")
        self.url = m.group(1)

    def stop(self) -> None:
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(5)


def need_chromium() -> None:
    """Fails the test with the setup command when Debian's chromium is missing."""
    if not os.access(CHROMIUM, os.X_OK):
        pytest.fail(f"{CHROMIUM} not found: bash tools/setup.sh installs Debian's chromium", pytrace=False)


def new_page(browser: Any, url: str) -> Any:
    """A 1400x1000 page at ``url`` whose waits last up to WAIT_MS."""
    pg = browser.new_page(viewport={"width": 1400, "height": 1000})
    pg.set_default_timeout(WAIT_MS)
    pg.goto(url)
    return pg


@contextlib.contextmanager
def opened(url: str) -> Iterator[Any]:
    """``url`` on a page of its own chromium (see :func:`browser`), closed afterwards."""
    need_chromium()
    with playwright_api.sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox"])
        try:
            yield new_page(b, url)
        finally:
            b.close()


@pytest.fixture(scope="module")
def boards(tmp_path_factory: Any) -> Iterator[Tuple[Emulator, Emulator]]:
    d = tmp_path_factory.mktemp("boards")
    actions_bin = os.path.join(os.path.dirname(emulator_binary()), "hubwire-actions-emulator")
    need_chromium()
    if not os.access(actions_bin, os.X_OK):
        pytest.fail(f"{actions_bin} not found: build it with `make emulator`", pytrace=False)
    rover, actions = Emulator(emulator_binary(), str(d / "rover")), Emulator(actions_bin, str(d / "actions"))
    rover.start()
    actions.start()
    yield rover, actions
    rover.stop()
    actions.stop()


@pytest.fixture(scope="module")
def browser() -> Iterator[Any]:
    """Debian's chromium, headless (Playwright downloads no browser of its own)."""
    with playwright_api.sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox"])
        yield b
        b.close()


@pytest.fixture(scope="module")
def page(boards: Tuple[Emulator, Emulator], browser: Any) -> Iterator[Any]:
    rover, actions = boards
    dash = Dashboard((rover.link, actions.link))
    pg = new_page(browser, dash.url)
    yield pg
    pg.close()
    dash.stop()


def sel(kind: str, key: str) -> str:
    return f'[data-hw-{kind}="{key}"]'


def field(page: Any, kind: str, key: str) -> Any:
    """The text box of an input (Quasar puts the attribute on the box itself or on its frame)."""
    s = sel(kind, key)
    return page.locator(f"input{s}, {s} input").first


def wait_text(page: Any, selector: str, pattern: str) -> str:
    """Scroll to the element (channels off screen are not redrawn), wait until its text matches
    ``pattern``; its text."""
    for attempt in range(20):  # a board's card is drawn anew when its device changes (a replug)
        try:
            page.locator(selector).scroll_into_view_if_needed()
            break
        except playwright_api.Error:
            if attempt == 19:
                raise
    playwright_api.expect(page.locator(selector)).to_have_text(re.compile(pattern), timeout=WAIT_MS)
    return str(page.locator(selector).inner_text())


def stamp(page: Any, key: str) -> float:
    page.locator(sel("value", key)).scroll_into_view_if_needed()
    v = page.locator(sel("value", key)).get_attribute("data-hw-at")
    return float(v) if v else 0.0


def wait_newer(page: Any, key: str, than: float) -> float:
    page.locator(sel("value", key)).scroll_into_view_if_needed()
    page.wait_for_function(
        "([s, t]) => { const e = document.querySelector(s); return e && parseFloat(e.dataset.hwAt || 0) > t }",
        arg=[sel("value", key), than], timeout=WAIT_MS)
    return stamp(page, key)


def test_page_lists_every_board_ready_with_its_channels(page: Any) -> None:
    wait_text(page, sel("state", "rover"), "^ready$")
    wait_text(page, sel("state", "actions"), "^ready$")
    for ch in ("left", "right", "imu", "range", "battery", "led", "name", "failsafes", "applied"):
        assert page.locator(sel("channel", f"rover.{ch}")).count() == 1, ch
    for ch in ("beep", "selftest"):
        assert page.locator(sel("action", f"rover.{ch}")).count() == 1, ch
    assert page.locator(sel("channel", "rover.bumper")).count() == 0  # events go to the log
    wait_text(page, sel("value", "rover.imu"), r"az: 9\.81")
    wait_text(page, sel("health", "rover.heartbeat"), r"^every 250 ms, last \d+ ms$")
    page.locator(sel("board", "rover")).get_by_text("link details").click()
    wait_text(page, sel("health", "rover.device-heartbeat"), r"^250 ms declared, last \d+ ms$")
    wait_text(page, sel("health", "rover.hub-heartbeat"), r"^250 ms declared, last \d+ ms$")
    page.locator(sel("board", "rover")).get_by_text("link details").click()


def test_a_streamed_value_updates(page: Any) -> None:
    first = wait_newer(page, "rover.imu", 0.0)
    second = wait_newer(page, "rover.imu", first)
    assert second > first
    wait_text(page, sel("achieved", "rover.imu"), r"^[1-9][0-9.]* Hz$")


LINES_JS = """() => { const box = document.querySelector('[data-hw-plot] [_echarts_instance_]');
    const chart = box && getElement(box.id.slice(1)).chart;
    const series = chart ? chart.getOption().series || [] : [];
    return series.map(x => x.name + ':' + (x.data.length > 1)).join(',') }"""


def drawn(page: Any) -> List[str]:
    return [x for x in page.evaluate(LINES_JS).split(",") if x]


def pick(page: Any, key: str, on: bool) -> None:
    box = page.locator(sel("pick", key))
    if (box.get_attribute("aria-checked") == "true") != on:
        box.click()


def wait_drawn(page: Any, names: List[str]) -> List[str]:
    """Wait until the plot draws exactly the lines ``names``, each with two points at least."""
    want = ",".join(f"{n}:true" for n in names)
    page.wait_for_function(f"w => ({LINES_JS})() === w", arg=want, timeout=WAIT_MS)
    return drawn(page)


def test_the_plot_starts_with_the_first_streamed_numbers_and_plots_what_is_picked(page: Any) -> None:
    wait_drawn(page, ["left", "right"])
    pick(page, "rover.left", False)
    pick(page, "rover.right", False)
    pick(page, "rover.imu", True)  # a struct: one line per number
    wait_drawn(page, ["imu.ax", "imu.ay", "imu.az", "imu.gyro[0]", "imu.gyro[1]", "imu.gyro[2]"])
    # the plotted channels' rate: a new subscription at 50 Hz (started at 10)
    page.locator(sel("rate", "main")).click()
    page.get_by_role("option", name="50 Hz").click()
    page.wait_for_function("s => parseFloat(document.querySelector(s).innerText) >= 25",
                           arg=sel("achieved", "rover.imu"), timeout=WAIT_MS)
    pick(page, "rover.imu", False)


def test_a_paused_plot_exports_what_it_shows_as_csv(page: Any) -> None:
    pick(page, "rover.range", True)
    pick(page, "actions.calls", True)  # another board, on the same time axis
    names = ["actions.calls", "rover.range[0]", "rover.range[1]", "rover.range[2]", "rover.range[3]"]
    wait_drawn(page, names)
    page.locator(sel("pause", "main")).click()
    with page.expect_download(timeout=WAIT_MS) as dl:
        page.locator(sel("csv", "main")).click()
    lines = open(dl.value.path()).read().splitlines()
    assert lines[0] == "time," + ",".join(names)
    rows = [line.split(",") for line in lines[1:]]
    assert any(r[1] for r in rows) and any(r[2] for r in rows)  # samples of both boards
    times = [float(r[0]) for r in rows]
    assert times == sorted(times)  # one time axis (samples read in one go share a time)
    with page.expect_download(timeout=WAIT_MS) as again:  # paused: the same rows, however long it is
        page.locator(sel("csv", "main")).click()
    assert open(again.value.path()).read().splitlines() == lines
    page.locator(sel("pause", "main")).click()
    pick(page, "rover.range", False)
    pick(page, "actions.calls", False)


def test_slider_write_reaches_the_board_and_is_acked(page: Any) -> None:
    applied = int(wait_text(page, sel("value", "rover.applied"), r"^\d+$"))
    slider = page.locator(sel("input", "rover.left"))
    box = slider.bounding_box()
    slider.click(position={"x": box["width"] * 0.75, "y": box["height"] / 2})
    status = wait_text(page, sel("status", "rover.left"), r"acked$")
    assert page.locator(sel("status", "rover.left")).get_attribute("data-hw-ok") == "1"
    written = float(status.split(":")[0])
    assert 0.3 <= written <= 0.7, status
    # the board's own stream of left shows the value, and its count of applied writes went up
    wait_text(page, sel("value", "rover.left"), rf"^{re.escape(f'{written:.6g}')} m/s$")
    page.locator(sel("value", "rover.applied")).scroll_into_view_if_needed()
    page.wait_for_function("([s, n]) => parseInt(document.querySelector(s).innerText) > n",
                           arg=[sel("value", "rover.applied"), applied], timeout=WAIT_MS)


def test_a_value_the_device_refuses_shows_its_nak(page: Any) -> None:
    field(page, "input", "actions.blink").fill("11")
    page.locator(sel("set", "actions.blink")).click()
    wait_text(page, sel("status", "actions.blink"), r"^refused by the board: the board's sketch turned the value down$")
    assert page.locator(sel("status", "actions.blink")).get_attribute("data-hw-ok") == "0"
    assert page.locator(sel("status", "actions.blink")).get_attribute("data-hw-code") == "REJECTED"
    field(page, "input", "actions.blink").fill("3")
    page.locator(sel("set", "actions.blink")).click()
    wait_text(page, sel("status", "actions.blink"), r"^3: acked$")


def test_a_value_the_hubs_checks_refuse_never_leaves(page: Any) -> None:
    box = field(page, "input", "rover.name")
    box.fill("a name far too long for sixteen bytes")
    page.locator(sel("set", "rover.name")).click()
    wait_text(page, sel("status", "rover.name"), r"^not sent: name: string of \d+ UTF-8 bytes exceeds the capacity of 16$")
    assert page.locator(sel("status", "rover.name")).get_attribute("data-hw-code") == "BAD_VALUE"
    wait_text(page, sel("value", "rover.name"), r'^"rover"$')


def test_an_action_returns_its_result_and_events_appear_once(page: Any, boards: Tuple[Emulator, Emulator]) -> None:
    rover = boards[0]
    rows = page.locator(sel("event", "rover.bumper"))
    before = rows.count()
    field(page, "arg", "rover.selftest").fill("3")
    page.locator(sel("call", "rover.selftest")).click()
    wait_text(page, sel("result", "rover.selftest"), r"^-> 3$")
    page.wait_for_function("([s, n]) => document.querySelectorAll(s).length >= n",
                           arg=[sel("event", "rover.bumper"), before + 3], timeout=WAIT_MS)
    # one more, from the bumper itself: once it shows, every earlier event has shown as often as it will
    rover.bump()
    page.wait_for_function("([s, n]) => document.querySelectorAll(s).length >= n",
                           arg=[sel("event", "rover.bumper"), before + 4], timeout=WAIT_MS)
    ns = [int(rows.nth(i).get_attribute("data-hw-n")) for i in range(rows.count())]
    assert len(ns) == before + 4 and len(set(ns)) == len(ns), ns
    texts = [rows.nth(i).inner_text() for i in range(4)]  # newest first
    assert [t.split("= ")[1] for t in texts] == ["true", "true", "false", "true"], texts
    field(page, "arg", "rover.beep").fill("2500")
    page.locator(sel("call", "rover.beep")).click()
    wait_text(page, sel("result", "rover.beep"), r"^-> false$")


def test_an_unplugged_board_shows_lost_and_comes_back(page: Any, boards: Tuple[Emulator, Emulator]) -> None:
    rover = boards[0]
    wait_text(page, sel("state", "rover"), "^ready$")
    rover.stop()  # the board goes away with its port
    wait_text(page, sel("state", "rover"), "^(lost|unplugged)$")  # its port went with it: unplugged
    gone = stamp(page, "rover.imu")
    rover.start()
    wait_text(page, sel("state", "rover"), "^ready$")
    wait_newer(page, "rover.imu", gone)
    wait_text(page, sel("state", "actions"), "^ready$")  # the other board was not disturbed


def test_with_a_token_the_page_needs_it(tmp_path: Any, browser: Any) -> None:
    board = Emulator(os.path.join(os.path.dirname(emulator_binary()), "hubwire-actions-emulator"),
                     str(tmp_path / "actions"))
    board.start()
    dash = Dashboard((board.link,), "--token", "s3cret")
    try:
        assert "s3cret" not in dash.url  # a token the user gave is never printed
        bare = dash.url.split("?")[0]
        ctx = browser.new_context()  # cookies of its own
        pg = ctx.new_page()
        pg.set_default_timeout(WAIT_MS)
        assert pg.goto(bare).status == 401
        assert pg.goto(bare + "?token=s3cre").status == 401
        assert pg.goto(bare + "?token=s3cret").status == 200
        wait_text(pg, sel("state", "actions"), "^ready$")
        assert pg.goto(bare).status == 200  # the token is remembered for this site
        wait_text(pg, sel("state", "actions"), "^ready$")
        ctx.close()
    finally:
        dash.stop()
        board.stop()
