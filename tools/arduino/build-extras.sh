#!/usr/bin/env bash
# Build the benchmark sketches under extras/ for the Uno, so that they keep compiling against the
# library and against the examples whose channels they include (each takes an example's
# channels.h through -I, as bench/ builds them).
#
#   tools/arduino/build-extras.sh [BUILD_ROOT]     (default: build/extras)
set -uo pipefail

SCRIPT_DIR=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
ROOT=$(realpath "$SCRIPT_DIR/../..")
BUILD_ROOT=$(realpath -m "${1:-$ROOT/build/extras}")

# sketch | build name | flags
CASES=(
  "extras/bench/SerialEcho|SerialEcho|"
  "extras/bench/ThermostatLocal|ThermostatLocal|"
  "extras/bench/RxCycles|RxCycles|-I$ROOT/examples/Rover"
  "extras/bench/lowerbound/NoHub|NoHub|-I$ROOT/examples/Minimal"
  "extras/bench/lowerbound/Tight|Tight|-I$ROOT/examples/Minimal"
  "extras/bench/lowerbound/Tight|TightS|-I$ROOT/examples/Minimal -DTIGHT_STREAMABLE"
)

fail=0
for c in "${CASES[@]}"; do
  IFS='|' read -r dir name flags <<<"$c"
  if out=$(EXTRA_FLAGS="$flags" "$SCRIPT_DIR/build-sketch.sh" "$ROOT/$dir" arduino:avr:uno "$BUILD_ROOT/$name" 2>&1); then
    echo "$out" | grep '^SIZE ' | sed "s/^SIZE [^ ]*/SIZE $name/"
  else
    echo "FAIL  $dir $flags"
    echo "$out" | tail -n 20
    fail=1
  fi
done
exit $fail
