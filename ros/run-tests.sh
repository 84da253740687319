#!/usr/bin/env bash
# Interop tests of the ROS 2 node (make test-ros): each test file in its own network namespace,
# with the ROS 2 venv and the rosidl-built interface package on the paths.
# ROS_TEST_REPEAT=N runs each file N times in a row, each run in a fresh namespace (nodes and
# peers started anew), and reports how many runs of each failed (make stress-ros).
set -euo pipefail
cd "$(dirname "$0")/.."
install=$PWD/target/ros/install
export LD_LIBRARY_PATH=$install/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
export PYTHONPATH=$install/lib/python3.11/site-packages
export RMW_IMPLEMENTATION=rmw_fastrtps_cpp
export BISTABLE_NODE=${BISTABLE_NODE:-$PWD/target/release/bistable_impact_node}
export BISTABLE_REFERENCE=${BISTABLE_REFERENCE:-$PWD/target/release/examples/reference_impacts}
repeat=${ROS_TEST_REPEAT:-1}
files=("$@")
[ ${#files[@]} -gt 0 ] || files=(tests/ros/test_*.py)
failed=()
for f in "${files[@]}"; do
  runs_failed=0
  for ((run = 1; run <= repeat; run++)); do
    [ "$repeat" -eq 1 ] && echo "== $f" || echo "== $f (run $run of $repeat)"
    start=$SECONDS
    bash ros/netns.sh ros/.venv/bin/python -m pytest -q -p no:cacheprovider "$f" || runs_failed=$((runs_failed + 1))
    echo "== $f: $((SECONDS - start)) s"
  done
  [ "$repeat" -eq 1 ] || echo "== $f: $repeat runs, $runs_failed failed"
  [ "$runs_failed" -eq 0 ] || failed+=("$f")
done
if [ ${#failed[@]} -gt 0 ]; then
  echo "FAILED: ${failed[*]}" >&2
  exit 1
fi
