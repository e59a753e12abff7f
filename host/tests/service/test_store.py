"""The service's state file (hubwire.daemon.store): what it keeps, its bounds, what happens when full."""
from __future__ import annotations

import os
import stat
from typing import Any, List

import pytest

from hubwire.errors import HubwireError

from hubwire.daemon.store import Store, StoredEvent, StoreFull, state_dir


class Clock:
    def __init__(self) -> None:
        self.t = 1000.0

    def __call__(self) -> float:
        return self.t


def test_state_dir_is_private(tmp_path: Any) -> None:
    d = tmp_path / "state"
    Store(str(d)).close()
    assert stat.S_IMODE(os.stat(d).st_mode) == 0o700
    assert stat.S_IMODE(os.stat(d / "hubwire.sqlite3").st_mode) & 0o077 == 0
    open_dir = tmp_path / "open"
    open_dir.mkdir(mode=0o755)
    os.chmod(open_dir, 0o755)
    Store(str(open_dir)).close()
    assert stat.S_IMODE(os.stat(open_dir).st_mode) == 0o700, "an existing directory is made 0700"


def test_one_service_per_state_dir(tmp_path: Any) -> None:
    s = Store(str(tmp_path))
    with pytest.raises(HubwireError, match="another hubwire serve"):
        Store(str(tmp_path))
    s.close()
    Store(str(tmp_path)).close()  # free again once the first one closed


