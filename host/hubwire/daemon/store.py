"""What ``hubwire serve`` keeps across its own restarts (docs/SERVICE.md, "What survives a restart"):
one SQLite file in the service's state directory.

- **Hub events** (``notify``, PROTOCOL.md 10.3) a client handed to the service for a board: a row
  from the moment the service accepts one until the device answers it. A restarted service (or the
  board's next session after a replug) sends the rows left, in order, before any new one.
- **The board's events**, as the service received them: each gets an id (1, 2, 3... per board, never
  reused), and is written before the service acknowledges it to the device, so an event the device
  was told is delivered is on disk. A client that subscribed says which id it saw last (``after``)
  and gets the rest, once. The log keeps at most ``event_keep`` events per board and none older
  than ``event_age`` seconds (oldest dropped first; a client resuming behind them is told how many
  it missed).
- Per board: the last id handed out and the device session nonce and seq of its last event, to
  recognise the device's retry of an event the service stored but died before acknowledging.
- Per port: the hub nonce the service said hello with, the seq of the last hub event the device
  acknowledged and the (row, seq, id) of the one in flight, written before it goes out: a restarted
  service resumes that hub session, so the device's duplicate memory holds (session/resume.py).
  At most ``board_limit`` ports (the one used longest ago forgotten first).

Durability: WAL with ``synchronous=NORMAL``: a committed row survives the process being killed
(SIGKILL included), not necessarily a power loss. Everything runs on the service's loop.
"""
from __future__ import annotations

import contextlib
import fcntl
import os
import sqlite3
import time
from dataclasses import dataclass
from typing import Any, Callable, Dict, Iterator, List, Optional, Sequence, Tuple

from ..errors import HubwireError
from ..session.hub_channels import HUB_EVENT_QUEUE_LIMIT

__all__ = ["Store", "StoredEvent", "StoreFull", "HubSessionRow", "state_dir", "SYSTEM_STATE_DIR",
           "EVENT_KEEP", "EVENT_AGE", "HUB_EVENT_LIMIT", "BOARD_LIMIT"]

#: where the system service keeps its state (systemd StateDirectory=hubwire)
SYSTEM_STATE_DIR = "/var/lib/hubwire"
#: events kept per board for clients that come back
EVENT_KEEP = 10000
#: seconds an event is kept for clients that come back
EVENT_AGE = 600.0
#: hub events waiting per board (as many as one session queues in memory)
HUB_EVENT_LIMIT = HUB_EVENT_QUEUE_LIMIT
#: boards remembered; beyond it the one idle longest (and its log) is forgotten
BOARD_LIMIT = 1024

_SCHEMA = """
CREATE TABLE IF NOT EXISTS boards (key TEXT PRIMARY KEY, last_id INTEGER NOT NULL, nonce INTEGER,
    seq INTEGER, used REAL NOT NULL);
CREATE TABLE IF NOT EXISTS events (board TEXT NOT NULL, id INTEGER NOT NULL, name TEXT NOT NULL,
    raw BLOB NOT NULL, seq INTEGER NOT NULL, at REAL NOT NULL, PRIMARY KEY (board, id));
CREATE TABLE IF NOT EXISTS hub_events (id INTEGER PRIMARY KEY AUTOINCREMENT, board TEXT NOT NULL,
    name TEXT NOT NULL, payload BLOB NOT NULL);
CREATE INDEX IF NOT EXISTS hub_events_board ON hub_events (board, id);
CREATE TABLE IF NOT EXISTS hub_sessions (port TEXT PRIMARY KEY, nonce INTEGER NOT NULL, acked INTEGER,
    row INTEGER, seq INTEGER, id INTEGER, used REAL NOT NULL);
"""


class StoreFull(HubwireError):
    """A board has ``hub_limit`` hub events waiting already (or ``board_limit`` boards have some):
    the new one is refused."""


@dataclass(frozen=True)
class StoredEvent:
    id: int
    name: str
    raw: bytes
    seq: int


