"""The model-based exactly-once test: the real hub against the soak sketch (extras/tests/Soak) in
its emulator, through :class:`FaultyTransport`, playing the bursts of :class:`.model.Planner`.

    python -m hubwire.testing.faultlink.model_run --seed 7 --bursts 100     # as the bounded test
    python -m hubwire.testing.faultlink.model_run --wraps 100 --json out.json  # every kind wraps 100 times

Every kind of message in both directions: hub reads, writes of ``token`` (strictly increasing),
descriptor chunks ``J`` (compared with the descriptor), subscribes ``S``, hub events ``tick``,
large ``blob`` writes and reads, device events (``selftest`` queues bumper events), the device's own
writes and calls to the hub (``hub_load``: ``tally`` and ``bump``), missions started, followed,
cancelled and failed. Faults: byte drops, duplicated frames, bit errors, delay, stalls, a cut link
and a device reboot. Counts and claims: :mod:`.model_count`.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import random
import shutil
import sys
import tempfile
import threading
import time
from typing import Any, Callable, Dict, Iterator, List, Optional

from ...transport import SerialTransport
from ...wire import messages as m
from . import FaultyTransport, stop_process
from .model import FAULTS, HUB_KINDS, KINDS, Burst, Planner
from .model_count import FAIL_GOAL, LONG_GOAL, Boot, check_run, summary
from .soak import soak_emulator_binary, start_emulator
from .soak_hub import HubTraffic
from .soak_large import BlobLoad, intact
from .soak_load import retry, wait_for

__all__ = ["ModelRun", "run_model"]

FAULT_SETTINGS: Dict[str, Dict[str, Any]] = {"drop": {"drop": 0.01}, "dup": {"dup": 0.01}, "ber": {"ber": 1e-4},
                                             "delay": {"delay": 0.03}}
CUT_S = 1.6  # longer than the device's loss timeout (4 heartbeats of 250 ms)
STALL_MS = 300.0
FAULTY_S = 2.0  # a burst under faults stops after this long


class _Link(FaultyTransport):
    """:class:`FaultyTransport` that never hands the device's bytes to the hub inside the hub's own
    write: the hub writes under its pacer's lock, and answering those bytes (an ACK to a mission
    update) writes again, on the same thread (a deadlock once delayed bytes fell due then)."""

    def write(self, data: bytes) -> None:
        if self._loop is None or threading.get_ident() != self._loop_thread:
            super().write(data)
            return
        self._dirs["h2d"].ingest(data, time.monotonic())
        self._loop.call_soon(self._pump)


class ModelRun:
    def __init__(self, seed: int, workdir: str, binary: str, log: Callable[[str], None],
                 fault_rate: float = 0.25) -> None:
        import hubwire

        self.seed, self.binary, self.log = seed, binary, log
        self.link = os.path.join(workdir, f"model-dev-{os.getpid()}")
        self.cache = tempfile.mkdtemp(prefix="model-cache-", dir=workdir)
        self.emu = start_emulator(binary, self.link)
        self.fl = _Link(SerialTransport(self.link), seed=seed)
        self.traffic = HubTraffic()
        self.dev: Any = hubwire.connect(transport=self.fl, cache_dir=self.cache, timeout=20, hub=self.traffic.hub)
        self.hw = hubwire
        self.planner = Planner(seed, fault_rate=fault_rate)
        # chunk offsets apart: a faulty burst's length varies with timing, the plan must not
        self.offsets = random.Random(seed + 1)
        self.blobs = BlobLoad(self.dev, log)
        self.token = 0
        self.boot = Boot(1, log)
        self.boots: List[Dict[str, Any]] = []
        self.dev.on("*", lambda ev: self.boot.on_event(ev) if ev.name == "bumper" else None)
        self.blob_acked = 0  # the last blob acknowledged in this boot: a read below it is a write lost
        self.hub_last: Dict[str, int] = {}
        self.device_last: Dict[str, int] = {}
        self.kinds = {k: {"bursts": 0, "aimed": 0, "messages": 0, "faults": 0} for k in KINDS}
        self.injected = {k: 0 for k in FAULTS}
        self.raw = self.dev.descriptor.raw
        self.battery = self.dev.channel("battery").id
        self.until = math.inf  # a burst on a cut link stops when the cut ends
        self.ops = 0  # messages of the burst so far

    # ------------------------------------------------------------------ counters

    def hub_seq(self) -> int:
        """The hub's transaction counter (kept by its seq rules where the hub has them)."""
        tx = self.dev.session.core.tx
        rules = getattr(tx, "rules", None)
        return int(rules.seq if rules is not None else getattr(tx, "_seq"))

    def device_count(self) -> int:
        """Device messages the hub took (duplicates too: a new message dropped as one took a seq)."""
        s = self.dev.session.stats
        return int(s.events + s.duplicate_events + s.device_writes + s.device_calls + s.device_duplicates
                + s.mission_updates + s.duplicate_mission_updates)

    # ------------------------------------------------------------------ one burst

    def play(self, b: Burst) -> None:
        before, t0 = self.fl.stats()["faults"], time.monotonic()
        self._fault_on(b.fault)
        k = self.kinds[b.kind]
        k["bursts"] += 1
        k["aimed"] += bool(b.aimed)
        if b.fault not in ("clean", "reboot"):  # retries make a faulty burst slow: it has a time
            self.until = time.monotonic() + (CUT_S if b.fault == "cut" else FAULTY_S)
        self.ops = 0
        k["messages"] += getattr(self, "_" + b.kind)(b)
        if b.fault == "cut":
            time.sleep(max(0.0, self.until - time.monotonic()))
        self.until = math.inf
        self._fault_off(b.fault)
        k["faults"] += self.fl.stats()["faults"] - before
        self.planner.log[-1] += f" {time.monotonic() - t0:.2f} s"
        if b.kind in HUB_KINDS:
            self.hub_last[b.kind] = self.hub_seq()
        else:
            self.device_last[b.kind] = self.device_count()

    def _fault_on(self, fault: str) -> None:
        if fault != "clean":
            self.injected[fault] += 1
        if fault in FAULT_SETTINGS:
            self.fl.set_faults(**FAULT_SETTINGS[fault])
        elif fault == "stall":
            self.fl.stall(STALL_MS)
        elif fault == "cut":
            self.fl.set_faults(cut=True)
        elif fault == "reboot":
            self.reboot()

    def _fault_off(self, fault: str) -> None:
        if fault in FAULT_SETTINGS or fault == "cut":
            self.fl.set_faults(drop=0.0, dup=0.0, ber=0.0, delay=0.0, cut=False)
        if not wait_for(lambda: self.dev.state == "ready", 30):
            raise RuntimeError(f"the link did not come back after a {fault} burst")

    def _ops(self, n: int) -> Iterator[int]:
        """0 .. n-1, or fewer once a cut link's time is up."""
        for i in range(n):
            if time.monotonic() >= self.until:
                return
            self.ops += 1
            yield i

    def _guard(self, fn: Callable[[], Any]) -> Optional[Any]:
        """One hub operation; None when its fate is unknown (Timeout, LinkLost, NOT_LINKED)."""
        try:
            return fn()
        except (self.hw.Timeout, self.hw.LinkLost):
            return None
        except self.hw.NakError as e:
            if e.error != "NOT_LINKED":
                self.boot.x["naks"] += 1
                self.log(f"model: NAK {e}")
            return None

    # hub -> device ------------------------------------------------------

    def _read(self, b: Burst) -> int:
        x = self.boot.x
        for _ in self._ops(b.n):
            v = self._guard(lambda: self.dev.token)
            if v is None:
                continue
            x["reads"] += 1
            if v > self.token or (v == 0 and self.boot.last_acked):
                x["bad_reads"] += 1
            elif v < self.boot.last_acked:
                x["stale_reads"] += 1  # a write acknowledged and not applied
        return self.ops

    def _write(self, b: Burst) -> int:
        seg = self.boot.seg
        for _ in self._ops(b.n):
            self.token += 1
            seg["tokens_sent"] += 1
            seg["last_sent"] = self.token
            try:
                self.dev.token = self.token
                seg["acked"] += 1
                self.boot.last_acked = self.token
            except self.hw.Timeout:
                seg["timeouts"] += 1
            except self.hw.LinkLost:
                seg["link_lost_errors"] += 1
            except self.hw.NakError as e:
                seg["not_linked" if e.error == "NOT_LINKED" else "timeouts"] += 1
                if e.error != "NOT_LINKED":
                    self.boot.x["naks"] += 1
        return self.ops

    def _chunk(self, b: Burst) -> int:
        rng, x = self.offsets, self.boot.x
        for _ in self._ops(b.n):
            off = rng.randrange(len(self.raw))
            a = self._guard(lambda: self.dev.session.transact(m.CHUNK, 0, m.ChunkRequest(off, 28).pack()))
            if a is None:
                continue
            x["chunks"] += 1
            c = m.Chunk.unpack(a.payload)
            if c.offset != off or c.total != len(self.raw) or c.data != self.raw[off:off + len(c.data)]:
                x["chunk_corrupt"] += 1
        return self.ops

    def _subscribe(self, b: Burst) -> int:
        for i in self._ops(b.n):  # on and off again, ending off
            ms = 50 if i % 2 == 0 and i < b.n - 1 else 0
            self._guard(lambda: self.dev.session.subscribe(self.battery, ms))
        return self.ops

    def _hub_event(self, b: Burst) -> int:
        for _ in self._ops(b.n):
            self.traffic.notified += 1
            self.dev.notify("tick", self.traffic.notified)
        self._guard(lambda: self.dev.wait_notified(10 if b.fault == "clean" else 0.2))
        return self.ops

    def _blob_write(self, b: Burst) -> int:
        for _ in self._ops(b.n):
            self.blob_acked = self.blobs.token if self.blobs._write() else self.blob_acked
        return self.ops

    def _blob_read(self, b: Burst) -> int:
        for _ in self._ops(b.n):
            self._read_blob()
        return self.ops

    def _read_blob(self) -> None:
        """An intact blob written, not older than the last acknowledged one, or the boot's zeros."""
        v = self._guard(lambda: self.dev.blob)
        if v is None:
            self.blobs.read_failures += 1
            return
        self.blobs.reads += 1
        if v[0] == 0 and not self.blob_acked and not any(v[1]) and v[2] == 0:
            return
        if not intact(v) or v[0] > self.blobs.token:
            self.blobs.bad_reads += 1
            self.log(f"model: blob read back torn or never written: token {v[0]}")
        elif v[0] < self.blob_acked:
            self.boot.x["stale_reads"] += 1

    # device -> hub -------------------------------------------------------

    def _device_event(self, b: Burst) -> int:
        seg, done, end = self.boot.seg, 0, time.monotonic() + 2 + b.n * 0.01
        while done < b.n and time.monotonic() < min(end, self.until):
            q = self._guard(lambda: self.dev.selftest(min(4, b.n - done)))
            if q is None:
                seg["selftest_timeouts"] += 1
                self.boot.batches.append(-1)
                continue
            seg["events_queued"] += q
            self.boot.batches.append(q)
            done += q
            if q < min(4, b.n - done + q):
                time.sleep(0.001)  # the board's queue is full: let it send
        if b.wait:
            wait_for(lambda: len(self.boot.events) >= seg["events_queued"], 5)
        return done

    def _device_write(self, b: Burst) -> int:
        s = self.dev.session.stats
        n0 = s.device_writes + s.device_calls + s.device_duplicates
        if self._guard(lambda: self._set_hub_load(True)) is None and b.fault == "cut":
            return 0
        wait_for(lambda: s.device_writes + s.device_calls + s.device_duplicates >= n0 + b.n,
                 min(3 + b.n * 0.05, self.until - time.monotonic()))
        retry(lambda: setattr(self.dev, "hub_load", False), "write hub_load")  # (its first try may have worked)
        if b.wait:
            wait_for(lambda: retry(lambda: self.dev.hub_queued_now, "read hub_queued_now") == 0, 5)
        return int(s.device_writes + s.device_calls + s.device_duplicates - n0)

    def _set_hub_load(self, on: bool) -> bool:
        self.dev.hub_load = on
        return True

    def _mission(self, b: Burst) -> int:
        return self._start(b.n, b, cancel=False)

    def _mission_cancel(self, b: Burst) -> int:
        return self._start(FAIL_GOAL if b.n % 5 == 0 else LONG_GOAL, b, cancel=b.n % 5 != 0)

    def _start(self, goal: int, b: Burst, cancel: bool) -> int:
        ms = self.boot.missions
        if ms.jobs and b.fault == "cut":
            return 0  # the run before cannot end while the link is cut: no start now
        ms.settle()
        s = self.dev.session.stats
        n0 = s.mission_updates
        try:
            job = self.dev.start("count", goal)
        except self.hw.NakError as e:
            ms.c["busy" if e.error == "BUSY" else "corrupt"] += 1
            return 0
        except (self.hw.Timeout, self.hw.LinkLost):
            ms.c["start_unknown"] += 1
            return 0
        ms.add(job, goal, cancel)
        if cancel:
            wait_for(lambda: s.mission_updates >= n0 + b.n, 3 + b.n * 0.02)
            self._guard(lambda: job.cancel())
        if b.wait or cancel:
            ms.settle()
        return int(s.mission_updates - n0)

    # ------------------------------------------------------------------ boots

    def close_boot(self, reboot: bool) -> None:
        """On a clean link: settle this boot's counts on both ends."""
        self.fl.set_faults(drop=0.0, dup=0.0, ber=0.0, delay=0.0, cut=False)
        wait_for(lambda: self.dev.state == "ready", 30)
        for _ in range(5):
            if self.blobs.reads:
                break
            self._read_blob()
        self.blobs.close_boot()
        self.blob_acked = 0
        self.traffic.close_boot(self.dev)
        b = self.boot.close(self.dev, self.token, reboot)
        self.token = b["token"]
        self.boots.append(b)
        self.boot = Boot(self.token + 1, self.log)

    def reboot(self) -> None:
        """Settle the boot, kill the emulator (SIGKILL) and start it again on the same path."""
        self.close_boot(reboot=True)
        r0 = self.dev.session.stats.reboots
        self.emu.kill()
        self.emu.wait(5)
        self.emu = start_emulator(self.binary, self.link)
        if not wait_for(lambda: self.dev.session.stats.reboots > r0 and self.dev.state == "ready", 30):
            raise RuntimeError("the rebooted board was not found again")
        self.hub_last.clear()
        self.device_last.clear()

    def close(self) -> None:
        self.dev.close()
        stop_process(self.emu)
        shutil.rmtree(self.cache, ignore_errors=True)

    def wraps(self) -> float:
        return min(k["messages"] for k in self.kinds.values()) / 256


