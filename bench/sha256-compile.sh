#!/usr/bin/env bash
# What the compile-time SHA-256 (src/hubwire/wire/sha256.h) costs the compiler: wall time and peak
# memory of one translation unit that digests a 600-byte and a 16 KiB text, for avr-g++ (as the
# Arduino IDE runs it: -std=gnu++11 -Os, no raised limits), g++ and clang++ (those found on PATH).
# Each unit static_asserts the digest against Python's hashlib, so every compiler is also checked
# (AVR's 16-bit size_t included). Then, for AVR, what lands in the object: only the 16 digest bytes.
#
#   bash bench/sha256-compile.sh        prints a Markdown table; files in build/sha256-compile/
set -euo pipefail
cd "$(dirname "$0")/.."
out=build/sha256-compile
mkdir -p "$out"

# unit LENGTH -> $out/digest_LENGTH.cpp: the text is a string literal, read through a constexpr array.
unit() {
  python3 - "$1" "$out/digest_$1.cpp" <<'EOF'
import hashlib, sys
n, path = int(sys.argv[1]), sys.argv[2]
alphabet = '{"name":[0-9],:.abcdefghijklmnopqrstuvwxyz}'
text = ''.join(alphabet[(i * 7 + i // 61) % len(alphabet)] for i in range(n))
d = hashlib.sha256(text.encode()).digest()
lines = '\n'.join('    "%s"' % text[i:i + 100].replace('\\', '\\\\').replace('"', '\\"')
                  for i in range(0, n, 100)) or '    ""'
open(path, 'w').write(f'''#include "hubwire/wire/sha256.h"
#if defined(__AVR__)
#include <avr/pgmspace.h>
#define FLASH PROGMEM
#else
#define FLASH
#endif
constexpr char kText[] =
{lines};
struct Text {{
  static constexpr size_t length() {{ return sizeof(kText) - 1; }}
  static constexpr char at(size_t i) {{ return kText[i]; }}
}};
extern const hubwire::sha256::Digest<16> kDigest FLASH;
const hubwire::sha256::Digest<16> kDigest FLASH = hubwire::sha256::digest<Text, 16>();
static_assert(Text::length() == {n}, "length");
static_assert(hubwire::sha256::digest<Text>().bytes[0] == {d[0]} && hubwire::sha256::digest<Text>().bytes[31] == {d[31]},
              "SHA-256 {d.hex()}");
''')
EOF
}

# measure LABEL CMD... -> "seconds, peak MiB", or "failed"
measure() {
  local label=$1
  shift
  if /usr/bin/time -f "%e %M" -o "$out/time.txt" "$@" >"$out/$label.log" 2>&1; then
    awk '{printf "%s s, %d MiB", $1, $2 / 1024}' "$out/time.txt"
  else
    echo "failed (see $out/$label.log)"
  fi
}

echo "| compiler | empty text (1 block) | 600 B | 16 KiB |"
echo "| --- | --- | --- | --- |"
unit 0
unit 600
unit 16384
row() {  # name, then the compile command without the source file
  local name=$1
  shift
  command -v "$1" >/dev/null || { echo "| $name | not installed | | |"; return; }
  local log=${1##*/}
  echo "| $name | $(measure "$log-0" "$@" "$out/digest_0.cpp") | $(measure "$log-600" "$@" "$out/digest_600.cpp") |" \
    "$(measure "$log-16384" "$@" "$out/digest_16384.cpp") |"
}
row "avr-g++ $(avr-g++ -dumpversion 2>/dev/null || true)" avr-g++ -std=gnu++11 -mmcu=atmega328p -Os -Isrc -c -o "$out/avr.o"
row "g++ $(g++ -dumpversion 2>/dev/null || true)" g++ -std=c++11 -O2 -Isrc -c -o "$out/host.o"
row "clang++ $(clang++ -dumpversion 2>/dev/null || true)" clang++ -std=c++11 -O2 -Isrc -c -o "$out/clang.o"
row "arm-none-eabi-g++ $(arm-none-eabi-g++ -dumpversion 2>/dev/null || true)" arm-none-eabi-g++ -std=gnu++11 -mcpu=cortex-m0 -mthumb -Os -Isrc -c -o "$out/arm.o"

# The AVR object of the 600-byte unit: no code, no data, the digest's 16 bytes in flash.
avr-g++ -std=gnu++11 -mmcu=atmega328p -Os -Isrc -c -o "$out/avr600.o" "$out/digest_600.cpp"
echo
echo "avr-size -A of the 600-byte unit (atmega328p, -Os):"
avr-size -A "$out/avr600.o" | awk '$1 ~ /^\.(text|data|bss|rodata|progmem)/'
echo "functions in it (avr-objdump -d):"
avr-objdump -d "$out/avr600.o" | grep -c '>:$' || true
echo "kDigest:"
avr-objdump -s -j .progmem.data "$out/avr600.o" | tail -n +5
