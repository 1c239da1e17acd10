# Two entry points for a fresh Debian machine (see README):
#   make demo   install, build (Release) and run the main job on the bundled model -> out/demo/
#   make test   install, build and run the whole test suite (+ sanitizers, + a bounded fuzz run)
BUILD ?= build
JOBS ?= $(shell nproc)
# CI builds from scratch: a compiler cache only adds risk there.
ifdef CI
export CCACHE_DISABLE := 1
endif

.PHONY: all setup build demo test test-fast test-sanitize fuzz bench clean

all: build

setup:
	bash scripts/setup.sh

$(BUILD)/build.ninja:
	cmake -S . -B $(BUILD) -G Ninja -DCMAKE_BUILD_TYPE=Release

build: setup $(BUILD)/build.ninja
	cmake --build $(BUILD) -j $(JOBS)

demo: build
	bash scripts/demo.sh $(BUILD)/linesurf out/demo

test-fast: build
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS)

test-sanitize: setup
	cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=None -DCMAKE_CXX_FLAGS="-O1 -g1" -DLINESURF_SANITIZE=ON -DLINESURF_BENCH=OFF -DLINESURF_PYTHON=OFF
	cmake --build build-asan -j $(JOBS) --target linesurf_tests linesurf
	cd build-asan && ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
	  ctest --output-on-failure -j $(JOBS) -E '^(Shared|PackageConsumer|Browser)'

fuzz: setup
	bash scripts/fuzz.sh 30

test: test-fast test-sanitize fuzz

bench: build
	$(BUILD)/linesurf_bench

clean:
	rm -rf build build-asan build-fuzz out
