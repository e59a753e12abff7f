#!/usr/bin/env bash
# The whole Python suite on a busy machine: one CPU burner per core (other processes at the same
# priority) for as long as the tests run, then killed. Timing-dependent tests must still pass.
#
#   bash tools/busy-test.sh [pytest arguments]      (after make emulator simuno uno-firmware)
set -uo pipefail
cd "$(dirname "$0")/.."
burners=()
stop() { kill "${burners[@]}" 2>/dev/null; wait "${burners[@]}" 2>/dev/null; }
trap stop EXIT
for _ in $(seq "$(nproc)"); do
	yes > /dev/null &
	burners+=($!)
done
echo "busy-test: ${#burners[@]} CPU burners (pids ${burners[*]}) on $(nproc) cores" >&2
.venv/bin/python -m pytest host/tests -q -p no:cacheprovider "$@"
status=$?
echo "busy-test: load average $(cut -d' ' -f1-3 /proc/loadavg); pytest exit status $status" >&2
exit $status
