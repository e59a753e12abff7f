"""Soak of the hub's channels through the faulty link: the device writes, calls and reads the hub,
and the hub sends it events, all under the soak's faults (:data:`faults.SOAK_FAULTS`).

    python -m hubwire.testing.faultlink.soak_hub --seconds 30

The device is a scripted peer on a pty that follows the device's rules of PROTOCOL.md §10 (one
device transaction at a time, retried with the same seq every 100 ms up to 5 tries; hub events
acked and deduplicated by seq and id; its own requests only once it got the bind report). The hub
is the real one, behind :class:`FaultLink`. Each side counts what it sent and what it applied:

- device writes ``tally`` (u32 tokens, strictly increasing) and calls ``bump`` (u32 -> u32, the hub
  returns the argument + 1): every token the device saw acked was applied exactly once by the hub,
  none twice, none that was never sent (a corrupt value accepted), and every call result is right;
- hub events ``tick`` (u32, strictly increasing): the device got every one, once, in order;
- device reads ``clock`` (the hub's function): every value read is one the hub produced.
"""
from __future__ import annotations

import argparse
import json
import os
import struct
import tempfile
import threading
import time
from dataclasses import asdict
from typing import Any, Dict, List, Optional, Set, Tuple

from ...wire import messages as m
from ...wire.frame import Frame
from ..ptypeer import PtyPeer
from . import FaultLink, Faults
from .faults import SOAK_FAULTS
from .soak_load import retry, wait_for

__all__ = ["HubPeer", "run_hub_soak", "check_hub_soak", "PEER_DESCRIPTOR"]

PEER_DESCRIPTOR = (b'{"p":1,"n":"peer","ch":[],"hub":[{"id":1,"n":"tally","a":"w","t":"u32"},'
                   b'{"id":2,"n":"bump","a":"c","t":"u32","rt":"u32"},{"id":3,"n":"tick","a":"e","t":"u32"},'
                   b'{"id":4,"n":"clock","a":"r","t":"u32"}]}')
_U32 = struct.Struct("<I")


