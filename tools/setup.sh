#!/usr/bin/env bash
# Installs everything the build, the tests, the demo and `make dist` need on Debian / Ubuntu /
# Raspberry Pi OS: Debian packages (only those missing) and a Python venv in .venv with the hub and
# test tools (and the documentation site's). Needs only bash and apt-get (a bare system has no make): the README's first command
# runs it. Safe to run again: it does nothing that is already done.
set -euo pipefail
cd "$(dirname "$0")/.."

PACKAGES=(
  make cmake g++ pkg-config git ca-certificates xxd zip unzip
  time                                                 # peak memory of a compile (make test-compile-cost)
  googletest libgtest-dev nlohmann-json3-dev           # C++ unit tests
  gcc-avr avr-libc binutils-avr arduino-core-avr arduino-builder arduino-ctags  # Uno/Mega/Leonardo builds
  simavr libsimavr-dev libsimavrparts1 libelf-dev      # the simulated Uno
  gcc-arm-none-eabi libnewlib-arm-none-eabi            # 32-bit (Cortex-M) compile checks
  clang libclang-rt-dev                                # libFuzzer + ASan/UBSan (test/fuzz)
  python3 python3-venv python3-pip python3-dev         # the hub; -dev builds cobs' C extension
  mosquitto mosquitto-clients                          # MQTT bridge tests and bench (a private broker)
  chromium                                             # the dashboard's browser tests (Playwright drives it)
)
missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]}"
  SUDO=""
  [ "$(id -u)" -eq 0 ] || SUDO=sudo
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

if [ ! -x .venv/bin/python ]; then
  echo "setup: creating .venv"
  python3 -m venv .venv
fi
stamp=.venv/.hubwire-installed
if [ ! -f "$stamp" ] || [ host/pyproject.toml -nt "$stamp" ]; then
  .venv/bin/pip install -q --upgrade pip
  # Playwright drives Debian's chromium: it must never download browsers of its own
  export PLAYWRIGHT_SKIP_BROWSER_DOWNLOAD=1
  .venv/bin/pip install -q -e "host[test,service]" platformio
  touch "$stamp"
fi
# The documentation site's tools (`make docs`), installed again only when their list changes
docs_stamp=.venv/.hubwire-docs-installed
if [ ! -f "$docs_stamp" ] || [ tools/docs/requirements.txt -nt "$docs_stamp" ]; then
  .venv/bin/pip install -q -r tools/docs/requirements.txt
  touch "$docs_stamp"
fi
