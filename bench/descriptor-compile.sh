#!/usr/bin/env bash
# What building the descriptor (its JSON, FNV-1a hash and SHA-256 digest, all worked out by the
# compiler: src/hubwire/channels/tables.h) costs the compiler: wall time and peak memory of the
# largest declaration (test_limits' 254 channels, 12.6 KB of JSON) and of examples/Rover, each with
# avr-g++ (as the Arduino IDE compiles a sketch for the Uno: -std=gnu++11 -Os) and g++ (as CMake
# builds the tests and the emulator: -std=c++11 -O2 -g). One translation unit each, compiled alone.
#
#   bash bench/descriptor-compile.sh [TREE]   TREE: a source tree to measure (default: this one), e.g.
#                                             an older commit's `git archive` to compare against
set -euo pipefail
cd "$(dirname "$0")/.."
here=$(pwd)
tree=$(realpath "${1:-.}")
out=$here/build/descriptor-compile
mkdir -p "$out"
core=/usr/share/arduino/hardware/arduino/avr

# test_limits' 254 channels as an AVR unit (the gtest suite itself does not build for AVR).
cat >"$out/limits254.cpp" <<'CPP'
#include "hubwire/channels/declare.h"
uint16_t level;
#define LEVEL(name) expose(#name, level).streamable()
#define LEVELS_1(p) LEVEL(p##0), LEVEL(p##1)
#define LEVELS_2(p) LEVELS_1(p##0), LEVELS_1(p##1)
#define LEVELS_3(p) LEVELS_2(p##0), LEVELS_2(p##1)
#define LEVELS_4(p) LEVELS_3(p##0), LEVELS_3(p##1)
#define LEVELS_5(p) LEVELS_4(p##0), LEVELS_4(p##1)
#define LEVELS_6(p) LEVELS_5(p##0), LEVELS_5(p##1)
#define LEVELS_7(p) LEVELS_6(p##0), LEVELS_6(p##1)
HUBWIRE_CHANNELS(most, "limits", LEVELS_7(level0), LEVELS_6(level10), LEVELS_5(level110), LEVELS_4(level1110),
                 LEVELS_3(level11110), LEVELS_2(level111110), LEVELS_1(level1111110));
const hubwire::ChannelTable* used = &most;
CPP

# measure LABEL CMD... -> "wall s (CPU s), peak MiB", or "failed". The CPU time (user + system) is
# what to compare on a busy machine: the wall time grows with whatever else runs.
measure() {
  local label=$1
  shift
  if /usr/bin/time -f "%e %U %S %M" -o "$out/time.txt" "$@" >"$out/$label.log" 2>&1; then
    awk '{printf "%s s (CPU %.2f s), %d MiB", $1, $2 + $3, $4 / 1024}' "$out/time.txt"
  else
    echo "failed (see $out/$label.log)"
  fi
}

avr=(avr-g++ -std=gnu++11 -mmcu=atmega328p -Os -fno-exceptions -fno-threadsafe-statics -ffunction-sections
     -fdata-sections -DF_CPU=16000000L -DARDUINO=10807 -DARDUINO_AVR_UNO -DARDUINO_ARCH_AVR)
host=(g++ -std=c++11 -O2 -g -DNDEBUG)
limits=(-DHUBWIRE_MAX_CHANNELS=254 -DHUBWIRE_MAX_STREAMS=0)

echo "| unit | avr-g++ $(avr-g++ -dumpversion) | g++ $(g++ -dumpversion) |"
echo "| --- | --- | --- |"
a=$(measure limits-avr "${avr[@]}" "${limits[@]}" -I"$tree/src" -c "$out/limits254.cpp" -o "$out/limits-avr.o")
g=$(measure limits-host "${host[@]}" "${limits[@]}" -DHUBWIRE_VECTORS_DIR=\"\" -I"$here/test/support" -I"$tree/src" \
    -c "$tree/test/test_limits/test_limits.cpp" -o "$out/limits-host.o")
echo "| 254 channels (avr: their declaration; g++: test/test_limits) | $a | $g |"
a=$(measure rover-avr "${avr[@]}" -x c++ -include Arduino.h -I"$core/cores/arduino" -I"$core/variants/standard" \
    -I"$tree/src" -c "$tree/examples/Rover/Rover.ino" -o "$out/rover-avr.o")
g=$(measure rover-host "${host[@]}" -DHUBWIRE_NONCE_SOURCE=emulatorNonce -I"$tree/tools/emulator/arduino" -I"$tree/src" \
    -c "$tree/tools/emulator/emulator.cpp" -o "$out/rover-host.o")
echo "| examples/Rover (avr: the sketch; g++: the emulator, which includes it) | $a | $g |"
