"""A board's strings are data on the page, never markup or script: a device whose name, firmware,
unit and description are crafted to break out of an attribute (a Vue ``:prop`` is evaluated as
JavaScript) or to be taken as HTML is shown as text in chromium and nothing it carries runs."""
from __future__ import annotations

import json
import sys
from typing import Any, Iterator

import pytest

from fakedevice import FakeDevice

if sys.version_info < (3, 10):
    pytest.skip("NiceGUI 3 and Playwright need Python 3.10+", allow_module_level=True)
import playwright.sync_api as playwright_api  # noqa: E402  (after the version check)

from test_dashboard_browser import WAIT_MS, Dashboard, need_chromium, opened  # noqa: E402

#: breaks out of a double-quoted prop into a Vue-evaluated one, then tries HTML and Markdown
PWN_NAME = 'x" :data-pwn="(()=>{window.hwPwned=1;return 1})()" y="'
PWN_HTML = '<img src=x onerror="window.hwPwned=2"><script>window.hwPwned=3</script>'
PWN_MD = '\n```\n<img src=y onerror="window.hwPwned=4">\n```'
DESCRIPTOR = json.dumps({"p": 1, "n": PWN_NAME, "fw": PWN_HTML, "ch": [
    {"id": 1, "n": "x", "a": "rw", "t": "u16", "u": PWN_HTML, "d": PWN_MD + PWN_HTML}]},
    separators=(",", ":")).encode()


@pytest.fixture(scope="module")
def page() -> Iterator[Any]:
    need_chromium()
    with FakeDevice(DESCRIPTOR, max_payload=64) as dev:
        dash = Dashboard((dev.path,))
        try:
            with opened(dash.url) as pg:
                yield pg
        finally:
            dash.stop()


def test_a_crafted_board_is_shown_as_text_and_runs_nothing(page: Any) -> None:
    # the board's card is drawn with its descriptor (the firmware text is part of it)
    playwright_api.expect(page.get_by_text(PWN_HTML, exact=False).first).to_be_attached(timeout=WAIT_MS)
    page.locator("[data-hw-board]").first.scroll_into_view_if_needed()
    for exp in page.locator(".q-expansion-item__container > .q-item").all():
        exp.click()  # open the descriptor too
    page.locator("[data-hw-channel]").first.get_by_text("x", exact=True).hover()  # its hover text: the description
    playwright_api.expect(page.locator(".q-tooltip")).to_contain_text("<img src=x", timeout=WAIT_MS)
    page.wait_for_timeout(1000)  # let anything that would run, run
    assert page.evaluate("window.hwPwned") is None
    assert page.locator("[data-pwn]").count() == 0
    assert page.locator("img").count() == 0
    body = page.locator("body").inner_text()
    assert PWN_HTML in body  # the firmware and unit, as text
    assert page.locator("[data-hw-board]").count() == 1


def test_no_element_props_classes_or_style_are_built_from_text() -> None:
    """props("...") parses its string, so one built with an f-string lets a quote in a board's string
    add props; attributes carrying data go through dashboard/attrs.py (tag) instead."""
    import re
    from pathlib import Path

    import hubwire.dashboard as pkg

    pattern = re.compile(r"\.(props|classes|style)\(\s*(f['\"]|[^)'\"]*\{)")
    found = []
    for path in sorted(Path(pkg.__file__).parent.glob("*.py")):
        for n, line in enumerate(path.read_text().splitlines(), 1):
            if pattern.search(line):
                found.append(f"{path.name}:{n}: {line.strip()}")
    assert not found, "\n".join(found)
