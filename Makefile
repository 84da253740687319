# bistable-impact: build, test, demo and benchmark entry points.
# Every target installs what it needs through scripts/setup.sh (Debian packages, Python venv).

CARGO ?= cargo
OUT ?= out
BISTABLE := target/release/bistable
DEMO_MAP = $(BISTABLE) map --omega-range 0.2:3.5:60 --velocity-range 0.005:0.2:40 \
	--out $(OUT)/map.csv --plot $(OUT)/map.png --json > $(OUT)/map_summary.json

.PHONY: all setup build test test-rust test-simd lint demo bench bench-ensemble stress stress-core clean

all: build

# Component makefiles (FMU, ROS 2 node, analyses) add their own test and demo steps to these.
TEST_TARGETS := test-rust test-simd
DEMO_TARGETS :=
STRESS_TARGETS := stress-core
-include fmu/fmu.mk
-include ros/ros.mk
-include python.mk

setup:
	bash scripts/setup.sh

build: setup
	$(CARGO) build --release --workspace

lint: setup
	$(CARGO) fmt --all -- --check
	$(CARGO) clippy --workspace --all-targets -- -D warnings
	RUSTDOCFLAGS="-D warnings" $(CARGO) doc --no-deps --workspace --quiet

## Every test: formatting, lints, Rust unit/integration/doc tests, and the components' suites.
## The release artefacts the suites use (CLI, FMU, node, Python module) are built with thin LTO
## and 16 codegen units, which take a third of the fat-LTO build's time; `make build`, `fmu`,
## `bench` keep the release profile's fat LTO. The numbers do not depend on it (no fast-math:
## LLVM keeps every floating-point operation as written either way).
test: export CARGO_PROFILE_RELEASE_LTO := thin
test: export CARGO_PROFILE_RELEASE_CODEGEN_UNITS := 16
test: lint
	@for t in $(TEST_TARGETS); do start=$$(date +%s); \
		$(MAKE) --no-print-directory $$t || exit 1; \
		echo "make test: $$t passed in $$(( $$(date +%s) - start )) s"; \
	done
	@echo "make test: all suites passed"

# The CLI's 30 x 20 map for every lane width runs in test-simd, on each SIMD path.
SIMD_MAP_TEST := map_is_the_same_for_every_lane_width

# The ROS 2 node's own tests run in test-ros, in the release build the ROS tests use (its DDS
# stack is the largest part of the workspace to compile); the Python module (no Rust tests) is
# tested by test-python. test-simd selects the same packages, so that cargo resolves the same
# dependency features and reuses test-rust's build instead of compiling it again.
RUST_TEST_PACKAGES := --workspace --exclude bistable_impact_node --exclude bistable-py

test-rust: setup
	$(CARGO) test $(RUST_TEST_PACKAGES) -- --skip $(SIMD_MAP_TEST)

## The SIMD paths (BISTABLE_SIMD, crates/bistable-core/src/simd.rs): the lanes' bit-identity
## tests (lanes against lone simulators, flights_at against mass_at) on the detected path, on
## the portable one and, on a CPU with AVX-512, on AVX2; the 30 x 20 map for every lane width
## on the detected and the portable path. Each run is headed by its path in the log, and the
## simd test prints the path in use.
test-simd: setup
	@paths="auto portable"; grep -qw avx512f /proc/cpuinfo 2>/dev/null && paths="$$paths avx2"; \
	for path in $$paths; do \
		echo "test-simd: SIMD path BISTABLE_SIMD=$$path: lanes against lone simulators"; \
		BISTABLE_SIMD=$$path $(CARGO) test $(RUST_TEST_PACKAGES) --test simd --test batch --test mass_at \
			-- --nocapture || exit 1; \
	done; \
	for path in auto portable; do \
		echo "test-simd: SIMD path BISTABLE_SIMD=$$path: the 30 x 20 map for every lane width"; \
		BISTABLE_SIMD=$$path $(CARGO) test $(RUST_TEST_PACKAGES) --test simd --test lanes \
			-- --nocapture --exact simd_path_is_the_one_asked_for $(SIMD_MAP_TEST) || exit 1; \
	done

