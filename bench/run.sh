#!/usr/bin/env bash
# Every Hubwire benchmark, then bench/RESULTS.md (table: target, measured value, command per row).
#
#   bash bench/run.sh            (make bench)
#
# Needs what `make setup` installs, plus a bench-only venv (build/bench-venv) holding pymavlink and
# pySerialTransfer from PyPI for the comparison in row 4: created here on first use, never .venv.
# PEERS_SRC=DIR: the peers' sources, for bench/peers.sh (bench/PEERS.md); without it that table is kept.
# Takes about 5 minutes (the dashboard row: about 1.5). A step that fails is reported as failed in RESULTS.md; the rest still run.
set -uo pipefail
cd "$(dirname "$0")/.."
PY=.venv/bin/python
BENCH_PY=build/bench-venv/bin/python
start=$(date +%s)
status=0
step() {  # name, command...
	local name=$1
	shift
	echo "== bench: $name: $*" >&2
	if ! "$@"; then
		echo "== bench: $name FAILED" >&2
		status=1
	fi
}

[ -x "$PY" ] || { echo "bench: $PY missing: run make setup" >&2; exit 1; }
make -s emulator simuno uno-firmware >/dev/null || { echo "bench: build failed" >&2; exit 1; }
if ! "$BENCH_PY" -c "import pymavlink, pySerialTransfer, cobs, serial, hubwire" 2>/dev/null; then
	echo "== bench: creating build/bench-venv (pymavlink, pySerialTransfer)" >&2
	python3 -m venv build/bench-venv &&
		build/bench-venv/bin/pip install -q pymavlink pySerialTransfer cobs pyserial -e host >&2 || status=1
fi
mkdir -p build/bench
rm -rf build/bench/results

step footprint bash bench/footprint.sh
# The peers' sources are not in this repository (bench/peers.sh): PEERS_SRC names a folder of them.
if [ -n "${PEERS_SRC:-}" ]; then
	step peers bash bench/peers.sh --sources "$PEERS_SRC" --check
else
	echo "== bench: peers skipped (PEERS_SRC not set): bench/PEERS.md kept from its last run" >&2
fi
step descriptor_compile bash bench/descriptor-compile.sh
step rx_cycles "$PY" bench/rx_cycles.py
step wire_bytes "$PY" bench/wire_bytes.py
step wire_large "$PY" bench/wire_large.py
step throughput "$BENCH_PY" bench/throughput.py
step connect "$PY" bench/connect.py
step rtt "$PY" bench/rtt.py
step large_rtt "$PY" bench/large_rtt.py
step missions "$PY" bench/missions.py
step many "$PY" bench/many.py
step mqtt "$PY" bench/mqtt_bridge.py
step dashboard "$PY" bench/dashboard.py
"$PY" bench/report.py "$(($(date +%s) - start))" || status=1
echo "bench: wrote bench/RESULTS.md in $(($(date +%s) - start)) s" >&2
exit $status