class HubPeer(PtyPeer):
    """The scripted device (see the module docstring); ``run_load()`` drives its transactions."""

    def __init__(self, retry: float = 0.1, tries: int = 5) -> None:
        super().__init__()
        self.retry, self.tries = retry, tries
        self._answer: Optional[Frame] = None
        self._want: Optional[Tuple[int, int]] = None
        self._answered = threading.Event()
        self._seq = 0
        self.hub_nonce: Optional[int] = None
        self.bound = threading.Event()
        self._last_event: Optional[Tuple[int, int]] = None
        self.ticks: List[int] = []
        self.counts: Dict[str, int] = dict(writes_sent=0, writes_acked=0, writes_timed_out=0, writes_refused=0,
                                           calls_sent=0, calls_answered=0, calls_timed_out=0, calls_wrong=0,
                                           reads=0, reads_timed_out=0, event_frames=0, event_duplicates=0,
                                           binds=0)
        self.acked_tokens: List[int] = []
        self.read_values: List[int] = []

    def handle(self, f: Frame) -> None:
        if f.type == m.HELLO:
            h = m.Hello.unpack(f.payload)
            if h.nonce != self.hub_nonce:  # a new hub session: forget the last event, bind again
                self.hub_nonce, self._last_event = h.nonce, None
                self.bound.clear()
            if not h.is_reply:
                hello = m.Hello(1, m.FLAG_DEVICE | m.FLAG_REPLY, 0x5EED, 32, 250, m.fnv1a32(PEER_DESCRIPTOR),
                                len(PEER_DESCRIPTOR))
                self.send(m.HELLO, 0, 0, hello.pack())
        elif f.type == m.CHUNK and len(f.payload) == 3:
            req = m.ChunkRequest.unpack(f.payload)
            data = PEER_DESCRIPTOR[req.offset:req.offset + min(req.want, 28)]
            self.send(m.CHUNK, f.seq, 0, m.Chunk(req.offset, len(PEER_DESCRIPTOR), data).pack())
        elif f.type == m.CONTROL and f.id == 0:
            self.counts["binds"] += 1
            ok = f.payload == bytes((1, 0, 0, 0, 0))
            self.send(m.ACK, f.seq, 0)
            if ok:
                self.bound.set()
        elif f.type == m.EVENT:
            self.counts["event_frames"] += 1
            if self._last_event == (f.seq, f.id):
                self.counts["event_duplicates"] += 1  # re-acked, not delivered again
            elif f.id == 3 and len(f.payload) == 4:
                self._last_event = (f.seq, f.id)
                self.ticks.append(_U32.unpack(f.payload)[0])
            self.send(m.ACK, f.seq, f.id)
        elif f.type in (m.ACK, m.NAK, m.RESPONSE, m.CHUNK) and self._want == (f.seq, f.id):
            self._answer, self._want = f, None
            self._answered.set()

    def transact(self, t: int, hub_id: int, payload: bytes = b"") -> Optional[Frame]:
        """One device transaction, stop and wait: the answer, or None after ``tries``."""
        self.bound.wait(30)
        self._seq = (self._seq + 1) & 0xFF
        seq = self._seq
        for _ in range(self.tries):
            self._answered.clear()
            self._want = (seq, hub_id)
            self.send(t, seq, hub_id, payload)
            if self._answered.wait(self.retry):
                return self._answer
        self._want = None
        return None

    def run_load(self, seconds: float, first_token: int = 1) -> None:
        """Writes of increasing tokens; every 4th step a call, every 8th a read."""
        token, end, step = first_token, time.monotonic() + seconds, 0
        c = self.counts
        while time.monotonic() < end:
            step += 1
            c["writes_sent"] += 1
            a = self.transact(m.CONTROL, 1, _U32.pack(token))
            if a is None:
                c["writes_timed_out"] += 1
            elif a.type == m.ACK:
                c["writes_acked"] += 1
                self.acked_tokens.append(token)
            else:
                c["writes_refused"] += 1
            token += 1
            if step % 4 == 0:
                c["calls_sent"] += 1
                arg = 1_000_000 + step
                a = self.transact(m.CONTROL, 2, _U32.pack(arg))
                if a is None:
                    c["calls_timed_out"] += 1
                elif a.type == m.RESPONSE and a.payload == _U32.pack(arg + 1):
                    c["calls_answered"] += 1
                else:
                    c["calls_wrong"] += 1
            if step % 8 == 0:
                a = self.transact(m.REQUEST, 4)
                if a is None:
                    c["reads_timed_out"] += 1
                elif a.type == m.RESPONSE and len(a.payload) == 4:
                    c["reads"] += 1
                    self.read_values.append(_U32.unpack(a.payload)[0])


