"""Soak: the soak sketch (extras/tests/Soak) in the emulator behind a faulty link, hammered with
writes, reads and events, through a cold discovery, a dead link and a device reboot.

    python -m hubwire.testing.faultlink.soak --seconds 75          # the bounded CI run
    python -m hubwire.testing.faultlink.soak --frames 1000000      # the long run

(``HUBWIRE_SOAK_FRAMES`` / ``HUBWIRE_SOAK_SECONDS`` set the same from the environment, which is how
``host/tests/reliability/test_soak.py`` is switched to the long mode.)

Every fault is on in both directions from the start, discovery included (a fresh cache directory,
so the descriptor is downloaded through the faults). The load (:mod:`.soak_load`) writes strictly
increasing tokens which the sketch counts per write, so a write applied twice is seen on the
device itself. The run is cut in three by two events:

- at half the run, a **dead link**: both directions cut for 5 loss timeouts; the device's failsafe
  must fire (``left`` reads 0 afterwards), the hub must declare the link lost once and restore it;
- at three quarters, a **device reboot**: the emulator is killed and started again; the hub must see
  the new nonce, take the descriptor from its cache (no second download), and events and writes
  must go on, each boot's counts checked on their own.

Streams (``left``, ``right``, ``battery``, ``range`` at 100 Hz, every sample checked) are opened on a
clean moment of the link and closed before each of the two events.

Large values run all along too (:class:`.soak_large.BlobLoad`): the sketch's 40-byte ``blob``
written and read back in fragments, counted per boot: 0 lost, 0 duplicated, 0 corrupt.
Missions run all along as well (:class:`.soak_missions.MissionTraffic`): runs started, followed,
sometimes cancelled, one cut short by the reboot; none lost, duplicated or corrupt.

The other direction runs all along (:class:`.soak_hub.HubTraffic`): the sketch writes tokens into
the hub's ``tally`` and calls its ``bump``, the hub sends ``tick`` events; each boot's counts are
settled on the clean link with the rest (:func:`.soak_hub.check_hub_boots`).
"""
from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import asdict
from typing import Any, Callable, Dict, List, Optional

from .. import repo_root
from . import FaultLink, Faults, stop_process
from .faults import SOAK_FAULTS
from .soak_hub import HubTraffic, check_hub_boots
from .soak_large import BlobLoad, check_blob_boot
from .soak_missions import MissionTraffic, check_missions
from .soak_load import Load, check_segment, first_after, retry, value_for, wait_for

__all__ = ["SOAK_FAULTS", "run_soak", "check", "value_for", "soak_emulator_binary"]

#: the dead link lasts this many of the device's loss timeouts (4 heartbeats of 250 ms)
DEAD_TIMEOUTS = 5
LOSS_TIMEOUT_S = 1.0
CLEAN = Faults()


def soak_emulator_binary() -> str:
    """``$HUBWIRE_SOAK_EMULATOR``, else the one ``make emulator`` builds in the source tree."""
    return os.environ.get("HUBWIRE_SOAK_EMULATOR") or os.path.join(
        repo_root() or os.getcwd(), "build", "emulator", "hubwire-soak-emulator")


def start_emulator(binary: str, link: str) -> "subprocess.Popen[bytes]":
    proc = subprocess.Popen([binary, "--link", link], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            stdin=subprocess.DEVNULL)
    assert proc.stdout is not None
    line = proc.stdout.readline().decode().strip()
    if line != f"READY {link}":
        proc.kill()
        raise RuntimeError(f"emulator said {line!r}")
    return proc


