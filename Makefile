# bistable-impact: build, test, demo and benchmark entry points.
# Every target installs what it needs through scripts/setup.sh (Debian packages, Python venv).

CARGO ?= cargo
OUT ?= out
BISTABLE := target/release/bistable

.PHONY: all setup build test test-rust lint demo bench clean

all: build

# Component makefiles (FMU, ROS 2 node, analyses) add their own test and demo steps to these.
TEST_TARGETS := test-rust
DEMO_TARGETS :=
-include fmu/fmu.mk
-include ros/ros.mk

setup:
	bash scripts/setup.sh

build: setup
	$(CARGO) build --release --workspace

lint: setup
	$(CARGO) fmt --all -- --check
	$(CARGO) clippy --workspace --all-targets -- -D warnings

## Every test: formatting, lints, Rust unit/integration/doc tests, and the components' suites.
test: lint
	$(MAKE) --no-print-directory $(TEST_TARGETS)
	@echo "make test: all suites passed"

test-rust: setup
	$(CARGO) test --workspace

## Builds everything and runs the paper's baseline case, writing plots and a summary under out/.
demo: build $(DEMO_TARGETS)
	mkdir -p $(OUT)
	$(BISTABLE) simulate --omega 1.75 --velocity 0.07 --periods 200 \
		--impacts $(OUT)/baseline_impacts.csv --plot $(OUT)/baseline --json > $(OUT)/baseline_summary.json
	$(BISTABLE) simulate --omega 0.2 --velocity 0.05 --t-end 60 \
		--impacts $(OUT)/chatter_impacts.csv --plot $(OUT)/chatter --json > $(OUT)/chatter_summary.json
	@echo "demo: results in $(OUT)/"

## Criterion benches and the work-precision comparison with SciPy (writes docs/benchmarks.md).
bench: setup
	bash bench/run.sh

clean:
	$(CARGO) clean
	rm -rf $(OUT)