def run_hub_soak(seconds: float = 30.0, seed: int = 1, workdir: Optional[str] = None,
                 faults: Optional[Faults] = None) -> Dict[str, Any]:
    """One run (see the module docstring); returns the counts :func:`check_hub_soak` judges."""
    import hubwire

    workdir = workdir or tempfile.mkdtemp(prefix="soak-hub-")
    peer = HubPeer()
    peer.start()
    link = os.path.join(workdir, f"soak-hub-link-{os.getpid()}")
    fl = FaultLink(peer.path, link, seed=seed).start()
    applied: Dict[int, int] = {}
    called: Dict[int, int] = {}
    clock: Set[int] = set()
    hub = hubwire.HubChannels("soak-hub")

    def tally(v: int) -> None:
        applied[v] = applied.get(v, 0) + 1

    def bump(v: int) -> int:
        called[v] = called.get(v, 0) + 1
        return v + 1

    def read_clock() -> int:
        v = int(time.monotonic() * 1000) & 0xFFFFFFFF
        clock.add(v)
        return v

    hub.accept("tally", tally, type="u32")
    hub.action("bump", bump, type="u32", returns="u32")
    hub.event("tick", type="u32")
    hub.provide("clock", read_clock, type="u32")
    notified = 0
    try:
        with hubwire.connect(link, cache_dir=False, timeout=20, hub=hub) as dev:
            fl.set_faults(**asdict(faults or SOAK_FAULTS))
            load = threading.Thread(target=peer.run_load, args=(seconds,), daemon=True)
            load.start()
            while load.is_alive():
                for _ in range(5):
                    notified += 1
                    dev.notify("tick", notified)
                time.sleep(0.05)
            fl.set_faults(**asdict(Faults()))  # settle on a clean link: every queued event arrives
            end = time.monotonic() + 30
            while dev.notifications_pending and time.monotonic() < end:
                time.sleep(0.05)
            stats = dev.session.stats.as_dict()
            pending = dev.notifications_pending
    finally:
        fl.stop()
        peer.close()
    return {"seconds": seconds, "seed": seed, "device": peer.counts, "hub": stats, "proxy": fl.stats(),
            "events_notified": notified, "events_pending": pending, "ticks": len(peer.ticks),
            "ticks_in_order": peer.ticks == list(range(1, len(peer.ticks) + 1)),
            "applied_twice": sum(1 for n in applied.values() if n > 1),
            "acked_not_applied": sum(1 for t in peer.acked_tokens if t not in applied),
            "applied_never_sent": sum(1 for t in applied if not 1 <= t <= peer.counts["writes_sent"]),
            "called_twice": sum(1 for n in called.values() if n > 1),
            "reads_never_produced": sum(1 for v in peer.read_values if v not in clock)}


def check_hub_soak(r: Dict[str, Any]) -> List[str]:
    """Everything wrong with a run's counts (empty: 0 lost, 0 applied twice, 0 corrupt accepted)."""
    bad = []
    for key in ("applied_twice", "acked_not_applied", "applied_never_sent", "called_twice", "reads_never_produced",
                "events_pending"):
        if r[key]:
            bad.append(f"{key}: {r[key]}")
    if r["device"]["calls_wrong"]:
        bad.append(f"calls answered with a wrong value: {r['device']['calls_wrong']}")
    if r["ticks"] != r["events_notified"] or not r["ticks_in_order"]:
        bad.append(f"hub events: {r['events_notified']} sent, {r['ticks']} delivered, in order: {r['ticks_in_order']}")
    return bad


