# Entry points for a fresh Debian machine (see README). Each builds only what it runs.
#   make demo      install packages, build the CLI (Release) and run the main job -> out/demo/
#   make install   build the CLI, library and Python module and install them under PREFIX (~/.local)
#   make test      install packages, build everything and run the whole test suite
#                  (+ sanitizers, + a bounded fuzz run)
BUILD ?= build
JOBS ?= $(shell nproc)
PREFIX ?= $(HOME)/.local
# CI builds from scratch: a compiler cache only adds risk there.
ifdef CI
export CCACHE_DISABLE := 1
endif

.PHONY: all setup configure build cli demo install test test-fast test-sanitize fuzz bench readme clean

all: build

setup:
	bash scripts/setup.sh

$(BUILD)/build.ninja:
	cmake -S . -B $(BUILD) -G Ninja -DCMAKE_BUILD_TYPE=Release

configure: setup $(BUILD)/build.ninja

# Everything: library, CLI, tests, benchmarks, Python module.
build: configure
	cmake --build $(BUILD) -j $(JOBS)

# The CLI alone (and the library it links): all that the demo and the README's examples run.
cli: configure
	cmake --build $(BUILD) -j $(JOBS) --target linesurf

demo: cli
	bash scripts/demo.sh $(BUILD)/linesurf out/demo

# What `cmake --install` copies: the CLI, the static library + headers + CMake package, and the
# Python module where it is configured (its target exists only when pybind11 and numpy were found).
install: configure
	cmake --build $(BUILD) -j $(JOBS) --target linesurf \
	  $$(ninja -C $(BUILD) -t targets all | grep -q '^linesurf_python:' && echo linesurf_python)
	cmake --install $(BUILD) --prefix $(PREFIX)
	@echo "installed under $(PREFIX); if $(PREFIX)/bin is not on PATH: export PATH=\"$(PREFIX)/bin:\$$PATH\""

test-fast: build
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS)

# Readme.Examples is left to the Release build: the README shows what the installed (Release) CLI
# prints, and -O1 need not round the last printed digit alike. MPI is off here: Open MPI's own
# start-up allocations are reported by LeakSanitizer (the Release run checks the MPI path). The
# Holes tests (random spheres of 10^5 points at 512², about 3.5 min in Release) run the render
# paths the render tests run at small sizes; under ASan they would take a quarter of the budget.
test-sanitize: setup
	cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=None -DCMAKE_CXX_FLAGS="-O1 -g1" -DLINESURF_SANITIZE=ON -DLINESURF_BENCH=OFF -DLINESURF_PYTHON=OFF -DLINESURF_MPI=OFF
	cmake --build build-asan -j $(JOBS) --target linesurf_tests linesurf
	cd build-asan && ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
	  ctest --output-on-failure -j $(JOBS) -E '^(Shared|PackageConsumer|Browser|Readme\.Examples|Holes\.)'

fuzz: setup
	bash scripts/fuzz.sh 30

test: test-fast test-sanitize fuzz

bench: build
	$(BUILD)/linesurf_bench

# Regenerates the README's Examples block from what its commands print now.
readme: cli
	bash scripts/readme_examples.sh --update --cli $(BUILD)/linesurf

clean:
	rm -rf build build-asan build-fuzz out
