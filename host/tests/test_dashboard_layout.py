"""The dashboard as a user sees it, in chromium at a laptop's, a large screen's and a phone's width:
what is in view without scrolling, what fits, what stays readable, and what a lost board looks like.

Screenshots go to $HUBWIRE_SCREENSHOTS (``HUBWIRE_SCREENSHOTS=docs/img`` regenerates the pictures
of docs/DASHBOARD.md), else to a temporary folder. Each test asserts layout facts measured in the
page (bounding boxes), not the picture."""
from __future__ import annotations

import os
import re
from typing import Any, Iterator

import pytest

from conftest import Emulator
from hubwire.testing import emulator_binary, repo_root

from test_dashboard_browser import WAIT_MS, Dashboard, browser, field, sel, wait_text  # noqa: F401

#: every element a user acts with, on the Rover
CONTROLS = "[data-hw-input^='rover.'], [data-hw-set^='rover.'], [data-hw-call^='rover.'], [data-hw-arg^='rover.']"
#: the chart's box (ECharts puts _echarts_instance_ on it)
CHART = "[data-hw-plot] [_echarts_instance_]"


@pytest.fixture(scope="module")
def rover(tmp_path_factory: Any) -> Iterator[Emulator]:
    """The emulated Rover, on a port named as a user's would be (it shows on the page)."""
    board = Emulator(emulator_binary(), str(tmp_path_factory.mktemp("dev") / "ttyACM0"))
    board.start()
    yield board
    board.stop()


@pytest.fixture(scope="module")
def page(rover: Emulator, browser: Any) -> Iterator[Any]:  # noqa: F811
    dash = Dashboard((rover.link,))
    ctx = browser.new_context(viewport={"width": 1366, "height": 768})
    pg = ctx.new_page()
    pg.set_default_timeout(WAIT_MS)
    pg.goto(dash.url)
    wait_text(pg, sel("state", "rover"), "^ready$")
    wait_text(pg, sel("value", "rover.imu"), r"az: 9\.81")
    # what a user would have done: moved a motor, run the self test (three bumper events)
    slider = pg.locator(sel("input", "rover.left"))
    box = slider.bounding_box()
    slider.click(position={"x": box["width"] * 0.8, "y": box["height"] / 2})
    wait_text(pg, sel("status", "rover.left"), r"acked$")
    field(pg, "arg", "rover.selftest").fill("3")
    pg.locator(sel("call", "rover.selftest")).click()
    pg.wait_for_function("s => document.querySelectorAll(s).length >= 3", arg=sel("event", "rover.bumper"))
    yield pg
    ctx.close()
    dash.stop()


def shoot(page: Any, width: int, height: int, name: str) -> str:
    """Screenshot of the page at ``width`` x ``height`` (the viewport, as a user sees it first)."""
    folder = os.environ.get("HUBWIRE_SCREENSHOTS")
    if folder:
        folder = folder if os.path.isabs(folder) else os.path.join(repo_root() or ".", folder)
    else:
        folder = os.path.join(os.environ.get("TMPDIR", "/tmp"), "hubwire-dashboard")
    os.makedirs(folder, exist_ok=True)
    path = os.path.join(folder, name)
    page.mouse.move(width - 1, height - 1)  # no hover text in the picture
    page.wait_for_timeout(300)
    page.screenshot(path=path)
    assert os.path.getsize(path) > 10_000
    return path


def at_width(page: Any, width: int, height: int) -> None:
    page.set_viewport_size({"width": width, "height": height})
    page.evaluate("window.scrollTo(0, 0)")
    page.wait_for_function(f"() => window.innerWidth === {width}")
    wait_text(page, sel("value", "rover.battery"), r"^\d+ mV$")
    page.evaluate("window.scrollTo(0, 0)")
    page.wait_for_timeout(600)  # a plot redraw (PLOT_REFRESH) after the resize


def boxes(page: Any, selector: str) -> Any:
    return page.evaluate("s => [...document.querySelectorAll(s)].map(e => { const r = e.getBoundingClientRect();"
                         " return {k: Object.values(e.dataset).join(' '), top: r.top, bottom: r.bottom,"
                         " left: r.left, right: r.right, w: r.width, h: r.height} })", selector)


def test_at_1366x768_every_control_and_the_events_are_in_view(page: Any) -> None:
    at_width(page, 1366, 768)
    shoot(page, 1366, 768, "dashboard-1366.png")
    controls = boxes(page, CONTROLS)
    assert len(controls) >= 7, controls  # left, right, led, name (+ set), beep (+ arg), selftest (+ arg)
    below = [c["k"] for c in controls if c["bottom"] > 768 or c["h"] == 0]
    assert not below, f"controls out of view at 1366x768: {below}"
    events = boxes(page, "[data-hw-events]")
    assert events and all(e["top"] < 768 - 60 for e in events), events  # the log's first lines show
    plot = boxes(page, CHART)
    assert plot and plot[0]["w"] >= 500 and plot[0]["bottom"] <= 768, plot
    rows = boxes(page, sel("event", "rover.bumper"))
    assert rows and rows[0]["bottom"] <= 768, rows  # the newest event is readable without scrolling
    channels = boxes(page, "[data-hw-channel^='rover.'], [data-hw-action^='rover.']")
    assert len(channels) == 11 and max(c["bottom"] for c in channels) <= 768, channels  # every channel too


