#!/usr/bin/env bash
# What building the descriptor (its JSON, FNV-1a hash and SHA-256 digest, the channel records: all
# worked out by the compiler, src/hubwire/channels/descriptor_text.h and tables.h) costs the
# compiler: CPU time and peak memory of one sketch's translation unit, compiled alone, for N float
# channels `expose(...).writable().range(-1.0f, 1.0f).unit("m/s").describe(D characters)`
# (bench/descriptor_sketch.py). avr-g++ compiles it as the Arduino IDE does for the Uno (the AVR
# platform's flags, -flto included); g++ as the emulator is built (-std=c++11 -O2 -g). The peer
# row is the same content as a hand-written descriptor string in flash (a framing-only library).
# Writes bench/DESCRIPTOR-COMPILE.md, with the targets of issue 32 marked met or missed.
#
#   bash bench/descriptor-compile.sh [TREE]   TREE: a source tree to measure (default: this one), e.g.
#                                             an older commit's `git archive` to compare against
#   bash bench/descriptor-compile.sh --check  (make test-compile-cost) only the 32-channel sketch with
#                                             60-character descriptions, for the Uno and with g++ (as
#                                             the emulator and the boards of a modern GCC build it),
#                                             each under a 256 MiB `ulimit -v`: fails when building it
#                                             needs more
#
# Each compile runs under `ulimit -v` of LIMIT_MIB (default 4096): a tree that needs more is
# reported as over the limit instead of pressing a shared machine into swap.
set -euo pipefail
cd "$(dirname "$0")/.."
here=$(pwd)
check=0
if [ "${1:-}" = --check ]; then check=1; shift; fi
tree=$(realpath "${1:-.}")
out=$(realpath -m "${BUILD:-build}/descriptor-compile")
mkdir -p "$out"
[ -x /usr/bin/time ] || { echo "descriptor-compile: /usr/bin/time is missing: apt-get install time (bash tools/setup.sh does)" >&2; exit 1; }
core=/usr/share/arduino/hardware/arduino/avr

# The AVR platform's compile recipe for a .cpp (platform.txt: compiler.cpp.flags and the Uno's
# defines), with the one define Debian's avr-gcc 5.4 needs (docs: TOOLCHAIN).
avr=(avr-g++ -c -g -Os -w -std=gnu++11 -fpermissive -fno-exceptions -ffunction-sections -fdata-sections
     -fno-threadsafe-statics -Wno-error=narrowing -flto -mmcu=atmega328p -DF_CPU=16000000L -DARDUINO=10807
     -DARDUINO_AVR_UNO -DARDUINO_ARCH_AVR -DDECIMAL_DIG=__DECIMAL_DIG__ -I"$core/cores/arduino"
     -I"$core/variants/standard")
host=(g++ -c -std=c++11 -O2 -g -DNDEBUG -DHUBWIRE_PORT_HEADER='"hubwire/port_arduino.h"'
      -I"$tree/tools/emulator/arduino")

