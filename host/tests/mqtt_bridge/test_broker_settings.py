"""`hubwire serve`'s broker settings: a TOML file, the command line over it, the password from a
file or the environment (never needed on the command line), TLS defaults."""
from __future__ import annotations

import argparse
from typing import Any, List

import pytest

from hubwire.bridge.broker import PASSWORD_ENV, load_config, settings_from_args
from hubwire.cli.serve import add_commands


def _args(argv: List[str]) -> argparse.Namespace:
    ap = argparse.ArgumentParser()
    add_commands(ap.add_subparsers(), argparse.ArgumentParser(add_help=False))
    return ap.parse_args(["serve", *argv])


def test_config_file_then_the_command_line_over_it(tmp_path: Any, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv(PASSWORD_ENV, raising=False)
    pw = tmp_path / "pw"
    pw.write_text("from the file\n")
    cfg = tmp_path / "mqtt.toml"
    cfg.write_text(f'address = "broker.lan:8884"\nusername = "hub"\npassword_file = "{pw}"\nid = "kitchen"\n'
                   'reply_prefixes = ["hubwire/", "clients/"]\n[tls]\nca_file = "/ca.crt"\n')
    s = settings_from_args(_args(["--mqtt-config", str(cfg)]))
    assert s is not None
    assert (s.host, s.effective_port, s.username, s.password) == ("broker.lan", 8884, "hub", "from the file")
    assert s.uses_tls and s.ca_file == "/ca.crt" and not s.insecure
    assert s.reply_prefixes == ("hubwire/", "clients/") and s.service_id == "kitchen"
    assert "from the file" not in repr(s)
    s = settings_from_args(_args(["--mqtt-config", str(cfg), "--mqtt", "other", "--mqtt-user", "u2",
                                  "--mqtt-id", "garage"]))
    assert s is not None and (s.host, s.effective_port, s.username, s.service_id) == ("other", 8884, "u2", "garage")


def test_password_from_the_environment_and_tls_port(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv(PASSWORD_ENV, "from env")
    s = settings_from_args(_args(["--mqtt", "b", "--mqtt-user", "hub", "--mqtt-tls"]))
    assert s is not None and s.password == "from env" and s.effective_port == 8883
    assert s.tls_context() is not None
    s = settings_from_args(_args(["--mqtt", "b"]))
    assert s is not None and s.effective_port == 1883 and s.tls_context() is None
    assert settings_from_args(_args([])) is None


def test_a_config_file_with_unknown_settings_is_refused(tmp_path: Any) -> None:
    cfg = tmp_path / "mqtt.toml"
    cfg.write_text('host = "b"\npasword = "typo"\n')
    with pytest.raises(ValueError, match="pasword"):
        load_config(str(cfg))
    cfg.write_text('host = "b"\n[tls]\ncafile = "x"\n')
    with pytest.raises(ValueError, match="tls"):
        load_config(str(cfg))
