#!/usr/bin/env bash
# Compiles each case of first_sketch.cpp for the Uno (avr-g++, as the Arduino IDE: every error
# printed) and checks the compiler's whole output: it says what is wrong, spells the channel's
# name (Channel<'t', 'h', ...>) and fits in 20 lines. Uses g++ where avr-g++ is missing.
set -uo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
out=${1:-/tmp/hubwire-first-sketch}
mkdir -p "$out"
if command -v avr-g++ >/dev/null; then
  cxx=(avr-g++ -std=gnu++11 -mmcu=atmega328p -Os -fno-exceptions -fno-rtti -fpermissive -flto)
else
  cxx=(g++ -std=gnu++11)
fi
spell() { echo "$1" | sed "s/./'&', /g; s/, \$//"; }  # threshold -> 't', 'h', ...
fail=0
check() {  # case, what the message must say, the channel's name
  local n=$1 says=$2 name=$3 log="$out/case$1.txt"
  "${cxx[@]}" -Wall -Wextra -I"$root/src" -I"$root/test/support" -DHUBWIRE_PORT_HEADER='"port_bare.h"' \
    -DHUBWIRE_CASE="$n" -fsyntax-only "$here/first_sketch.cpp" >"$log" 2>&1
  local rc=$? lines
  lines=$(wc -l <"$log")
  if [ "$n" = 0 ]; then
    [ $rc = 0 ] || { echo "first_sketch case 0 does not compile:"; cat "$log"; fail=1; }
    return
  fi
  if [ $rc = 0 ]; then echo "first_sketch case $n compiles but must not ($says)"; fail=1; return; fi
  grep -qF -- "$says" "$log" || { echo "first_sketch case $n: no \"$says\" in:"; cat "$log"; fail=1; }
  grep -qF -- "Channel<$(spell "$name")>" "$log" || { echo "first_sketch case $n: channel $name not named in:"; cat "$log"; fail=1; }
  [ "$lines" -le 20 ] || { echo "first_sketch case $n: $lines lines of errors (at most 20):"; head -40 "$log"; fail=1; }
}
check 0 "" ""
check 1 "failsafe(): a value the channel's type cannot hold" threshold
check 2 "failsafe(): the value is outside the channel's own range()" threshold
check 3 "range(): min or max is a value the channel's type cannot hold" threshold
check 4 "failsafe(): a value the channel's type cannot hold" threshold
check 5 "two channels have the same name" moisture
check 6 "range(): only a number" label
check 7 "channel name: letters, digits and _ only" "dry level"
[ $fail = 0 ] && echo "first_sketch: 7 mistakes, each named with its channel in at most 20 lines (${cxx[0]})"
exit $fail