# measure LABEL CMD... -> "CPU s|peak MiB|status": CPU = user + system (what to compare on a busy
# machine). status: ok, "refused" (the library's own compile error: a descriptor over 16 KiB, found
# from the parts' lengths before the text is built) or failed.
limit=${LIMIT_MIB:-4096}
measure() {
  local label=$1 status=ok
  shift
  (ulimit -v $((limit * 1024)) && exec /usr/bin/time -f "%U %S %M" -o "$out/$label.time" "$@") >"$out/$label.log" 2>&1 ||
    status=failed
  if [ $status = failed ] && grep -q "descriptor longer than the 16 KiB" "$out/$label.log"; then status=refused; fi
  if [ $status = failed ] && grep -q "memory exhausted\|out of memory\|Cannot allocate" "$out/$label.log"; then status=limit; fi
  tail -n 1 "$out/$label.time" | awk -v s=$status '{printf "%.2f|%d|%s", $1 + $2, $3 / 1024, s}' # after any "exited" line
}
sketch() {  # N D|bare [--peer] -> path of the generated unit
  local f=$out/sketch-$1-$2${3:-}.cpp flags=()
  if [ "$2" = bare ]; then flags=(--bare); fi
  python3 bench/descriptor_sketch.py "$1" "${2/bare/0}" "${flags[@]}" "${@:3}" >"$f"
  echo "$f"
}
cell() {  # "CPU|MiB|status" -> table cell
  IFS='|' read -r c m s <<<"$1"
  case $s in
    ok) echo "$m MiB / $c s" ;;
    refused) echo "$m MiB / $c s (refused: over 16 KiB, before it is built)" ;;
    limit) echo "over $limit MiB (stopped after $c s)" ;;
    *) echo "failed" ;;
  esac
}
verdict() {  # "CPU|MiB|status" max-MiB max-CPU(or -) -> met / **missed**
  IFS='|' read -r c m s <<<"$1"
  if [ "$s" = failed ] || [ "$s" = limit ]; then echo "**missed**"; return; fi
  if [ "$m" -le "$2" ] && { [ "$3" = - ] || awk -v c="$c" -v t="$3" 'BEGIN{exit !(c <= t)}'; }; then
    if [ "$s" = refused ]; then echo "met, as a refusal"; else echo met; fi
  else
    echo "**missed**"
  fi
}
json_bytes() {  # N D|bare -> the descriptor's length (the peer sketch's string is the same JSON)
  local bare=False
  if [ "$2" = bare ]; then bare=True; fi
  python3 -c "import sys; sys.path.insert(0, 'bench'); import descriptor_sketch as s; print(len(s.descriptor($1, ${2/bare/0}, $bare)))"
}
# More channels than the default 32 need HUBWIRE_MAX_CHANNELS raised (config.h), as a sketch would.
max() { if [ "$1" -gt 32 ]; then echo -DHUBWIRE_MAX_CHANNELS=254; else echo -DHUBWIRE_MAX_CHANNELS=32; fi; }
avr_unit() { measure "avr-$1-$2" "${avr[@]}" "$(max "$1")" -I"$tree/src" -x c++ "$(sketch "$1" "$2")" -o "$out/avr.o"; }
host_unit() { measure "host-$1-$2" "${host[@]}" "$(max "$1")" -I"$tree/src" -x c++ "$(sketch "$1" "$2")" -o "$out/host.o"; }
peer_unit() { measure "peer-$1-$2" "${avr[@]}" -x c++ "$(sketch "$1" "$2" --peer)" -o "$out/peer.o"; }

if [ $check = 1 ]; then
  limit=256
  for which in avr host; do
    r=$(${which}_unit 32 60)
    IFS='|' read -r c m st <<<"$r"
    if [ "$st" != ok ]; then
      echo "descriptor-compile: 32 channels with 60-character descriptions do not build ($which) in $limit MiB" \
        "(see $out/$which-32-60.log)" >&2
      exit 1
    fi
    echo "descriptor-compile: 32 channels with 60-character descriptions build ($which) in $m MiB, $c s CPU" \
      "(limit $limit MiB of address space)"
  done
  exit 0
fi

declare -A A H P
rows=("5 8" "5 60" "20 8" "20 60" "32 8" "32 60" "80 8" "80 60" "254 bare" "254 60")
for r in "${rows[@]}"; do
  read -r n d <<<"$r"
  A[$n-$d]=$(avr_unit "$n" "$d")
  H[$n-$d]=$(host_unit "$n" "$d")
  P[$n-$d]=$(peer_unit "$n" "$d")
  echo "descriptor-compile: $n channels, $d-character descriptions: avr ${A[$n-$d]}, g++ ${H[$n-$d]}, peer ${P[$n-$d]}" >&2
done
sweep=(0 60 120 180 250)
declare -A S
for d in "${sweep[@]}"; do
  if [ -n "${A[20-$d]:-}" ]; then S[$d]=${A[20-$d]}; else S[$d]=$(avr_unit 20 "$d"); fi
done

