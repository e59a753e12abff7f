"""Soak: the Rover emulator behind a faulty link, hammered with writes, reads and events.

    python -m hubwire.testing.faultlink.soak --seconds 75          # the bounded CI run
    python -m hubwire.testing.faultlink.soak --frames 1000000      # the long run

(``HUBWIRE_SOAK_FRAMES`` / ``HUBWIRE_SOAK_SECONDS`` set the same from the environment, which is how
``host/tests/reliability/test_soak.py`` is switched to the long mode.)

The hub connects over a clean link (handshake and descriptor download are tested under faults
elsewhere), then every fault is switched on in both directions for the whole run:

- writes to ``left``, each with a value never written before (k/2^20, exact in f32);
- a read of ``left`` every 10 writes: the value must be one that was written (or 0, the initial and
  failsafe value) -- a corrupted frame accepted by either side would show up here;
- ``selftest(4)`` every 40 writes: the device queues up to 4 bumper events (True, False, ...) and
  returns how many it queued; the hub must deliver exactly those, in order, no duplicate.

At the end the faults are switched off and the device's ``applied`` counter is compared with the
number of writes the hub reported as acknowledged: equal, or more by at most the number of writes
that raised Timeout (those may or may not have been applied; counted separately).
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import threading
import time
from typing import Any, Callable, Dict, List, Optional, Tuple

from .. import emulator_binary
from . import FaultLink, Faults, stop_process


#: the issue's link: BER 1e-4, 1% byte drops, 0.5% duplicated frames, a garbage burst (8..64 random bytes) every 1 s
SOAK_FAULTS = Faults(ber=1e-4, drop=0.01, dup=0.005, garbage_every=1.0, garbage_len=(8, 64))


def value_for(k: int) -> float:
    """k-th written value: distinct for k < 2^21, within -1..1, exactly representable in f32."""
    return (((k * 7919) % (1 << 21)) - (1 << 20)) / float(1 << 20)


def start_emulator(binary: str, link: str) -> subprocess.Popen:
    proc = subprocess.Popen([binary, "--link", link], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            stdin=subprocess.DEVNULL)
    assert proc.stdout is not None
    line = proc.stdout.readline().decode().strip()
    if line != f"READY {link}":
        proc.kill()
        raise RuntimeError(f"emulator said {line!r}")
    return proc


def _retry(fn: Callable[[], Any], what: str, deadline: float = 30.0) -> Any:
    """Call fn until it does not raise Timeout/LinkLost (reads are idempotent)."""
    import hubwire

    end = time.monotonic() + deadline
    while True:
        try:
            return fn()
        except (hubwire.Timeout, hubwire.LinkLost):
            if time.monotonic() > end:
                raise RuntimeError(f"{what}: no answer for {deadline} s")
            time.sleep(0.05)


#: channels streamed at 100 Hz during the soak, each sample checked against what it can be
STREAMS = ("left", "right", "battery", "range")


def plausible(name: str, value: Any, written: set) -> bool:
    """What a sample of Rover's channel can be: left was written by the soak, right never was,
    battery and range hold their initial values or follow the sketch's formulas (examples/Rover/
    Rover.ino, readSensors())."""
    if name == "left":
        return value in written
    if name == "right":
        return value == 0.0
    if name == "battery":  # sags by up to 150 mV per motor at full speed
        return 7100 <= value <= 7400
    if name == "range":  # all zero until the sketch's first sensor read, 20 ms after boot; then
        # front and back (and the two sides) move by the same amount in opposite directions
        return len(value) == 4 and (tuple(value) == (0, 0, 0, 0) or (
            value[0] + value[2] == 300 and value[1] + value[3] == 300 and all(50 <= x <= 250 for x in value)))
    return True


class _Soak:
    """One soak run on a connected device: the load (writes, reads, selftests), the listeners
    (events, link losses, streams) and the counts."""

    def __init__(self, dev: Any, fl: Any, log: Callable[[str], None]) -> None:
        import hubwire

        self.hw = hubwire
        self.dev, self.fl, self.log = dev, fl, log
        self.applied0, self.failsafes0 = dev.applied, dev.failsafes
        self.events: List[Tuple[int, bool]] = []
        self.ev_cv = threading.Condition()
        self.lost: List[float] = []
        dev.on("*", self._on_event)
        dev.on("link_lost", lambda: self.lost.append(time.monotonic()))
        self.written = {0.0}
        self.k = self.acked = self.timeouts = self.link_lost_errors = self.naks = 0
        self.reads = self.bad_reads = self.read_timeouts = 0
        self.bad_values: List[float] = []
        self.st_calls = self.st_returned = self.st_timeouts = self.st_timeout_max = 0
        self.st_batches: List[int] = []
        self.last_acked: Optional[float] = None
        self.last_timed_out: List[float] = []
        self.samples = {n: 0 for n in STREAMS}
        self.bad_samples: List[Any] = []
        self.stop_streams = threading.Event()
        self.opened: List[Any] = []
        self.consumers: List[threading.Thread] = []

    def _on_event(self, ev: Any) -> None:
        with self.ev_cv:
            self.events.append((ev.seq, ev.value))
            self.ev_cv.notify_all()

    # streams (opened on the clean link): many more frames, every sample checked
    def start_streams(self) -> None:
        self.opened = [self.dev.stream(n, interval_ms=10, timeout=1.0) for n in STREAMS]
        self.consumers = [threading.Thread(target=self._consume, args=(st, st.channel.name), daemon=True)
                          for st in self.opened]
        for t in self.consumers:
            t.start()

    def _consume(self, st: Any, name: str) -> None:
        while not self.stop_streams.is_set():
            try:
                v = next(st)
            except self.hw.Timeout:
                continue
            except (self.hw.LinkLost, StopIteration):
                return
            self.samples[name] += 1
            if not plausible(name, v, self.written):
                self.bad_samples.append((name, v))

    def stop_streams_now(self) -> None:
        self.stop_streams.set()
        for t in self.consumers:
            t.join(5)
        for st in self.opened:
            try:
                st.close()  # unsubscribe; on a faulty link this may time out, dev.close() ends it anyway
            except self.hw.HubwireError:
                pass

    # the load
    def step(self) -> None:
        """One write with a value never written before, a read every 10, a selftest every 40."""
        hw, dev = self.hw, self.dev
        self.k += 1
        v = value_for(self.k)
        self.written.add(v)
        try:
            dev.left = v
            self.acked += 1
            self.last_acked = v
            self.last_timed_out = []
        except hw.Timeout:
            self.timeouts += 1
            self.last_timed_out.append(v)
        except hw.LinkLost:
            self.link_lost_errors += 1
            time.sleep(0.05)
            return
        except hw.NakError as e:  # a corrupted frame that passed the CRC would show here
            self.naks += 1
            self.log(f"soak: NAK on write {self.k}: {e}")
        if self.k % 10 == 0:
            self._read()
        if self.k % 40 == 0:
            self._selftest()

    def _read(self) -> None:
        try:
            got = self.dev.left
            self.reads += 1
            if got not in self.written:
                self.bad_reads += 1
                self.bad_values.append(got)
        except (self.hw.Timeout, self.hw.LinkLost):
            self.read_timeouts += 1

    def _selftest(self) -> None:
        self.st_calls += 1
        try:
            q = self.dev.selftest(4)
            self.st_returned += q
            self.st_batches.append(q)
        except self.hw.Timeout:
            self.st_timeouts += 1
            self.st_timeout_max += 4
            self.st_batches.append(-1)
        except self.hw.LinkLost:
            self.link_lost_errors += 1

    def run(self, seconds: Optional[float], frames: Optional[int]) -> Tuple[float, Dict[str, Any], int]:
        """The load until ``seconds`` passed or ``frames`` went through; (elapsed, proxy stats, f0)."""
        t0 = time.monotonic()
        f0 = self.fl.stats()["frames"]
        next_report = t0 + 10
        while True:
            now = time.monotonic()
            if seconds is not None and now - t0 >= seconds:
                break
            if frames is not None and self.fl.stats()["frames"] - f0 >= frames:
                break
            if now >= next_report:
                st = self.fl.stats()
                self.log(f"soak: {now - t0:.0f} s, {st['frames'] - f0} frames, {st['faults']} faults, "
                         f"{self.acked} acked, {self.timeouts} timeouts, {len(self.events)} events")
                next_report = now + 10
            self.step()
        return time.monotonic() - t0, self.fl.stats(), f0

    def settle(self) -> Tuple[List[Tuple[int, bool]], int, int, float]:
        """On the clean link: every queued event in, then the device's counters."""
        lo = self.st_returned
        with self.ev_cv:
            self.ev_cv.wait_for(lambda: len(self.events) >= lo, 15)
        time.sleep(0.5)  # retried events still in flight (there should be none beyond the queued ones)
        applied = _retry(lambda: self.dev.applied, "read applied") - self.applied0
        failsafes = _retry(lambda: self.dev.failsafes, "read failsafes") - self.failsafes0
        final_left = _retry(lambda: self.dev.left, "read left")
        with self.ev_cv:
            evs = list(self.events)
        return evs, applied, failsafes, final_left

    def result(self, elapsed: float, during: Dict[str, Any], f0: int, frames: Optional[int], seed: int) -> Dict[str, Any]:
        evs, applied, failsafes, final_left = self.settle()
        s, dev = self.dev.session, self.dev
        seq_steps = [(b[0] - a[0]) & 0xFF for a, b in zip(evs, evs[1:])]
        expected_values = [i % 2 == 0 for q in self.st_batches if q >= 0 for i in range(q)]
        health = s.health()
        stats = s.stats.as_dict()
        return {
            "mode": "frames" if frames is not None else "seconds", "seconds": round(elapsed, 1), "seed": seed,
            "faults": self.fl.config()["h2d"],
            "proxy": {"frames": during["frames"] - f0, "faults": during["faults"], "h2d": during["h2d"], "d2h": during["d2h"]},
            "writes": self.k, "acked": self.acked, "timeouts": self.timeouts, "naks": self.naks,
            "link_lost_errors": self.link_lost_errors, "applied": applied, "applied_minus_acked": applied - self.acked,
            "reads": self.reads, "bad_reads": self.bad_reads, "bad_values": self.bad_values[:10],
            "read_timeouts": self.read_timeouts, "selftest_calls": self.st_calls, "events_queued": self.st_returned,
            "selftest_timeouts": self.st_timeouts, "events_delivered": len(evs),
            "event_seq_gaps_or_dups": sum(1 for d in seq_steps if d != 1),
            "event_order_ok": self.st_timeouts > 0 or [v for _, v in evs] == expected_values,
            "samples": dict(self.samples), "bad_samples": len(self.bad_samples),
            "bad_sample_values": self.bad_samples[:10], "failsafes": failsafes, "link_lost_callbacks": len(self.lost),
            "reboots": s.stats.reboots, "state": dev.state, "final_left": final_left, "last_acked": self.last_acked,
            "last_timed_out": self.last_timed_out,
            "hub_stats": {k2: stats[k2] for k2 in ("retries", "events", "duplicate_events", "unmatched_answers",
                                                   "link_lost", "rehandshakes", "not_linked", "unknown_frames")},
            "hub_rx_counters": health.hub_counters, "device_rx_counters": health.device_counters,
        }


