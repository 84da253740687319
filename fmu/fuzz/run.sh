#!/usr/bin/env bash
# Runs each cargo-fuzz (libFuzzer) target of the FMU for FUZZ_SECONDS and reports, from
# libFuzzer's final statistics, the executions, the coverage (edges "cov", features "ft") and
# the corpus size. Installs cargo-fuzz (cargo install --locked) and the nightly toolchain when
# missing. Part of `make stress-fmu`.
#
#   bash fmu/fuzz/run.sh [SECONDS] [TARGET...]
#   FUZZ_SECONDS (default 300), FUZZ_TIMEOUT (per input, default 20 s), FUZZ_CORPUS (working
#   corpus, default fmu/fuzz/corpus; kept between runs, not committed), FUZZ_JOBS (default 1).
# A crash, timeout or leak stops the run with libFuzzer's report and the artifact under
# fmu/fuzz/artifacts/<target>/ (reproduce: cd fmu && cargo +nightly fuzz run <target> <artifact>).
set -euo pipefail
cd "$(dirname "$0")/.."   # fmu/

seconds=${1:-${FUZZ_SECONDS:-300}}
shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(deserialize_state setters)
timeout_s=${FUZZ_TIMEOUT:-20}
corpus_root=${FUZZ_CORPUS:-fuzz/corpus}

if ! rustup toolchain list | grep -q '^nightly'; then
  echo "fuzz: installing the nightly toolchain (cargo-fuzz needs it for the sanitizer flags)"
  rustup toolchain install nightly --profile minimal
fi
if ! cargo fuzz --version >/dev/null 2>&1; then
  echo "fuzz: installing cargo-fuzz"
  cargo install cargo-fuzz --locked
fi

logdir=$(mktemp -d /tmp/fmufuzz-XXXXXX)
trap 'rm -rf "$logdir"' EXIT
status=0
summary=()
for t in "${targets[@]}"; do
  mkdir -p "$corpus_root/$t"
  seeds=()
  [ -d "fuzz/seeds/$t" ] && seeds=("fuzz/seeds/$t")
  echo "fuzz: $t for ${seconds} s (corpus $corpus_root/$t${seeds:+, seeds ${seeds[*]}})"
  log="$logdir/$t.log"
  start=$(date +%s)
  if ! cargo +nightly fuzz run "$t" "$corpus_root/$t" "${seeds[@]}" -- \
      -max_total_time="$seconds" -timeout="$timeout_s" -print_final_stats=1 >"$log" 2>&1; then
    tail -n 60 "$log"
    echo "fuzz: $t FAILED (see the artifact above)"
    status=1
  fi
  wall=$(( $(date +%s) - start ))
  done_line=$(grep -E '^#[0-9]+[[:space:]]+DONE' "$log" | tail -n 1 || true)
  runs=$(sed -n 's/^Done \([0-9]*\) runs in \([0-9]*\) second.*/\1 executions in \2 s/p' "$log" | tail -n 1)
  cov=$(sed -n 's/.*cov: \([0-9]*\) ft: \([0-9]*\) corp: \([0-9]*\)\/\([^ ]*\).*exec\/s: \([0-9]*\).*/cov \1 edges, ft \2 features, corpus \3 inputs (\4), \5 exec\/s/p' <<<"$done_line")
  line="fuzz: $t: ${runs:-no final stats}; ${cov:-?}; wall ${wall} s incl. build"
  echo "$line"
  summary+=("$line")
done
printf '%s\n' "${summary[@]}"
exit $status