## Builds everything and runs the paper's baseline case, writing plots and a summary under out/.
demo: build $(DEMO_TARGETS)
	mkdir -p $(OUT)
	$(BISTABLE) simulate --omega 1.75 --velocity 0.07 --periods 200 \
		--impacts $(OUT)/baseline_impacts.csv --plot $(OUT)/baseline --json > $(OUT)/baseline_summary.json
	$(BISTABLE) simulate --omega 0.2 --velocity 0.05 --t-end 60 \
		--impacts $(OUT)/chatter_impacts.csv --plot $(OUT)/chatter --json > $(OUT)/chatter_summary.json
	# The paper's analyses: classes, map (Fig. 9; resumes from an existing map.csv), bifurcation
	# diagram with orbit branches (Fig. 6/8), continuation of period-1 orbits (Fig. 11a),
	# energy map with a chaotic run's impacts, spectra of a periodic and a chaotic response.
	$(BISTABLE) classify --omega 0.85 --velocity 0.11 > $(OUT)/classify_0.85_0.11.json
	$(BISTABLE) classify --omega 0.85 --velocity 0.15 > $(OUT)/classify_0.85_0.15.json
	$(BISTABLE) thresholds --json > $(OUT)/thresholds.json
	# The map resumes from an existing map.csv; one written by an older version (other columns)
	# is refused by the CLI as "not a map file", and the demo then starts the map afresh.
	$(DEMO_MAP) 2> $(OUT)/map.err || { cat $(OUT)/map.err; grep -q "is not a map file" $(OUT)/map.err \
		&& rm -f $(OUT)/map.csv && $(DEMO_MAP); }
	$(BISTABLE) bifurcation --param omega --range 2.0:2.7:141 --velocity 0.07 \
		--out $(OUT)/bifurcation.csv --plot $(OUT)/bifurcation.png --json > $(OUT)/bifurcation_summary.json
	$(BISTABLE) orbit --continue-omega 0.6:3.0:121 --velocity 0.03,0.05,0.07 --arclength \
		--out $(OUT)/orbits.csv --plot $(OUT)/orbits.png --json > $(OUT)/orbits_summary.json
	$(BISTABLE) energy-map --overlay --omega 2.45 --velocity 0.07 --periods 300 --plot $(OUT)/energy_map.png
	$(BISTABLE) spectrum --omega 2.2 --velocity 0.07 --plot $(OUT)/spectrum_p2.png --json > $(OUT)/spectrum_p2.json
	$(BISTABLE) spectrum --omega 2.45 --velocity 0.07 --plot $(OUT)/spectrum_chaos.png --json > $(OUT)/spectrum_chaos.json
	@echo "demo: results in $(OUT)/"

## Criterion benches and the work-precision comparison with SciPy (writes docs/benchmarks.md).
bench: setup
	bash bench/run.sh

## Ensembles in SIMD lanes against one trajectory at a time, and heyoka's batch mode
## (docs/benchmarks.md, "Ensembles"); ENSEMBLE_FULL=1 adds the 300 x 200 map and the
## 1,000 x 1,000 basins grid.
bench-ensemble: setup
	bash bench/ensemble.sh

## The long stress and fault campaign (docs/reliability.md): numerical long runs, FMU fault
## sequences/fuzzing/valgrind, ROS 2 fault tests. Each component adds its steps to STRESS_TARGETS.
stress: setup
	$(MAKE) --no-print-directory $(STRESS_TARGETS)
	@echo "make stress: all stress suites passed"

## Numerical long runs of the core (ignored by the quick `cargo test`), figures printed.
stress-core: setup
	$(CARGO) test --release -p bistable-core --test stress_long -- --ignored --nocapture --test-threads 1

clean:
	$(CARGO) clean
	rm -rf $(OUT)
