"""The guided part of `make demo`: every kind of message the protocol has, on a Rover board.

    python tools/demo_tour.py PORT          (tools/demo.sh runs it on the simulated Uno)

Step by step, with the Python that does it printed beside what happened: discovery, reads, a
stream whose values follow the motor commands, writes acknowledged by the board, a value refused
(with the reason), an action with a result, events delivered once each, link health.
Exits 0 when every step did what the protocol promises, 1 (with the reason) otherwise.
"""
from __future__ import annotations

import argparse
import sys
import time
from typing import Any, Callable, List

import hubwire
from hubwire.testing import tap_of, tapped

PAUSE = [0.6]  # seconds between steps, so a person can follow (--pause)


def show(code: str, result: Any = "") -> None:
    tail = f"   ->  {result}" if result != "" else ""
    print(f"  >>> {code}{tail}", flush=True)


def title(text: str) -> None:
    print(f"\n== {text}", flush=True)
    time.sleep(PAUSE[0])


def settled(read: Callable[[], Any], ok: Callable[[Any], bool], seconds: float = 3.0) -> Any:
    """The first value ``read()`` gives that ``ok`` accepts (the board refreshes its sensors every
    20 ms of its own time), or the last one read after ``seconds``."""
    end = time.monotonic() + seconds
    value = read()
    while not ok(value) and time.monotonic() < end:
        time.sleep(0.05)
        value = read()
    return value


def imu_while_driving(rover: hubwire.Device, left: float, right: float, samples: int) -> List[Any]:
    rover.left, rover.right = left, right
    show(f"rover.left, rover.right = {left}, {right}", "acked")
    got = []
    with rover.stream("imu", hz=20, timeout=5.0) as imu:
        for value in imu:
            got.append(value)
            if len(got) == samples:
                break
    last = got[-1]
    show('for imu in rover.stream("imu", hz=20)',
         f"{len(got)} samples, last ax={last.ax:.2f} ay={last.ay:.2f} gyro z={last.gyro[2]}")
    return got


def read_or_none(rover: hubwire.Device, name: str) -> Any:
    """A read, or None while the link is coming back."""
    try:
        return rover.read(name)
    except hubwire.HubwireError:
        return None


def tour(rover: hubwire.Device, check: Callable[[bool, str], None]) -> None:
    title("Discovery: the board described itself; nothing here was written for this sketch")
    print(rover.table())

    title("Reads (R -> r)")
    show("rover.battery", f"{rover.battery} mV")
    show("rover.range", rover.range)

    title("Writes with ACK (C -> ACK), and a stream (S -> D D D ...) that follows them")
    forward = imu_while_driving(rover, 0.8, 0.8, 5)[-1]
    check(forward.ax > 0.3 and forward.gyro[2] == 0, f"driving straight should give ax>0.3 and no turn: {forward}")
    front_moving = settled(lambda: rover.range[0], lambda v: v < 150)
    show("rover.range[0]", f"{front_moving} cm ahead while driving forward")
    turning = imu_while_driving(rover, 0.6, -0.6, 5)[-1]
    check(turning.gyro[2] > 50, f"spinning should turn the gyro: {turning}")
    rover.left, rover.right = 0.0, 0.0
    front_stopped = settled(lambda: rover.range[0], lambda v: v == 150)
    show("rover.left, rover.right = 0, 0; rover.range[0]", f"stopped, {front_stopped} cm ahead")
    check(front_moving < front_stopped, f"the front range should shrink while driving: {front_moving} vs {front_stopped}")

    title("Values refused, and why")
    try:
        rover.left = 2.0
        check(False, "left = 2.0 should have been refused")
    except hubwire.InvalidValue as e:
        show("rover.left = 2.0", f"InvalidValue {e.error}: {e} (checked against the descriptor before "
                                 "sending; the board answers NAK OUT_OF_RANGE to a hub that does not check)")
    refused = rover.beep(5000)
    show("rover.beep(5000)", f"{refused} (the sketch's own rule: no beeps over 2000 ms)")
    check(refused is False, f"beep(5000) should return False, got {refused!r}")

    title("An action with a result, and events delivered exactly once (! -> ACK)")
    with rover.events("bumper", timeout=5.0) as events:
        queued = rover.selftest(3)
        show("rover.selftest(3)", f"{queued} bumper events queued on the board")
        seen = []
        for ev in events:
            seen.append(ev)
            show("  event", f"{ev.name} = {ev.value} (seq {ev.seq})")
            if len(seen) == queued:
                break
    check(len(seen) == queued == 3, f"expected 3 events once each, got {len(seen)}")
    check([e.value for e in seen] == [True, False, True], "events arrive in the order they were emitted")

    title("A failsafe: the hub falls silent, the board stops the motors by itself")
    rover.left, rover.right = 0.5, 0.5
    before = rover.failsafes
    show("rover.left, rover.right = 0.5, 0.5", f"driving; failsafes so far: {before}")
    tap = tap_of(rover)
    tap.paused = True  # nothing the hub writes reaches the board: no heartbeats, as if it hung
    show("(the hub stops writing for 2.5 s)", "the board misses 4 heartbeats (1 s), applies the failsafe values")
    time.sleep(2.5)
    tap.paused = False
    after = settled(lambda: read_or_none(rover, "failsafes"), lambda v: v is not None and v > before, 10.0)
    left = settled(lambda: read_or_none(rover, "left"), lambda v: v is not None, 10.0)
    show("rover.failsafes, rover.left", f"{after}, {left}: the link came back by itself, the motors stopped")
    check(after is not None and after > before and left == 0.0, f"the failsafe should have stopped the motors: "
                                                                 f"failsafes {before} -> {after}, left {left}")

    title("Link health: heartbeats both ways, error counters of both receivers")
    h = rover.health()
    show("rover.health()", f"state {h.state}, device heartbeat every {h.device_heartbeat_ms} ms, "
                           f"{h.device_heartbeats} heard, hub errors {h.hub_counters}, "
                           f"device errors {h.device_counters}")
    check(h.state == "ready" and h.device_heartbeats > 0, f"link should be ready with heartbeats: {h}")
    show("rover.applied", f"{rover.applied} writes applied on the board, each exactly once")


def main(argv: Any = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("port", help="serial port or pyserial URL of a board running examples/Rover")
    p.add_argument("--pause", type=float, default=PAUSE[0], help="seconds between steps (default %(default)s)")
    args = p.parse_args(argv)
    PAUSE[0] = args.pause
    failures: List[str] = []

    def check(ok: bool, why: str) -> None:
        if not ok:
            failures.append(why)
            print(f"  !! {why}", flush=True)

    show(f'rover = hubwire.connect("{args.port}")', "rides through the reset, handshakes, discovers")
    with hubwire.connect(transport=tapped(args.port)) as rover:  # tapped: for the failsafe step
        tour(rover, check)
    if failures:
        print(f"\ndemo tour: {len(failures)} step(s) did not do what the protocol promises", file=sys.stderr)
        return 1
    print("\ndemo tour: every step did what the protocol promises", flush=True)
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except KeyboardInterrupt:
        sys.exit(130)
