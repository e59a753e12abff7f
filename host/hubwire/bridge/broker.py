"""How ``hubwire serve`` reaches its MQTT broker: address, username and password, TLS, and where
replies may go (docs/MQTT.md "Security model").

From the command line (``--mqtt``, ``--mqtt-user``, ``--mqtt-password-file``, ``--mqtt-cafile``,
``--mqtt-cert``, ``--mqtt-key``, ``--mqtt-insecure``) and/or a TOML file (``--mqtt-config``); the
command line wins. The password never has to be on the command line, where every user of the
machine can read it: it comes from a file, the config file, or ``$HUBWIRE_MQTT_PASSWORD``.
"""
from __future__ import annotations

import os
import ssl
from dataclasses import dataclass, field
from typing import Any, Dict, List, Optional, Tuple

__all__ = ["BrokerSettings", "load_config", "settings_from_args", "broker_address", "PASSWORD_ENV"]

#: the environment variable a password may come from
PASSWORD_ENV = "HUBWIRE_MQTT_PASSWORD"


@dataclass
class BrokerSettings:
    host: str = "localhost"
    port: Optional[int] = None  # None: 8883 with TLS, else 1883
    username: Optional[str] = None
    password: Optional[str] = field(default=None, repr=False)
    #: TLS is on when any of these is given (or ``tls``): the CA that signed the broker's
    #: certificate (None: the system's CAs), and this client's certificate and key
    tls: bool = False
    ca_file: Optional[str] = None
    cert_file: Optional[str] = None
    key_file: Optional[str] = None
    #: skip the check that the broker's certificate names the host (never the CA check); off
    insecure: bool = False
    #: topics replies may be published under (default: the bridge's own prefix)
    reply_prefixes: Tuple[str, ...] = ()
    service_id: Optional[str] = None

    @property
    def uses_tls(self) -> bool:
        return self.tls or any((self.ca_file, self.cert_file, self.key_file))

    @property
    def effective_port(self) -> int:
        return self.port if self.port is not None else (8883 if self.uses_tls else 1883)

    def tls_context(self) -> Optional[ssl.SSLContext]:
        """The TLS context the bridge connects with, or None for plain TCP. Files that cannot be
        read raise ``OSError`` / ``ssl.SSLError`` here, before the service starts."""
        if not self.uses_tls:
            return None
        ctx = ssl.create_default_context(ssl.Purpose.SERVER_AUTH, cafile=self.ca_file)
        if self.cert_file:
            ctx.load_cert_chain(self.cert_file, self.key_file)
        if self.insecure:
            ctx.check_hostname = False  # the chain is still checked against the CA
        return ctx

    def bridge_kwargs(self) -> Dict[str, Any]:
        """Keyword arguments of :func:`hubwire.bridge.mqtt.run_bridge` beyond host and port."""
        kw: Dict[str, Any] = {}
        if self.username is not None:
            kw.update(username=self.username, password=self.password)
        ctx = self.tls_context()
        if ctx is not None:
            kw.update(tls_context=ctx)
        if self.reply_prefixes:
            kw.update(reply_prefixes=self.reply_prefixes)
        if self.service_id:
            kw.update(service_id=self.service_id)
        return kw


def broker_address(where: str) -> Tuple[str, Optional[int]]:
    """``HOST:PORT`` (or ``HOST``: the default port)."""
    host, _, port = where.rpartition(":")
    if not host or not port.isdigit():
        return where, None
    return host, int(port)


def _read_secret(path: str) -> str:
    with open(os.path.expanduser(path), encoding="utf-8") as f:
        return f.read().strip("\r\n")


def load_config(path: str) -> BrokerSettings:
    """Settings from a TOML file::

        host = "broker.lan"            # or address = "broker.lan:8883"
        port = 8883
        username = "hub"
        password_file = "/etc/hubwire/mqtt-password"   # or password = "..." (keep the file 0600)
        id = "kitchen"
        reply_prefixes = ["hubwire/", "clients/"]
        [tls]
        ca_file = "/etc/hubwire/ca.crt"
        cert_file = "/etc/hubwire/hub.crt"
        key_file = "/etc/hubwire/hub.key"
        insecure = false
    """
    try:
        import tomllib  # type: ignore[import-not-found,unused-ignore]
    except ImportError:  # Python < 3.11
        import tomli as tomllib  # type: ignore[import-not-found,no-redef,unused-ignore]
    with open(path, "rb") as f:
        data = tomllib.load(f)
    s = BrokerSettings()
    known = {"host", "address", "port", "username", "password", "password_file", "id", "reply_prefixes", "tls"}
    unknown = set(data) - known
    if unknown:
        raise ValueError(f"{path}: unknown settings {', '.join(sorted(unknown))}; known: {', '.join(sorted(known))}")
    if "address" in data:
        s.host, s.port = broker_address(str(data["address"]))
    s.host = str(data.get("host", s.host))
    s.port = int(data["port"]) if "port" in data else s.port
    s.username = data.get("username")
    s.password = data.get("password")
    if "password_file" in data:
        s.password = _read_secret(str(data["password_file"]))
    s.service_id = data.get("id")
    prefixes = data.get("reply_prefixes", [])
    if not isinstance(prefixes, list) or not all(isinstance(p, str) and p for p in prefixes):
        raise ValueError(f"{path}: reply_prefixes is a list of topic prefixes")
    s.reply_prefixes = tuple(prefixes)
    tls = data.get("tls", {})
    if not isinstance(tls, dict) or set(tls) - {"enabled", "ca_file", "cert_file", "key_file", "insecure"}:
        raise ValueError(f"{path}: [tls] takes enabled, ca_file, cert_file, key_file, insecure")
    s.tls = bool(tls.get("enabled", bool(tls)))
    s.ca_file, s.cert_file, s.key_file = tls.get("ca_file"), tls.get("cert_file"), tls.get("key_file")
    s.insecure = bool(tls.get("insecure", False))
    return s