# The same 32 x 60 compile with less address space: GCC collects its garbage sooner (below).
lows=(200 150 128 112)
declare -A L
for l in "${lows[@]}"; do L[$l]=$(limit=$l avr_unit 32 60); done
# ... and with GCC told to collect at every point it may (what the compile really holds at once).
eager_flags=(--param ggc-min-heapsize=4096 --param ggc-min-expand=0)
eager=$(measure avr-32-60-eager "${avr[@]}" "${eager_flags[@]}" "$(max 32)" -I"$tree/src" -x c++ "$(sketch 32 60)" -o "$out/avr.o")
# With -Q GCC names each function it compiles and prints "{GC before -> after}" at each collection:
# the heap allocated between two of the macro's collection points is what that step cost.
"${avr[@]}" "${eager_flags[@]}" -Q "$(max 32)" -I"$tree/src" -x c++ "$(sketch 32 60)" -o "$out/avr.o" 2>"$out/avr-32-60-steps.log"
steps=$(python3 - "$out/avr-32-60-steps.log" <<'PY'
import re, sys
text = open(sys.argv[1], errors="replace").read()
parts = re.split(r"\{GC (\d+)k -> (\d+)k\}", text)
kinds = {"headers, declarations and their report": 0.0, "the parts' lengths and the characters (TextStep)": 0.0,
         "FNV-1a (HashStep)": 0.0, "SHA-256 (DigestStep)": 0.0, "the flash tables and their checks": 0.0}
names = list(kinds)
kind, prev = 0, 0
for i in range((len(parts) - 1) // 3):
    before, after = int(parts[3 * i + 1]), int(parts[3 * i + 2])
    kinds[names[kind]] += (before - prev) / 1024
    prev = after
    step = re.findall(r"hubwire_collect_(reported|TextStep8|HashStep8|DigestStep8)\(\)", parts[3 * i][-300:])
    if step:
        kind = min(kind + 1, len(names) - 1)
print(", ".join(f"{k} {v:.0f}" for k, v in kinds.items()))
PY
)

{
  echo "# What the descriptor costs the compiler"
  echo
  echo "Measured by \`bash bench/descriptor-compile.sh\` (\`make bench\` runs it) on $(date -u +%Y-%m-%d): one sketch's"
  echo "translation unit compiled alone under \`/usr/bin/time\`, peak memory (maximum resident set) and CPU"
  echo "time (user + system; the machine is shared, so wall time says little). The sketch: N float channels"
  echo "\`expose(\"v000\", v[0]).writable().range(-1.0f, 1.0f).unit(\"m/s\").describe(...)\` with descriptions of the"
  echo "given length (bench/descriptor_sketch.py). avr-g++ $(avr-g++ -dumpversion) with the Arduino AVR platform's flags for the"
  echo "Uno (-Os -flto -std=gnu++11 -fpermissive ...); g++ $(g++ -dumpversion) as the emulator is built (-O2 -g). Peer: the"
  echo "same JSON as a hand-written string in PROGMEM, sent on request (a framing-only library), same"
  echo "avr-g++ flags. A descriptor over the 16 KiB a hub accepts is refused with a compile error, found from"
  echo "its parts' lengths before its text, hash and digest are worked out (254 channels with 60-character"
  echo "descriptions: 34 KB, which no AVR could hold either: avr-gcc makes no object over 32 KiB): its row"
  echo "is the cost of that refusal."
  echo
  echo "## Targets (issue 32)"
  echo
  echo "| target | measured | verdict |"
  echo "| --- | --- | --- |"
  echo "| 32 channels, 60-character descriptions, avr-g++: at most 150 MiB and 1.5 s CPU | $(cell "${A[32-60]}") | $(verdict "${A[32-60]}" 150 1.5) |"
  echo "| 254 channels, 60-character descriptions, avr-g++: at most 600 MiB | $(cell "${A[254-60]}") | $(verdict "${A[254-60]}" 600 -) |"
  echo "| (no target) 32 channels, 60-character descriptions, g++ $(g++ -dumpversion) (before: 1884 MiB / 17.27 s) | $(cell "${H[32-60]}") | - |"
  echo
  echo "## Channels x description length"
  echo
  echo "Description \"bare\": \`expose(\"v000\", v[0])\` alone, no options (254 such channels fit 16 KiB)."
  echo
  echo "| channels | description | JSON bytes | avr-g++ | g++ | peer (avr-g++) |"
  echo "| --- | --- | --- | --- | --- | --- |"
  for r in "${rows[@]}"; do
    read -r n d <<<"$r"
    echo "| $n | $d | $(json_bytes "$n" "$d") | $(cell "${A[$n-$d]}") | $(cell "${H[$n-$d]}") | $(cell "${P[$n-$d]}") |"
  done
  echo
  echo "## 20 channels, description length alone (avr-g++)"
  echo
  echo "| description | JSON bytes | avr-g++ |"
  echo "| --- | --- | --- |"
  for d in "${sweep[@]}"; do echo "| $d | $(json_bytes 20 "$d") | $(cell "${S[$d]}") |"; done
  echo
  echo "## With less memory (avr-g++, 32 x 60)"
  echo
  echo "GCC collects its garbage only once its heap has grown past ggc-min-heapsize and then by"
  echo "ggc-min-expand percent: on a machine with 1 GB of RAM or more 128 MB and 100 %, so a compile that"
  echo "allocates less than 256 MB is never collected; with less RAM, or a limited address space (GCC reads"
  echo "RLIMIT_AS), both are smaller. So the peak above is what GCC keeps when memory is plentiful, not what"
  echo "the sketch needs. The same command, unchanged, under a smaller \`ulimit -v\` (as a container or a shell"
  echo "with a limit sets it):"
  echo
  echo "| address-space limit | avr-g++ 32 x 60 |"
  echo "| --- | --- |"
  echo "| $limit MiB (as above) | $(cell "${A[32-60]}") |"
  for l in "${lows[@]}"; do
    IFS='|' read -r c m s <<<"${L[$l]}"
    if [ "$s" = ok ]; then echo "| $l MiB | $m MiB / $c s |"; else echo "| $l MiB | does not build ($s) |"; fi
  done
  echo "| $limit MiB, GCC collecting at every point it may (\`--param ggc-min-heapsize=4096 --param ggc-min-expand=0\`, not an Arduino flag: what the compile holds at once) | $(cell "$eager") |"
  echo
  echo "The same flags with \`-Q\` print the heap before and after each collection and the functions"
  echo "compiled between, so the heap each step of HUBWIRE_CHANNELS allocates (steps.h) can be added up."
  echo "32 x 60, MB allocated (mostly garbage, which the eager collection above frees): $steps."
  cat <<'MD'

## Before this change (41b85b1, the same script)

| channels | description | JSON bytes | avr-g++ | g++ |
| --- | --- | --- | --- | --- |
| 5 | 8 | 431 | 45 MiB / 0.12 s | 156 MiB / 1.03 s |
| 5 | 60 | 691 | 52 MiB / 0.15 s | 339 MiB / 2.77 s |
| 20 | 8 | 1657 | 97 MiB / 0.30 s | 460 MiB / 3.74 s |
| 20 | 60 | 2697 | 128 MiB / 0.40 s | 1194 MiB / 10.55 s |
| 32 | 8 | 2641 | 141 MiB / 0.47 s | 706 MiB / 5.86 s |
| 32 | 60 | 4305 | 187 MiB / 0.66 s | 1884 MiB / 17.27 s |
| 80 | 8 | 6577 | 324 MiB / 1.45 s | 1707 MiB / 15.78 s |
| 80 | 60 | 10737 | 449 MiB / 2.23 s | over 4096 MiB (stopped after 37.48 s) |
| 254 | bare | 10078 | 805 MiB / 5.31 s | 758 MiB / 7.79 s |
| 254 | 60 | 34208 | 1505 MiB / 7.65 s (refused: over 16 KiB) | over 4096 MiB (stopped after 34.93 s) |

What changed it (src/hubwire/channels/): g++ from 10 on remembers only constexpr calls nested less
than 8 deep, so each character of an entry was found by a walk over the pieces and the text before
it: now each piece's lengths and texts are constants of their own (PieceConst, descriptor_text.h)
and a character takes two calls. Every template was named after the declaration list's type, which
spells all its declarations: g++ wrote that name into the debug information of each of thousands of
instantiations (at 254 channels, 547 MB of the 916 MB): the list now has a short type of the
sketch's own (HUBWIRE_CHANNELS' Sketch). avr-g++ 5.4 collects its garbage only between declarations,
and the whole descriptor was one: it is now worked out in 24 steps with a collection point after each
(steps.h), which caps what large sketches cost it (GCC collects only once its heap has grown well
past 128 MB, ggc-min-heapsize on a machine of 1 GB or more, so a 32-channel sketch does not gain). A descriptor over the hub's limit is
refused from its parts' lengths before it is built.

What did not help on avr-g++ 5.4 (which remembers every call, and keeps what each allocates until it
collects): the piece constants above (sixteen classes a channel cost it more than the calls they
save: 204 MiB for 32 x 60), the piece ends as constants instead of calls (190 MiB), or as template
arguments of one character function a channel (272 MiB), FNV-1a worked out from the words the digest
reads, or those words kept as arrays a part (no change), SHA-256 rounds with 9 arguments reading a
remembered message schedule (+7 %), or with their 24 words in one struct argument (+60 %).

Where avr-g++'s 186 MiB for 32 x 60 go (the macro's declarations compiled one more at a time):
24 MiB the Arduino and library headers, 20 the declarations, their checks and the channel records,
23 the pieces' lengths, 43 the characters (10 KB each: a few calls, each remembered with its
arguments), 8 the FNV-1a hash and 65 the SHA-256 digest (0.95 MB a 64-byte block, 64 calls of 24
arguments): what still misses the 150 MiB of the target.

