#!/usr/bin/env bash
# Uno flash/SRAM/heap of the peers over the Serial-echo baseline, built with the same toolchain and
# builder as bench/footprint.sh (arduino-builder, avr-gcc, Arduino AVR core): for each peer its
# published example, and beside it a sketch of Minimal's shape written with that library
# (extras/bench/peers/, what each does and lacks in its README.md), with Hubwire's examples/Minimal
# built the way bench/footprint.sh builds it. The peers' sources are not part of this repository:
# pass the folders holding them (a clone or an unpacked archive of each public repository), one by
# one or all under one folder; a peer whose folder is not given is skipped.
#
#   bash bench/peers.sh [--sources DIR] [--packetserial DIR] [--serialtransfer DIR] [--telemetrix DIR]
#                       [--rosserial DIR] [--firmata DIR --servo DIR] [--markdown] [--check]
#
#   --sources DIR: DIR/PacketSerial, DIR/SerialTransfer, DIR/Telemetrix4Arduino,
#           DIR/rosserial_arduino_lib, DIR/arduino (Firmata), DIR/Servo, each where it exists (what
#           `make bench` passes from PEERS_SRC)
#   DIR for --packetserial  github.com/bakercp/PacketSerial            (examples/PacketSerialReverseEcho)
#           --serialtransfer github.com/PowerBroker2/SerialTransfer     (examples/uart_tx_data: framing only, no prints)
#           --telemetrix    github.com/MrYsLab/Telemetrix4Arduino       (its sketch, every *_ENABLED off)
#           --rosserial     github.com/frankjoshua/rosserial_arduino_lib (examples/HelloWorld; the
#                           Library Manager's generated ros_lib, which ros-drivers/rosserial only builds
#                           inside a ROS workspace)
#           --firmata       github.com/firmata/arduino                  (examples/StandardFirmata)
#           --servo         github.com/arduino-libraries/Servo          (StandardFirmata includes it)
#
# Prints one row per sketch: flash and static SRAM (avr-size -A: .text+.data, .data+.bss), both
# over extras/bench/SerialEcho, and the heap taken at start (bench/heap.c: malloc's break after 2 s
# in simavr; "none" when malloc is not linked). --markdown prints the rows as a Markdown table;
# either way the table goes to bench/PEERS.md as well (bench/report.py puts it into RESULTS.md).
# --check: then run bench/peers_check.py, which drives each sketch of Minimal's shape on the
# simulated Uno (make simuno) to see that it does what extras/bench/peers/README.md says.
set -euo pipefail
cd "$(dirname "$0")/.."
declare -A DIR=()
MD=0
CHECK=0
while [ $# -gt 0 ]; do
  case $1 in
    --packetserial|--serialtransfer|--telemetrix|--rosserial|--firmata|--servo)
      [ $# -ge 2 ] || { echo "peers: $1 needs a folder" >&2; exit 2; }
      DIR[${1#--}]=$(realpath -e "$2"); shift 2 ;;
    --sources)
      [ $# -ge 2 ] || { echo "peers: $1 needs a folder" >&2; exit 2; }
      src=$(realpath -e "$2"); shift 2
      for pair in packetserial:PacketSerial serialtransfer:SerialTransfer telemetrix:Telemetrix4Arduino \
          rosserial:rosserial_arduino_lib firmata:arduino servo:Servo; do
        [ -d "$src/${pair#*:}" ] && DIR[${pair%%:*}]=$src/${pair#*:}
      done ;;
    --markdown) MD=1; shift ;;
    --check) CHECK=1; shift ;;
    *) echo "peers: unknown option $1 (see the header of $0)" >&2; exit 2 ;;
  esac
done
OUT=$(realpath -m "${BUILD:-build}/peers")  # BUILD: another build folder, as make BUILD=... gives
WORK=$(mktemp -d "${TMPDIR:-/tmp}/hubwire-peers.XXXXXX")
trap 'rm -rf "$WORK"' EXIT
mkdir -p "$OUT"
SHAPE=extras/bench/peers  # the sketches of Minimal's shape

# The heap meter; without libsimavr-dev (make setup installs it) the heap column says "?".
HEAP=$OUT/heap
if ! cc -I/usr/include/simavr -std=gnu99 -O2 -o "$HEAP" bench/heap.c -lsimavr -lsimavrparts -lelf \
    -lpthread -lutil 2>"$OUT/heap.log"; then
  echo "peers: bench/heap.c did not build (see $OUT/heap.log): no heap figures" >&2
  HEAP=""
fi

# heap ELF -> bytes malloc took at start, "none" when malloc is not linked, "?" when not measured.
heap() {
  local brk start
  brk=$(avr-nm "$1" | awk '$3=="__brkval"{print $1}')
  start=$(avr-nm "$1" | awk '$3=="__heap_start"{print $1}')
  if ! avr-nm "$1" | grep -qw malloc; then echo none
  elif [ -z "$HEAP" ] || [ -z "$brk" ] || [ -z "$start" ]; then echo "?"
  else "$HEAP" "$1" "$brk" "$start" 2>/dev/null | tail -1 || echo "?"
  fi
}

# sizes ELF -> "flash sram heap"
sizes() {
  avr-size -A "$1" | awk '$1==".text"{t=$2} $1==".data"{d=$2} $1==".bss"{b=$2} END{printf "%d %d ", t+d, d+b}'
  heap "$1"
}

# build NAME SKETCH_DIR [LIBRARY_DIR...] -> "flash sram heap"; the libraries are linked into a
# private folder, so nothing else installed on the machine is picked up.
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
  sizes "$OUT/$name/$(basename "$sketch").ino.elf"
}

