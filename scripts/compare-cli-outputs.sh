#!/usr/bin/env bash
# Runs every `bistable` subcommand on small but representative inputs with two binaries and
# compares what they write, byte for byte: stdout, stderr, exit codes, CSV files and PNGs.
#
#   scripts/compare-cli-outputs.sh BEFORE_BIN AFTER_BIN [WORKDIR]
#
# Used to check that moving code between crates leaves the CLI's outputs unchanged. Each binary
# runs in its own directory under WORKDIR (default: a fresh temporary directory) with relative
# paths, so file names in the outputs agree. Wall-clock figures (wall_time_s, plot_time_s,
# points_per_second, point_time_s and the map CSV's wall_time_s column) are replaced by `T`
# before comparing; everything else must be identical. Runs that spread work over threads use
# --threads 1 (results arrive in a fixed order), except one map run on 2 threads whose rows are
# compared sorted. Exit code 0 when all outputs agree, 1 otherwise (the differences are listed).
set -euo pipefail

if [ $# -lt 2 ]; then
  echo "usage: $0 BEFORE_BIN AFTER_BIN [WORKDIR]" >&2
  exit 2
fi
before=$(realpath "$1")
after=$(realpath "$2")
work=${3:-$(mktemp -d)}
mkdir -p "$work"
work=$(realpath "$work")

# run NAME ARGS...: stdout, stderr and exit code of `bistable ARGS` go to NAME.{out,err,code}.
run() {
  local name=$1
  shift
  local code=0
  "$BIN" "$@" >"$name.out" 2>"$name.err" || code=$?
  echo "$code" >"$name.code"
}

record() { # BIN DIR
  BIN=$1
  rm -rf "$2"
  mkdir -p "$2"
  (
    cd "$2"
    run simulate_baseline simulate --omega 1.75 --velocity 0.07 --periods 100 \
      --impacts sim/impacts.csv --trace sim/trace.csv --dt 0.05 --json
    run simulate_chatter simulate --omega 0.2 --velocity 0.05 --t-end 60 \
      --impacts chatter/impacts.csv --trace chatter/trace.csv --dt 0.01 --trace-mode \
      --plot chatter/plots --json
    run simulate_text simulate --omega 2.45 --velocity 0.07 --periods 50 --chatter paper
    run classify_intrawell classify --omega 0.85 --velocity 0.11
    run classify_well2 classify --omega 0.85 --velocity 0.15
    run classify_chaos classify --omega 2.45 --velocity 0.07
    run classify_full classify --omega 0.85 --velocity 0.11 --full --max-periods 3000 \
      --restitution 0.7
    run map map --omega-range 0.4:3.2:12 --velocity-range 0.01:0.2:8 --max-periods 3000 \
      --out map/map.csv --plot map/map.png --threads 1 --json
    run map_resume map --omega-range 0.4:3.2:12 --velocity-range 0.01:0.2:8 \
      --max-periods 3000 --out map/map.csv --threads 1 --json
    run map_threads map --omega-range 0.4:3.2:6 --velocity-range 0.01:0.2:4 \
      --max-periods 3000 --out map/map2.csv --threads 2 --json
    run bifurcation_omega bifurcation --param omega --range 2.0:2.7:15 --velocity 0.07 \
      --transient 300 --record 40 --out bif/omega.csv --plot bif/omega.png --threads 1 --json
    run bifurcation_velocity bifurcation --param velocity --range 0.05:0.15:6 --omega 0.85 \
      --transient 300 --record 30 --out bif/velocity.csv --threads 1
    run orbit_json orbit --omega 1.75 --velocity 0.07 --json
    run orbit_p2 orbit --omega 2.2 --velocity 0.07 --period 2
    run orbit_guess orbit --omega 2.2 --velocity 0.07 --guess 0.05,0.1 --json
    run orbit_natural orbit --continue-omega 1.4:2.6:13 --velocity 0.05,0.07 --settle 500 \
      --out orbit/natural.csv --plot orbit/natural.png --threads 1 --json
    run orbit_arclength orbit --continue-omega 1.4:2.6:13 --velocity 0.05,0.07 --settle 500 \
      --arclength --out orbit/arc.csv --plot orbit/arc.png --threads 1
    run orbit_folds orbit --continue-omega 0.8:2.0:31 --velocity 0.03 --settle 500 \
      --arclength --out orbit/folds.csv --threads 1 --json
    run basins basins --omega 1.45 --velocity 0.05 --x-range 0.1:1.3:12 --v-range -0.5:0.5:10 \
      --max-periods 2000 --uncertainty-samples 40 --out basins/basins.csv --plot basins/basins.png \
      --threads 1 --json
    run basins_resume basins --omega 1.45 --velocity 0.05 --x-range 0.1:1.3:12 --v-range -0.5:0.5:10 \
      --max-periods 2000 --uncertainty-samples 40 --out basins/basins.csv --threads 1 --json
    run bad_basins_start basins --omega 1.45 --velocity 0.05 --x-range -0.5:0.5:3 --v-range 0:0.1:2 \
      --out x.csv
    run thresholds thresholds
    run thresholds_json thresholds --restitution 0.7 --omega 0.3 --json
    run energy_map energy-map --plot em/plain.png
    run energy_map_overlay energy-map --overlay --omega 2.45 --velocity 0.07 --periods 100 \
      --plot em/overlay.png --restitution 0.8
    run spectrum_chaos spectrum --omega 2.45 --velocity 0.07 --record 256 --json \
      --out sp/chaos.csv --plot sp/chaos.png
    run spectrum_p2 spectrum --omega 2.2 --velocity 0.07 --record 128 --transient 300
    run bad_restitution classify --omega 1 --velocity 0.1 --restitution 1.5
    run bad_range map --omega-range 0:1:3 --velocity-range 0.1:0.2:2 --out x.csv
    run bad_period orbit --omega 1 --velocity 0.1 --period 0
    run bad_samples bifurcation --param omega --range 1:2:3 --velocity 0.1 --samples 4 --json
    run bad_record spectrum --omega 2 --velocity 0.1 --record 0
    run bad_spectrum_samples spectrum --omega 2 --velocity 0.1 --samples 3
    run bad_threads map --omega-range 1:2:2 --velocity-range 0.1:0.2:2 --out x.csv --threads 0
  )
  # Wall-clock figures vary from run to run; map's class counts are a hash map printed in
  # an arbitrary order (sorted here, trailing commas dropped).
  find "$2" -name '*.out' -exec sed -i -E \
    -e 's/("(wall_time_s|plot_time_s|points_per_second|point_time_s)": )[-0-9.e+]+/\1T/' \
    -e 's/(Taylor steps, )[0-9.]+ s/\1T s/; s/\(\+ [0-9.]+ s plotting\)/(+ T s plotting)/' \
    -e 's/(recorded shaker periods per point, )[0-9.]+ s\)/\1T s)/' {} +
  for f in "$2"/map*.out; do
    awk '/"counts": \{/ { print; inside = 1; n = 0; next }
         inside && /^ *\}/ { sort_counts(); inside = 0 }
         inside { sub(/,$/, ""); lines[n++] = $0; next }
         { print }
         function sort_counts(  i, j, t) {
           for (i = 1; i < n; i++) for (j = i; j > 0 && lines[j - 1] > lines[j]; j--) {
             t = lines[j]; lines[j] = lines[j - 1]; lines[j - 1] = t }
           for (i = 0; i < n; i++) print lines[i]
         }' "$f" >"$f.tmp" && mv "$f.tmp" "$f"
  done
  for f in "$2"/map/map.csv "$2"/map/map2.csv; do
    # Mask the column named wall_time_s (wherever it is) in every row but the header.
    [ -f "$f" ] && awk -F, -v OFS=, 'NR == 1 { for (i = 1; i <= NF; i++) if ($i == "wall_time_s") c = i; print; next }
      c { $c = "T" } { print }' "$f" >"$f.tmp" && mv "$f.tmp" "$f"
  done
  if [ -f "$2/map/map2.csv" ]; then
    (head -n1 "$2/map/map2.csv" && tail -n +2 "$2/map/map2.csv" | sort) >"$2/map/map2.sorted"
    rm "$2/map/map2.csv"
  fi
}

record "$before" "$work/before"
record "$after" "$work/after"

status=0
files=0
while IFS= read -r f; do
  files=$((files + 1))
  if [ ! -f "$work/after/$f" ]; then
    echo "only before: $f"
    status=1
  elif ! cmp -s "$work/before/$f" "$work/after/$f"; then
    echo "differs: $f"
    status=1
  fi
done < <(cd "$work/before" && find . -type f | sort)
while IFS= read -r f; do
  [ -f "$work/before/$f" ] || { echo "only after: $f"; status=1; }
done < <(cd "$work/after" && find . -type f | sort)

if [ $status -eq 0 ]; then
  echo "compare-cli-outputs: all $files files identical ($work)"
else
  echo "compare-cli-outputs: outputs differ ($work)"
fi
exit $status
