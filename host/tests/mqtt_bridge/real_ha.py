"""A real Home Assistant core for the tests: installed from PyPI by tools/ha/setup-ha.sh into a venv
of its own (cached), started on a temporary config folder, onboarded through its REST API (an owner
user and a token), with the MQTT integration added through its config flow.

Every wait is on Home Assistant's own answers (its HTTP API up, the config flow done, an entity's
state), with deadlines generous for a loaded 2-core machine."""
from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import time
import urllib.error
import urllib.parse
import urllib.request
from typing import Any, Callable, Dict, List, Optional

from hubwire.testing import repo_root

#: Home Assistant's first start on a busy machine (it loads the frontend and sets up its storage)
START_S = 300.0
#: an entity's state following an MQTT message (HA reacts within milliseconds when idle)
STATE_S = 60.0
CLIENT_ID = "http://127.0.0.1/"


def setup_ha() -> str:
    """The venv of Home Assistant (installed once, then cached: tools/ha/setup-ha.sh)."""
    script = os.path.join(repo_root() or os.getcwd(), "tools", "ha", "setup-ha.sh")
    r = subprocess.run(["bash", script], capture_output=True, text=True, timeout=1800)
    if r.returncode != 0:
        raise RuntimeError(f"tools/ha/setup-ha.sh failed:\n{r.stderr[-3000:]}")
    return r.stdout.strip().splitlines()[-1]


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def wait(pred: Callable[[], Any], timeout: float, what: str, every: float = 0.2) -> Any:
    deadline = time.monotonic() + timeout
    while True:
        got = pred()
        if got:
            return got
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out after {timeout:.0f} s waiting for {what}")
        time.sleep(every)