class _Run:
    """One soak run: the emulator, the proxy, the hub's device, the load and the events of the run."""

    def __init__(self, binary: str, workdir: str, seed: int, faults: Faults, streams: bool,
                 log: Callable[[str], None]) -> None:
        self.binary, self.faults, self.streams, self.log = binary, faults, streams, log
        self.dev_link = os.path.join(workdir, f"soak-dev-{os.getpid()}")
        self.hub_link = os.path.join(workdir, f"soak-hub-{os.getpid()}")
        self.cache = tempfile.mkdtemp(prefix="soak-cache-", dir=workdir)
        self.emu = start_emulator(binary, self.dev_link)
        self.fl = FaultLink(self.dev_link, self.hub_link, seed=seed).start()
        self.dev: Any = None
        self.load: Any = None
        self.blobs: Any = None
        self.traffic = HubTraffic()
        self.missions = MissionTraffic(log)
        self.report: Dict[str, Any] = {}

    def set_faults(self, f: Faults) -> None:
        self.fl.set_faults(**asdict(f))

    def connect(self) -> None:
        """Cold discovery through the faults: handshake and the whole descriptor download."""
        import hubwire

        self.set_faults(self.faults)
        t = time.monotonic()
        self.dev = hubwire.connect(self.hub_link, cache_dir=self.cache, timeout=20, hub=self.traffic.hub)
        self.report["connect"] = {"seconds": round(time.monotonic() - t, 2),
                                  "downloads": self.dev.session.stats.downloads,
                                  "chunk_requests": self.dev.session.stats.chunk_requests}
        self.load = Load(self.dev, self.log)
        self.blobs = BlobLoad(self.dev, self.log)
        self.traffic.start(self.dev)
        self.missions.start(self.dev)

    def open_streams(self) -> None:
        """Subscribe on a clean moment (subscribing is not what is tested here), again until it
        works: on a loaded machine even a clean link can time out."""
        import hubwire

        self.set_faults(CLEAN)
        end = time.monotonic() + 60
        while self.streams:
            wait_for(lambda: self.dev.state == "ready", 30)
            try:
                self.load.start_streams()
                break
            except hubwire.HubwireError:
                self.load.stop_streams()
                if time.monotonic() > end:
                    raise
        self.set_faults(self.faults)

    def until(self, done: Callable[[], float], fraction: float) -> None:
        next_report = time.monotonic() + 10
        while done() < fraction:
            if time.monotonic() >= next_report:
                st = self.fl.stats()
                self.log(f"soak: {done() * 100:.0f} %, {st['frames']} frames, {st['faults']} faults, "
                         f"token {self.load.token}, {len(self.load.lost)} link losses")
                next_report = time.monotonic() + 10
            self.load.step()
            self.blobs.step()
            self.traffic.step(self.dev)
            self.missions.step(self.dev)
            self._revive_streams()

    def _revive_streams(self) -> None:
        """A link loss outside the planned events ends the subscriptions: open them again."""
        import hubwire

        load = self.load
        alive = load.consumers and all(t.is_alive() for t in load.consumers)
        if not self.streams or alive or self.dev.state != "ready":
            return
        load.stop_streams()
        try:
            load.start_streams()
            self.report["stream_restarts"] = self.report.get("stream_restarts", 0) + 1
        except hubwire.HubwireError:  # the subscribe itself lost on the noisy link: next step
            load.stop_streams()

    def dead_link(self) -> None:
        """Both directions cut for DEAD_TIMEOUTS loss timeouts, the load going on (it fails fast)."""
        load, dev = self.load, self.dev
        load.stop_streams()
        fs0 = retry(lambda: dev.failsafes, "read failsafes")
        lost0 = len(load.lost)
        t = time.monotonic()
        self.set_faults(Faults(cut=True))
        while time.monotonic() - t < DEAD_TIMEOUTS * LOSS_TIMEOUT_S:
            load.step()
            self.blobs.step()
            self.traffic.step(dev)
            self.missions.step(dev)
        lost = load.lost[lost0:]
        self.set_faults(self.faults)
        t_back = time.monotonic()
        restored = wait_for(lambda: dev.state == "ready", 20)
        left = retry(lambda: dev.left, "read left")  # before any new write: the failsafe value
        first = first_after(lost, t)
        self.report["dead_link"] = {
            "seconds": round(t_back - t, 2), "hub_losses": len(lost), "restored": restored,
            "restored_after_s": round(time.monotonic() - t_back, 2),
            "hub_lost_after_s": None if first is None else round(first - t, 2),
            "failsafes": retry(lambda: dev.failsafes, "read failsafes") - fs0, "left_after": left}
        self.open_streams()

    def reboot(self) -> None:
        """Kill the emulator (SIGKILL) and start it again on the same path, faults on."""
        load, dev = self.load, self.dev
        load.stop_streams()
        self.set_faults(CLEAN)
        load.close_segment(final=False)
        self.blobs.close_boot()
        self.traffic.close_boot(dev)
        self.missions.close_boot(dev)
        self.set_faults(self.faults)
        cut = self.missions.cut_by_reboot(dev)  # a run going when the board dies: MissionLost
        r0, dl0 = len(load.reconnects), dev.session.stats.downloads
        self.emu.kill()
        self.emu.wait(5)
        t = time.monotonic()
        self.emu = start_emulator(self.binary, self.dev_link)
        ok = wait_for(lambda: len(load.reconnects) > r0 and dev.state == "ready", 30)
        self.report["reboot"] = {"reconnected": ok, "seconds": round(time.monotonic() - t, 2),
                                 "downloads": dev.session.stats.downloads - dl0,
                                 "cache_hits": dev.session.stats.cache_hits}
        self.missions.ended_by_reboot(cut)
        self.traffic.start(dev)
        self.missions.start(dev)
        self.open_streams()

    def close(self) -> None:
        if self.dev is not None:
            self.dev.close()
        self.fl.stop()
        stop_process(self.emu)
        shutil.rmtree(self.cache, ignore_errors=True)


