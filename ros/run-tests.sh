#!/usr/bin/env bash
# Interop tests of the ROS 2 node (make test-ros): each test file in its own network namespace,
# with the ROS 2 venv and the rosidl-built interface package on the paths.
set -euo pipefail
cd "$(dirname "$0")/.."
install=$PWD/target/ros/install
export LD_LIBRARY_PATH=$install/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
export PYTHONPATH=$install/lib/python3.11/site-packages
export RMW_IMPLEMENTATION=rmw_fastrtps_cpp
export BISTABLE_NODE=${BISTABLE_NODE:-$PWD/target/release/bistable_impact_node}
export BISTABLE_REFERENCE=${BISTABLE_REFERENCE:-$PWD/target/release/examples/reference_impacts}
files=("$@")
[ ${#files[@]} -gt 0 ] || files=(tests/ros/test_*.py)
failed=()
for f in "${files[@]}"; do
  echo "== $f"
  start=$SECONDS
  bash ros/netns.sh ros/.venv/bin/python -m pytest -q -p no:cacheprovider "$f" || failed+=("$f")
  echo "== $f: $((SECONDS - start)) s"
done
if [ ${#failed[@]} -gt 0 ]; then
  echo "FAILED: ${failed[*]}" >&2
  exit 1
fi
