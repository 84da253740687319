#!/usr/bin/env bash
# `make bench`: builds the release binaries, runs the criterion benches in quick mode and the
# work-precision comparison against SciPy, and rewrites docs/benchmarks.md and
# docs/work_precision.png from the measurements of this run.
#
# Environment: BENCH_QUICK=1 for a fast smoke run (fewer tolerances, SciPy's 20,000-period run
# extrapolated from tau = 2000: numbers not for publication); BENCH_LONG_REF=1 to compute the
# reference over the whole 20,000 periods (about 35 min, cached in target/bench-cache/).
# Extra arguments go to bench/work_precision.py.
set -euo pipefail
cd "$(dirname "$0")/.."

# Single-threaded timings: no BLAS/OpenMP thread pools in the Python peer.
export OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 MKL_NUM_THREADS=1

[ -x .venv/bin/python ] || bash scripts/setup.sh

echo "== build (release)"
cargo build --release -p bistable-reference --bin bistable-reference
cargo build --release -p bistable-core --example work_precision

mkdir -p target/bench-cache
echo "== criterion (quick)"
cargo bench -p bistable-core --bench simulate -- --quick 2>&1 | tee target/bench-cache/criterion.txt

echo "== work-precision"
args=(--criterion-log target/bench-cache/criterion.txt)
[ "${BENCH_QUICK:-0}" = 1 ] && args+=(--quick)
[ "${BENCH_LONG_REF:-0}" = 1 ] && args+=(--long-ref)
.venv/bin/python bench/work_precision.py "${args[@]}" "$@"