def run_soak(*, seconds: Optional[float] = None, frames: Optional[int] = None, seed: int = 1,
             faults: Faults = SOAK_FAULTS, workdir: str = "/tmp", binary: Optional[str] = None,
             streams: bool = True, log: Callable[[str], None] = print) -> Dict[str, Any]:
    """Run the soak until ``seconds`` pass or ``frames`` went through the proxy; return the counts."""
    if seconds is None and frames is None:
        seconds = 75.0
    run = _Run(binary or soak_emulator_binary(), workdir, seed, faults, streams, log)
    try:
        t0 = time.monotonic()
        run.connect()
        f0 = run.fl.stats()["frames"]
        if frames is not None:
            n = frames
            done = lambda: (run.fl.stats()["frames"] - f0) / n  # noqa: E731
        else:
            total = float(seconds or 0)
            done = lambda: (time.monotonic() - t0) / total  # noqa: E731
        run.open_streams()
        run.until(done, 0.5)
        run.dead_link()
        run.until(done, 0.75)
        run.reboot()
        run.until(done, 1.0)
        elapsed, during = time.monotonic() - t0, run.fl.stats()
        run.load.stop_streams()
        run.set_faults(CLEAN)  # accounting on a clean link
        run.load.close_segment(final=True)
        run.blobs.close_boot()
        run.traffic.close_boot(run.dev)
        run.missions.close_boot(run.dev)
        return _result(run, elapsed, during, f0, frames, seed)
    finally:
        run.close()


