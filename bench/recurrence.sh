#!/usr/bin/env bash
# Basins decided by recurrence against the full decision (docs/benchmarks.md, "Basins by
# recurrence"; docs/sensitivity.md): `bistable basins` on a 1,000 x 1,000 grid, x0 in [0, 1.2],
# x0' in [-0.6, 0.6], plate phase 0, both cores, 4 lanes, with the uncertainty exponent.
#   1. at (1.45, 0.05): --full-decision and the default (recurrence) alternated, ROUNDS rounds
#      (default 2), wall and CPU (user) time from /usr/bin/time;
#   2. with POINTS="1.75:0.07 0.85:0.11" (the default) one pair at each further point;
# then per point the agreement of the two CSVs: cells whose outcome (class, period, chaotic,
# final well, at rest) or attractor (steady state and cycle anchor to 1e-4) differ, listed
# with their distance in grid steps to the nearest cell of another attractor (1: on a
# boundary of the full decision's basins).
set -euo pipefail
cd "$(dirname "$0")/.."
out=target/bench-cache/recurrence
mkdir -p "$out"
cargo build --release -p bistable-cli >/dev/null
bin=target/release/bistable
n=${N:-1000}
grid=(--x-range "0:1.2:$n" --v-range "-0.6:0.6:$n")

# Runs `bistable basins` at point $1 ($2 = omega, $3 = velocity) with decision $4 (full|rec).
timed() {
  local tag=$1 w=$2 v=$3 mode=$4 csv="$out/$1_$4.csv" extra=()
  [ "$mode" = full ] && extra=(--full-decision)
  rm -f "$csv"
  /usr/bin/time -f "%e %U" -o "$out/time.txt" "$bin" basins --omega "$w" --velocity "$v" \
    "${grid[@]}" --out "$csv" --json "${extra[@]}" >"$out/$1_$4.json"
  read -r wall user <"$out/time.txt"
  echo "| ($w, $v) | $mode | $wall | $user |"
}

echo "== machine: $(grep -m1 "model name" /proc/cpuinfo | sed 's/.*: //'), $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg)"
echo "| point | decision | wall (s) | CPU (s) |"
echo "|---|---|---|---|"
for round in $(seq 1 "${ROUNDS:-2}"); do
  timed p145 1.45 0.05 full
  timed p145 1.45 0.05 rec
done
tags=(p145)
for p in ${POINTS-1.75:0.07 0.85:0.11}; do
  w=${p%%:*} v=${p##*:} tag="p${p//[.:]/}"
  timed "$tag" "$w" "$v" full
  timed "$tag" "$w" "$v" rec
  tags+=("$tag")
done
echo "== load at the end: $(cut -d' ' -f1-3 /proc/loadavg)"

for tag in "${tags[@]}"; do
  .venv/bin/python - "$out/${tag}_full.csv" "$out/${tag}_rec.csv" "$n" <<'PY'
import csv, sys
n = int(sys.argv[3])
def load(p):
    return {(float(r["x0"]), float(r["v0"])): r for r in csv.DictReader(open(p))}
full, rec = load(sys.argv[1]), load(sys.argv[2])
def outcome(r):
    return tuple(r[k] for k in ("class", "period", "chaotic", "final_well", "at_rest_in_second_well"))
def attractor(r):
    a = tuple(round(float(r[k]), 4) if r[k] else None for k in ("anchor_x", "anchor_v"))
    return (r["class"] == "continuous_interwell", r["period"], r["chaotic"], r["final_well"],
            r["at_rest_in_second_well"], a)
xs = sorted({k[0] for k in full}); vs = sorted({k[1] for k in full})
ix = {x: i for i, x in enumerate(xs)}; iv = {v: j for j, v in enumerate(vs)}
at = {(ix[k[0]], iv[k[1]]): attractor(r) for k, r in full.items()}
def boundary_distance(i, j):
    # Grid steps to the nearest cell of another attractor in the full decision (Chebyshev).
    for d in range(1, 50):
        for a in range(i - d, i + d + 1):
            for b in range(j - d, j + d + 1):
                if max(abs(a - i), abs(b - j)) == d and (a, b) in at and at[(a, b)] != at[(i, j)]:
                    return d
    return None
differ = [k for k in full if outcome(full[k]) != outcome(rec[k]) or attractor(full[k]) != attractor(rec[k])]
captured = sum(r["decided_by"] == "recurrence" for r in rec.values())
pf = sum(float(r["periods_simulated"]) for r in full.values())
pr = sum(float(r["periods_simulated"]) for r in rec.values())
sf = {attractor(r) for r in full.values()}; sr = {attractor(r) for r in rec.values()}
print(f"{sys.argv[2]}: {len(full)} cells, {len(differ)} differ ({100 * (1 - len(differ) / len(full)):.4f} % agree), "
      f"attractor sets {'equal' if sf == sr else 'DIFFERENT'} ({len(sf)}), {captured} decided by recurrence, "
      f"natural periods simulated {pr:.0f} against {pf:.0f} ({pf / pr:.2f}x)")
for k in sorted(differ):
    d = boundary_distance(ix[k[0]], iv[k[1]])
    print(f"  x0 = {k[0]}, x0' = {k[1]}: full {outcome(full[k])} {attractor(full[k])[5]}, "
          f"recurrence {outcome(rec[k])} {attractor(rec[k])[5]} ({rec[k]['decided_by']}); "
          f"{d} grid steps from another basin")
PY
done