class HomeAssistant:
    """``hass`` on 127.0.0.1:<free port> with config folder ``config``."""

    def __init__(self, venv: str, config: str) -> None:
        self.venv = venv
        self.config = config
        self.port = _free_port()
        self.url = f"http://127.0.0.1:{self.port}"
        self.token: Optional[str] = None
        self.refresh_token: Optional[str] = None
        self.proc: Optional[subprocess.Popen] = None  # type: ignore[type-arg]
        os.makedirs(config, exist_ok=True)
        with open(os.path.join(config, "configuration.yaml"), "w") as f:
            # no default_config: only what the test needs (its packages are installed by setup-ha)
            f.write("homeassistant:\n  name: Hubwire test\n  unit_system: metric\n  time_zone: UTC\n"
                    "  latitude: 0\n  longitude: 0\n  elevation: 0\n  currency: EUR\n  country: DE\n"
                    f"http:\n  server_host: 127.0.0.1\n  server_port: {self.port}\n"
                    "frontend:\nconfig:\napi:\nlogger:\n  default: info\n")
        # every onboarding step but the owner user done already: the core_config step would set up
        # integrations of its own (weather, radio, text-to-speech) whose packages are not here
        os.makedirs(os.path.join(config, ".storage"), exist_ok=True)
        with open(os.path.join(config, ".storage", "onboarding"), "w") as f:
            json.dump({"version": 4, "minor_version": 1, "key": "onboarding",
                       "data": {"done": ["core_config", "analytics", "integration"]}}, f)

    @property
    def log_path(self) -> str:
        return os.path.join(self.config, "home-assistant.log")

    def start(self) -> None:
        env = {k: v for k, v in os.environ.items() if not k.startswith(("PYTHON", "VIRTUAL_ENV"))}
        self.proc = subprocess.Popen([os.path.join(self.venv, "bin", "hass"), "-c", self.config, "--skip-pip"],
                                     stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                     stdin=subprocess.DEVNULL, env=env)

        def up() -> bool:
            if self.proc is not None and self.proc.poll() is not None:
                raise RuntimeError(f"Home Assistant exited ({self.proc.returncode}):\n{self.log_tail()}")
            try:
                self.request("GET", "/api/onboarding", auth=False)
                return True
            except (OSError, urllib.error.URLError):
                return False
        wait(up, START_S, "Home Assistant's HTTP API", 0.5)

    def stop(self) -> None:
        p, self.proc = self.proc, None
        if p is not None and p.poll() is None:
            p.send_signal(signal.SIGTERM)
            try:
                p.wait(120)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait(10)

    def log_tail(self, n: int = 4000) -> str:
        try:
            with open(self.log_path, encoding="utf-8", errors="replace") as f:
                return f.read()[-n:]
        except OSError:
            return ""

    def log_lines(self) -> List[str]:
        with open(self.log_path, encoding="utf-8", errors="replace") as f:
            return f.read().splitlines()

    # ------------------------------------------------------------------------------ REST

    def request(self, method: str, path: str, body: Any = None, *, auth: bool = True,
                form: Optional[Dict[str, str]] = None) -> Any:
        headers = {}
        data = None
        if form is not None:
            data = urllib.parse.urlencode(form).encode()
            headers["Content-Type"] = "application/x-www-form-urlencoded"
        elif body is not None:
            data = json.dumps(body).encode()
            headers["Content-Type"] = "application/json"
        if auth and self.token:
            headers["Authorization"] = f"Bearer {self.token}"
        req = urllib.request.Request(self.url + path, data=data, headers=headers, method=method)
        with urllib.request.urlopen(req, timeout=60) as r:
            text = r.read().decode()
        return json.loads(text) if text else None

    def onboard(self) -> None:
        """The owner user and a token: the last onboarding step (so the frontend opens)."""
        got = self.request("POST", "/api/onboarding/users", {
            "client_id": CLIENT_ID, "name": "Test", "username": "test", "password": "test-password-1",
            "language": "en"}, auth=False)
        tok = self.request("POST", "/auth/token", form={"grant_type": "authorization_code",
                                                         "code": got["auth_code"], "client_id": CLIENT_ID},
                           auth=False)
        self.token, self.refresh_token = tok["access_token"], tok["refresh_token"]
        assert all(step["done"] for step in self.request("GET", "/api/onboarding", auth=False))

    def add_mqtt(self, port: int) -> Dict[str, Any]:
        """The MQTT integration through its config flow, on the broker at 127.0.0.1:port."""
        flow = self.request("POST", "/api/config/config_entries/flow", {"handler": "mqtt",
                                                                        "show_advanced_options": False})
        for _ in range(5):
            if flow.get("type") != "form":
                break
            data: Dict[str, Any] = {}
            names = {f["name"] for f in flow.get("data_schema", [])}
            if "broker" in names:
                data.update(broker="127.0.0.1", port=port)
            flow = self.request("POST", f"/api/config/config_entries/flow/{flow['flow_id']}", data)
        assert flow.get("type") == "create_entry", flow
        return flow  # type: ignore[no-any-return]

    def states(self) -> Dict[str, Dict[str, Any]]:
        return {s["entity_id"]: s for s in self.request("GET", "/api/states")}

    def state(self, entity_id: str) -> Optional[Dict[str, Any]]:
        try:
            return self.request("GET", f"/api/states/{entity_id}")  # type: ignore[no-any-return]
        except urllib.error.HTTPError as e:
            if e.code == 404:
                return None
            raise

    def call(self, domain: str, service: str, **data: Any) -> Any:
        return self.request("POST", f"/api/services/{domain}/{service}", data)

    def wait_state(self, entity_id: str, pred: Callable[[Dict[str, Any]], bool], what: str,
                   timeout: float = STATE_S) -> Dict[str, Any]:
        def ok() -> Optional[Dict[str, Any]]:
            s = self.state(entity_id)
            return s if s is not None and pred(s) else None
        return wait(ok, timeout, f"{entity_id}: {what}")  # type: ignore[no-any-return]

    # ------------------------------------------------------------------------- websocket

    def ws(self, *messages: Dict[str, Any]) -> List[Any]:
        """Send ``messages`` over one websocket session; the result of each."""
        from websockets.sync.client import connect
        out = []
        with connect(self.url.replace("http", "ws") + "/api/websocket", open_timeout=60) as c:
            json.loads(c.recv(60))
            c.send(json.dumps({"type": "auth", "access_token": self.token}))
            assert json.loads(c.recv(60))["type"] == "auth_ok"
            for i, m in enumerate(messages, 1):
                c.send(json.dumps(dict(m, id=i)))
                while True:
                    r = json.loads(c.recv(60))
                    if r.get("id") == i and r.get("type") == "result":
                        assert r["success"], r
                        out.append(r["result"])
                        break
        return out

    def registry(self) -> Dict[str, Dict[str, Any]]:
        """The entity registry: entity_id -> entry (platform, unique_id, entity_category, ...)."""
        return {e["entity_id"]: e for e in self.ws({"type": "config/entity_registry/list"})[0]}

    def devices(self) -> List[Dict[str, Any]]:
        """The device registry's entries (id, name, model, ...)."""
        return self.ws({"type": "config/device_registry/list"})[0]  # type: ignore[no-any-return]

    def state_changes(self, entity_id: str, action: Callable[[], Any], done: Callable[[List[Dict[str, Any]]], bool],
                      timeout: float = STATE_S) -> List[Dict[str, Any]]:
        """The new states of ``entity_id`` from before ``action`` until ``done(states)``."""
        from websockets.sync.client import connect
        got: List[Dict[str, Any]] = []
        with connect(self.url.replace("http", "ws") + "/api/websocket", open_timeout=60) as c:
            json.loads(c.recv(60))
            c.send(json.dumps({"type": "auth", "access_token": self.token}))
            assert json.loads(c.recv(60))["type"] == "auth_ok"
            c.send(json.dumps({"id": 1, "type": "subscribe_events", "event_type": "state_changed"}))
            assert json.loads(c.recv(60))["success"]
            action()
            deadline = time.monotonic() + timeout
            while not done(got):
                left = deadline - time.monotonic()
                if left <= 0:
                    raise AssertionError(f"timed out after {timeout:.0f} s: {entity_id} changed {len(got)} times")
                try:
                    msg = json.loads(c.recv(left))
                except TimeoutError:
                    continue
                data = msg.get("event", {}).get("data", {})
                if data.get("entity_id") == entity_id and data.get("new_state") is not None:
                    got.append(data["new_state"])
        return got
