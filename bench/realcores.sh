#!/usr/bin/env bash
# Every example compiled (and, where the script links, linked and sized) against the real Arduino
# cores, with the real-core scripts (a folder of teensy41.sh, rp2040.sh, stm32-nucleo-f401re.sh,
# esp32c3.sh; in this project's shared area) and vendor core trees unpacked outside the repository.
# A board whose core folder is not given is skipped. Writes the size tables to bench/REALCORES.md
# (bench/report.py puts them into RESULTS.md).
#
#   bash bench/realcores.sh --scripts DIR [--teensy CORES] [--pico PICO] [--stm32 STM32 --cmsis6 CMSIS6]
#                           [--esp32 ESP32]
#
# The trees and commits each script expects are in its README. ESP32-C3 is compile only, and also
# compiles the ESP32-only examples under examples/ESP32/, with the include folders of the core's
# libraries they use (WiFi, ESPmDNS), as the Arduino builder adds them.
set -uo pipefail
cd "$(dirname "$0")/.."
ROOT=$(pwd)
declare -A DIR=()
while [ $# -gt 0 ]; do
  case $1 in
    --scripts|--teensy|--pico|--stm32|--cmsis6|--esp32)
      [ $# -ge 2 ] || { echo "realcores: $1 needs a folder" >&2; exit 2; }
      DIR[${1#--}]=$(realpath -e "$2") || exit 2; shift 2 ;;
    *) echo "realcores: unknown option $1 (see the header of $0)" >&2; exit 2 ;;
  esac
done
S=${DIR[scripts]:-}
[ -n "$S" ] || { echo "realcores: --scripts DIR is required" >&2; exit 2; }
OUT=$ROOT/build/realcores
mkdir -p "$OUT"
fail=0
md=$OUT/REALCORES.md
: >"$md"

# sizes LOG BOARD NOTE: a table of the SIZE lines (text/data/bss) and their growth over _Baseline.
sizes() {
  local log=$1
  awk '/^SIZE /{n=$2; sub(":", "", n); split($3, t, "="); split($4, d, "="); split($5, b, "=");
         if (n == "_Baseline") { bt=t[2]; bd=d[2]; bb=b[2]; next }
         rows[++k]=n; T[n]=t[2]; D[n]=d[2]; B[n]=b[2] }
       END { print "| example | text | data | bss | text over baseline | data + bss over baseline |";
             print "| --- | --- | --- | --- | --- | --- |";
             printf "| (baseline: Serial echo) | %d | %d | %d | | |\n", bt, bd, bb;
             for (i = 1; i <= k; i++) { n=rows[i];
               printf "| %s | %d | %d | %d | %+d | %+d |\n", n, T[n], D[n], B[n], T[n]-bt, D[n]+B[n]-bd-bb } }' "$log"
}

run() {  # NAME LOG COMMAND...
  local name=$1 log=$2
  shift 2
  echo "== $name" >&2
  if nice "$@" >"$log" 2>&1; then
    echo "realcores: $name OK" >&2
  else
    echo "realcores: $name FAILED (see $log)" >&2
    fail=1
  fi
}

if [ -n "${DIR[teensy]:-}" ]; then
  run teensy41 "$OUT/teensy41.log" bash "$S/teensy41.sh" "$ROOT" "${DIR[teensy]}" "$OUT/teensy41"
  {
    echo "### Teensy 4.1 (PaulStoffregen/cores, teensy4/, linked with imxrt1062_t41.ld)"
    echo
    echo "$(tail -1 "$OUT/teensy41.log"). Sizes from arm-none-eabi-size (text includes the flash copies of"
    echo "ITCM code and of .data). Teensy 4 copies .rodata into RAM (DTCM): the last column is what of"
    echo "Hubwire's sits in RAM as initialised data (avr-nm-style sum over .data symbols named hubwire or"
    echo "channels), its constants being in the flash section HUBWIRE_FLASH names (text.h)."
    echo
    sizes "$OUT/teensy41.log" | awk -v dir="$OUT/teensy41/ex" 'NR<=2{ if (NR==1) print $0 " Hubwire constants in RAM |"; else print $0 " --- |"; next }
      NR==3{print $0 " |"; next}
      { split($0, f, "|"); n=f[2]; gsub(/ /, "", n);
        cmd="arm-none-eabi-nm -C -S " dir "/" n "/" n ".elf | awk '\''$3 ~ /^[dD]$/ && /hubwire|channels/ {s += (\"0x\" $2) + 0} END {print s + 0}'\''";
        cmd | getline v; close(cmd); print $0 " " v " B |" }'
    echo
  } >>"$md"
fi
if [ -n "${DIR[pico]:-}" ]; then
  run rp2040 "$OUT/rp2040.log" bash "$S/rp2040.sh" "$ROOT" "${DIR[pico]}" "$OUT/rp2040" link
  { echo "### Raspberry Pi Pico (earlephilhower/arduino-pico, linked)"; echo; echo "$(tail -1 "$OUT/rp2040.log")."; echo
    sizes "$OUT/rp2040.log"; echo; } >>"$md"
fi
if [ -n "${DIR[stm32]:-}" ]; then
  [ -n "${DIR[cmsis6]:-}" ] || { echo "realcores: --stm32 needs --cmsis6" >&2; exit 2; }
  run stm32 "$OUT/stm32.log" bash "$S/stm32-nucleo-f401re.sh" "$ROOT" "${DIR[stm32]}" "${DIR[cmsis6]}" "$OUT/stm32"
  { echo "### STM32 Nucleo-F401RE (stm32duino/Arduino_Core_STM32, linked)"; echo; echo "$(tail -1 "$OUT/stm32.log")."; echo
    sizes "$OUT/stm32.log"; echo; } >>"$md"
fi
if [ -n "${DIR[esp32]:-}" ]; then
  # A view of the project whose examples/ also holds the ESP32-only sketches, one level deep as the
  # script expects, and a compiler that adds the core libraries' include folders.
  view=$OUT/esp32-view
  rm -rf "$view"
  mkdir -p "$view/examples"
  ln -s "$ROOT/src" "$view/src"
  for d in "$ROOT"/examples/*/ "$ROOT"/examples/ESP32/*/; do
    [ -f "$d/$(basename "$d").ino" ] && ln -s "$d" "$view/examples/$(basename "$d")"
  done
  cat >"$OUT/esp32-cxx" <<CXX
#!/bin/sh
exec riscv64-unknown-elf-g++ "\$@" -I"${DIR[esp32]}/libraries/WiFi/src" -I"${DIR[esp32]}/libraries/ESPmDNS/src"
CXX
  chmod +x "$OUT/esp32-cxx"
  run esp32c3 "$OUT/esp32c3.log" env CXX="$OUT/esp32-cxx" bash "$S/esp32c3.sh" "$view" "${DIR[esp32]}" "$OUT/esp32c3"
  { echo "### ESP32-C3 (arduino-esp32 2.0.14 from PlatformIO's framework-arduinoespressif32, compile only)"; echo
    echo "$(tail -1 "$OUT/esp32c3.log"): every example, and examples/ESP32/WiFiHub (WiFi, ESPmDNS), compiled with"
    echo "-Wall -Werror=all -Wextra: $(grep -c '^+ \[' "$OUT/esp32c3.log") sketches. Not linked (the script's Debian RISC-V"
    echo "compiler stands in for Espressif's), so no sizes."; echo; } >>"$md"
fi
cp "$md" bench/REALCORES.md
cat bench/REALCORES.md
exit $fail