# A copy of a sketch folder under WORK (the .ino renamed after its folder when it is a .pde).
copy_sketch() {
  local src=$1 dst=$WORK/sketches/$(basename "$1")
  mkdir -p "$dst"
  cp -r "$src"/. "$dst"/
  for f in "$dst"/*.pde; do [ -e "$f" ] && mv "$f" "${f%.pde}.ino"; done
  echo "$dst"
}

read -r bf bs bh < <(build baseline extras/bench/SerialEcho)
rows=()
ver() { sed -n 's/^version=//p' "$1/library.properties" 2>/dev/null | head -1 | tr -d '\r'; }
row() {  # library sketch "flash sram heap"
  local f s h
  read -r f s h <<<"$3"
  rows+=("$1|$2|$f|$s|$h|+$((f - bf))|+$((s - bs))")
}
# Hubwire's own row, built as bench/footprint.sh builds the examples.
bash tools/arduino/build-sketch.sh examples/Minimal arduino:avr:uno "$OUT/Minimal" >/dev/null
row "Hubwire $(ver .)" "examples/Minimal" "$(sizes "$OUT/Minimal/Minimal.ino.elf")"

if [ -n "${DIR[packetserial]:-}" ]; then
  d=${DIR[packetserial]}
  out=$(build PacketSerial "$d/examples/PacketSerialReverseEcho" "$d") && row "PacketSerial $(ver "$d")" PacketSerialReverseEcho "$out"
  out=$(build PacketSerialMinimal "$SHAPE/PacketSerialMinimal" "$d") && row "PacketSerial $(ver "$d")" "Minimal's shape: $SHAPE/PacketSerialMinimal" "$out"
fi
if [ -n "${DIR[serialtransfer]:-}" ]; then
  d=${DIR[serialtransfer]}
  # It reads Serial1 (a Mega's second port); the Uno's one port is Serial.
  t=$(copy_sketch "$d/examples/uart_tx_data")
  sed -i 's/\bSerial1\b/Serial/g' "$t/uart_tx_data.ino"
  out=$(build SerialTransfer "$t" "$d") && row "SerialTransfer $(ver "$d")" uart_tx_data "$out"
  out=$(build SerialTransferMinimal "$SHAPE/SerialTransferMinimal" "$d") && row "SerialTransfer $(ver "$d")" "Minimal's shape: $SHAPE/SerialTransferMinimal" "$out"
fi
if [ -n "${DIR[telemetrix]:-}" ]; then
  d=${DIR[telemetrix]}
  # Every optional feature off: the *_ENABLED switches at the top of the sketch removed, so it needs
  # none of the libraries they pull in (Servo, Wire, SPI, OneWire, DHTStable, Ultrasonic, AccelStepper).
  # The library is this one sketch, with no API to write another against: Minimal's shape is this
  # firmware driven by the host (extras/bench/peers/README.md), so its second row is the same build.
  t=$(copy_sketch "$d/examples/Telemetrix4Arduino")
  sed -i -E 's/^#define (SPI|ONE_WIRE|DHT|SONAR|SERVO|STEPPERS|I2C)_ENABLED 1/\/\/ & (off)/' "$t/Telemetrix4Arduino.ino"
  if out=$(build Telemetrix4Arduino "$t" "$d"); then
    row "Telemetrix4Arduino $(ver "$d")" "Telemetrix4Arduino, every feature off" "$out"
    row "Telemetrix4Arduino $(ver "$d")" "Minimal's shape: the same firmware, driven by the host" "$out"
  fi
fi
if [ -n "${DIR[rosserial]:-}" ]; then
  d=${DIR[rosserial]}
  t=$(copy_sketch "$d/examples/HelloWorld")
  out=$(build rosserial "$t" "$d") && row "rosserial $(ver "$d")" HelloWorld "$out"
  out=$(build RosserialMinimal "$SHAPE/RosserialMinimal" "$d") && row "rosserial $(ver "$d")" "Minimal's shape: $SHAPE/RosserialMinimal" "$out"
fi
if [ -n "${DIR[firmata]:-}" ]; then
  d=${DIR[firmata]}
  [ -n "${DIR[servo]:-}" ] || { echo "peers: --firmata needs --servo (StandardFirmata includes Servo.h)" >&2; exit 2; }
  out=$(build StandardFirmata "$d/examples/StandardFirmata" "$d" "${DIR[servo]}") && row "Firmata $(ver "$d")" StandardFirmata "$out"
  out=$(build FirmataMinimal "$SHAPE/FirmataMinimal" "$d") && row "Firmata $(ver "$d")" "Minimal's shape: $SHAPE/FirmataMinimal" "$out"
fi

table() {
  echo "| library | sketch | flash | SRAM | heap at start | flash over baseline | SRAM over baseline |"
  echo "| --- | --- | --- | --- | --- | --- | --- |"
  echo "| (baseline) | extras/bench/SerialEcho | $bf | $bs | $bh | | |"
  for r in "${rows[@]}"; do echo "| ${r//|/ | } |"; done
}
{
  echo "### Peers on the Uno"
  echo
  echo "Measured by \`bash bench/peers.sh\` on $(date -u +%Y-%m-%d) with $(avr-gcc --version | head -1), Arduino"
  echo "AVR core $(dpkg-query -W -f='${Version}' arduino-core-avr 2>/dev/null || echo '?'): for each peer its published example, then a sketch"
  echo "of Minimal's shape written with it ($SHAPE/), all built like bench/footprint.sh builds Hubwire's"
  echo "(flash = .text + .data, SRAM = .data + .bss). Heap at start: what malloc had taken (its block"
  echo "headers included) after 2 s in simavr, not counted in SRAM; none: malloc is not linked."
  echo
  table
  echo
  sed -n '/^## /,$p' "$SHAPE/README.md" | sed 's/^## /#### /'
} >bench/PEERS.md
if [ $MD = 1 ]; then
  table
else
  printf '%-20s %-56s %6s %5s %5s %7s %6s\n' library sketch flash SRAM heap +flash +SRAM
  printf '%-20s %-56s %6s %5s %5s\n' baseline extras/bench/SerialEcho "$bf" "$bs" "$bh"
  for r in "${rows[@]}"; do IFS='|' read -r a b c d e g h <<<"$r"; printf '%-20s %-56s %6s %5s %5s %7s %6s\n' "$a" "$b" "$c" "$d" "$e" "$g" "$h"; done
fi
if [ $CHECK = 1 ]; then
  .venv/bin/python bench/peers_check.py "$OUT" "${BUILD:-build}/simuno/simuno"
fi
