"""`hubwire serve --mqtt` as a user runs it: over TLS with a password (from a config file, or from
the command line with the password in the environment) against a mosquitto that requires both, and
a clean stop (SIGTERM, Ctrl-C) that leaves the service's retained status `offline`."""
from __future__ import annotations

import signal
import subprocess
import time
from typing import Any, List

import pytest

from conftest import Emulator
from hubwire.testing import emulator_binary
from service.conftest import Serve, wait_for

from .conftest import Broker
from .tls import SecureBroker, make_pki

#: the service's own shutdown deadline is 2 s (docs/SERVICE.md); a busy test machine gets margin
EXIT_WITHIN_S = 10.0


def _serve(tmp_path: Any, args: List[str], extra_env: Any = None) -> Serve:
    boards = tmp_path / "boards"
    boards.mkdir(exist_ok=True)
    return Serve.own(str(boards), tmp_path, ["--mqtt-id", "t", *args], extra_env)


def _retained(sub: List[str], topic: str) -> str:
    """The retained message on ``topic`` (mosquitto_sub reads the broker's store)."""
    r = subprocess.run(["mosquitto_sub", *sub, "-t", topic, "-C", "1", "-W", "5"], capture_output=True,
                       text=True, timeout=30)
    return r.stdout.strip()


def _stop(serve: Serve, sig: int) -> float:
    p = serve.proc
    assert p is not None
    t0 = time.monotonic()
    p.send_signal(sig)
    try:
        status = p.wait(EXIT_WITHIN_S + 20)
    except subprocess.TimeoutExpired:
        p.kill()
        raise AssertionError(f"hubwire serve did not exit after {sig}; its log:\n{serve.log_text()}") from None
    serve.proc = None
    assert status == 0, serve.log_text()
    return time.monotonic() - t0


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT], ids=["SIGTERM", "SIGINT"])
def test_a_clean_stop_publishes_offline(broker: Broker, tmp_path: Any, sig: int) -> None:
    emu = Emulator(emulator_binary(), str(tmp_path / "boards" / "a"))
    (tmp_path / "boards").mkdir()
    emu.start()
    serve = _serve(tmp_path, ["--mqtt", f"127.0.0.1:{broker.port}"])
    sub = ["-h", "127.0.0.1", "-p", str(broker.port)]
    try:
        serve.start()
        wait_for(lambda: _retained(sub, "hubwire/rover/status") == "online", 30, "the board online")
        assert _retained(sub, "hubwire/_service/t/status") == "online"
        took = _stop(serve, sig)
        assert took < EXIT_WITHIN_S, f"hubwire serve took {took:.1f} s to stop"
        # the broker still runs: a clean disconnect drops the will, so only our own publish says it
        assert _retained(sub, "hubwire/_service/t/status") == "offline", serve.log_text()
        assert "Traceback" not in serve.log_text()
    finally:
        serve.stop()
        emu.stop()


@pytest.mark.parametrize("how", ["config", "argv"])
def test_serve_over_tls_with_a_password(tmp_path: Any, how: str) -> None:
    pki = make_pki(str(tmp_path / "pki"))
    emu = Emulator(emulator_binary(), str(tmp_path / "boards" / "a"))
    (tmp_path / "boards").mkdir()
    with SecureBroker(str(tmp_path / "broker"), pki, user="hub", password="s3cret pass") as broker:
        pw = tmp_path / "mqtt-password"
        pw.write_text("s3cret pass\n")
        if how == "config":
            cfg = tmp_path / "mqtt.toml"
            cfg.write_text(f'host = "localhost"\nport = {broker.port}\nusername = "hub"\n'
                           f'password_file = "{pw}"\n[tls]\nca_file = "{pki.ca}"\n'
                           f'cert_file = "{pki.client_cert}"\nkey_file = "{pki.client_key}"\n')
            serve = _serve(tmp_path, ["--mqtt-config", str(cfg)])
        else:
            serve = _serve(tmp_path, ["--mqtt", f"localhost:{broker.port}", "--mqtt-user", "hub",
                                      "--mqtt-cafile", pki.ca, "--mqtt-cert", pki.client_cert,
                                      "--mqtt-key", pki.client_key],
                           {"HUBWIRE_MQTT_PASSWORD": "s3cret pass"})
        try:
            emu.start()
            serve.start()
            sub = broker.client_args("hub", "s3cret pass")
            wait_for(lambda: _retained(sub, "hubwire/rover/status") == "online", 30, "the board online over TLS")
            assert _retained(sub, "hubwire/_service/t/status") == "online"
            assert "s3cret" not in " ".join(serve.args)  # the password never was on the command line
            _stop(serve, signal.SIGTERM)
            assert _retained(sub, "hubwire/_service/t/status") == "offline"
        finally:
            serve.stop()
            emu.stop()


def test_a_wrong_password_is_logged_not_a_traceback(tmp_path: Any) -> None:
    pki = make_pki(str(tmp_path / "pki"))
    with SecureBroker(str(tmp_path / "broker"), pki, user="hub", password="right") as broker:
        (tmp_path / "boards").mkdir()
        serve = _serve(tmp_path, ["--mqtt", f"localhost:{broker.port}", "--mqtt-user", "hub",
                                  "--mqtt-cafile", pki.ca, "--mqtt-cert", pki.client_cert,
                                  "--mqtt-key", pki.client_key], {"HUBWIRE_MQTT_PASSWORD": "wrong"})
        serve.start()
        try:
            wait_for(lambda: "not authorized" in serve.log_text().lower(), 30, "the refusal in the log")
        finally:
            assert serve.stop() == 0
        assert "Traceback" not in serve.log_text()
