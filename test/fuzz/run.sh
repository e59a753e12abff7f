#!/usr/bin/env bash
# Build and run the libFuzzer harnesses over the C++ core (clang++, ASan + UBSan), into build/fuzz/.
#
#   bash test/fuzz/run.sh                 bounded: ~25 s per harness (~60 s in all), as `make test` runs it
#   bash test/fuzz/run.sh --long [SECS]   long: SECS per harness (default 1800)
#   HUBWIRE_FUZZ_SECONDS=N bash test/fuzz/run.sh      N seconds per harness
#   bash test/fuzz/run.sh --build         build only
#   bash test/fuzz/run.sh --repro FILE    run FILE through both harnesses (a reproducer)
#
# Seeds come from test/vectors/*.json (test/fuzz/make_corpus.py, at build time); the corpus grows
# in build/fuzz/corpus/<harness>/. A crash fails the script and leaves its reproducer in
# build/fuzz/artifacts/ (printed with a hex dump). Reproducers worth keeping go to
# test/fuzz/regressions/<harness>/ and are replayed first on every run.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
OUT="$ROOT/build/fuzz"
CXX="${CXX_FUZZ:-clang++}"
SECONDS_EACH="${HUBWIRE_FUZZ_SECONDS:-25}"
MODE=run
REPRO=""
case "${1:-}" in
  --long) SECONDS_EACH="${2:-${HUBWIRE_FUZZ_SECONDS:-1800}}" ;;
  --build) MODE=build ;;
  --repro) MODE=repro; REPRO="$(cd "$(dirname "$2")" && pwd)/$(basename "$2")" ;;
  "") ;;
  *) echo "usage: $0 [--long [SECONDS] | --build | --repro FILE]" >&2; exit 2 ;;
esac

HARNESSES=(frame session)
CORE=("$ROOT"/src/hubwire/*.cpp "$ROOT"/src/hubwire/wire/*.cpp "$ROOT"/src/hubwire/session/*.cpp)
FLAGS=(-std=c++11 -g -O1 -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=all
       -fno-omit-frame-pointer -Wall -Wextra -I"$ROOT/src" -I"$ROOT/test/fuzz"
       -DHUBWIRE_PORT_HEADER='"fuzz_port.h"')
mkdir -p "$OUT/artifacts"

build() {
  local h=$1 bin="$OUT/fuzz_$1" src="$ROOT/test/fuzz/fuzz_$1.cpp"
  local newest
  newest=$(ls -t "$src" "$ROOT/test/fuzz/fuzz_port.h" "${CORE[@]}" "$ROOT"/src/hubwire/*.h "$ROOT"/src/hubwire/*/*.h | head -1)
  if [[ -x "$bin" && "$bin" -nt "$newest" ]]; then return 0; fi
  "$CXX" "${FLAGS[@]}" "$src" "${CORE[@]}" -o "$bin.tmp" && mv "$bin.tmp" "$bin"
}

pids=()
for h in "${HARNESSES[@]}"; do build "$h" & pids+=($!); done
for p in "${pids[@]}"; do wait "$p"; done
python3 "$ROOT/test/fuzz/make_corpus.py" "$OUT/seeds" >/dev/null
[[ $MODE == build ]] && { echo "fuzz: built ${HARNESSES[*]} in $OUT"; exit 0; }

if [[ $MODE == repro ]]; then
  rc=0
  for h in "${HARNESSES[@]}"; do "$OUT/fuzz_$h" "$REPRO" || rc=1; done
  exit $rc
fi

export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
status=0
for h in "${HARNESSES[@]}"; do
  corpus="$OUT/corpus/$h"
  mkdir -p "$corpus"
  extra=()
  [[ -d "$ROOT/test/fuzz/regressions/$h" ]] && extra=("$ROOT/test/fuzz/regressions/$h")  # past crashes
  log="$OUT/fuzz_$h.log"
  echo "fuzz: $h for ${SECONDS_EACH} s (log $log)"
  set +e
  "$OUT/fuzz_$h" -max_total_time="$SECONDS_EACH" -timeout=10 -rss_limit_mb=2048 -max_len=1024 \
    -print_final_stats=1 -artifact_prefix="$OUT/artifacts/$h-" "$corpus" "$OUT/seeds/$h" "${extra[@]}" >"$log" 2>&1
  rc=$?
  set -e
  grep -E "^stat::number_of_executed_units|^stat::peak_rss_mb|^stat::new_units_added" "$log" | sed "s/^/fuzz: $h: /" || true
  grep -E "^#[0-9]+ +DONE" "$log" | tail -1 | sed "s/^/fuzz: $h: /" || true
  if [[ $rc -ne 0 ]]; then
    status=1
    echo "fuzz: $h FAILED (exit $rc); last lines of $log:" >&2
    grep -E "ERROR|SUMMARY|check failed|runtime error|Test unit written" "$log" | head -20 >&2 || true
    for a in "$OUT"/artifacts/"$h"-*; do
      [[ -f "$a" ]] || continue
      echo "fuzz: reproducer $a (replay: $OUT/fuzz_$h $a):" >&2
      xxd "$a" | head -20 >&2 || od -An -tx1 "$a" | head -20 >&2
    done
  fi
done
[[ $status -eq 0 ]] && echo "fuzz: no crash (${SECONDS_EACH} s per harness)"
exit $status
