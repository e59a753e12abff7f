"""Home Assistant's entities page in Debian's chromium (Playwright drives it; it downloads no
browser of its own), logged in with the test's token, as the README's picture."""
from __future__ import annotations

import json
import time
from typing import Optional

from .real_ha import START_S, HomeAssistant

CHROMIUM = "/usr/bin/chromium"


def device_page(ha: HomeAssistant, device_id: str, out: Optional[str]) -> str:
    """The text of the battery's row on a board's device page (its entities with their states:
    controls, sensors, diagnostics); a screenshot to ``out``."""
    import playwright.sync_api as pw

    tokens = {"access_token": ha.token, "token_type": "Bearer", "expires_in": 1800, "hassUrl": ha.url,
              "clientId": "http://127.0.0.1/", "expires": int(time.time() * 1000) + 1800_000,
              "refresh_token": ha.refresh_token}
    with pw.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox"])
        try:
            ctx = browser.new_context(viewport={"width": 1300, "height": 1420})
            # the frontend reads its tokens from localStorage before it asks anyone to log in
            ctx.add_init_script(f"window.localStorage.setItem('hassTokens', {json.dumps(json.dumps(tokens))});")
            page = ctx.new_page()
            page.goto(f"{ha.url}/config/devices/device/{device_id}", timeout=START_S * 1000)
            # locators see into the shadow DOM; a hidden table elsewhere may name "Battery" too
            row = page.locator("text=Battery >> visible=true").first
            row.wait_for(timeout=START_S * 1000)
            page.wait_for_timeout(1000)  # icons and the last rows settle (a picture only)
            if out is not None:
                page.screenshot(path=out)
            text: str = row.inner_text()
            return text
        finally:
            browser.close()
