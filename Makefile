# Hubwire top-level build. `make test` runs every check; `make demo` shows the hub discovering a
# simulated Uno running examples/Rover. Both install what they need first (tools/setup.sh).
SHELL := /bin/bash
BUILD := build
PY := .venv/bin/python
JOBS ?= 2

.PHONY: all setup test test-cpp test-avr-core test-compile-errors test-compile-cost test-examples test-config-limits test-arm test-manifests test-static test-python test-fuzz emulator simuno uno-firmware demo dashboard-demo bench soak fuzz-long dist clean

all: emulator simuno

setup:
	@bash tools/setup.sh

$(BUILD)/cmake/Makefile: CMakeLists.txt
	cmake -S . -B $(BUILD)/cmake -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null

cpp: $(BUILD)/cmake/Makefile
	cmake --build $(BUILD)/cmake -j$(JOBS)

emulator: cpp

simuno:
	$(MAKE) -C tools/simuno BUILD_DIR=$(abspath $(BUILD))/simuno

# Every example for the Uno, as the simulated-Uno tests (and, for Rover, the demo) run them: the
# folders holding a sketch of their name (examples/ESP32/ holds examples for that family only).
EXAMPLES := $(foreach d,$(wildcard examples/*/),$(if $(wildcard $(d)$(notdir $(patsubst %/,%,$(d))).ino),$(notdir $(patsubst %/,%,$(d)))))
# Each is a target of its own, built again only when its example or the library changed (about 10 to
# 40 s a sketch; a line says which one is being built, the compiler's output goes to its .log).
LIB_SOURCES := $(shell find src -type f) library.properties tools/arduino/build-sketch.sh
UNO_FIRMWARE := $(foreach e,$(EXAMPLES),$(BUILD)/uno/$(e)/$(e).ino.elf) $(BUILD)/uno/MinimalBoardId/Minimal.ino.elf
uno-firmware: $(UNO_FIRMWARE)

define uno_sketch
$(BUILD)/uno/$(1)/$(1).ino.elf: $$(wildcard examples/$(1)/*) $$(LIB_SOURCES)
	@echo "uno-firmware: building examples/$(1) for the Uno (log: $(BUILD)/uno/$(1).log)"
	@bash tools/arduino/build-sketch.sh examples/$(1) arduino:avr:uno $(BUILD)/uno/$(1) >/dev/null
endef
$(foreach e,$(EXAMPLES),$(eval $(call uno_sketch,$(e))))

# Minimal again, keeping a board id in EEPROM (test_board_id_on_uno.py)
$(BUILD)/uno/MinimalBoardId/Minimal.ino.elf: $(wildcard examples/Minimal/*) $(LIB_SOURCES)
	@echo "uno-firmware: building examples/Minimal with a board id in EEPROM for the Uno"
	@EXTRA_FLAGS=-DHUBWIRE_BOARD_ID_EEPROM=16 bash tools/arduino/build-sketch.sh examples/Minimal arduino:avr:uno \
	  $(BUILD)/uno/MinimalBoardId >/dev/null

test: setup
	$(MAKE) test-cpp test-avr-core test-compile-errors test-compile-cost test-examples test-config-limits test-arm test-manifests test-fuzz test-static test-docs test-python
	@echo "make test: all checks passed"

test-cpp: cpp
	cd $(BUILD)/cmake && ctest --output-on-failure

# The portable core alone, for the Uno's MCU, warnings as errors (no Arduino.h involved).
CORE_SOURCES := $(shell find src/hubwire -name '*.cpp')
test-avr-core:
	@mkdir -p $(BUILD)/avr-core
	@for f in $(CORE_SOURCES); do \
	  avr-g++ -std=gnu++11 -mmcu=atmega328p -Os -Wall -Wextra -Werror -fno-exceptions -fno-rtti \
	    -Itest/support -DHUBWIRE_PORT_HEADER='"port_bare.h"' -c $$f -o $(BUILD)/avr-core/$$(basename $$f).o || exit 1; \
	done
	@echo "test-avr-core: $(words $(CORE_SOURCES)) files compile for atmega328p with -Wall -Wextra -Werror"

# A first sketch's declaration mistakes, compiled for the Uno as the Arduino IDE does: each message
# names the channel and the mistake in at most 20 lines (test/compile_fail/first_sketch.sh).
test-compile-errors:
	bash test/compile_fail/first_sketch.sh $(BUILD)/compile-errors

# What a sketch's descriptor costs the compiler stays small: 32 channels with 60-character
# descriptions (the default HUBWIRE_MAX_CHANNELS) build for the Uno and with g++ (the emulator; the
# boards of a modern GCC) each within 256 MiB of address space (bench/descriptor-compile.sh; `make
# bench` measures the whole curve).
test-compile-cost:
	BUILD=$(BUILD) bash bench/descriptor-compile.sh --check

# Every example for the AVR boards, then the benchmark sketches under extras/ for the Uno.
test-examples:
	bash tools/arduino/build-all.sh
	bash tools/arduino/build-extras.sh

# Every config.h setting at the ends of its range still builds without warnings from our code.
test-config-limits:
	bash tools/arduino/build-config-limits.sh

test-arm:
	bash tools/arm-check/check-arm.sh

# libFuzzer + ASan/UBSan over the frame receiver and the device session: regressions, then ~60 s.
test-fuzz:
	bash test/fuzz/run.sh

test-manifests:
	$(PY) tools/check_manifests.py

# Static checks of the hub: mypy --strict on the package (its settings in host/pyproject.toml) and
# ruff on host/ and bench/*.py with ruff's classic default rules (pyflakes and the E4/E7/E9 errors),
# named here so that a newer ruff with a wider default set gives the same verdict.
test-static:
	.venv/bin/mypy --config-file host/pyproject.toml host/hubwire
	.venv/bin/ruff check --isolated --select E4,E7,E9,F host bench/*.py

test-python: emulator simuno uno-firmware
	$(PY) -m pytest host/tests -q

# The demo needs Rover only: nothing is built again when nothing changed.
demo: setup simuno $(BUILD)/uno/Rover/Rover.ino.elf
	@HUBWIRE_BUILD=$(BUILD) bash tools/demo.sh

# The browser dashboard on the same simulated Uno, at the address (with a token) it prints, until Ctrl-C.
dashboard-demo: setup simuno $(BUILD)/uno/Rover/Rover.ino.elf
	@HUBWIRE_BUILD=$(BUILD) bash tools/demo.sh --dashboard

# Every benchmark row (footprint, AVR cycles, wire bytes, hub throughput, connect time, round
# trips, many devices) into bench/RESULTS.md. PEERS_SRC=DIR (the peers' sources, see
# bench/peers.sh) also rebuilds the peers table, bench/PEERS.md; without it that table is kept.
bench: setup emulator simuno uno-firmware
	bash bench/run.sh

# Long modes of the reliability checks (docs/RELIABILITY.md): 1,000,000 frames through the faulty
# link (the soak sketch in its emulator: discovery, a dead link and a reboot under faults; counts in
# build/reliability/soak-1M.json), the model-based exactly-once test until every message kind
# wrapped its 8-bit counter 100 times (HUBWIRE_MODEL_WRAPS, HUBWIRE_MODEL_SEED; counts in
# build/reliability/model-wraps100-seed<S>.json), and each fuzzer for half an hour (FUZZ_SECONDS to change).
soak: setup emulator
	HUBWIRE_WRAP_BURSTS=$${HUBWIRE_WRAP_BURSTS:-20000} $(BUILD)/cmake/test_wrap_model --gtest_filter='WrapModel.*'
	HUBWIRE_SOAK_FRAMES=$${HUBWIRE_SOAK_FRAMES:-1000000} $(PY) -m pytest host/tests/reliability/test_soak.py::test_soak_exactly_once_no_corruption_no_reset -s -q
	HUBWIRE_MODEL_WRAPS=$${HUBWIRE_MODEL_WRAPS:-100} $(PY) -m pytest host/tests/reliability/test_model.py::test_every_kind_exactly_once_in_any_mix -s -q

FUZZ_SECONDS ?= 1800
fuzz-long: setup
	bash test/fuzz/run.sh --long $(FUZZ_SECONDS)

# The documentation site from docs/ (mkdocs.yml) into $(BUILD)/site, offline: the Python API from
# the docstrings, the sketch API from the headers' /// comments (tools/docs/sketch_api.py). Strict:
# a broken link, a missing page or an API name that does not resolve fails it. Then every link of
# README.md to a file of the repository is checked (tools/docs/check_readme_links.py). Not -q:
# mkdocs -q hides the warnings and then strict mode no longer counts them.
MKDOCS := .venv/bin/mkdocs
.PHONY: docs test-docs
docs: setup
	$(MAKE) test-docs
test-docs:
	NO_MKDOCS_2_WARNING=1 $(MKDOCS) build --strict --clean -d $(abspath $(BUILD)/site)
	$(PY) tools/docs/check_readme_links.py
	@echo "docs: built into $(BUILD)/site (open $(BUILD)/site/index.html)"

# The library alone, as users install it: build/dist/Hubwire-<version>.zip for the Arduino IDE's
# "Add .ZIP Library" and the `pio pkg pack` tarball for PlatformIO (tools/dist.py, offline).
dist: setup
	$(PY) tools/dist.py

clean:
	rm -rf $(BUILD)