def settings_from_args(args: Any) -> Optional[BrokerSettings]:
    """The broker ``hubwire serve`` was told to use (None: no MQTT). Raises ``ValueError`` or
    ``OSError`` for a config or password file it cannot use."""
    if not args.mqtt and not args.mqtt_config:
        return None
    s = load_config(args.mqtt_config) if args.mqtt_config else BrokerSettings()
    if args.mqtt:
        s.host, port = broker_address(args.mqtt)
        s.port = port if port is not None else s.port
    if args.mqtt_user is not None:
        s.username = args.mqtt_user
    if args.mqtt_password_file:
        s.password = _read_secret(args.mqtt_password_file)
    elif s.password is None and os.environ.get(PASSWORD_ENV):
        s.password = os.environ[PASSWORD_ENV]
    for name in ("ca_file", "cert_file", "key_file"):
        v = getattr(args, f"mqtt_{name}")
        if v:
            setattr(s, name, v)
    s.tls = s.tls or args.mqtt_tls
    s.insecure = s.insecure or args.mqtt_insecure
    if args.mqtt_reply_prefix:
        s.reply_prefixes = tuple(args.mqtt_reply_prefix)
    if args.mqtt_id:
        s.service_id = args.mqtt_id
    return s


def argv_options() -> List[Tuple[Tuple[str, ...], Dict[str, Any]]]:
    """The ``serve`` options for the broker (added by ``hubwire.cli.serve``)."""
    return [
        (("--mqtt-config",), dict(metavar="FILE", default=None,
                                  help="MQTT settings from this TOML file (docs/MQTT.md); options below override it")),
        (("--mqtt-user",), dict(metavar="NAME", default=None, help="username on the broker")),
        (("--mqtt-password-file",), dict(metavar="FILE", default=None,
                                         help=f"the broker password, read from this file (or set ${PASSWORD_ENV})")),
        (("--mqtt-tls",), dict(action="store_true", help="TLS with the system's CAs (implied by --mqtt-cafile)")),
        (("--mqtt-cafile",), dict(dest="mqtt_ca_file", metavar="FILE", default=None,
                                  help="TLS: the CA certificate that signed the broker's")),
        (("--mqtt-cert",), dict(dest="mqtt_cert_file", metavar="FILE", default=None,
                                help="TLS: this service's client certificate")),
        (("--mqtt-key",), dict(dest="mqtt_key_file", metavar="FILE", default=None,
                               help="TLS: the key of the client certificate")),
        (("--mqtt-insecure",), dict(action="store_true",
                                    help="TLS: do not check that the broker's certificate names its host (off)")),
        (("--mqtt-reply-prefix",), dict(action="append", default=[], metavar="PREFIX",
                                        help="topics replies may go to (repeatable; default: the bridge's prefix)")),
    ]


#: a broker that stays unreachable is mentioned again at most this often (seconds)
SAY_AGAIN_S = 60.0


class BrokerTrouble:
    """What the bridge logs about reaching its broker: the first failure of a streak with a hint of
    what to do, then at most one line every :data:`SAY_AGAIN_S` while it keeps trying (the retries in
    between at debug level); the connection itself at info level (``hubwire serve -v``)."""

    def __init__(self, log: Any, where: str, retry_s: float) -> None:
        self.log = log
        self.where = where
        self.retry_s = retry_s
        self.failures = 0
        self._since: Optional[float] = None
        self._said_at: Optional[float] = None

    def failed(self, error: BaseException, answered: bool, now: float) -> None:
        """A connection attempt failed; ``answered``: the broker itself refused (a password, a
        certificate), rather than nothing answering."""
        self.failures += 1
        if self._since is None:
            self._since = now
        if self._said_at is not None and now - self._said_at < SAY_AGAIN_S:
            self.log.debug("hubwire serve: MQTT: broker %s: %s", self.where, error)
            return
        still = f" (still, {self.failures} tries in {now - self._since:.0f} s)" if self._said_at is not None else ""
        self._said_at = now
        if answered:
            self.log.warning("hubwire serve: MQTT: the broker at %s refused the connection: %s%s; trying again "
                             "every %g s", self.where, error, still, self.retry_s)
        else:
            self.log.warning("hubwire serve: MQTT: no MQTT broker answers at %s (%s)%s: start one (Debian: "
                             "sudo apt install mosquitto, which listens on localhost:1883) or point --mqtt HOST:PORT "
                             "at yours; trying again every %g s", self.where, error, still, self.retry_s)

    def connected(self, service_id: str, now: float) -> None:
        after = f" after {self.failures} failed tries in {now - self._since:.0f} s" if self._since is not None else ""
        (self.log.warning if after else self.log.info)(
            "hubwire serve: MQTT: connected to the broker at %s as service %r%s", self.where, service_id, after)
        self.failures = 0
        self._since = self._said_at = None