def run_soak(*, seconds: Optional[float] = None, frames: Optional[int] = None, seed: int = 1,
             faults: Faults = SOAK_FAULTS, workdir: str = "/tmp", binary: Optional[str] = None,
             streams: bool = True, log: Callable[[str], None] = print) -> Dict[str, Any]:
    """Run the soak until ``seconds`` pass or ``frames`` went through the proxy; return the counts."""
    import hubwire

    if seconds is None and frames is None:
        seconds = 75.0
    binary = binary or emulator_binary()
    dev_link = os.path.join(workdir, f"soak-rover-{os.getpid()}")
    hub_link = os.path.join(workdir, f"soak-hub-{os.getpid()}")
    emu = start_emulator(binary, dev_link)
    fl = FaultLink(dev_link, hub_link, seed=seed)
    fl.start()
    dev = None
    try:
        dev = hubwire.connect(hub_link, cache_dir=False, timeout=10)
        soak = _Soak(dev, fl, log)
        if streams:
            soak.start_streams()
        fl.set_faults(**{k: getattr(faults, k) for k in ("ber", "drop", "dup", "truncate", "garbage_every",
                                                        "garbage_len", "delay", "stall_every", "stall_ms")})
        elapsed, during, f0 = soak.run(seconds, frames)
        soak.stop_streams_now()
        # accounting on a clean link
        fl.set_faults(ber=0.0, drop=0.0, dup=0.0, truncate=0.0, garbage_every=0.0, delay=0.0, stall_every=0.0)
        return soak.result(elapsed, during, f0, frames, seed)
    finally:
        if dev is not None:
            dev.close()
        fl.stop()
        stop_process(emu)


