# nimbus: the two commands of the README.
#   make demo   installs missing Debian packages, builds, renders the built-in scene to out/demo.{exr,png}
#   make test   installs missing Debian packages, builds, runs the whole suite through ctest
# Also: make (build only), make test-fast (no statistical tests), make asan (sanitizer build + fast tests).
BUILD ?= build
JOBS ?= $(shell nproc)
CMAKE_FLAGS ?=

.PHONY: all deps configure build demo test test-fast asan bench clean

all: build

deps:
	@./scripts/install-deps.sh

$(BUILD)/build.ninja:
	cmake -S . -B $(BUILD) -G Ninja -DCMAKE_BUILD_TYPE=Release $(CMAKE_FLAGS)

configure: $(BUILD)/build.ninja

build: configure
	cmake --build $(BUILD) -j $(JOBS)

demo: deps
	@$(MAKE) --no-print-directory build
	@mkdir -p out
	$(BUILD)/bin/nimbus render -o out/demo.exr --preview out/demo.png
	@echo "nimbus: demo written to out/demo.exr and out/demo.png"

test: deps
	@$(MAKE) --no-print-directory build
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS)

test-fast: deps
	@$(MAKE) --no-print-directory build
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS) -LE slow

asan: deps
	@$(MAKE) --no-print-directory build BUILD=build-asan CMAKE_FLAGS="-DNIMBUS_SANITIZE=ON -DNIMBUS_BUILD_BENCH=OFF"
	cd build-asan && ctest --output-on-failure -j $(JOBS) -LE slow

bench: build
	$(BUILD)/bin/bench_render

clean:
	rm -rf $(BUILD) build-asan
