"""Soak of the hub's channels through the faulty link: the device writes, calls and reads the hub,
and the hub sends it events, all under the soak's faults (:data:`soak.SOAK_FAULTS`).

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

    from .soak import SOAK_FAULTS

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
