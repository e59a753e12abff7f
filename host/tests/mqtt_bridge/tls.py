"""A throwaway certificate authority (openssl CLI) and a mosquitto that requires TLS with a client
certificate and a password (mosquitto_passwd)."""
from __future__ import annotations

import getpass
import os
import shutil
import subprocess
from dataclasses import dataclass
from typing import Any, List

import pytest

from .conftest import MOSQUITTO, Broker


@dataclass
class Pki:
    ca: str
    server_cert: str
    server_key: str
    client_cert: str
    client_key: str


def _openssl(*args: str) -> None:
    subprocess.run(["openssl", *args], check=True, capture_output=True, timeout=60)


def make_pki(d: str) -> Pki:
    if shutil.which("openssl") is None:
        pytest.fail("openssl missing (apt-get install openssl)", pytrace=False)
    os.makedirs(d)
    p = lambda name: os.path.join(d, name)  # noqa: E731
    _openssl("req", "-x509", "-newkey", "rsa:2048", "-nodes", "-days", "2", "-subj", "/CN=test ca",
             "-keyout", p("ca.key"), "-out", p("ca.crt"))
    with open(p("san.ext"), "w") as f:
        f.write("subjectAltName=DNS:localhost,IP:127.0.0.1\n")
    for who in ("server", "client"):
        _openssl("req", "-newkey", "rsa:2048", "-nodes", "-subj", f"/CN={'localhost' if who == 'server' else 'hub'}",
                 "-keyout", p(f"{who}.key"), "-out", p(f"{who}.csr"))
        _openssl("x509", "-req", "-in", p(f"{who}.csr"), "-CA", p("ca.crt"), "-CAkey", p("ca.key"),
                 "-CAcreateserial", "-days", "2", "-extfile", p("san.ext"), "-out", p(f"{who}.crt"))
    return Pki(p("ca.crt"), p("server.crt"), p("server.key"), p("client.crt"), p("client.key"))


class SecureBroker(Broker):
    """mosquitto on localhost with TLS only, a client certificate required and a password file."""

    def __init__(self, workdir: str, pki: Pki, user: str, password: str) -> None:
        if MOSQUITTO is None or shutil.which("mosquitto_passwd") is None:
            pytest.fail("mosquitto missing: apt-get install mosquitto mosquitto-clients", pytrace=False)
        os.makedirs(workdir)
        super().__init__(MOSQUITTO, workdir, persistence=False)
        self.pki = pki
        passwd = os.path.join(workdir, "passwd")
        subprocess.run(["mosquitto_passwd", "-c", "-b", passwd, user, password], check=True, timeout=30,
                       capture_output=True)
        os.chmod(passwd, 0o600)
        with open(self.conf, "w") as f:
            f.write(f"listener {self.port} 127.0.0.1\nallow_anonymous false\npassword_file {passwd}\n"
                    f"cafile {pki.ca}\ncertfile {pki.server_cert}\nkeyfile {pki.server_key}\n"
                    "require_certificate true\ntls_version tlsv1.2\npersistence false\n"
                    f"log_dest stderr\nlog_type error\nlog_type warning\nuser {getpass.getuser()}\n")

    def client_args(self, user: str, password: str) -> List[str]:
        """mosquitto_sub / mosquitto_pub options to reach this broker."""
        return ["-h", "localhost", "-p", str(self.port), "--cafile", self.pki.ca, "--cert", self.pki.client_cert,
                "--key", self.pki.client_key, "-u", user, "-P", password]

    def __enter__(self) -> "SecureBroker":
        self.start()
        return self

    def __exit__(self, *exc: Any) -> None:
        self.stop()
