#!/usr/bin/env bash
# `make demo`: the hub discovering a simulated Arduino Uno that runs examples/Rover.
#
# Starts build/simuno/simuno (real AVR firmware in simavr, its UART on a pty that resets the board
# when opened, with a bootloader delay like a real Uno), walks through every kind of message with
# tools/demo_tour.py (reads, acked writes, a stream following the motors, a refused value, an
# action, events once each, a failsafe, link health), then runs `hubwire watch` while the bumper is
# pressed every 2 s. docs/DEMO.md says exactly what it shows and what it does not. Watch runs until Ctrl-C on a
# terminal; about 15 s when stdin or stdout is not a terminal. Always stops the simulator and
# removes the link; Ctrl-C is a normal way to end (exit status 0). Needs `make simuno uno-firmware` (and `make setup`
# for the venv) first; `make demo` does all of it.
#
# `make dashboard-demo` (`tools/demo.sh --dashboard`): the same simulated Uno shown in the browser
# dashboard instead (`hubwire dashboard`, at the address with a token it prints) until Ctrl-C.
#
# Environment: HUBWIRE_BUILD (the build folder, default build), HUBWIRE_PYTHON (default .venv/bin/python), DEMO_DURATION (seconds, overrides the
# default), DEMO_BOOT_DELAY_MS (default 1000), DASHBOARD_PORT (default 8080).
set -euo pipefail
# Job control: each command runs in its own process group and owns the terminal while it runs, so
# Ctrl-C reaches only the hub command (which ends cleanly), not make or this script.
set -m
cd "$(dirname "$0")/.."

BUILD=${HUBWIRE_BUILD:-build}
SIMUNO=$BUILD/simuno/simuno
ELF=$BUILD/uno/Rover/Rover.ino.elf
PY=${HUBWIRE_PYTHON:-.venv/bin/python}
BOOT_DELAY_MS=${DEMO_BOOT_DELAY_MS:-1000}
MODE=tour
[ "${1:-}" != "--dashboard" ] || MODE=dashboard

die() { echo "demo: $*" >&2; exit 1; }

