#!/usr/bin/env bash
# Every compile-time setting in src/hubwire/config.h at the ends of its allowed range: an example
# must still build for the Uno with no warning from our code (build-sketch.sh enforces that).
# The default build only proves the defaults; a user who sets HUBWIRE_MAX_STREAMS=0 to save RAM
# should not be the first to compile that branch.
#
#   tools/arduino/build-config-limits.sh [BUILD_ROOT]     (default: build/config-limits)
set -uo pipefail

SCRIPT_DIR=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
ROOT=$(realpath "$SCRIPT_DIR/../..")
BUILD_ROOT=$(realpath -m "${1:-$ROOT/build/config-limits}")

# sketch | flags. Rover declares every kind of channel; Minimal's values fit the smallest payload;
# Thermostat declares the hub's channels (its four need HUBWIRE_MAX_HUB_CHANNELS=4, its float argument 4 bytes).
# Largest buffers are taken one at a time: all of them at once need more than the Uno's 2 KB.
# The smallest settings are the smallest Minimal fits: its three channels need
# HUBWIRE_MAX_CHANNELS=3 (fewer is a compile error by design, declare.h), its largest value 2 bytes
# HUBWIRE_MAX_VALUE=2. LargeValues: fragments of 11 bytes (payload 16), and with payload 255 no
# value large at all (its lists alone).
CASES=(
  "Rover|-DHUBWIRE_MAX_STREAMS=0"
  "Rover|-DHUBWIRE_MAX_STREAMS=32 -DHUBWIRE_EVENT_QUEUE=64 -DHUBWIRE_MAX_CHANNELS=254 -DHUBWIRE_MAX_PAYLOAD=255 -DHUBWIRE_MIN_STREAM_INTERVAL_MS=1"
  "Rover|-DHUBWIRE_MAX_PAYLOAD=255 -DHUBWIRE_EVENT_MAX_PAYLOAD=255 -DHUBWIRE_MAX_RETURN=255 -DHUBWIRE_MIN_STREAM_INTERVAL_MS=60000"
  "Minimal|-DHUBWIRE_MAX_STREAMS=1 -DHUBWIRE_EVENT_QUEUE=1 -DHUBWIRE_MAX_CHANNELS=3 -DHUBWIRE_MAX_PAYLOAD=16 -DHUBWIRE_EVENT_MAX_PAYLOAD=1 -DHUBWIRE_MAX_RETURN=1"
  "Minimal|-DHUBWIRE_HEARTBEAT_MS=10 -DHUBWIRE_LOST_AFTER_BEATS=2 -DHUBWIRE_ANNOUNCE_MS=10 -DHUBWIRE_EVENT_RETRY_MS=10"
  "Minimal|-DHUBWIRE_HEARTBEAT_MS=10 -DHUBWIRE_LOST_AFTER_BEATS=6553"
  "Minimal|-DHUBWIRE_HEARTBEAT_MS=16383 -DHUBWIRE_ANNOUNCE_MS=60000 -DHUBWIRE_EVENT_RETRY_MS=60000"
  "Minimal|-DHUBWIRE_MAX_VALUE=2"
  "LargeValues|-DHUBWIRE_MAX_VALUE=65535 -DHUBWIRE_MAX_PAYLOAD=16"
  "LargeValues|-DHUBWIRE_MAX_PAYLOAD=255"
  "Thermostat|-DHUBWIRE_HUB_QUEUE=1 -DHUBWIRE_HUB_MAX_VALUE=4 -DHUBWIRE_MAX_HUB_CHANNELS=4 -DHUBWIRE_HUB_RETRY_MS=10 -DHUBWIRE_HUB_TRIES=1"
  "Thermostat|-DHUBWIRE_HUB_QUEUE=32 -DHUBWIRE_HUB_MAX_VALUE=32 -DHUBWIRE_MAX_HUB_CHANNELS=31 -DHUBWIRE_HUB_RETRY_MS=257 -DHUBWIRE_HUB_TRIES=255"
)

fail=0
i=0
for c in "${CASES[@]}"; do
  sketch=${c%%|*}
  flags=${c#*|}
  i=$((i + 1))
  if out=$(EXTRA_FLAGS="$flags" "$SCRIPT_DIR/build-sketch.sh" "$ROOT/examples/$sketch" arduino:avr:uno \
      "$BUILD_ROOT/$i-$sketch" 2>&1); then
    echo "ok    $sketch $flags"
  else
    echo "FAIL  $sketch $flags"
    echo "$out" | tail -n 20
    fail=1
  fi
done
[ $fail -eq 0 ] && echo "build-config-limits: ${#CASES[@]} builds at the limits of config.h, no warnings from our code"
exit $fail