def check(r: Dict[str, Any]) -> List[str]:
    """The soak's claims; returns the violated ones (empty: all hold)."""
    bad = []
    if r["bad_reads"]:
        bad.append(f"{r['bad_reads']} reads returned values never written: {r['bad_values']}")
    if r.get("bad_samples"):
        bad.append(f"{r['bad_samples']} streamed samples were impossible values: {r['bad_sample_values']}")
    if r["naks"]:
        bad.append(f"{r['naks']} writes were NAKed (a corrupted frame accepted as valid?)")
    if not r["acked"] <= r["applied"] <= r["acked"] + r["timeouts"]:
        bad.append(f"applied {r['applied']} is not within acked {r['acked']} .. acked + timeouts "
                   f"{r['acked'] + r['timeouts']}")
    lo, hi = r["events_queued"], r["events_queued"] + 4 * r["selftest_timeouts"]
    if not lo <= r["events_delivered"] <= hi:
        bad.append(f"{r['events_delivered']} events delivered, expected {lo}..{hi}")
    if r["event_seq_gaps_or_dups"]:
        bad.append(f"{r['event_seq_gaps_or_dups']} event seq steps were not +1 (lost or duplicated)")
    if not r["event_order_ok"]:
        bad.append("event values are not the selftest patterns in order")
    if r["reboots"] or r["state"] != "ready":
        bad.append(f"session ended {r['state']} after {r['reboots']} reboots")
    if r["failsafes"] == 0 and r["last_timed_out"] == [] and r["last_acked"] is not None \
            and r["final_left"] != r["last_acked"]:
        bad.append(f"left is {r['final_left']}, last acked write was {r['last_acked']}")
    return bad


def main(argv: Optional[List[str]] = None) -> int:
    p = argparse.ArgumentParser(prog="faultlink.soak", description=__doc__.split("\n\n")[0])
    p.add_argument("--seconds", type=float, default=None, help="run this long (default 75 unless --frames)")
    p.add_argument("--frames", type=int, default=None, help="run until this many frames went through the proxy")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--json", default=None, help="also write the result here")
    a = p.parse_args(argv)
    seconds = a.seconds if a.seconds is not None else (
        float(os.environ["HUBWIRE_SOAK_SECONDS"]) if os.environ.get("HUBWIRE_SOAK_SECONDS") else None)
    frames = a.frames if a.frames is not None else (
        int(os.environ["HUBWIRE_SOAK_FRAMES"]) if os.environ.get("HUBWIRE_SOAK_FRAMES") else None)
    r = run_soak(seconds=seconds, frames=frames, seed=a.seed, log=lambda s: print(s, file=sys.stderr, flush=True))
    text = json.dumps(r, indent=1)
    print(text)
    if a.json:
        with open(a.json, "w") as fh:
            fh.write(text + "\n")
    bad = check(r)
    for b in bad:
        print("FAIL:", b, file=sys.stderr)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
