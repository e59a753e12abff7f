"""The soak's load on a connected device (the sketch extras/tests/Soak) and its per-boot counts.

Each step writes ``token`` with the next of a strictly increasing series; every 10 steps it writes
``left`` with a value never written before and reads it back; every 40 it calls ``selftest(4)``.
A *segment* is one device boot: its tokens, the writes the hub saw acknowledged or not, and the
events delivered; :meth:`Load.close_segment` settles it on a clean link and reads the device's own
counters (``tokens_applied``, ``twice``, ``gaps``, ``first_token``, ``last_token``).
"""
from __future__ import annotations

import threading
import time
from typing import Any, Callable, Dict, List, Optional, Set, Tuple

#: channels streamed at 100 Hz, each sample checked against what it can be
STREAMS = ("left", "right", "battery", "range")


def value_for(k: int) -> float:
    """k-th written value: distinct for k < 2^21, within -1..1, exactly representable in f32."""
    return (((k * 7919) % (1 << 21)) - (1 << 20)) / float(1 << 20)


def plausible(name: str, value: Any, written: Set[float]) -> bool:
    """What a sample can be (extras/tests/Soak/Soak.ino, readSensors()): left was written by the
    soak (or is the failsafe 0), right never was, battery and range follow the sketch's formulas."""
    if name == "left":
        return value in written
    if name == "right":
        return bool(value == 0.0)
    if name == "battery":
        return bool(7200 <= value <= 7400)
    if name == "range":  # all zero until the sketch's first sensor read, 20 ms after boot
        return len(value) == 4 and (tuple(value) == (0, 0, 0, 0)
                                    or all(100 + 50 * i <= x < 120 + 50 * i for i, x in enumerate(value)))
    return True


def retry(fn: Callable[[], Any], what: str, deadline: float = 30.0) -> Any:
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


class Segment:
    """What the hub did during one device boot."""

    def __init__(self, first_token: int) -> None:
        self.first_sent = first_token
        self.sent = self.acked = self.timeouts = self.lost = self.not_linked = 0
        self.events: List[Tuple[int, bool]] = []
        self.st_returned = self.st_timeouts = 0
        self.st_batches: List[int] = []


class Load:
    """The load, the listeners (events, link losses, streams) and the counts of one soak run."""

    def __init__(self, dev: Any, log: Callable[[str], None]) -> None:
        import hubwire

        self.hw, self.dev, self.log = hubwire, dev, log
        self.ev_cv = threading.Condition()
        self.lost: List[float] = []
        self.reconnects: List[float] = []
        dev.on("*", self._on_event)
        dev.on("link_lost", lambda: self.lost.append(time.monotonic()))
        dev.on("reconnect", lambda *_: self.reconnects.append(time.monotonic()))
        self.written = {0.0}
        self.token = self.k = self.naks = 0
        self.reads = self.bad_reads = self.read_timeouts = 0
        self.bad_values: List[float] = []
        self.seg = Segment(1)
        self.segments: List[Dict[str, Any]] = []
        self.samples = {n: 0 for n in STREAMS}
        self.bad_samples: List[Any] = []
        self._stop_streams = threading.Event()
        self.opened: List[Any] = []
        self.consumers: List[threading.Thread] = []

    def _on_event(self, ev: Any) -> None:
        with self.ev_cv:
            self.seg.events.append((ev.seq, ev.value))
            self.ev_cv.notify_all()

    # streams: many more frames, every sample checked
    def start_streams(self) -> None:
        self._stop_streams.clear()
        self.opened = []
        for n in STREAMS:  # one by one: if a subscribe fails, those made are still closed
            self.opened.append(self.dev.stream(n, interval_ms=10, timeout=1.0))
        self.consumers = [threading.Thread(target=self._consume, args=(st, st.channel.name), daemon=True)
                          for st in self.opened]
        for t in self.consumers:
            t.start()

    def _consume(self, st: Any, name: str) -> None:
        while not self._stop_streams.is_set():
            try:
                v = next(st)
            except self.hw.Timeout:
                continue
            except (self.hw.LinkLost, StopIteration):
                return
            self.samples[name] += 1
            if not plausible(name, v, self.written):
                self.bad_samples.append((name, v))

    def stop_streams(self) -> None:
        self._stop_streams.set()
        for t in self.consumers:
            t.join(5)
        for st in self.opened:
            try:
                st.close()  # unsubscribe; on a faulty link this may time out, dev.close() ends it anyway
            except self.hw.HubwireError:
                pass
        self.opened, self.consumers = [], []

    # the load
    def step(self) -> None:
        """One token write; a write and read of ``left`` every 10 steps, a selftest every 40."""
        hw, seg = self.hw, self.seg
        self.k += 1
        self.token += 1
        seg.sent += 1
        try:
            self.dev.token = self.token
            seg.acked += 1
        except hw.Timeout:
            seg.timeouts += 1
        except hw.LinkLost:
            seg.lost += 1
            time.sleep(0.05)
            return
        except hw.NakError as e:
            if e.error == "NOT_LINKED":  # the device had dropped the link: refused, not applied
                seg.not_linked += 1
                return
            self.naks += 1  # a corrupted frame that passed the CRC would show here
            self.log(f"soak: NAK on token {self.token}: {e}")
        if self.k % 10 == 0:
            self._write_and_read_left()
        if self.k % 40 == 0:
            self._selftest()

    def _write_and_read_left(self) -> None:
        v = value_for(self.k)
        self.written.add(v)
        try:
            self.dev.left = v
            got = self.dev.left
            self.reads += 1
            if got not in self.written:
                self.bad_reads += 1
                self.bad_values.append(got)
        except (self.hw.Timeout, self.hw.LinkLost):
            self.read_timeouts += 1
        except self.hw.NakError as e:
            if e.error != "NOT_LINKED":
                self.naks += 1
                self.log(f"soak: NAK on left: {e}")

    def _selftest(self) -> None:
        seg = self.seg
        try:
            q = self.dev.selftest(4)
            seg.st_returned += q
            seg.st_batches.append(q)
        except (self.hw.Timeout, self.hw.LinkLost, self.hw.NakError):  # run or not: up to 4 events more
            seg.st_timeouts += 1
            seg.st_batches.append(-1)

    def counters(self) -> Dict[str, int]:
        names = ("tokens_applied", "twice", "gaps", "first_token", "last_token", "failsafes")
        return {n: retry(lambda: getattr(self.dev, n), f"read {n}") for n in names}

    def close_segment(self, final: bool) -> Dict[str, Any]:
        """On the clean link: one last acked token, every queued event in, the device's counters."""
        seg = self.seg
        while True:  # the link is clean; should it still drop, the next token is the last one
            self.token += 1
            seg.sent += 1
            wait_for(lambda: self.dev.state == "ready", 30)
            try:
                self.dev.token = self.token
                seg.acked += 1
                break
            except self.hw.Timeout:
                seg.timeouts += 1
            except self.hw.LinkLost:
                seg.lost += 1
        with self.ev_cv:
            self.ev_cv.wait_for(lambda: len(seg.events) >= seg.st_returned, 15)
        time.sleep(0.5)  # retried events still in flight (there should be none beyond the queued ones)
        c = self.counters()
        with self.ev_cv:
            evs = list(seg.events)
        steps = [(b[0] - a[0]) & 0xFF for a, b in zip(evs, evs[1:])]
        expected = [i % 2 == 0 for q in seg.st_batches if q >= 0 for i in range(q)]
        r = {"tokens_sent": seg.sent, "first_sent": seg.first_sent, "last_sent": self.token,
             "acked": seg.acked, "timeouts": seg.timeouts, "link_lost_errors": seg.lost,
             "not_linked": seg.not_linked,
             "device": c, "events_queued": seg.st_returned, "selftest_timeouts": seg.st_timeouts,
             "events_delivered": len(evs), "event_seq_repeated": sum(1 for d in steps if d == 0),
             "event_order_ok": seg.st_timeouts > 0 or [v for _, v in evs] == expected}
        self.segments.append(r)
        if not final:
            self.seg = Segment(self.token + 1)
        return r