## Then: avr-g++ 5.4, 32 x 60 from 186 to 166 MiB (d72eb4a, the same script)

What GCC 5 costs was measured piece by piece (a change, then 32 x 60 again): every constexpr call
it makes costs about 1 to 2 KB that it keeps (the call remembered, with a copy of each argument:
a round of 24 word arguments about 7 KB), and every operation it evaluates about 40 to 50 bytes, even
one whose value it has seen before (it remembers calls, not expressions). So what lowers it is fewer
calls with fewer arguments, not less arithmetic. Each step, in order (MiB for 32 x 60):

| step | avr-g++ 32 x 60 |
| --- | --- |
| before (d72eb4a) | 186 |
| a character's piece found by a binary search written out (four remembered piece starts asked, not fifteen) | 185 |
| FNV-1a written into the hash of a part, not a call of fnv1a() a character | 182 |
| a word of the digest's message read from the part in one call: no layer between the padding and the parts' tree, the tree's nodes reading their halves' words directly (sha256.h PaddedWord, descriptor_digest.h Parts) | 180 |
| the schedule's window passed as pairs of words in 64-bit parameters, even and odd rounds alternating, so that a pair passes on unchanged (16 or 17 parameters a round, not 24) | 176 |
| a 64-byte block read with one descent of the parts' tree where it lies in one part (Parts::block, GCC 5 only: g++ 12 paid 4 MiB more for it), not one descent a word | 169 |
| FNV-1a reading each character's remembered call itself, not through partChar() | 166 |

