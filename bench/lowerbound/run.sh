#!/usr/bin/env bash
# The lower bound for row 1 of bench/MISSES.md: a size-first device written for examples/Minimal
# alone (extras/bench/lowerbound/Tight: scalars only, the descriptor as a flash string), what
# Minimal's own loop costs without any hub (NoHub), both against extras/bench/SerialEcho; then
# Tight and TightS (blink_ms also streamable) driven by the real Python hub on the simulated Uno. Reference code, not product
# code: it shows how far below the library a device for this protocol can go.
#
#   bash bench/lowerbound/run.sh      (after `make simuno`)
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
cd "$ROOT"
OUT=build/lowerbound
size() { bash tools/arduino/build-sketch.sh "$1" arduino:avr:uno "$2" | awk '/^SIZE/ {split($4, f, "="); split($5, s, "="); print f[2], s[2]}'; }
read -r bf bs < <(size extras/bench/SerialEcho $OUT/SerialEcho)
for v in "Tight|extras/bench/lowerbound/Tight|" "TightS|extras/bench/lowerbound/Tight|-DTIGHT_STREAMABLE" \
         "Tight, no streams or failsafes|extras/bench/lowerbound/Tight|-DTW_HAS_STREAMS=0 -DTW_HAS_FAILSAFE=0" \
         "NoHub|extras/bench/lowerbound/NoHub|"; do
  IFS='|' read -r name dir flags <<<"$v"
  dest=$OUT/${name%%,*}
  [[ $name == *"no streams"* ]] && dest=$OUT/TightBare
  # The sketches take Minimal's values (and declarations) from its own channels.h.
  read -r f s < <(EXTRA_FLAGS="-I$ROOT/examples/Minimal $flags" size "$dir" "$dest")
  printf '%-32s flash %5d B (+%d)  SRAM %4d B (+%d)\n' "$name" "$f" $((f - bf)) "$s" $((s - bs))
done
.venv/bin/python -m pytest -q bench/lowerbound/test_tight.py