def check_segment(i: int, s: Dict[str, Any]) -> List[str]:
    """Exactly once, counted on the device: nothing applied twice, applied + never applied = sent,
    and what was never applied is at most the writes the hub did not see acknowledged."""
    bad, c = [], s["device"]
    where = f"boot {i + 1}"
    if c["twice"]:
        bad.append(f"{where}: {c['twice']} token writes were applied twice (or out of order)")
    never = c["gaps"] + (c["first_token"] - s["first_sent"])
    if c["tokens_applied"] + never != s["tokens_sent"]:
        bad.append(f"{where}: applied {c['tokens_applied']} + never applied {never} != sent {s['tokens_sent']}")
    if c["last_token"] != s["last_sent"]:
        bad.append(f"{where}: the device's last token is {c['last_token']}, the hub's {s['last_sent']}")
    uncertain = s["timeouts"] + s["link_lost_errors"] + s.get("not_linked", 0)
    if not s["acked"] <= c["tokens_applied"] <= s["acked"] + uncertain or never > uncertain:
        bad.append(f"{where}: applied {c['tokens_applied']}, never applied {never}: not within acked "
                   f"{s['acked']} .. acked + unacknowledged {uncertain}")
    lo, hi = s["events_queued"], s["events_queued"] + 4 * s["selftest_timeouts"]
    if not lo <= s["events_delivered"] <= hi:
        bad.append(f"{where}: {s['events_delivered']} events delivered, expected {lo}..{hi}")
    # the device numbers its events and its own requests to the hub from one counter, so events step
    # by 1 or more (any step, as the counter wraps); the same seq twice running is a duplicate
    # delivered, a lost event shows in the count and the pattern
    if s["event_seq_repeated"]:
        bad.append(f"{where}: {s['event_seq_repeated']} events repeated the seq of the one before")
    if not s["event_order_ok"]:
        bad.append(f"{where}: event values are not the selftest patterns in order")
    return bad


def wait_for(cond: Callable[[], bool], seconds: float) -> bool:
    end = time.monotonic() + seconds
    while not cond():
        if time.monotonic() > end:
            return False
        time.sleep(0.02)
    return True


def first_after(times: List[float], t: float) -> Optional[float]:
    later = [x for x in times if x >= t]
    return min(later) if later else None
