# Makefile -- thin wrapper over CMake. `make run` and `make test` do all set-up on a fresh Debian 12:
# they install missing packages (apt-get; sudo only when not root), configure, build, then run.
.PHONY: all deps build run test bench format format-check clean

BUILD      ?= build
TEST_BUILD ?= build-asan
JOBS       ?= $(shell nproc)
SUDO       := $(shell [ "$$(id -u)" = 0 ] || echo sudo)

# Every Debian package the build, the tests and the tools need.
PACKAGES := build-essential cmake pkg-config git clang-format \
            libembree-dev libcgal-dev libgmp-dev libmpfr-dev libboost-dev \
            libwebsockets-dev libssl-dev libcap-dev zlib1g-dev \
            libassimp-dev libcjson-dev libturbojpeg0-dev libopenexr-dev libpng-dev \
            libcmocka-dev ffmpeg python3 python3-matplotlib

all: build

deps:
	@missing=$$(for p in $(PACKAGES); do \
	    dpkg-query -W -f='$${Status}' $$p 2>/dev/null | grep -q 'install ok installed' || echo $$p; done); \
	if [ -n "$$missing" ]; then \
	    echo "Installing: $$missing"; \
	    $(SUDO) apt-get update -qq && \
	    DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -qq --no-install-recommends $$missing; \
	fi

build: deps
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release -DIIR_WERROR=ON >/dev/null
	cmake --build $(BUILD) -j $(JOBS)

# The main job on the built-in Cornell box.
run: build
	mkdir -p out
	$(BUILD)/iird render --method pt --spp 256 --bounces 2 --size 512x512 --out out/cornell.png
	@echo "Wrote out/cornell.png (open it in an image viewer)."

# Sanitizer build (ASan + UBSan) and the whole suite through ctest, plus the format check.
test: deps format-check
	cmake -S . -B $(TEST_BUILD) -DCMAKE_BUILD_TYPE=RelWithDebInfo -DIIR_WERROR=ON \
	    -DIIR_SANITIZE=address,undefined >/dev/null
	cmake --build $(TEST_BUILD) -j $(JOBS)
	cd $(TEST_BUILD) && ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
	    ctest --output-on-failure -j $(JOBS)

# Benchmarks (not tests): ray rates, then the methods over a 200-frame orbit with references.
# About 6 minutes on 2 cores. Results in out/bench/.
bench: build
	mkdir -p out/bench/cornell out/bench/conference
	$(BUILD)/iird raybench conference
	$(BUILD)/iird raybench
	$(BUILD)/iird bench --frames 200 --ref-every 50 --ref-spp 256 --out out/bench/cornell
	$(BUILD)/iird bench conference --frames 100 --ref-spp 0 --out out/bench/conference

FORMAT_FILES = $(shell git ls-files '*.c' '*.h' '*.cpp' '*.hpp' 2>/dev/null)
format:
	clang-format -i $(FORMAT_FILES)
format-check:
	@clang-format --dry-run --Werror $(FORMAT_FILES) && echo "clang-format: clean"

clean:
	rm -rf $(BUILD) $(TEST_BUILD)
