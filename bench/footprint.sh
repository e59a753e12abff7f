#!/usr/bin/env bash
# Uno flash/SRAM of the examples over a sketch that only echoes Serial bytes (avr-size on
# arduino-builder output), and whether malloc is linked at all. Writes bench/FOOTPRINT.md.
#
#   bash bench/footprint.sh
set -euo pipefail
cd "$(dirname "$0")/.."
out=${BUILD:-build}/footprint  # BUILD: another build folder, as make BUILD=... gives
size_of() {  # sketch dir -> "flash sram heap"
  local dir=$1 name
  name=$(basename "$dir")
  rm -rf "$out/$name"
  bash tools/arduino/build-sketch.sh "$dir" arduino:avr:uno "$out/$name" >/dev/null
  local elf=$out/$name/$name.ino.elf
  local text data bss heap
  text=$(avr-size -A "$elf" | awk '$1==".text"{print $2}')
  data=$(avr-size -A "$elf" | awk '$1==".data"{print $2}')
  bss=$(avr-size -A "$elf" | awk '$1==".bss"{print $2}')
  if avr-nm "$elf" | grep -qw malloc; then heap=yes; else heap=no; fi
  echo "$((text + data)) $((data + bss)) $heap"
}
read -r bf bs _ < <(size_of extras/bench/SerialEcho)
{
  echo "# Footprint on the Uno (ATmega328P)"
  echo
  echo "Measured by \`bash bench/footprint.sh\` with $(avr-gcc --version | head -1), Arduino AVR core"
  echo "$(dpkg-query -W -f='${Version}' arduino-core-avr 2>/dev/null || echo '?'), on $(date -u +%Y-%m-%d)."
  echo "flash = .text + .data, static SRAM = .data + .bss (avr-size -A). Baseline: extras/bench/SerialEcho"
  echo "(flash $bf B, SRAM $bs B). Default settings (src/hubwire/config.h)."
  echo
  echo "| sketch | flash | SRAM | flash over baseline | SRAM over baseline | target flash / SRAM | flash | SRAM | malloc linked |"
  echo "| --- | --- | --- | --- | --- | --- | --- | --- | --- |"
  # Targets for Minimal and Rover (issue 21): flash below SerialTransfer's for Minimal, Rover's own
  # code (tone(), analogWrite(), float stand-ins: ~2.3 KB) on top for Rover; SRAM no higher than
  # before that work. The focused examples show the fixed cost apart from what each channel adds.
  for dir in examples/*/; do
    name=$(basename "$dir")
    [ -f "$dir/$name.ino" ] || continue  # examples/ESP32/: not for the Uno
    case $name in
      Minimal) tf=3500 ts=176 ;;
      Rover) tf=8500 ts=249 ;;
      *) tf="" ts="" ;;
    esac
    read -r f r heap < <(size_of "examples/$name")
    df=$((f - bf)); ds=$((r - bs))
    if [ -z "$tf" ]; then
      echo "| $name | $f | $r | +$df | +$ds | none | - | - | $heap |"
      continue
    fi
    vf="met"; vs="met"
    if [ $df -gt "$tf" ]; then vf="**missed**"; fi
    if [ $ds -gt "$ts" ]; then vs="**missed**"; fi
    echo "| $name | $f | $r | +$df | +$ds | +$tf / +$ts | $vf | $vs | $heap |"
  done
  # What talking to the hub's own channels costs (docs/PROTOCOL.md 10): the Thermostat example against
  # the same sketch with the setpoint, report, alarm and mode kept on the board.
  read -r tf ts _ < <(size_of examples/Thermostat)
  read -r lf ls _ < <(size_of extras/bench/ThermostatLocal)
  echo
  echo "Hub channels (examples/Thermostat: remote() read and written, remoteAction(), remoteEvent(), with"
  echo "their calls) over extras/bench/ThermostatLocal (the same sketch without them): flash $tf - $lf ="
  echo "+$((tf - lf)) B, static SRAM $ts - $ls = +$((ts - ls)) B (the hub link: queue of HUBWIRE_HUB_QUEUE"
  echo "requests, bind status, health). A sketch that declares no hub channel links none of the hub link"
  echo "(no code of session/hub_link.cpp, none of its RAM)."
} > bench/FOOTPRINT.md
cat bench/FOOTPRINT.md
