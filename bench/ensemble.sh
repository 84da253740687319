#!/usr/bin/env bash
# Ensembles in SIMD lanes against one trajectory at a time, each pair measured alternately in
# one run on this machine (docs/benchmarks.md, "Ensembles"):
#   1. trajectory-steps per second (thread CPU time) of lone simulators and of batches of 4 and 8 lanes, on one
#      core: aperiodic runs of the map and free flights (crates/bistable-core/examples/
#      batch_throughput.rs);
#   2. heyoka's batch mode against its scalar mode on the free flight (bench/heyoka_batch.py;
#      heyoka from bench/requirements.txt, installed into .venv here), the peer's anchor;
#   3. `bistable map` 60 x 40 (sensitivity test on) with --lanes 1, 4 and 8, twice each, and a
#      400-point bifurcation diagram's recorded runs with --lanes 1 and 4, twice each;
#   4. with ENSEMBLE_FULL=1 also the 300 x 200 map and a 1,000 x 1,000 basins grid at
#      (1.45, 0.05), --lanes 4 against --lanes 1 (about 25 minutes).
# Wall and CPU (user) times from /usr/bin/time; CSVs compared in every column but the wall time.
set -euo pipefail
cd "$(dirname "$0")/.."
[ -x .venv/bin/python ] || bash scripts/setup.sh
out=target/bench-cache/ensemble
mkdir -p "$out"
cargo build --release -p bistable-cli -p bistable-core --example batch_throughput >/dev/null
bin=target/release/bistable

echo "== machine"
grep -m1 "model name" /proc/cpuinfo | sed 's/.*: //'
echo "cores: $(nproc); AVX-512F: $(grep -q avx512f /proc/cpuinfo && echo yes || echo no)"

echo "== 1. trajectory-steps per second, one core"
target/release/examples/batch_throughput 64 2000 3
target/release/examples/batch_throughput 256 200 3 flight

echo "== 2. heyoka batch mode (free flight)"
if .venv/bin/pip install -q -r bench/requirements.txt; then
  .venv/bin/python bench/heyoka_batch.py --json "$out/heyoka_batch.json"
else
  echo "heyoka could not be installed: skipped"
fi

# Runs `bistable map|basins ... --lanes N --out FILE` under /usr/bin/time; prints a table row.
timed() {
  local label=$1 lanes=$2 csv=$3; shift 3
  rm -f "$csv"
  /usr/bin/time -f "%e %U" -o "$out/time.txt" "$bin" "$@" --lanes "$lanes" --out "$csv" --json >/dev/null
  read -r wall user <"$out/time.txt"
  echo "| $label | $lanes | $wall | $user |"
}

# Every column but the wall time equal between two CSVs (rows in any order).
same() {
  .venv/bin/python - "$1" "$2" <<'PY'
import csv, sys
def rows(p):
    with open(p) as f:
        r = list(csv.DictReader(f))
    return sorted(tuple(v for k, v in row.items() if "wall" not in k) for row in r)
a, b = rows(sys.argv[1]), rows(sys.argv[2])
print(f"{sys.argv[1]} vs {sys.argv[2]}: {len(a)} rows, {'identical' if a == b else 'DIFFERENT'}")
sys.exit(0 if a == b else 1)
PY
}

echo "== 3. map 60 x 40, both cores"
map60=(map --omega-range 0.2:3.5:60 --velocity-range 0.005:0.2:40)
echo "| run | lanes | wall (s) | CPU (s) |"
echo "|---|---|---|---|"
for round in 1 2; do
  for lanes in 1 4 8; do
    timed "60 x 40, round $round" "$lanes" "$out/map60_$lanes.csv" "${map60[@]}"
  done
done
same "$out/map60_1.csv" "$out/map60_4.csv"
same "$out/map60_1.csv" "$out/map60_8.csv"

echo "== 3b. bifurcation diagram, 400 points, both cores (no branches: the recorded runs only)"
bif=(bifurcation --param omega --range 0.5:3.0:400 --velocity 0.07 --transient 2000 --record 200
  --no-branches)
echo "| run | lanes | wall (s) | CPU (s) |"
echo "|---|---|---|---|"
for round in 1 2; do
  for lanes in 1 4; do
    timed "bifurcation, round $round" "$lanes" "$out/bif_$lanes.csv" "${bif[@]}"
  done
done
if cmp -s "$out/bif_1.csv" "$out/bif_4.csv"; then
  echo "$out/bif_1.csv vs $out/bif_4.csv: identical bytes"
else
  echo "$out/bif_1.csv vs $out/bif_4.csv: DIFFERENT"
  exit 1
fi

if [ "${ENSEMBLE_FULL:-0}" = 1 ]; then
  echo "== 4. map 300 x 200 and basins 1000 x 1000, both cores"
  map300=(map --omega-range 0.2:3.5:300 --velocity-range 0.005:0.2:200)
  basins=(basins --omega 1.45 --velocity 0.05 --x-range 0:1.2:1000 --v-range -0.6:0.6:1000)
  echo "| run | lanes | wall (s) | CPU (s) |"
  echo "|---|---|---|---|"
  timed "map 300 x 200" 4 "$out/map300_4.csv" "${map300[@]}"
  timed "map 300 x 200" 1 "$out/map300_1.csv" "${map300[@]}"
  timed "basins 1000 x 1000" 1 "$out/basins_1.csv" "${basins[@]}"
  timed "basins 1000 x 1000" 4 "$out/basins_4.csv" "${basins[@]}"
  same "$out/map300_1.csv" "$out/map300_4.csv"
  same "$out/basins_1.csv" "$out/basins_4.csv"
fi