def main(argv: Optional[List[str]] = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seconds", type=float, default=30.0)
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args(argv)
    r = run_hub_soak(args.seconds, args.seed)
    print(json.dumps(r, indent=1))
    bad = check_hub_soak(r)
    for b in bad:
        print("FAIL:", b)
    return 1 if bad else 0


if __name__ == "__main__":
    raise SystemExit(main())


# ------------------------------------------------------------------ the C++ soak sketch's hub channels


class HubTraffic:
    """The hub's side of the soak sketch's hub channels (extras/tests/Soak: ``tally``, ``bump``,
    ``tick``), counted per device boot: :meth:`close_boot` stops the sketch's requests on a clean
    link, lets every event in, and returns what both sides counted (:func:`check_hub_boots`)."""

    #: hub events waiting at most (the soak notifies one per step while fewer wait)
    PENDING = 20

    def __init__(self) -> None:
        import hubwire

        self.lock = threading.Lock()
        self.applied: Dict[int, int] = {}
        self.called: Dict[int, int] = {}
        self.notified = 0
        self.boots: List[Dict[str, Any]] = []
        self.hub = hubwire.HubChannels("soak-hub")
        self.hub.accept("tally", self._tally, type="u32")
        self.hub.action("bump", self._bump, type="u32", returns="u32")
        self.hub.event("tick", type="u32")

    def _tally(self, token: int) -> None:
        with self.lock:
            self.applied[token] = self.applied.get(token, 0) + 1

    def _bump(self, arg: int) -> int:
        with self.lock:
            self.called[arg] = self.called.get(arg, 0) + 1
        return (arg + 1) & 0xFFFFFFFF

    def start(self, dev: Any) -> None:
        """Let the sketch drive the hub's channels (a write, retried until it is acknowledged)."""

        retry(lambda: setattr(dev, "hub_load", True), "write hub_load")

    def step(self, dev: Any) -> None:
        """One more tick event, unless enough wait (during a dead link they pile up, bounded)."""
        import hubwire

        if dev.notifications_pending < self.PENDING:
            try:
                dev.notify("tick", self.notified + 1)
                self.notified += 1
            except hubwire.HubwireError:
                pass

    def close_boot(self, dev: Any) -> Dict[str, Any]:
        """On a clean link: stop the sketch's requests, wait until none is left and every event is
        in, read the sketch's counters, and settle this boot's counts."""

        retry(lambda: setattr(dev, "hub_load", False), "write hub_load")
        wait_for(lambda: retry(lambda: dev.hub_queued_now, "read hub_queued_now") == 0, 15)
        wait_for(lambda: dev.notifications_pending == 0, 15)
        names = ("tally_token", "tally_acked", "tally_failed", "bump_ok", "bump_wrong", "bump_failed", "ticks",
                 "tick_first", "tick_last", "tick_twice", "tick_gaps", "last_hub_failure", "hub_queued_now")
        device = {n: retry(lambda: getattr(dev, n), f"read {n}") for n in names}
        with self.lock:
            applied, called = self.applied, self.called
            self.applied, self.called = {}, {}
        t = device["tally_token"]
        boot = {"device": device, "notified": self.notified, "pending": dev.notifications_pending,
                "applied": len(applied), "applied_twice": sum(1 for n in applied.values() if n > 1),
                "applied_never_sent": sum(1 for k in applied if not 1 <= k <= t),
                "called": len(called), "called_twice": sum(1 for n in called.values() if n > 1),
                "called_never_sent": sum(1 for k in called if not (1 <= k <= t and k % 4 == 0))}
        self.boots.append(boot)
        return boot


def check_hub_boots(boots: List[Dict[str, Any]]) -> List[str]:
    """Exactly once both ways, per boot: nothing applied twice, nothing acked and not applied,
    nothing accepted that was never sent; ticks once each and in order across the boots."""
    bad: List[str] = []
    prev_last = 0
    for i, b in enumerate(boots):
        c, where = b["device"], f"boot {i + 1} (hub channels)"
        t, a, f = c["tally_token"], c["tally_acked"], c["tally_failed"]
        if a + f != t or c["hub_queued_now"]:
            bad.append(f"{where}: {t} tally writes, {a} acked + {f} failed, {c['hub_queued_now']} still queued")
        for key in ("applied_twice", "applied_never_sent", "called_twice", "called_never_sent", "pending"):
            if b[key]:
                bad.append(f"{where}: {key} {b[key]}")
        if not a <= b["applied"] <= a + f:
            bad.append(f"{where}: the hub applied {b['applied']} tokens, the device saw {a} acked and {f} failed")
        calls = t // 4
        if c["bump_ok"] + c["bump_wrong"] + c["bump_failed"] != calls or c["bump_wrong"]:
            bad.append(f"{where}: {calls} calls: {c['bump_ok']} right, {c['bump_wrong']} wrong, {c['bump_failed']} failed")
        if not c["bump_ok"] <= b["called"] <= c["bump_ok"] + c["bump_failed"]:
            bad.append(f"{where}: the hub ran bump for {b['called']} arguments, the device got {c['bump_ok']} answers")
        if c["tick_twice"] or c["tick_gaps"]:
            bad.append(f"{where}: ticks applied twice {c['tick_twice']}, skipped {c['tick_gaps']}")
        if c["ticks"] and (c["tick_first"] != prev_last + 1 or c["ticks"] != c["tick_last"] - c["tick_first"] + 1):
            bad.append(f"{where}: ticks {c['tick_first']}..{c['tick_last']} ({c['ticks']}) after {prev_last}")
        prev_last = c["tick_last"] or prev_last
    if boots and prev_last != boots[-1]["notified"]:
        bad.append(f"hub events: {boots[-1]['notified']} notified, the last the device got is {prev_last}")
    return bad