missing=()
[ -x "$SIMUNO" ] || missing+=("$SIMUNO")
[ -f "$ELF" ] || missing+=("$ELF")
[ ${#missing[@]} -eq 0 ] || die "missing ${missing[*]}: build them with \`make simuno uno-firmware\` (or run \`make demo\`)"
if [ ! -x "$PY" ]; then
  die "no Python venv at $PY: run \`make setup\` (or set HUBWIRE_PYTHON to a python with hubwire installed)"
fi
"$PY" -c 'import hubwire' 2>/dev/null || die "$PY cannot import hubwire: run \`make setup\`"

tmp=$(mktemp -d "${TMPDIR:-/tmp}/hubwire-demo.XXXXXX")
link="$tmp/uno"
simuno_pid=""

cleanup() {
  trap - EXIT INT TERM HUP
  if [ -n "$simuno_pid" ] && kill -0 "$simuno_pid" 2>/dev/null; then
    kill -TERM "$simuno_pid" 2>/dev/null || true
    for _ in $(seq 50); do kill -0 "$simuno_pid" 2>/dev/null || break; sleep 0.1; done
    kill -KILL "$simuno_pid" 2>/dev/null || true
  fi
  [ -z "$simuno_pid" ] || wait "$simuno_pid" 2>/dev/null || true
  rm -rf "$tmp"
}
trap cleanup EXIT
trap 'exit 0' INT
trap 'exit 143' TERM HUP

# the simulated Uno; its chatter goes to a log (shown if something fails)
"$SIMUNO" "$ELF" --link "$link" --reset-on-open --boot-delay "$BOOT_DELAY_MS" \
  >"$tmp/simuno.out" 2>"$tmp/simuno.log" </dev/null &
simuno_pid=$!
for _ in $(seq 100); do
  grep -q '^READY ' "$tmp/simuno.out" 2>/dev/null && break
  kill -0 "$simuno_pid" 2>/dev/null || break
  sleep 0.1
done
if ! grep -q "^READY $link\$" "$tmp/simuno.out" 2>/dev/null; then
  cat "$tmp/simuno.log" >&2 || true
  die "simuno did not start"
fi

if [ "$MODE" = dashboard ]; then
  port=${DASHBOARD_PORT:-8080}
  cat <<EOF
================================================================================
 Hubwire dashboard demo: examples/Rover on a simulated Arduino Uno ($link)

 Open the address printed below (http://localhost:$port/?token=..., the token is
 made up at each start) in a browser: live values and plots, sliders for the
 motors, actions, the bumper's events, link health and the descriptor.
 ${DEMO_DURATION:+It stops by itself after $DEMO_DURATION s; }Ctrl-C stops it.

 With real boards:  .venv/bin/hubwire dashboard /dev/ttyACM0 [/dev/ttyACM1 ...]
================================================================================
EOF
  status=0
  if [ -n "${DEMO_DURATION:-}" ]; then
    timeout -s INT "$DEMO_DURATION" "$PY" -m hubwire dashboard "$link" --http "$port" || status=$?
    [ "$status" -ne 124 ] || status=0
  else
    "$PY" -m hubwire dashboard "$link" --http "$port" || status=$?
  fi
  if [ "$status" -ne 0 ] && [ "$status" -ne 130 ]; then
    echo "demo: hubwire dashboard exited with status $status; simulator log:" >&2
    tail -n 20 "$tmp/simuno.log" >&2 || true
    exit "$status"
  fi
  echo "demo: done (simulator stopped)."
  exit 0
fi

duration_args=()
if [ -n "${DEMO_DURATION:-}" ]; then
  duration_args=(--duration "$DEMO_DURATION")
elif [ ! -t 0 ] || [ ! -t 1 ]; then
  duration_args=(--duration 15)  # not interactive (CI, a pipe): end by itself
fi
if [ ${#duration_args[@]} -gt 0 ]; then
  how_long="for ${duration_args[1]} s"
else
  how_long="until you press Ctrl-C"
fi

cat <<EOF
================================================================================
 Hubwire demo: a simulated Arduino Uno talking to the Python hub

 Running: examples/Rover compiled for the Uno ($ELF)
          in simavr ($SIMUNO), its serial port on $link.
          Opening the port resets the board and its bootloader holds it for
          ${BOOT_DELAY_MS} ms, like a real Uno; the hub rides through that by itself.

 First a tour of what Rover uses (tools/demo_tour.py; docs/DEMO.md), then
 \`hubwire watch\` with live values, events and link health, $how_long.

 With a real board: upload examples/Rover to an Uno (Arduino IDE or arduino-cli),
 then run
     .venv/bin/hubwire watch /dev/ttyACM0      (or: hubwire watch auto)
 and in Python:
     import hubwire
     with hubwire.connect("/dev/ttyACM0") as rover:
         rover.left = 0.5; print(rover.battery)
================================================================================
EOF

status=0
echo "\$ python tools/demo_tour.py $link"
"$PY" tools/demo_tour.py "$link" || status=$?
if [ "$status" -eq 0 ]; then
  echo
  echo "\$ hubwire watch $link ${duration_args[*]}      (the bumper is pressed and released every 2 s)"
  # something moving on the board's side: simuno toggles the bumper's pin on SIGUSR2
  ( set +m; while kill -USR2 "$simuno_pid" 2>/dev/null; do sleep 2; done ) &
  presser=$!
  "$PY" -m hubwire watch "$link" "${duration_args[@]}" || status=$?
  kill "$presser" 2>/dev/null || true
  wait "$presser" 2>/dev/null || true
fi
if [ "$status" -ne 0 ] && [ "$status" -ne 130 ]; then
  echo "demo: hubwire exited with status $status; simulator log:" >&2
  tail -n 20 "$tmp/simuno.log" >&2 || true
  exit "$status"
fi
echo
echo "demo: done (simulator stopped)."