What did not help: a tree of eight subtrees a node instead of two (182: fewer levels, more calls
to find the subtree); each channel's entry built piece by piece, each piece's prefix, value and
suffix a pack read straight from its text (14 MiB less for the text, but the hashes then read the
arrays, which GCC 5 copies at each read or each call that is given one: 13 MiB more); those arrays
four characters to a word (185); FNV-1a 32 characters a call (169, and g++ 12 164); two rounds a call with the
working variables also in pairs (115 MiB for a 4.3 KB text alone against 67: the second round
evaluates the first one's results again, and evaluating costs memory even when the values are
known); Ch and Maj with fewer operations (no change); a character's piece and offset written into
its at() instead of asked of charOf() (175: the remembered calls asked again cost more than the one
call). The pairs cost g++ 12 about 2 MiB (137 to 139 for 32 x 60; 80 channels 2 to 4 MiB); avr-g++
254 bare channels, where it collects its garbage between steps, 376 became 379. What still misses the target, by
the same kind of measurement: the characters (at(), pieceOf() and charOf(): about 35 MiB), the
64 rounds a block (about 40), reading the message for them (8) and FNV-1a (5).

## Then: avr-g++ 5.4, 32 x 60 from 167 to 148 MiB (the same script)

Measured as above, a change and then 32 x 60 again (peak of three runs; the heap each macro step
allocates with GCC collecting at every point it may). What this showed: inside the channel
templates (ChannelPart, Parts, Decl), a constexpr function costs avr-g++ 5.4 at every call it works
out for all its arms, also those the call does not take (a free function of the same shape does
not: a test file of 2,000 calls with ten untaken calls in each cost nothing more). So a function
asked at every character, block or piece is kept small, and its rarer cases are functions of their
own. Each step, in order (MiB for 32 x 60):

