#!/usr/bin/env bash
# Uno flash/SRAM of the peers' published example sketches over the Serial-echo baseline, built with
# the same toolchain and builder as bench/footprint.sh (arduino-builder, avr-gcc, Arduino AVR core).
# Their sources are not part of this repository: pass the folders holding them (a clone or an
# unpacked archive of each public repository); a peer whose folder is not given is skipped.
#
#   bash bench/peers.sh [--packetserial DIR] [--serialtransfer DIR] [--telemetrix DIR]
#                       [--rosserial DIR] [--firmata DIR --servo DIR] [--markdown]
#
#   DIR for --packetserial  github.com/bakercp/PacketSerial            (examples/PacketSerialReverseEcho)
#           --serialtransfer github.com/PowerBroker2/SerialTransfer     (examples/uart_tx_data: framing only, no prints)
#           --telemetrix    github.com/MrYsLab/Telemetrix4Arduino       (its sketch, every *_ENABLED off)
#           --rosserial     github.com/frankjoshua/rosserial_arduino_lib (examples/HelloWorld; the
#                           Library Manager's generated ros_lib, which ros-drivers/rosserial only builds
#                           inside a ROS workspace)
#           --firmata       github.com/firmata/arduino                  (examples/StandardFirmata)
#           --servo         github.com/arduino-libraries/Servo          (StandardFirmata includes it)
#
# Prints one row per sketch: flash and static SRAM (avr-size -A: .text+.data, .data+.bss) and both
# over extras/bench/SerialEcho. --markdown prints the rows as a Markdown table; either way the table
# goes to bench/PEERS.md as well (bench/report.py puts it into RESULTS.md).
set -euo pipefail
cd "$(dirname "$0")/.."
declare -A DIR=()
MD=0
while [ $# -gt 0 ]; do
  case $1 in
    --packetserial|--serialtransfer|--telemetrix|--rosserial|--firmata|--servo)
      [ $# -ge 2 ] || { echo "peers: $1 needs a folder" >&2; exit 2; }
      DIR[${1#--}]=$(realpath -e "$2"); shift 2 ;;
    --markdown) MD=1; shift ;;
    *) echo "peers: unknown option $1 (see the header of $0)" >&2; exit 2 ;;
  esac
done
OUT=$(realpath -m build/peers)
WORK=$(mktemp -d "${TMPDIR:-/tmp}/hubwire-peers.XXXXXX")
trap 'rm -rf "$WORK"' EXIT
mkdir -p "$OUT"

# build NAME SKETCH_DIR [LIBRARY_DIR...] -> "flash sram"; the libraries are linked into a private
# folder, so nothing else installed on the machine is picked up.
build() {
  local name=$1 sketch=$2 libs=$WORK/libs-$1 lib
  shift 2
  mkdir -p "$libs"
  for lib in "$@"; do ln -sfn "$lib" "$libs/$(basename "$lib")"; done
  rm -rf "$OUT/$name"
  mkdir -p "$OUT/$name"
  if ! arduino-builder -compile -warnings none \
      -hardware /usr/share/arduino/hardware -hardware /usr/share/arduino-builder \
      -tools /usr/share/arduino-builder -libraries "$libs" -fqbn arduino:avr:uno \
      -build-path "$OUT/$name" -prefs=compiler.cpp.extra_flags=-DDECIMAL_DIG=__DECIMAL_DIG__ \
      "$sketch/$(basename "$sketch").ino" >"$OUT/$name.log" 2>&1; then
    echo "peers: $name failed to build, see $OUT/$name.log" >&2
    return 1
  fi
  avr-size -A "$OUT/$name/$(basename "$sketch").ino.elf" |
    awk '$1==".text"{t=$2} $1==".data"{d=$2} $1==".bss"{b=$2} END{print t+d, d+b}'
}

# A copy of a sketch folder under WORK (the .ino renamed after its folder when it is a .pde).
copy_sketch() {
  local src=$1 dst=$WORK/sketches/$(basename "$1")
  mkdir -p "$dst"
  cp -r "$src"/. "$dst"/
  for f in "$dst"/*.pde; do [ -e "$f" ] && mv "$f" "${f%.pde}.ino"; done
  echo "$dst"
}

read -r bf bs < <(build baseline extras/bench/SerialEcho)
rows=()
ver() { sed -n 's/^version=//p' "$1/library.properties" 2>/dev/null | head -1 | tr -d '\r'; }
row() {  # peer sketch flash sram
  rows+=("$1|$2|$3|$4|+$(($3 - bf))|+$(($4 - bs))")
}
if [ -n "${DIR[packetserial]:-}" ]; then
  if out=$(build PacketSerial "${DIR[packetserial]}/examples/PacketSerialReverseEcho" "${DIR[packetserial]}"); then
    read -r f s <<<"$out"
    row "PacketSerial $(ver "${DIR[packetserial]}")" PacketSerialReverseEcho "$f" "$s"
  fi
fi
if [ -n "${DIR[serialtransfer]:-}" ]; then
  # It reads Serial1 (a Mega's second port); the Uno's one port is Serial.
  t=$(copy_sketch "${DIR[serialtransfer]}/examples/uart_tx_data")
  sed -i 's/\bSerial1\b/Serial/g' "$t/uart_tx_data.ino"
  if out=$(build SerialTransfer "$t" "${DIR[serialtransfer]}"); then
    read -r f s <<<"$out"
    row "SerialTransfer $(ver "${DIR[serialtransfer]}")" uart_tx_data "$f" "$s"
  fi
fi
if [ -n "${DIR[telemetrix]:-}" ]; then
  # Every optional feature off: the *_ENABLED switches at the top of the sketch removed, so it needs
  # none of the libraries they pull in (Servo, Wire, SPI, OneWire, DHTStable, Ultrasonic, AccelStepper).
  t=$(copy_sketch "${DIR[telemetrix]}/examples/Telemetrix4Arduino")
  sed -i -E 's/^#define (SPI|ONE_WIRE|DHT|SONAR|SERVO|STEPPERS|I2C)_ENABLED 1/\/\/ & (off)/' "$t/Telemetrix4Arduino.ino"
  if out=$(build Telemetrix4Arduino "$t" "${DIR[telemetrix]}"); then
    read -r f s <<<"$out"
    row "Telemetrix4Arduino $(ver "${DIR[telemetrix]}")" "Telemetrix4Arduino, every feature off" "$f" "$s"
  fi
fi
if [ -n "${DIR[rosserial]:-}" ]; then
  t=$(copy_sketch "${DIR[rosserial]}/examples/HelloWorld")
  if out=$(build rosserial "$t" "${DIR[rosserial]}"); then
    read -r f s <<<"$out"
    row "rosserial $(ver "${DIR[rosserial]}")" HelloWorld "$f" "$s"
  fi
fi
if [ -n "${DIR[firmata]:-}" ]; then
  [ -n "${DIR[servo]:-}" ] || { echo "peers: --firmata needs --servo (StandardFirmata includes Servo.h)" >&2; exit 2; }
  if out=$(build StandardFirmata "${DIR[firmata]}/examples/StandardFirmata" "${DIR[firmata]}" "${DIR[servo]}"); then
    read -r f s <<<"$out"
    row "Firmata $(ver "${DIR[firmata]}")" StandardFirmata "$f" "$s"
  fi
fi

table() {
  echo "| library | sketch | flash | SRAM | flash over baseline | SRAM over baseline |"
  echo "| --- | --- | --- | --- | --- | --- |"
  echo "| (baseline) | extras/bench/SerialEcho | $bf | $bs | | |"
  for r in "${rows[@]}"; do echo "| ${r//|/ | } |"; done
}
{
  echo "### Peers on the Uno"
  echo
  echo "Measured by \`bash bench/peers.sh\` on $(date -u +%Y-%m-%d) with $(avr-gcc --version | head -1), Arduino AVR core"
  echo "$(dpkg-query -W -f='${Version}' arduino-core-avr 2>/dev/null || echo '?'): each library's published example,"
  echo "built like bench/footprint.sh builds Hubwire's (flash = .text + .data, SRAM = .data + .bss)."
  echo
  table
} >bench/PEERS.md
if [ $MD = 1 ]; then
  table
else
  printf '%-20s %-40s %6s %5s %7s %6s\n' library sketch flash SRAM +flash +SRAM
  printf '%-20s %-40s %6s %5s\n' baseline extras/bench/SerialEcho "$bf" "$bs"
  for r in "${rows[@]}"; do IFS='|' read -r a b c d e g <<<"$r"; printf '%-20s %-40s %6s %5s %7s %6s\n' "$a" "$b" "$c" "$d" "$e" "$g"; done
fi
