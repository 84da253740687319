#!/usr/bin/env bash
# valgrind memcheck over the C host: the `test` scenario and fuzz seeds, against the release
# library with line tables (target/release/libbistable_impact.so; the packaged copy is stripped).
# Prints, per scenario, the error count and the leak summary (definitely / indirectly / possibly
# lost, still reachable) and fails on any error or definite/possible leak (memcheck's defaults
# with --error-exitcode=1). No suppression file is used. The fuzz seeds' digests under valgrind
# must equal those of a native run: a seed's sequence does not depend on the allocator.
#
#   bash fmu/valgrind.sh HOST LIB.so SEEDS NCALLS        (part of make stress-fmu)
#   bash fmu/valgrind.sh HOST3 LIB.so SEEDS NCALLS MD3   the FMI 3.0 host (target/fmu/host3) with the
#                                                        FMI 3.0 modelDescription.xml
set -euo pipefail
cd "$(dirname "$0")/.."
host=$1 lib=$2 seeds=$3 calls=$4
md=${5:-modelDescription.xml}

if ! command -v valgrind >/dev/null; then
  echo "valgrind: installing the Debian package"
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq valgrind >/dev/null
fi

dir=$(mktemp -d /tmp/fmuvalgrind-XXXXXX)
trap 'rm -rf "$dir"' EXIT
status=0

# memcheck NAME ARGS...: runs the host under memcheck, prints the figures.
memcheck() {
  local name=$1; shift
  local start rc=0
  start=$(date +%s)
  FUZZ_CALL_TIMEOUT=600 valgrind --tool=memcheck --leak-check=full --error-exitcode=1 \
    --log-file="$dir/$name.vg" "$host" "$@" >"$dir/$name.out" 2>&1 || rc=$?
  local errors definite indirect possible reachable
  errors=$(sed -n 's/.*ERROR SUMMARY: \([0-9,]*\) errors.*/\1/p' "$dir/$name.vg" | tail -n 1)
  definite=$(sed -n 's/.*definitely lost: \([0-9,]*\) bytes.*/\1/p' "$dir/$name.vg" | tail -n 1)
  indirect=$(sed -n 's/.*indirectly lost: \([0-9,]*\) bytes.*/\1/p' "$dir/$name.vg" | tail -n 1)
  possible=$(sed -n 's/.*possibly lost: \([0-9,]*\) bytes.*/\1/p' "$dir/$name.vg" | tail -n 1)
  reachable=$(sed -n 's/.*still reachable: \([0-9,]*\) bytes in \([0-9,]*\) blocks.*/\1 bytes in \2 blocks/p' "$dir/$name.vg" | tail -n 1)
  grep -q "All heap blocks were freed" "$dir/$name.vg" && definite=0 indirect=0 possible=0 reachable="0 bytes"
  echo "valgrind: $name: ${errors:-?} errors; definitely lost ${definite:-?} B, indirectly lost ${indirect:-?} B, possibly lost ${possible:-?} B, still reachable ${reachable:-?}; $(( $(date +%s) - start )) s; exit $rc"
  if [ "$rc" -ne 0 ]; then
    tail -n 40 "$dir/$name.out"
    grep -v '^==[0-9]*== *$' "$dir/$name.vg" | head -n 80
    status=1
  fi
}

memcheck test test "$lib" "$md"
grep -E 'passed, [0-9]+ failed' "$dir/test.out" | sed 's/^/valgrind: test: /'
memcheck fuzz fuzz "$lib" "$md" "$seeds" "$calls"
grep -E '^fuzz: [0-9]+ invariant violations|^fuzz:   calls ' "$dir/fuzz.out" | sed 's/^/valgrind: /'

# The same seeds natively: identical digests.
"$host" fuzz "$lib" "$md" "$seeds" "$calls" >"$dir/native.out" 2>&1 || status=1
if diff <(grep -o '^seed [0-9]*:.*digest [0-9a-f]*' "$dir/fuzz.out" | sed 's/:.*digest/ digest/') \
        <(grep -o '^seed [0-9]*:.*digest [0-9a-f]*' "$dir/native.out" | sed 's/:.*digest/ digest/') >/dev/null; then
  echo "valgrind: fuzz digests under valgrind equal the native run's ($(grep -c '^seed ' "$dir/native.out") seeds)"
else
  echo "valgrind: fuzz digests differ between valgrind and the native run"
  status=1
fi
exit $status