def test_at_1920_the_page_uses_the_width(page: Any) -> None:
    at_width(page, 1920, 1080)
    shoot(page, 1920, 1080, "dashboard-1920.png")
    plot = boxes(page, CHART)
    assert plot and plot[0]["w"] >= 800, plot
    below = [c["k"] for c in boxes(page, CONTROLS) if c["bottom"] > 1080]
    assert not below, below


def test_at_390_nothing_sticks_out_sideways(page: Any) -> None:
    at_width(page, 390, 844)
    shoot(page, 390, 844, "dashboard-390.png")
    assert page.evaluate("document.documentElement.scrollWidth") <= 390
    wide = [b["k"] for b in boxes(page, "[data-hw-board] *, [data-hw-plot], [data-hw-overview] *")
            if b["right"] > 390.5 and b["w"] > 0]
    assert not wide, f"wider than a 390 px phone: {wide[:10]}"
    at_width(page, 1366, 768)


#: the x axis' tick labels of the chart in ``s``: their boxes in the chart (ECharts draws on a canvas:
#: its own scene graph says where each text is)
TICKS_JS = """s => { const box = document.querySelector(s); if (!box) return null;
  const chart = getElement(box.id.slice(1)).chart;
  const grid = chart.getModel().getComponent('grid').coordinateSystem.getRect();
  const out = [];
  for (const el of chart.getZr().storage.getDisplayList(true)) {
    if ((el.type !== 'text' && el.type !== 'tspan') || el.invisible || !el.style || !el.style.text) continue;
    const r = el.getBoundingRect().clone(); r.applyTransform(el.getComputedTransform());
    const cy = r.y + r.height / 2;
    if (cy > grid.y + grid.height && cy < grid.y + grid.height + 24) out.push([el.style.text, r.x, r.x + r.width]);
  }
  return out.sort((a, b) => a[1] - b[1]); }"""

SPAN_JS = """s => { const box = document.querySelector(s); if (!box) return 0;
  const series = getElement(box.id.slice(1)).chart.getOption().series || [];
  const t = series.flatMap(x => x.data.map(p => p[0])); return t.length ? (Math.max(...t) - Math.min(...t)) / 1000 : 0 }"""


@pytest.mark.parametrize("width", [1366, 390])
def test_plot_time_labels_never_overlap(page: Any, width: int) -> None:
    at_width(page, width, 844)
    page.locator(CHART).scroll_into_view_if_needed()
    # once 35 s of history is drawn (labels overlapped from about 30 s on)
    page.wait_for_function(f"s => ({SPAN_JS})(s) >= 35", arg=CHART, timeout=WAIT_MS + 40_000)
    page.wait_for_timeout(600)
    ticks = page.evaluate(TICKS_JS, CHART)
    assert ticks and len(ticks) >= 2, ticks
    clashes = [(a[0], b[0]) for a, b in zip(ticks, ticks[1:]) if b[1] < a[2] + 4]
    assert not clashes, f"time labels overlap at {width} px: {clashes} in {ticks}"
    at_width(page, 1366, 768)


def test_a_refused_entry_keeps_what_the_user_typed_and_says_why_plainly(page: Any) -> None:
    typed = "a name far too long for sixteen bytes"
    field(page, "input", "rover.name").fill(typed)
    page.locator(sel("set", "rover.name")).click()
    status = wait_text(page, sel("status", "rover.name"), r".+16")
    assert page.locator(sel("status", "rover.name")).get_attribute("data-hw-ok") == "0"
    assert field(page, "input", "rover.name").input_value() == typed  # to correct, not to retype
    assert not re.search(r"\b[A-Z]{2,}_[A-Z_]+\b|\bNAK\b|InvalidValue", status), status  # no protocol words
    wait_text(page, sel("value", "rover.name"), r'^"rover"$')  # the board still holds its name


DISABLED_JS = """s => [...document.querySelectorAll(s)].map(e => e.matches(
  '[disabled], [aria-disabled=true], .disabled, .q-field--disabled')
  || !!e.querySelector('input[disabled], [aria-disabled=true]'))"""


def test_a_lost_board_shows_stale_values_and_disabled_controls_then_comes_back(page: Any, rover: Emulator) -> None:
    at_width(page, 1366, 768)
    rover.stop()  # the board goes away with its port
    try:
        # lost (silent for 4 heartbeats) or unplugged (its port gone): whichever the hub notices first
        wait_text(page, sel("state", "rover"), "^(lost|unplugged)$")
        page.wait_for_function("s => document.querySelector(s).dataset.hwStale === '1'",
                               arg=sel("value", "rover.battery"), timeout=WAIT_MS)
        page.wait_for_function(f"s => ({DISABLED_JS})(s).every(x => x)", arg=CONTROLS, timeout=WAIT_MS)
        shoot(page, 1366, 768, "dashboard-lost-1366.png")
    finally:
        rover.start()
    wait_text(page, sel("state", "rover"), "^ready$")
    page.wait_for_function("s => document.querySelector(s).dataset.hwStale === '0'",
                           arg=sel("value", "rover.battery"), timeout=WAIT_MS)
    page.wait_for_function(f"s => ({DISABLED_JS})(s).every(x => !x)", arg=CONTROLS, timeout=WAIT_MS)
    # the link line counts the loss and the return
    wait_text(page, sel("health", "rover.link-lost"), r"^1 time, back after \d+(\.\d)? s$")