@dataclass(frozen=True)
class HubSessionRow:
    """The hub session last used on a port: its hub nonce, the seq of the last hub event the device
    acknowledged, and (row, seq, id) of the hub event in flight."""
    nonce: int
    acked: Optional[int]
    head: Optional[Tuple[int, int, int]]


def state_dir(given: Optional[str] = None) -> str:
    """``given``, else $HUBWIRE_STATE_DIR, else /var/lib/hubwire as root, else
    $XDG_STATE_HOME/hubwire (~/.local/state/hubwire)."""
    if given:
        return given
    env = os.environ.get("HUBWIRE_STATE_DIR")
    if env:
        return env
    if os.geteuid() == 0:
        return SYSTEM_STATE_DIR
    base = os.environ.get("XDG_STATE_HOME") or os.path.join(os.path.expanduser("~"), ".local", "state")
    return os.path.join(base, "hubwire")


def _private_dir(path: str) -> None:
    """Create ``path`` 0700, or make an existing one of ours 0700; refuse one owned by someone else."""
    os.makedirs(path, mode=0o700, exist_ok=True)
    st = os.stat(path)
    if st.st_uid != os.geteuid():
        raise HubwireError(f"state directory {path} belongs to uid {st.st_uid}, not to this user: "
                           "give the service a directory of its own (--state DIR)")
    if st.st_mode & 0o077:
        os.chmod(path, 0o700)


