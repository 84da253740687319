#!/usr/bin/env bash
# Installs everything the build, the tests and the demo need: Debian packages listed in
# scripts/apt-packages.txt (only those missing), a Python venv at .venv with
# scripts/requirements.txt, the patched dependencies in .deps/ (scripts/patch-deps.sh) and the
# Python package crates/bistable-py. Safe to run repeatedly; does nothing when all is in place.
set -euo pipefail
cd "$(dirname "$0")/.."

mapfile -t pkgs < <(grep -v '^\s*#' scripts/apt-packages.txt | tr -s ' \t' '\n' | grep -v '^$')
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ "${#missing[@]}" -gt 0 ]; then
  echo "setup: installing Debian packages: ${missing[*]}"
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${missing[@]}" >/dev/null
fi

stamp=.venv/.requirements.stamp
if [ ! -x .venv/bin/python ] || ! cmp -s scripts/requirements.txt "$stamp"; then
  echo "setup: creating Python venv .venv"
  python3 -m venv .venv
  .venv/bin/pip install -q --upgrade pip
  .venv/bin/pip install -q -r scripts/requirements.txt
  cp scripts/requirements.txt "$stamp"
fi

bash scripts/patch-deps.sh

# The Python package bistable_impact (crates/bistable-py) in .venv, rebuilt only when its sources
# or those of the crates it wraps change (a hash of them is kept in the stamp).
py_stamp=.venv/.bistable-py.stamp
py_hash=$(find crates/bistable-py crates/bistable-core crates/bistable-analysis Cargo.toml Cargo.lock \
  -type f \( -name '*.rs' -o -name '*.py' -o -name '*.pyi' -o -name '*.toml' -o -name '*.lock' \
  -o -name py.typed -o -name '*.md' \) -not -path '*/__pycache__/*' -not -path '*/benches/*' \
  -not -path '*/tests/*' -not -path '*/examples/*' | LC_ALL=C sort | xargs sha256sum | sha256sum | cut -d' ' -f1)
if [ "$(cat "$py_stamp" 2>/dev/null)" != "$py_hash" ]; then
  echo "setup: installing the Python package bistable_impact (crates/bistable-py) into .venv"
  .venv/bin/pip install -q crates/bistable-py
  echo "$py_hash" >"$py_stamp"
fi
