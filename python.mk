# Python package bistable_impact (crates/bistable-py, PyO3 + maturin). Included by the top-level
# Makefile. scripts/setup.sh installs it into .venv whenever its sources (or the Rust crates it
# wraps) change; `pip install crates/bistable-py` installs it into any venv.
#   make test-python   pytest tests/python against the CLI and the high-precision reference
#   make python-wheel  target/wheels/bistable_impact-*-cp39-abi3-*.whl

.PHONY: test-python python-wheel

TEST_TARGETS += test-python

test-python: setup
	$(CARGO) build --release -p bistable-cli -p bistable-reference
	.venv/bin/python -m pytest -q tests/python

python-wheel: setup
	.venv/bin/pip wheel --no-deps -w target/wheels crates/bistable-py
