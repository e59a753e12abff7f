"""The service's socket lives in a directory the service made and owns (0700; a group under systemd):
it refuses one another user made first or anyone may write to, and clients look where it listens."""
from __future__ import annotations

import asyncio
import os
import socket
import stat
from typing import Any

import pytest

from hubwire.errors import HubwireError
from hubwire.client import protocol
from hubwire.daemon.fleet import Fleet
from hubwire.daemon.server import Server

NOBODY = 65534  # another local user (tests run as root and hand the directory over)


def start(path: str) -> None:
    async def main() -> None:
        server = Server(Fleet(usb=False, udev=False), path)
        await server.start()
        await server.close()
    asyncio.run(main())


def hostile(d: Any, mode: int = 0o777, owner: int = NOBODY) -> str:
    d.mkdir()
    os.chmod(d, mode)
    os.chown(d, owner, owner)
    return str(d)


def test_a_directory_another_user_made_first_is_refused(tmp_path: Any) -> None:
    d = hostile(tmp_path / "hubwire-1000")
    with pytest.raises(HubwireError, match="owned by uid 65534") as e:
        start(os.path.join(d, "hubwire.sock"))
    assert "remove it" in str(e.value) and d in str(e.value)
    assert os.listdir(d) == []


def test_a_directory_others_may_write_to_is_refused_even_if_ours(tmp_path: Any) -> None:
    for mode in (0o777, 0o770, 0o1777):
        d = tmp_path / f"m{mode:o}"
        hostile(d, mode, os.geteuid())
        with pytest.raises(HubwireError, match="writable by"):
            start(str(d / "hubwire.sock"))


def test_a_symlink_in_place_of_the_directory_is_refused(tmp_path: Any) -> None:
    target = tmp_path / "elsewhere"
    target.mkdir(mode=0o700)
    (tmp_path / "hubwire-1000").symlink_to(target)
    with pytest.raises(HubwireError, match="symbolic link"):
        start(str(tmp_path / "hubwire-1000" / "hubwire.sock"))
    assert os.listdir(target) == []


def test_the_service_makes_its_directory_private(tmp_path: Any) -> None:
    d = tmp_path / "fresh" / "hubwire"
    (tmp_path / "fresh").mkdir()
    start(str(d / "hubwire.sock"))
    st = os.lstat(d)
    assert stat.S_IMODE(st.st_mode) == 0o700 and st.st_uid == os.geteuid()


def _listen(path: str) -> socket.socket:
    s = socket.socket(socket.AF_UNIX)
    s.bind(path)
    s.listen()
    return s


def test_clients_look_where_a_service_without_xdg_runtime_dir_listens(tmp_path: Any, monkeypatch: Any) -> None:
    monkeypatch.delenv("HUBWIRE_SOCKET", raising=False)
    monkeypatch.delenv("XDG_RUNTIME_DIR", raising=False)
    monkeypatch.setattr(protocol, "TMP", str(tmp_path), raising=False)
    monkeypatch.setattr(protocol, "SYSTEM_SOCKET", str(tmp_path / "no-system" / "hubwire.sock"))
    d = tmp_path / f"hubwire-{os.getuid()}"
    d.mkdir(mode=0o700)
    with _listen(str(d / "hubwire.sock")):
        assert protocol.socket_path() == str(d / "hubwire.sock")
        assert protocol.default_serve_socket() in (str(d / "hubwire.sock"), protocol.SYSTEM_SOCKET)


def test_clients_do_not_trust_a_socket_in_a_directory_another_user_made(tmp_path: Any, monkeypatch: Any) -> None:
    monkeypatch.delenv("HUBWIRE_SOCKET", raising=False)
    monkeypatch.delenv("XDG_RUNTIME_DIR", raising=False)
    monkeypatch.setattr(protocol, "TMP", str(tmp_path), raising=False)
    monkeypatch.setattr(protocol, "SYSTEM_SOCKET", str(tmp_path / "no-system" / "hubwire.sock"))
    d = tmp_path / f"hubwire-{os.getuid()}"
    d.mkdir()
    with _listen(str(d / "hubwire.sock")):
        os.chown(d, NOBODY, NOBODY)
        assert protocol.socket_path() is None
