# The one entry point for people and CI. See README.md.
SHELL := /bin/bash
BUILD_DIR ?= build
ASAN_DIR ?= build-asan
JOBS ?= $(shell nproc)
CMAKE_FLAGS ?=
SOURCES = $(shell git ls-files --cached --others --exclude-standard '*.cpp' '*.hpp' '*.h' '*.c' '*.inc' 2>/dev/null)

.PHONY: all deps configure build test tidy asan bench bench-compare fuzz fuzz-long soak format format-check run clean install package

all: build

deps:
	@scripts/install-deps.sh

$(BUILD_DIR)/build.ninja:
	cmake -S . -B $(BUILD_DIR) -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo $(CMAKE_FLAGS)

configure: $(BUILD_DIR)/build.ninja

build: configure
	cmake --build $(BUILD_DIR) -j $(JOBS)

# Installs under PREFIX (default /usr; the configuration goes to /etc/canemu then, else
# PREFIX/etc/canemu) into DESTDIR if set. docs/security.md, "Installing".
PREFIX ?= /usr
install: build
	DESTDIR=$(DESTDIR) cmake --install $(BUILD_DIR) --prefix $(PREFIX)

# A Debian package in $(BUILD_DIR): canemu_VERSION_ARCH.deb.
package: build
	cd $(BUILD_DIR) && cpack -G DEB

# ctest runs everything: the C++ suites, the checks and the docs' examples, and the Python
# suites under .venv and .venv-debian (tests/CMakeLists.txt; tests/README.md).
test: deps build
	ctest --test-dir $(BUILD_DIR) --output-on-failure -j $(JOBS)

# clang-tidy over the daemon's sources with .clang-tidy's checks, every finding an error.
tidy: deps build
	scripts/tidy.sh $(BUILD_DIR)

asan: deps
	cmake -S . -B $(ASAN_DIR) -G Ninja -DCMAKE_BUILD_TYPE=Debug -DCANEMU_SANITIZE=ON \
	      -DCANEMU_BUILD_BENCH=OFF $(CMAKE_FLAGS)
	cmake --build $(ASAN_DIR) -j $(JOBS)
	ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
	  ctest --test-dir $(ASAN_DIR) --output-on-failure -j $(JOBS)

# libFuzzer targets (clang; scripts/fuzz.sh): `make fuzz` runs each for FUZZ_SECONDS with the
# sanitizers; `make fuzz-long` runs each for FUZZ_RUNS executions built for speed, then replays
# what they found through the sanitizers. Figures in build-fuzz*/fuzz-figures.json.
FUZZ_SECONDS ?= 60
FUZZ_RUNS ?= 10000000
fuzz: deps
	@scripts/install-deps.sh scripts/apt-packages-fuzz.txt
	scripts/fuzz.sh time $(FUZZ_SECONDS)

fuzz-long: deps
	@scripts/install-deps.sh scripts/apt-packages-fuzz.txt
	scripts/fuzz.sh runs $(FUZZ_RUNS)  # FUZZ_TARGETS="..." for some of them

# Clients that come, go and get killed against canemud in real time for SOAK_SECONDS; checks
# that nothing leaks or stalls (tests/soak/soak.py; figures as JSON on stdout).
SOAK_SECONDS ?= 60
soak: deps build
	.venv/bin/python tests/soak/soak.py --seconds $(SOAK_SECONDS) --build $(BUILD_DIR)

# Benchmarks write one JSON file each into $(BUILD_DIR)/bench-results/. CI passes short runs:
# BENCH_ARGS, WEB_BENCH_ARGS, BUSY_BENCH_ARGS="--smoke" (256 busy buses for 0.2 s).
bench: deps build
	@mkdir -p $(BUILD_DIR)/bench-results
	$(BUILD_DIR)/bin/firmware_model_bench --benchmark_out=$(BUILD_DIR)/bench-results/firmware_model.json \
	  --benchmark_out_format=json $(BENCH_ARGS)
	$(BUILD_DIR)/bin/ipc_bench --benchmark_out=$(BUILD_DIR)/bench-results/ipc.json \
	  --benchmark_out_format=json $(BENCH_ARGS)
	$(BUILD_DIR)/bin/daemon_bench --benchmark_out=$(BUILD_DIR)/bench-results/daemon.json \
	  --benchmark_out_format=json $(BENCH_ARGS)
	$(BUILD_DIR)/bin/restbus_bench --benchmark_out=$(BUILD_DIR)/bench-results/restbus.json \
	  --benchmark_out_format=json $(BENCH_ARGS)
	$(BUILD_DIR)/bin/vci_bench --benchmark_out=$(BUILD_DIR)/bench-results/vci.json \
	  --benchmark_out_format=json $(BENCH_ARGS)
	$(BUILD_DIR)/bin/instructions_bench --benchmark_out=$(BUILD_DIR)/bench-results/instructions.json \
	  --benchmark_out_format=json
	.venv/bin/python bench/python/python_can_bench.py --out $(BUILD_DIR)/bench-results/python.json
	.venv/bin/python bench/python/python_latency_bench.py --out $(BUILD_DIR)/bench-results/python_latency.json
	.venv/bin/python bench/python/busy_receivers_bench.py --out $(BUILD_DIR)/bench-results/busy_receivers.json $(BUSY_BENCH_ARGS)
	.venv/bin/python bench/python/web_bench.py --out $(BUILD_DIR)/bench-results/web.json $(WEB_BENCH_ARGS)
	@python3 bench/ratios.py $(BUILD_DIR)/bench-results
	@echo "bench: results in $(BUILD_DIR)/bench-results/"

# The figures of two result sets side by side with their ratio (bench/compare.py):
#   make bench-compare A=build-main/bench-results B=build/bench-results
bench-compare:
	@python3 bench/compare.py $(A) $(B)

format:
	clang-format -i $(SOURCES)

format-check:
	clang-format --dry-run --Werror $(SOURCES)

# canemud in the foreground on the embedded default config. The socket: $CANEMU_SOCKET, else
# /run/canemu/canemud.sock when that directory can be used, else build/canemud.sock.
run: deps build
	@sock="$${CANEMU_SOCKET:-}"; \
	if [ -z "$$sock" ]; then \
	  if mkdir -p /run/canemu 2>/dev/null && [ -w /run/canemu ]; then sock=/run/canemu/canemud.sock; \
	  else sock=$(CURDIR)/$(BUILD_DIR)/canemud.sock; fi; \
	fi; \
	exec $(BUILD_DIR)/bin/canemud --socket "$$sock"

clean:
	rm -rf $(BUILD_DIR) $(ASAN_DIR) build-fuzz build-fuzz-fast
