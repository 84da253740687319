#!/usr/bin/env bash
# The coexistence map's cost (docs/benchmarks.md, "Coexistence map"): the 60 × 40 grid of the
# paper's Fig. 9 with 400 starts per point (`bistable coexistence`'s defaults), once by the CLI
# on all cores and once through the Python package on the package's lean Dask LocalCluster
# (bi.cluster.local_cluster) of 2 worker processes of 1 thread each (bench/coexistence_dask.py),
# alternated (CLI, Dask, CLI, Dask unless ROUNDS says otherwise); wall and CPU
# time of each (CPU: the process and its reaped children, i.e. the Dask workers), and a check
# that the Dask table equals the CLI's CSV value for value. Also the consistency with
# `bistable map`: the share of points where the paper's start has the class and period the map
# reports. Writes under OUT (default out/bench-coexistence).
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=${OUT:-out/bench-coexistence}
ROUNDS=${ROUNDS:-2}
GRID=(--omega-range 0.2:3.5:60 --velocity-range 0.005:0.2:40)
mkdir -p "$OUT"
cargo build --release -q -p bistable-cli
bash scripts/setup.sh >/dev/null
timed() { # label, command...
  local label=$1; shift
  /usr/bin/time -f "$label wall %e s, CPU %U s user + %S s sys" "$@"
}
for r in $(seq "$ROUNDS"); do
  rm -f "$OUT/cli.csv"
  timed "round $r cli:" target/release/bistable coexistence "${GRID[@]}" --out "$OUT/cli.csv" \
    --json > "$OUT/cli.json"
  timed "round $r dask:" .venv/bin/python bench/coexistence_dask.py "$OUT"
  .venv/bin/python - "$OUT" <<'PY'
import sys
import pandas as pd
import bistable_impact as bi
out = sys.argv[1]
cli = bi.coexistence.read_csv(f"{out}/cli.csv")
dask = bi.coexistence.read_csv(f"{out}/dask.csv")
pd.testing.assert_frame_equal(cli, dask, check_exact=True)
print(f"dask table equals the CLI's: {len(cli)} rows, {cli.groupby(['omega', 'velocity']).ngroups} points")
PY
done
if [ ! -f "$OUT/map.csv" ]; then
  target/release/bistable map "${GRID[@]}" --out "$OUT/map.csv" --json > /dev/null
fi
.venv/bin/python - "$OUT" <<'PY'
import sys
import pandas as pd
import bistable_impact as bi
out = sys.argv[1]
co = bi.coexistence.read_csv(f"{out}/cli.csv")
m = bi.sweep.read_csv(f"{out}/map.csv")
paper = co[co["paper_start"]].set_index(["omega", "velocity"])
m = m.set_index(["omega", "velocity"])
j = paper.merge(m[["class", "period", "sensitive"]], left_index=True, right_index=True,
                how="left", suffixes=("", "_map"))
same = (j["paper_class"] == j["class_map"]) & (j["paper_period"].fillna(-1) == j["period_map"].fillna(-1))
print(f"consistency with bistable map: {same.sum()} of {len(j)} points ({100 * same.mean():.2f} %)")
for k, r in j[~same].iterrows():
    print(f"  differs at {k}: {r['paper_class']} P-{r['paper_period']} against {r['class_map']} P-{r['period_map']} (map sensitive: {r['sensitive']})")
counts = co.groupby(["omega", "velocity"])["attractors"].first().value_counts().sort_index()
print("points by coexisting attractors:", dict(counts))
print("points where the paper's start is in a minority basin:",
      int((paper["fraction"] < 0.5).sum()))
PY
