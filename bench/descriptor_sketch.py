"""A sketch of N float channels for bench/descriptor-compile.sh and `make test-compile-cost`.

Each channel is declared as `expose("vNNN", v[NNN]).writable().range(-1.0f, 1.0f).unit("m/s")`
with a description of the given length; `--bare`: `expose("vNNN", v[NNN])` alone (254 such
channels fit the 16 KiB a hub accepts). `--peer` writes the same content for a framing-only
library instead: the descriptor as a hand-written string in flash, sent on request.

    python3 bench/descriptor_sketch.py CHANNELS DESCRIPTION_LENGTH [--bare] [--peer] > sketch.cpp
"""

import sys


def description(i: int, length: int) -> str:
    text = f"channel {i:03d} " + "abcdefghijklmnopqrstuvwxyz " * 10
    return text[:length]


def hubwire_sketch(n: int, d: int, bare: bool) -> str:
    lines = ["#include <Arduino.h>", "#include <Hubwire.h>", "", "Hubwire hub(Serial);", f"float v[{n}];", "",
             'HUBWIRE_CHANNELS(channels, "bench",']
    decls = []
    for i in range(n):
        decl = f'  expose("v{i:03d}", v[{i}])'
        if not bare:
            decl += '.writable().range(-1.0f, 1.0f).unit("m/s")'
        if d:
            decl += f'.describe("{description(i, d)}")'
        decls.append(decl)
    lines.append(",\n".join(decls) + ");")
    lines += ["", "void setup() {", "  Serial.begin(115200);", "  hub.begin(channels);", "}", "",
              "void loop() { hub.update(); }", ""]
    return "\n".join(lines)


def descriptor(n: int, d: int, bare: bool = False) -> str:
    entries = []
    for i in range(n):
        entry = f'{{"id":{i + 1},"n":"v{i:03d}","a":"r","t":"f32"' if bare else \
            f'{{"id":{i + 1},"n":"v{i:03d}","a":"rw","t":"f32","u":"m/s","min":-1,"max":1'
        if d:
            entry += f',"d":"{description(i, d)}"'
        entries.append(entry + "}")
    return '{"p":1,"n":"bench","ch":[' + ",".join(entries) + "]}"


def peer_sketch(n: int, d: int, bare: bool) -> str:
    text = descriptor(n, d, bare)
    chunks = "\n".join('    "' + text[i:i + 100].replace("\\", "\\\\").replace('"', '\\"') + '"'
                        for i in range(0, len(text), 100))
    return "\n".join([
        "#include <Arduino.h>",
        "#include <avr/pgmspace.h>",
        "",
        f"float v[{n}];",
        "const char descriptor[] PROGMEM =",
        chunks + ";",
        "",
        "void setup() { Serial.begin(115200); }",
        "",
        "void loop() {",
        "  if (Serial.available() && Serial.read() == 'J') {",
        "    for (size_t i = 0; i < sizeof(descriptor) - 1; ++i) Serial.write(pgm_read_byte(descriptor + i));",
        "  }",
        "}",
        "",
    ])


def main() -> None:
    n, d, bare = int(sys.argv[1]), int(sys.argv[2]), "--bare" in sys.argv[3:]
    sys.stdout.write(peer_sketch(n, d, bare) if "--peer" in sys.argv[3:] else hubwire_sketch(n, d, bare))


if __name__ == "__main__":
    main()
