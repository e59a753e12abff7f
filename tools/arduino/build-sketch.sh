#!/usr/bin/env bash
# Compile one sketch with Debian's arduino-builder, using this repository
# itself as the Arduino library (library.properties + src/).
#
#   tools/arduino/build-sketch.sh SKETCH_DIR FQBN BUILD_DIR
#
# FQBN examples: arduino:avr:uno  arduino:avr:mega:cpu=atmega2560  arduino:avr:leonardo
#
# Fails when arduino-builder fails, or when a warning points into the
# library's own sources (src/) or into the sketch. Warnings from the Arduino
# core are printed and allowed. Prints `avr-size -A` and a summary line:
#   SIZE <sketch> <fqbn> flash=<text+data> sram=<data+bss>
#
# Environment:
#   HUBWIRE_LIB_DIR   library root to use instead of this repository (tests)
#   EXTRA_FLAGS       extra compiler flags (e.g. -DHUBWIRE_MAX_CHANNELS=8)
#   STRICT_SKETCH=0   allow warnings in the sketch itself
#   KEEP_LIBS=1       keep the temporary libraries folder (debugging)
set -euo pipefail

die() { echo "build-sketch: $*" >&2; exit 1; }

[ $# -eq 3 ] || die "usage: $0 SKETCH_DIR FQBN BUILD_DIR"
SKETCH_DIR=$(realpath -e "$1") || die "no such sketch dir: $1"
FQBN=$2
BUILD_DIR=$(realpath -m "$3")

SCRIPT_DIR=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
LIB_ROOT=$(realpath -e "${HUBWIRE_LIB_DIR:-$SCRIPT_DIR/../..}")
STRICT_SKETCH=${STRICT_SKETCH:-1}

command -v arduino-builder >/dev/null || die "arduino-builder not installed (apt-get install arduino-builder arduino-core-avr)"
command -v avr-size >/dev/null || die "avr-size not installed (apt-get install binutils-avr)"
[ -f "$LIB_ROOT/library.properties" ] || die "$LIB_ROOT/library.properties missing"
[ -d "$LIB_ROOT/src" ] || die "$LIB_ROOT/src missing"

LIB_NAME=$(sed -n 's/^name=\(.*\)$/\1/p' "$LIB_ROOT/library.properties" | head -n1 | tr -d '\r')
[ -n "$LIB_NAME" ] || die "no name= in $LIB_ROOT/library.properties"

SKETCH_NAME=$(basename "$SKETCH_DIR")
INO="$SKETCH_DIR/$SKETCH_NAME.ino"
[ -f "$INO" ] || die "$INO not found (a sketch folder holds <folder>.ino)"

# A private libraries folder holding only this library. arduino-builder
# follows symlinks (checked with 1.3.25), so nothing is copied.
LIBS=$(mktemp -d "${TMPDIR:-/tmp}/hubwire-libs.XXXXXX")
cleanup() { [ "${KEEP_LIBS:-0}" = 1 ] || rm -rf "$LIBS"; }
trap cleanup EXIT
mkdir -p "$LIBS/$LIB_NAME"
ln -s "$LIB_ROOT/library.properties" "$LIBS/$LIB_NAME/library.properties"
ln -s "$LIB_ROOT/src" "$LIBS/$LIB_NAME/src"

mkdir -p "$BUILD_DIR"
# Outside the build path: arduino-builder wipes that folder when the build options change.
LOG="$BUILD_DIR.log"

# -hardware /usr/share/arduino-builder provides the ctags recipe
# (without it: "ctags pattern is missing").
set +e
arduino-builder -compile -warnings all \
	-hardware /usr/share/arduino/hardware \
	-hardware /usr/share/arduino-builder \
	-tools /usr/share/arduino-builder \
	-libraries "$LIBS" \
	-fqbn "$FQBN" \
	-build-path "$BUILD_DIR" \
	"-prefs=compiler.cpp.extra_flags=-DDECIMAL_DIG=__DECIMAL_DIG__ ${EXTRA_FLAGS:-}" \
	"-prefs=compiler.c.extra_flags=${EXTRA_FLAGS:-}" \
	"$INO" >"$LOG" 2>&1
RC=$?
set -e

# Show the log with the temporary library path mapped back to the repository.
sed "s#$LIBS/$LIB_NAME/#$LIB_ROOT/#g" "$LOG"

if [ $RC -ne 0 ]; then
	die "arduino-builder failed ($RC) for $SKETCH_NAME on $FQBN"
fi

# Warnings that point into our own files.
PATTERNS=("$LIBS/$LIB_NAME/src/" "$LIB_ROOT/src/")
if [ "$STRICT_SKETCH" = 1 ]; then
	PATTERNS+=("$SKETCH_DIR/" "$BUILD_DIR/sketch/")
fi
OWN=""
for p in "${PATTERNS[@]}"; do
	hits=$(grep -F -- "$p" "$LOG" | grep -E ': warning: ' || true)
	[ -n "$hits" ] && OWN+="$hits"$'\n'
done
if [ -n "$OWN" ]; then
	echo "build-sketch: warnings in our own code ($SKETCH_NAME, $FQBN):" >&2
	printf '%s' "$OWN" | sed "s#$LIBS/$LIB_NAME/#$LIB_ROOT/#g" | sort -u >&2
	exit 1
fi

ELF="$BUILD_DIR/$SKETCH_NAME.ino.elf"
[ -f "$ELF" ] || die "$ELF not produced"
avr-size -A "$ELF"
avr-size -A "$ELF" | awk -v s="$SKETCH_NAME" -v f="$FQBN" '
	$1 == ".text" { t = $2 } $1 == ".data" { d = $2 } $1 == ".bss" { b = $2 }
	END { printf "SIZE %s %s flash=%d sram=%d\n", s, f, t + d, d + b }'