def test_state_dir_default(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("HUBWIRE_STATE_DIR", "/x/state")
    assert state_dir("/given") == "/given"
    assert state_dir() == "/x/state"
    monkeypatch.delenv("HUBWIRE_STATE_DIR")
    monkeypatch.setenv("XDG_STATE_HOME", "/home/u/.st")
    if os.geteuid() != 0:
        assert state_dir() == "/home/u/.st/hubwire"


def test_hub_events_kept_until_done_across_reopen(tmp_path: Any) -> None:
    s = Store(str(tmp_path))
    rows = [s.hub_add("rover", "tick", bytes([i])) for i in range(3)]
    s.hub_add("other", "tick", b"\x09")
    s.hub_done(rows[0])
    s.close()
    s = Store(str(tmp_path))  # a new process
    assert s.hub_pending("rover") == [(rows[1], "tick", b"\x01"), (rows[2], "tick", b"\x02")]
    assert [p for _r, _n, p in s.hub_pending("other")] == [b"\x09"]
    s.close()


def test_hub_events_full_refuses_the_new_one(tmp_path: Any) -> None:
    s = Store(str(tmp_path), hub_limit=3)
    for i in range(3):
        s.hub_add("rover", "tick", bytes([i]))
    with pytest.raises(StoreFull):
        s.hub_add("rover", "tick", b"\x03")
    assert [p for _r, _n, p in s.hub_pending("rover")] == [b"\x00", b"\x01", b"\x02"], "the kept ones stay"
    s.hub_add("other", "tick", b"\x04")  # per board
    s.hub_done(s.hub_pending("rover")[0][0])
    s.hub_add("rover", "tick", b"\x05")  # room again once the device answered one


def test_event_ids_per_board_and_resume(tmp_path: Any) -> None:
    s = Store(str(tmp_path))
    got: List[StoredEvent] = []
    stop = s.listen("rover", got.append)
    for i in range(5):
        s.event_add("rover", "bumper" if i % 2 else "other", bytes([i]), i + 1, 77)
    s.event_add("arm", "bumper", b"\x01", 1, 5)
    stop()
    s.event_add("rover", "bumper", b"\x09", 9, 77)
    assert [e.id for e in got] == [1, 2, 3, 4, 5], "the listener hears its board until removed"
    rows, missed, last = s.events_after("rover", 2)
    assert [e.id for e in rows] == [3, 4, 5, 6] and missed == 0 and last == 6
    rows, _m, _l = s.events_after("rover", 0, ["bumper"])
    assert [e.id for e in rows] == [2, 4, 6]
    s.close()
    s = Store(str(tmp_path))
    assert s.event_add("rover", "bumper", b"\x01", 10, 77).id == 7, "ids go on after a restart"  # type: ignore[union-attr]
    assert s.events_after("arm", 0)[2] == 1


def test_event_log_bounded_by_count(tmp_path: Any) -> None:
    s = Store(str(tmp_path), event_keep=5)
    for i in range(8):
        s.event_add("rover", "bumper", bytes([i]), i, 1)
    rows, missed, last = s.events_after("rover", 0)
    assert [e.id for e in rows] == [4, 5, 6, 7, 8] and missed == 3 and last == 8, "oldest dropped, counted"
    rows, missed, _ = s.events_after("rover", 5)
    assert [e.id for e in rows] == [6, 7, 8] and missed == 0
    assert s.stats()["events"] == 5


def test_event_log_bounded_by_age(tmp_path: Any) -> None:
    clock = Clock()
    s = Store(str(tmp_path), event_age=60, clock=clock)
    for i in range(3):
        s.event_add("rover", "bumper", bytes([i]), i, 1)
    clock.t += 61
    rows, missed, last = s.events_after("rover", 1)
    assert rows == [] and missed == 2 and last == 3, "too old: not sent, but counted as missed"
    s.event_add("rover", "bumper", b"\x05", 5, 1)
    assert s.stats()["events"] == 1


def test_device_retry_of_the_last_stored_event_is_not_stored_again(tmp_path: Any) -> None:
    """The service stored an event and was killed before acknowledging it: the device sends it again
    (same session nonce, same seq, same bytes) to the next service."""
    s = Store(str(tmp_path))
    assert s.event_add("rover", "bumper", b"\x01", 7, 1234) is not None
    s.close()
    s = Store(str(tmp_path))
    assert s.event_add("rover", "bumper", b"\x01", 7, 1234) is None
    assert s.event_add("rover", "bumper", b"\x01", 7, 999) is not None, "a rebooted device: a new event"
    assert s.event_add("rover", "bumper", b"\x00", 7, 999) is not None, "other bytes: a new event"
    assert s.last_id("rover") == 3


def test_boards_bounded_idlest_forgotten(tmp_path: Any) -> None:
    clock = Clock()
    s = Store(str(tmp_path), board_limit=2, clock=clock)
    s.event_add("a", "e", b"\x01", 1, 1)
    clock.t += 1
    s.hub_add("b", "tick", b"\x01")  # a board with hub events waiting is never forgotten
    clock.t += 1
    s.event_add("c", "e", b"\x01", 1, 1)
    assert s.stats()["boards"] == 2
    assert s.last_id("a") == 0 and s.events_after("a", 0)[0] == [], "the idlest board and its log are gone"
    assert len(s.hub_pending("b")) == 1
    clock.t += 1
    s.hub_add("c", "tick", b"\x01")
    with pytest.raises(StoreFull):
        s.hub_add("d", "tick", b"\x01")  # every board remembered has hub events waiting
    assert s.stats()["boards"] == 2


def test_an_event_is_stored_whole_or_not_at_all(tmp_path: Any) -> None:
    """Stopped between writing an event and moving the board's last id on, the store keeps neither:
    the next event takes that id (rather than clashing with a half-written one for ever)."""
    import sqlite3

    s = Store(str(tmp_path))
    s.event_add("rover", "e", b"\x01", 1, 1)
    real = s.db

    class Dies:
        def execute(self, sql: str, *args: Any) -> Any:
            if sql.startswith("UPDATE boards"):
                raise sqlite3.OperationalError("the process died here")
            return real.execute(sql, *args)

        def __enter__(self) -> Any:
            return real.__enter__()

        def __exit__(self, *exc: Any) -> Any:
            return real.__exit__(*exc)
    s.db = Dies()  # type: ignore[assignment]
    with pytest.raises(sqlite3.OperationalError):
        s.event_add("rover", "e", b"\x02", 2, 1)
    s.db = real
    ev = s.event_add("rover", "e", b"\x03", 3, 1)
    assert ev is not None and ev.id == 2
    rows, _missed, last = s.events_after("rover", 0)
    assert [(e.id, e.raw) for e in rows] == [(1, b"\x01"), (2, b"\x03")] and last == 2


def test_hub_session_round_trip_across_reopen(tmp_path: Any) -> None:
    """The hub nonce of a port and the seqs of its hub events, as a restarted service reads them back."""
    s = Store(str(tmp_path))
    assert s.hub_session("/dev/ttyACM0") is None
    s.hub_session_new("/dev/ttyACM0", 0x12345678)
    r1 = s.hub_add("uno", "tick", b"\x01\x00\x00\x00")
    r2 = s.hub_add("uno", "tick", b"\x02\x00\x00\x00")
    s.hub_sent("/dev/ttyACM0", r1, 200, 3)  # kept before the event goes out
    s.close()
    s = Store(str(tmp_path))  # the service restarted
    got = s.hub_session("/dev/ttyACM0")
    assert got is not None and got.nonce == 0x12345678 and got.acked is None and got.head == (r1, 200, 3), got
    s.hub_done(r1, "/dev/ttyACM0", 200)  # ACK: the device remembers seq 200
    s.hub_sent("/dev/ttyACM0", r2, 201, 3)
    s.close()
    s = Store(str(tmp_path))
    got = s.hub_session("/dev/ttyACM0")
    assert got is not None and got.acked == 200 and got.head == (r2, 201, 3), got
    s.hub_done(r2, "/dev/ttyACM0", None)  # NAK: the device still remembers 200
    got = s.hub_session("/dev/ttyACM0")
    assert got is not None and got.acked == 200 and got.head is None, got
    s.hub_session_new("/dev/ttyACM0", 0x9ABCDEF0, fresh=False)  # the port was opened again
    got = s.hub_session("/dev/ttyACM0")
    assert got is not None and got.nonce == 0x9ABCDEF0 and got.acked == 200, "only the nonce changes"
    s.hub_session_new("/dev/ttyACM0", 0x11111111)  # a new hub session: nothing of the old one counts
    got = s.hub_session("/dev/ttyACM0")
    assert got is not None and (got.nonce, got.acked, got.head) == (0x11111111, None, None), got
    s.close()


def test_hub_sessions_bounded_oldest_forgotten(tmp_path: Any) -> None:
    clock = Clock()
    s = Store(str(tmp_path), board_limit=3, clock=clock)
    for i in range(5):
        clock.t += 1
        s.hub_session_new(f"/dev/pts/{i}", i + 1)
    assert sorted(s.hub_session_ports()) == ["/dev/pts/2", "/dev/pts/3", "/dev/pts/4"]
    assert s.stats()["hub_sessions"] == 3
    s.close()
