"""Who may use the dashboard: a token even on loopback (made up and printed once when none is given,
never printed when the user gave it), only the host names it serves (DNS rebinding), and no
websocket or request from a page of another origin. Against `hubwire dashboard` as a user starts it."""
from __future__ import annotations

import os
import re
import socket
import sys
from typing import Any, Dict, Iterator, Optional, Tuple
from urllib.parse import urlsplit

import pytest

from fakedevice import FakeDevice

if sys.version_info < (3, 10):
    pytest.skip("NiceGUI 3 needs Python 3.10+", allow_module_level=True)

from test_dashboard_browser import Dashboard  # noqa: E402

WS_PATH = "/_nicegui_ws/socket.io/?EIO=4&transport=websocket"


def request(port: int, path: str, host: str, headers: Optional[Dict[str, str]] = None) -> Tuple[int, bytes]:
    """One raw HTTP/1.1 request with exactly these headers: (status, head of the answer)."""
    lines = [f"GET {path} HTTP/1.1", f"Host: {host}", "Connection: close"]
    lines += [f"{k}: {v}" for k, v in (headers or {}).items()]
    with socket.create_connection(("127.0.0.1", port), 10) as s:
        s.sendall(("\r\n".join(lines) + "\r\n\r\n").encode())
        s.settimeout(10)
        got = b""
        while b"\r\n\r\n" not in got:
            chunk = s.recv(4096)
            if not chunk:
                break
            got += chunk
    m = re.match(rb"HTTP/1\.[01] (\d{3})", got)
    assert m, got[:200]
    return int(m.group(1)), got


def websocket(port: int, path: str, host: str, origin: Optional[str]) -> int:
    headers = {"Upgrade": "websocket", "Connection": "Upgrade", "Sec-WebSocket-Version": "13",
               "Sec-WebSocket-Key": "dGhlIHNhbXBsZSBub25jZQ=="}
    if origin is not None:
        headers["Origin"] = origin
    lines = [f"GET {path} HTTP/1.1", f"Host: {host}"] + [f"{k}: {v}" for k, v in headers.items()]
    with socket.create_connection(("127.0.0.1", port), 10) as s:
        s.sendall(("\r\n".join(lines) + "\r\n\r\n").encode())
        s.settimeout(10)
        got = s.recv(4096)
    m = re.match(rb"HTTP/1\.[01] (\d{3})", got)
    assert m, got[:200]
    return int(m.group(1))


@pytest.fixture(scope="module")
def device() -> Iterator[FakeDevice]:
    with FakeDevice() as dev:
        yield dev


def start(dev: FakeDevice, *options: str, env: Optional[Dict[str, str]] = None) -> Dashboard:
    old = dict(os.environ)
    os.environ.update(env or {})
    try:
        return Dashboard((dev.path,), *options)
    finally:
        os.environ.clear()
        os.environ.update(old)


def output(dash: Dashboard) -> str:
    dash.stop()
    assert dash.proc.stdout is not None and dash.proc.stderr is not None
    # the first line (read by Dashboard) had the address
    return dash.url + "\n" + dash.proc.stdout.read().decode() + dash.proc.stderr.read().decode()


def test_on_loopback_without_a_token_one_is_made_and_required(device: FakeDevice) -> None:
    dash = start(device)
    try:
        url = urlsplit(dash.url)
        assert re.fullmatch(r"token=[A-Za-z0-9_-]{20,}", url.query), dash.url
        host = f"localhost:{dash.port}"
        assert request(dash.port, "/", host)[0] == 401
        assert request(dash.port, "/?token=wrong", host)[0] == 401
        assert request(dash.port, "/?" + url.query, host)[0] == 200
    finally:
        text = output(dash)
    assert text.count(url.query) == 1  # printed once


def test_only_the_host_names_it_serves_are_answered(device: FakeDevice) -> None:
    dash = start(device, "--allow-host", "bench.lan")
    try:
        q = "/?" + urlsplit(dash.url).query
        for host in ("localhost", "127.0.0.1", "[::1]", "bench.lan"):
            assert request(dash.port, q, f"{host}:{dash.port}")[0] == 200, host
        for host in ("evil.example", "localhost.evil.example", "127.0.0.1.nip.io", ""):
            status = request(dash.port, q, f"{host}:{dash.port}" if host else "")[0]
            assert 400 <= status < 500, (host, status)
    finally:
        dash.stop()


def test_a_websocket_from_another_origin_is_refused(device: FakeDevice) -> None:
    dash = start(device)
    try:
        token = urlsplit(dash.url).query
        host = f"localhost:{dash.port}"
        path = WS_PATH + "&" + token
        assert websocket(dash.port, path, host, f"http://{host}") == 101
        for origin in ("http://evil.example", f"http://evil.example:{dash.port}", "null",
                       f"https://localhost.evil.example:{dash.port}"):
            assert websocket(dash.port, path, host, origin) != 101, origin
        # a page of another origin cannot fetch through it either
        assert request(dash.port, "/?" + token, host, {"Origin": "http://evil.example"})[0] == 403
    finally:
        dash.stop()


def test_a_token_the_user_gives_is_never_printed(device: FakeDevice, tmp_path: Any) -> None:
    secret_file = tmp_path / "token"
    secret_file.write_text("from-a-file-5b1f\n")
    secret_file.chmod(0o600)
    for options, env, secret in ((("--token", "on-the-line-93c2"), {}, "on-the-line-93c2"),
                                 (("--token-file", str(secret_file)), {}, "from-a-file-5b1f"),
                                 ((), {"HUBWIRE_DASHBOARD_TOKEN": "from-env-77aa"}, "from-env-77aa")):
        dash = start(device, *options, env=env)
        try:
            host = f"localhost:{dash.port}"
            assert request(dash.port, "/", host)[0] == 401
            assert request(dash.port, "/?token=" + secret, host)[0] == 200
        finally:
            text = output(dash)
        assert secret not in text, (options, env)