def _result(run: _Run, elapsed: float, during: Dict[str, Any], f0: int, frames: Optional[int],
            seed: int) -> Dict[str, Any]:
    load, s = run.load, run.dev.session
    health, stats = s.health(), s.stats.as_dict()
    segs = load.segments
    return {
        "mode": "frames" if frames is not None else "seconds", "seconds": round(elapsed, 1), "seed": seed,
        "faults": asdict(run.faults),
        "proxy": {"frames": during["frames"] - f0, "faults": during["faults"], "h2d": during["h2d"],
                  "d2h": during["d2h"]},
        **run.report,
        "boots": segs,
        "tokens_sent": sum(x["tokens_sent"] for x in segs), "acked": sum(x["acked"] for x in segs),
        "timeouts": sum(x["timeouts"] for x in segs), "link_lost_errors": sum(x["link_lost_errors"] for x in segs),
        "applied": sum(x["device"]["tokens_applied"] for x in segs),
        "applied_twice": sum(x["device"]["twice"] for x in segs), "naks": load.naks,
        "reads": load.reads, "bad_reads": load.bad_reads, "bad_values": load.bad_values[:10],
        "read_timeouts": load.read_timeouts,
        "events_queued": sum(x["events_queued"] for x in segs),
        "events_delivered": sum(x["events_delivered"] for x in segs),
        "samples": dict(load.samples), "bad_samples": len(load.bad_samples),
        "bad_sample_values": load.bad_samples[:10], "link_lost_callbacks": len(load.lost),
        "reboots": s.stats.reboots, "state": run.dev.state,
        "hub_stats": {k: stats[k] for k in ("retries", "events", "duplicate_events", "unmatched_answers", "link_lost",
                                            "link_restored", "rehandshakes", "not_linked", "unknown_frames",
                                            "downloads", "cache_hits")},
        "hub_rx_counters": health.hub_counters, "device_rx_counters": health.device_counters,
        "blobs": {"boots": run.blobs.boots, **{k: sum(b[k] for b in run.blobs.boots)
                                               for k in ("sent", "acked", "applied", "reads", "lost", "duplicated",
                                                         "corrupt")},
                  "reassembled": s.core.link.reassembler.completed,
                  "fragments_dropped": s.core.link.reassembler.refused},
        "hub_channels": {"boots": run.traffic.boots, "ticks_notified": run.traffic.notified,
                         **{k: stats[k] for k in ("device_writes", "device_calls", "device_duplicates",
                                                  "hub_events_delivered", "hub_event_retries", "binds_sent")}},
        "missions": run.missions.report(),
    }


def check(r: Dict[str, Any]) -> List[str]:
    """The soak's claims; returns the violated ones (empty: all hold)."""
    bad = []
    if r["bad_reads"]:
        bad.append(f"{r['bad_reads']} reads returned values never written: {r['bad_values']}")
    if r["bad_samples"]:
        bad.append(f"{r['bad_samples']} streamed samples were impossible values: {r['bad_sample_values']}")
    if r["naks"]:
        bad.append(f"{r['naks']} writes were NAKed (a corrupted frame accepted as valid?)")
    if r["connect"]["downloads"] != 1:
        bad.append(f"cold connect: {r['connect']['downloads']} descriptor downloads, expected 1")
    if len(r["boots"]) != 2:
        bad.append(f"{len(r['boots'])} boots accounted, expected 2")
    for i, seg in enumerate(r["boots"]):
        bad += check_segment(i, seg)
    d = r["dead_link"]
    if d["hub_losses"] != 1 or not d["restored"]:
        bad.append(f"dead link: the hub declared {d['hub_losses']} losses (expected 1), restored: {d['restored']}")
    if d["failsafes"] < 1 or d["left_after"] != 0.0:
        bad.append(f"dead link: {d['failsafes']} failsafes on the device, left {d['left_after']} (expected >= 1, 0.0)")
    b = r["reboot"]
    if not b["reconnected"] or b["downloads"] != 0 or r["reboots"] != 1:
        bad.append(f"reboot: reconnected {b['reconnected']}, {r['reboots']} reboots seen, "
                   f"{b['downloads']} downloads (expected True, 1, 0: the descriptor comes from the cache)")
    if r["state"] != "ready":
        bad.append(f"session ended {r['state']}")
    if len(r["hub_channels"]["boots"]) != 2:
        bad.append(f"{len(r['hub_channels']['boots'])} boots of hub channel traffic accounted, expected 2")
    bad += check_hub_boots(r["hub_channels"]["boots"])
    if len(r["blobs"]["boots"]) != 2:
        bad.append(f"{len(r['blobs']['boots'])} boots of large values accounted, expected 2")
    for i, b in enumerate(r["blobs"]["boots"]):
        bad += check_blob_boot(i, b)
    bad += check_missions(r.get("missions"))
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
