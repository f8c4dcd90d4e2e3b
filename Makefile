# nimbus: the two commands of the README.
#   make demo   installs missing Debian packages, builds, renders the built-in scene with mfs to
#               out/demo.{exr,png} and with pathtrace in the same time to out/demo_pathtrace.{exr,png}
#   make test   installs missing Debian packages, builds, runs the whole suite through ctest
# Also: make (build only), make python (the Python module in build/python/: docs/python.md),
# make test-fast (no statistical tests), make asan (clang sanitizer build build-san/ + fast tests),
# make fuzz-smoke (libFuzzer targets, 60 s each), make fuzz FUZZ_SECONDS=N (N s each): docs/reliability.md.
# make farm-test (as root: a one-node Slurm cluster renders a sequence, a split frame, a killed task): docs/farm.md.
BUILD ?= build
JOBS ?= $(shell nproc)
CMAKE_FLAGS ?=
FUZZ_SECONDS ?= 600
# Left out of the sanitizer run (docs/reliability.md): 30 s to 2 min each under ASan, and their code
# paths are the ones the other fast tests (Mfs.* among them) already take there (the emitting-cell mask:
# Emission.*; source_blur: one medium lookup at an offset point, its offset tested by MfsEstimators.LateralOffset*;
# camera_tilt: every other Mfs test takes it, its probe tested by MfsEstimators.FootprintProbe*).
ASAN_SKIP ?= ^Stress\.ExtremeScenesHaveNoNonFiniteSamples$$|^Determinism\.EveryIntegratorIsBitIdenticalForAnyThreadCount$$|^Mfs\.(WhiteFurnaceWithAllOrders|FilteredLookupsOfTheScatterGrid|GrowingStepsMatchFixedSteps|BitIdenticalForAnyThreadCount|MoreWideScattersAddLight|IsotropicMediumMatchesPathTracerOrderByOrder|BeamGridReproducesTheStraightBeamWithoutDeflection|EmittingCellsMarchAtFixedSteps|SourceBlurKeepsASlabAndDarkensARim|CameraTiltBalancesTheLitAndFarHalves)$$

.PHONY: all deps configure build python demo test test-fast asan bench clean fuzz-build fuzz-smoke fuzz fuzz-seeds farm-test

all: build

deps:
	@./scripts/install-deps.sh

$(BUILD)/build.ninja:
	cmake -S . -B $(BUILD) -G Ninja -DCMAKE_BUILD_TYPE=Release $(CMAKE_FLAGS)

configure: $(BUILD)/build.ninja

build: configure
	cmake --build $(BUILD) -j $(JOBS)

python: configure
	cmake --build $(BUILD) -j $(JOBS) --target nimbus_python
	@echo "nimbus: PYTHONPATH=$(abspath $(BUILD))/python /usr/bin/python3 -c 'import nimbus'"

demo: deps
	@$(MAKE) --no-print-directory build
	@./scripts/demo.sh $(BUILD) out

test: deps
	@$(MAKE) --no-print-directory build
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS)

test-fast: deps
	@$(MAKE) --no-print-directory build
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS) -LE slow

# One sanitizer build, build-san/ (clang-14, ASan + UBSan, libFuzzer coverage), serves both the fast
# suite under the sanitizers and the fuzz targets: the library is compiled once for both. -O1 (the level
# the sanitizers' documentation suggests): it compiles in 0.78x the time of -O3 and the fast suite still
# runs in about 5 minutes.
SAN_BUILD ?= build-san
$(SAN_BUILD)/build.ninja:
	cmake -S . -B $(SAN_BUILD) -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_COMPILER=clang++-14 \
	  -DNIMBUS_SANITIZE=ON -DNIMBUS_FUZZ=ON -DNIMBUS_BUILD_BENCH=OFF -DNIMBUS_PYTHON=OFF \
	  -DCMAKE_CXX_FLAGS_RELEASE="-O1 -DNDEBUG"

asan: deps $(SAN_BUILD)/build.ninja
	cmake --build $(SAN_BUILD) -j $(JOBS) --target nimbus_fast_tests nimbus_cli
	cd $(SAN_BUILD) && ctest --output-on-failure -j $(JOBS) -LE slow -E '$(ASAN_SKIP)'

bench: build
	$(BUILD)/bin/bench_render

# A one-node Slurm cluster on this machine (as root), a sequence, a split frame and a killed task:
# scripts/farm/farm_test.sh, docs/farm.md. Bounded by timeout; the daemons stop on every exit.
farm-test: deps
	@$(MAKE) --no-print-directory build
	timeout 600 ./scripts/farm/farm_test.sh $(BUILD)

# libFuzzer targets (fuzz/), in the sanitizer build. See docs/reliability.md.
fuzz-build: deps $(SAN_BUILD)/build.ninja
	cmake --build $(SAN_BUILD) -j $(JOBS) --target scene_fuzz vdb_fuzz cli_fuzz mesh_fuzz

fuzz-smoke: fuzz-build
	FUZZ_SEED=1 BUILD_FUZZ=$(SAN_BUILD) fuzz/run.sh 60

fuzz: fuzz-build
	BUILD_FUZZ=$(SAN_BUILD) fuzz/run.sh $(FUZZ_SECONDS)

# Regenerates fuzz/data/tiny.{vdb,nvdb} and the volume seeds in fuzz/corpus/vdb/ (committed).
fuzz-seeds: fuzz-build
	cmake --build $(SAN_BUILD) -j $(JOBS) --target make_seeds
	ASAN_OPTIONS=detect_leaks=0 $(SAN_BUILD)/bin/make_seeds fuzz/data fuzz/corpus/vdb

clean:
	rm -rf $(BUILD) $(SAN_BUILD)
