#!/usr/bin/env bash
# Build every examples/*/ sketch for the AVR boards we support.
#
#   tools/arduino/build-all.sh [BUILD_ROOT]     (default: build/arduino)
#
# Each build lands in BUILD_ROOT/<board>/<sketch>/. Prints a size table at
# the end; exits non-zero if any build failed.
# Environment: FQBNS="fqbn1 fqbn2" overrides the board list; EXAMPLES_DIR
# overrides the examples folder; the rest is passed to build-sketch.sh.
set -uo pipefail

SCRIPT_DIR=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
ROOT=$(realpath "$SCRIPT_DIR/../..")
BUILD_ROOT=$(realpath -m "${1:-$ROOT/build/arduino}")
EXAMPLES_DIR=${EXAMPLES_DIR:-$ROOT/examples}
FQBNS=${FQBNS:-"arduino:avr:uno arduino:avr:mega:cpu=atmega2560 arduino:avr:leonardo"}

shopt -s nullglob
# Folders holding a sketch of their name (examples/ESP32/ holds examples for that family only).
sketches=()
for d in "$EXAMPLES_DIR"/*/; do
	[ -f "$d/$(basename "$d").ino" ] && sketches+=("$d")
done
if [ ${#sketches[@]} -eq 0 ]; then
	echo "build-all: no sketches under $EXAMPLES_DIR" >&2
	exit 1
fi

fail=0
summary=()
for fqbn in $FQBNS; do
	board=$(echo "$fqbn" | tr ':=' '__')
	for dir in "${sketches[@]}"; do
		name=$(basename "$dir")
		echo "=== $name on $fqbn"
		out=$("$SCRIPT_DIR/build-sketch.sh" "$dir" "$fqbn" "$BUILD_ROOT/$board/$name" 2>&1)
		rc=$?
		echo "$out"
		if [ $rc -eq 0 ]; then
			summary+=("$(echo "$out" | grep '^SIZE ' | tail -n1)")
		else
			summary+=("FAIL $name $fqbn")
			fail=1
		fi
	done
done

echo
echo "=== summary"
printf '%s\n' "${summary[@]}" | column -t
exit $fail
