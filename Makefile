# bistable-impact: build, test, demo and benchmark entry points.
# Every target installs what it needs through scripts/setup.sh (Debian packages, Python venv).

CARGO ?= cargo
OUT ?= out
BISTABLE := target/release/bistable

.PHONY: all setup build test lint demo bench clean

all: build

setup:
	bash scripts/setup.sh

build: setup
	$(CARGO) build --release --workspace

lint: setup
	$(CARGO) fmt --all -- --check
	$(CARGO) clippy --workspace --all-targets -- -D warnings

## Every test: formatting, lints, Rust unit/integration/doc tests.
test: lint
	$(CARGO) test --workspace
	@echo "make test: all suites passed"

## Builds everything and runs the paper's baseline case, writing plots and a summary under out/.
demo: build
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