| step | avr-g++ 32 x 60 |
| --- | --- |
| before (36a9843) | 167 |
| Decl::piece() as four functions of four pieces, not one of sixteen (the parts' lengths: 21.5 MB allocated, then 15.4) | 161 |
| a character's piece found from the previous character's (remembered: Chars::make() asks them in order), not by a search over the sixteen starts | 155 |
| a character asked with its own index (no call for its offset in the piece, pieceFrom() only past the previous character's piece), and a text's length without escapes in one walk (cx::plainLength: one call a character, not two) | 152 |
| ChannelPart::charIn() holding only the prefix and a value written as it is, the suffix and the worked-out values (numbers, access letters) in restIn(); a block across two parts (Parts::across), a value's length for numbers and for texts, and FNV-1a's last characters (fnvTail), each apart | 148 |

Where the 127 MB it still allocates go: 21 the headers, the declarations and their report, 14 the
parts' lengths, 31 the characters (7 KB each), 3 FNV-1a, 45 SHA-256 (64 rounds of 16 or 17
arguments a block) and 12 the tables after the digest (the records and the flash copies they point
to: 6). g++ 12 and clang are unchanged (139 and 122 MiB). avr-g++ for 254 bare channels, where it
collects between steps, 380 MiB became 325; the refusal of 254 x 60, 435 became 370.

What did not help: the pieces as eight functions of two (15.2 MB for the lengths, against 15.4 for
four of four); the lengths adding each piece's three parts in pieceStart() instead of calling
pieceLength() (14.4 MB, against 14.0); pieceFrom() asked at every character (the characters 36.2 MB,
against 34.5); charIn() written into at(), its piece asked again in each arm (35.8); the numbers'
characters asked of floatAt() and integerAt() from charIn() itself, skipping valueAt()'s Piece
argument (46.2: the larger function cost every character); a character read through a remembered
charAt(text, i) (35.1, against 34.4); the characters in three functions, prefix, value, rest (32.8,
against 31.7); SHA-256's round constants as eight functions of eight (no change); the macro's JSON
copied from Json<>::value rather than through Stored::json() (0.3 MB less: left out).

## Before issue 32 (a5c2de9, avr-g++, the same script)

| channels | description | JSON bytes | avr-g++ |
| --- | --- | --- | --- |
| 5 | 8 | 431 | 87 MiB / 0.22 s |
| 5 | 60 | 691 | 166 MiB / 0.41 s |
| 20 | 8 | 1657 | 334 MiB / 0.87 s |
| 20 | 60 | 2697 | 770 MiB / 1.85 s |
| 32 | 8 | 2641 | 604 MiB / 1.39 s |
| 32 | 60 | 4305 | 1445 MiB / 3.12 s |
| 80 | 8 | 6577 | 2322 MiB / 4.55 s |
| 80 | 60 | 10737 | over 4096 MiB (stopped after 7.43 s) |
| 254 | bare | 10078 | over 4096 MiB (stopped after 7.46 s) |
| 254 | 60 | 34208 | over 4096 MiB (stopped after 10.78 s) |

20 channels, description length alone: none 261 MiB, 60 characters 770, 120: 1295, 180: 1946,
250: 3400 (superlinear: each character was found by a walk from the start of its text). At 41b85b1
g++ 12 still cost about what it had cost before: its constexpr evaluator remembers only calls nested
less than 8 deep, so it took the walks (channels/constexpr_text.h, HUBWIRE_CX_REMEMBERS).
MD
} >"$out/DESCRIPTOR-COMPILE.md"
if [ "$tree" = "$here" ]; then cp "$out/DESCRIPTOR-COMPILE.md" bench/DESCRIPTOR-COMPILE.md; fi
cat "$out/DESCRIPTOR-COMPILE.md"