class Store:
    """The state file in ``directory`` (created 0700; the file itself 0600)."""

    def __init__(self, directory: str, *, event_keep: int = EVENT_KEEP, event_age: float = EVENT_AGE,
                 hub_limit: int = HUB_EVENT_LIMIT, board_limit: int = BOARD_LIMIT,
                 clock: Callable[[], float] = time.time) -> None:
        _private_dir(directory)
        self.path = os.path.join(directory, "hubwire.sqlite3")
        self.event_keep, self.event_age = event_keep, event_age
        self.hub_limit, self.board_limit = hub_limit, board_limit
        self.clock = clock
        old = os.umask(0o077)
        try:
            # one service per state directory: two would both send the same kept hub events
            self._lock = os.open(os.path.join(directory, "lock"), os.O_RDWR | os.O_CREAT, 0o600)
            try:
                fcntl.flock(self._lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError:
                os.close(self._lock)
                raise HubwireError(f"another hubwire serve uses the state directory {directory}: give each "
                                   "service its own (--state DIR)") from None
            self.db = sqlite3.connect(self.path, isolation_level=None, check_same_thread=False)
        finally:
            os.umask(old)
        self.db.execute("PRAGMA journal_mode=WAL")
        self.db.execute("PRAGMA synchronous=NORMAL")
        self.db.executescript(_SCHEMA)
        #: live listeners per board: called with each new event once it is stored
        self._listeners: Dict[str, List[Callable[[StoredEvent], None]]] = {}

    @contextlib.contextmanager
    def _txn(self) -> Iterator[None]:
        """One transaction: all its statements on disk, or none (autocommit mode otherwise)."""
        self.db.execute("BEGIN IMMEDIATE")
        try:
            yield
        except BaseException:
            self.db.execute("ROLLBACK")
            raise
        self.db.execute("COMMIT")

    def close(self) -> None:
        self.db.close()
        os.close(self._lock)  # (the lock goes with it)

    # ----------------------------------------------------------------------------- boards

    def _board(self, key: str) -> Tuple[int, Optional[int], Optional[int]]:
        """(last id, nonce, seq) of ``key``, adding it (and forgetting the idlest beyond the limit)."""
        row = self.db.execute("SELECT last_id, nonce, seq FROM boards WHERE key=?", (key,)).fetchone()
        if row is not None:
            return int(row[0]), row[1], row[2]
        (n,) = self.db.execute("SELECT COUNT(*) FROM boards").fetchone()
        if n >= self.board_limit:
            for (old,) in self.db.execute(
                    "SELECT key FROM boards WHERE key NOT IN (SELECT board FROM hub_events) ORDER BY used "
                    "LIMIT ?", (n - self.board_limit + 1,)).fetchall():
                self.db.execute("DELETE FROM events WHERE board=?", (old,))
                self.db.execute("DELETE FROM boards WHERE key=?", (old,))
            (n,) = self.db.execute("SELECT COUNT(*) FROM boards").fetchone()
            if n >= self.board_limit:
                raise StoreFull(f"{n} boards have hub events waiting: no room for {key}")
        self.db.execute("INSERT INTO boards (key, last_id, used) VALUES (?, 0, ?)", (key, self.clock()))
        return 0, None, None

    # ------------------------------------------------------------------------ hub events

    def hub_add(self, key: str, name: str, payload: bytes) -> int:
        """Keep a hub event for ``key`` until :meth:`hub_done`; its row id. StoreFull at the limit."""
        with self._txn():
            (n,) = self.db.execute("SELECT COUNT(*) FROM hub_events WHERE board=?", (key,)).fetchone()
            if n >= self.hub_limit:
                raise StoreFull(f"{self.hub_limit} hub events wait for {key} already")
            self._board(key)
            cur = self.db.execute("INSERT INTO hub_events (board, name, payload) VALUES (?, ?, ?)",
                                  (key, name, payload))
            return int(cur.lastrowid or 0)

    def hub_done(self, row: int, port: Optional[str] = None, acked: Optional[int] = None) -> None:
        """The device answered hub event ``row`` (sent on ``port``; ``acked``: its seq if it was an
        ACK): forget it, and keep what the device now remembers."""
        with self._txn():
            self.db.execute("DELETE FROM hub_events WHERE id=?", (row,))
            if port is not None:
                self.db.execute("UPDATE hub_sessions SET acked=COALESCE(?, acked), row=NULL, seq=NULL, id=NULL "
                                "WHERE port=? AND row=?", (acked, port, row))

    # ----------------------------------------------------------------------- hub sessions

    def hub_session(self, port: str) -> Optional[HubSessionRow]:
        """The hub session last used on ``port``, if any."""
        r = self.db.execute("SELECT nonce, acked, row, seq, id FROM hub_sessions WHERE port=?", (port,)).fetchone()
        if r is None:
            return None
        head = (int(r[2]), int(r[3]), int(r[4])) if None not in (r[2], r[3], r[4]) else None
        return HubSessionRow(int(r[0]), None if r[1] is None else int(r[1]), head)

    def hub_session_ports(self) -> List[str]:
        return [str(p) for (p,) in self.db.execute("SELECT port FROM hub_sessions")]

    def hub_session_new(self, port: str, nonce: int, *, fresh: bool = True) -> None:
        """``port`` says hello with hub ``nonce`` from now on; ``fresh``: a new hub session (nothing
        the device remembers of an earlier one counts), else only the nonce changes."""
        with self._txn():
            if fresh or self.db.execute("UPDATE hub_sessions SET nonce=?, used=? WHERE port=?",
                                        (nonce, self.clock(), port)).rowcount == 0:
                self.db.execute("INSERT OR REPLACE INTO hub_sessions (port, nonce, used) VALUES (?, ?, ?)",
                                (port, nonce, self.clock()))
            self.db.execute("DELETE FROM hub_sessions WHERE port IN (SELECT port FROM hub_sessions "
                            "ORDER BY used DESC LIMIT -1 OFFSET ?)", (self.board_limit,))

    def hub_sent(self, port: str, row: int, seq: int, id: int) -> None:
        """Hub event ``row`` goes out on ``port`` with ``seq`` and ``id`` (and every retry with them)."""
        self.db.execute("UPDATE hub_sessions SET row=?, seq=?, id=?, used=? WHERE port=?",
                        (row, seq, id, self.clock(), port))

    def hub_pending(self, key: str) -> List[Tuple[int, str, bytes]]:
        """(row, name, payload) of every hub event still waiting for ``key``, oldest first."""
        return [(int(r), str(n), bytes(p)) for r, n, p in self.db.execute(
            "SELECT id, name, payload FROM hub_events WHERE board=? ORDER BY id", (key,))]

    # ----------------------------------------------------------------------- board events

    def event_add(self, key: str, name: str, raw: bytes, seq: int, nonce: Optional[int]) -> Optional[StoredEvent]:
        """Store an event the device sent (session ``nonce``, ``seq``) and hand it to the listeners;
        None when it is the device's retry of the last event stored (same nonce, seq, name, bytes):
        the service stored it and was stopped before acknowledging it."""
        now = self.clock()
        with self._txn():
            last, lnonce, lseq = self._board(key)
            if nonce is not None and lnonce == nonce and lseq == seq:
                prev = self.db.execute("SELECT name, raw FROM events WHERE board=? AND id=?", (key, last)).fetchone()
                if prev is not None and prev[0] == name and bytes(prev[1]) == raw:
                    return None
            ev = StoredEvent(last + 1, name, raw, seq)
            self.db.execute("INSERT INTO events (board, id, name, raw, seq, at) VALUES (?, ?, ?, ?, ?, ?)",
                            (key, ev.id, name, raw, seq, now))
            self.db.execute("UPDATE boards SET last_id=?, nonce=?, seq=?, used=? WHERE key=?",
                            (ev.id, nonce, seq, now, key))
            self.db.execute("DELETE FROM events WHERE board=? AND (id<=? OR at<?)",
                            (key, ev.id - self.event_keep, now - self.event_age))
        for cb in list(self._listeners.get(key, ())):
            cb(ev)
        return ev

    def events_after(self, key: str, after: int, names: Sequence[str] = ()) -> Tuple[List[StoredEvent], int, int]:
        """The events of ``key`` after id ``after`` (of ``names``; all when empty), the number of
        events after it no longer kept (dropped for count or age), and the last id handed out."""
        row = self.db.execute("SELECT last_id FROM boards WHERE key=?", (key,)).fetchone()
        last = int(row[0]) if row is not None else 0
        self.db.execute("DELETE FROM events WHERE board=? AND at<?", (key, self.clock() - self.event_age))
        rows = [StoredEvent(int(i), str(n), bytes(r), int(s)) for i, n, r, s in self.db.execute(
            "SELECT id, name, raw, seq FROM events WHERE board=? AND id>? ORDER BY id", (key, after))]
        first = rows[0].id if rows else last + 1
        missed = max(0, first - after - 1) if after < last else 0
        if names:
            rows = [e for e in rows if e.name in names]
        return rows, missed, last

    def last_id(self, key: str) -> int:
        row = self.db.execute("SELECT last_id FROM boards WHERE key=?", (key,)).fetchone()
        return int(row[0]) if row is not None else 0

    def listen(self, key: str, cb: Callable[[StoredEvent], None]) -> Callable[[], None]:
        """Call ``cb`` with each event of ``key`` stored from now on; returns the remover."""
        lst = self._listeners.setdefault(key, [])
        lst.append(cb)

        def remove() -> None:
            if cb in lst:
                lst.remove(cb)
            if not lst and self._listeners.get(key) is lst:
                del self._listeners[key]
        return remove

    def stats(self) -> Dict[str, Any]:
        (ev,) = self.db.execute("SELECT COUNT(*) FROM events").fetchone()
        (hub,) = self.db.execute("SELECT COUNT(*) FROM hub_events").fetchone()
        (boards,) = self.db.execute("SELECT COUNT(*) FROM boards").fetchone()
        (ports,) = self.db.execute("SELECT COUNT(*) FROM hub_sessions").fetchone()
        return {"events": ev, "hub_events": hub, "boards": boards, "hub_sessions": ports}