def run_model(*, seed: int = 1, bursts: Optional[int] = None, wraps: Optional[float] = None,
              workdir: str = "/tmp", binary: Optional[str] = None, fault_rate: float = 0.25,
              log: Callable[[str], None] = print) -> Dict[str, Any]:
    """Play bursts until ``bursts`` were played, or until every kind sent ``wraps`` x 256 messages."""
    if bursts is None and wraps is None:
        bursts = 100
    run = ModelRun(seed, workdir, binary or soak_emulator_binary(), log, fault_rate)
    t0, played, next_log = time.monotonic(), 0, time.monotonic() + 30
    try:
        while (bursts is not None and played < bursts) or (wraps is not None and run.wraps() < wraps):
            run.planner.favour = min(run.kinds, key=lambda k: run.kinds[k]["messages"])
            b = run.planner.next(run.hub_seq(), run.hub_last, run.device_count(), run.device_last)
            run.play(b)
            played += 1
            if time.monotonic() > next_log:
                next_log = time.monotonic() + 30
                log(f"model: {played} bursts, {run.wraps():.1f} wraps of the slowest kind")
        run.close_boot(reboot=False)
        r = {"seed": seed, "bursts": played, "seconds": round(time.monotonic() - t0, 1), "boots": run.boots,
             "blobs": run.blobs.boots, "hub_channels": run.traffic.boots, "faults_injected": run.injected,
             "link": run.fl.stats(), "hub_stats": run.dev.session.stats.as_dict(),
             "kinds": {k: dict(v, wraps=round(v["messages"] / 256, 2)) for k, v in run.kinds.items()},
             "plan": run.planner.log}
        r["hub_counter_wraps"] = round(sum(v["messages"] for k, v in run.kinds.items() if k in HUB_KINDS) / 256, 1)
        r["device_counter_wraps"] = round(run.device_count() / 256, 1)
        r["per_kind"] = summary(r)
        r["failures"] = check_run(r)
        return r
    finally:
        run.close()


def main(argv: Optional[List[str]] = None) -> int:
    p = argparse.ArgumentParser(prog="faultlink.model_run", description=__doc__.split("\n\n")[0])
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--bursts", type=int, default=None)
    p.add_argument("--wraps", type=float, default=None, help="run until every kind sent this many x 256 messages")
    p.add_argument("--json", default=None)
    a = p.parse_args(argv)
    r = run_model(seed=a.seed, bursts=a.bursts, wraps=a.wraps, log=lambda s: print(s, file=sys.stderr, flush=True))
    text = json.dumps(r, indent=1)
    print(text)
    if a.json:
        with open(a.json, "w") as fh:
            fh.write(text + "\n")
    for f in r["failures"]:
        print("FAIL:", f, file=sys.stderr)
    return 1 if r["failures"] else 0


if __name__ == "__main__":
    sys.exit(main())
