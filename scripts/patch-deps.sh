#!/usr/bin/env bash
# Patched dependencies (used through [patch.crates-io] in the top-level Cargo.toml): downloads
# the published crate from crates.io, checks it against the checksum below, unpacks it into
# .deps/ and applies our patches from ros/patches/ in order. Nothing of the dependency is
# committed here; only the patches are. Safe to run repeatedly: does nothing when the patched tree is current.
set -euo pipefail
cd "$(dirname "$0")/.."

patch_crate() { # name version sha256 patch-file...
  local name=$1 version=$2 sum=$3
  shift 3
  local dest=.deps/$name stamp=.deps/$name.stamp
  local want="$name $version $sum $(cat "$@" | sha256sum | cut -d' ' -f1)"
  if [ -f "$dest/Cargo.toml" ] && [ "$(cat "$stamp" 2>/dev/null)" = "$want" ]; then
    return
  fi
  echo "setup: $name $version from crates.io with $*"
  local tmp
  tmp=$(mktemp -d)
  local cached
  cached=$(ls ~/.cargo/registry/cache/*/"$name-$version.crate" 2>/dev/null | head -n1 || true)
  if [ -n "$cached" ]; then
    cp "$cached" "$tmp/crate.tar.gz"
  else
    curl -sSfL --retry 3 -o "$tmp/crate.tar.gz" "https://static.crates.io/crates/$name/$name-$version.crate"
  fi
  echo "$sum  $tmp/crate.tar.gz" | sha256sum -c --quiet -
  rm -rf "$dest" && mkdir -p .deps
  tar xzf "$tmp/crate.tar.gz" -C "$tmp"
  mv "$tmp/$name-$version" "$dest"
  local patchfile
  for patchfile in "$@"; do
    patch -s -p1 -d "$dest" < "$patchfile"
  done
  rm -rf "$tmp"
  echo "$want" > "$stamp"
}

# rustdds (the DDS layer under ros2-client), ros/patches/README.md: a DATA that cannot become a
# sample no longer stalls a reliable reader; a transient-local KEEP_LAST writer offers a
# late-joining reader exactly its last `depth` samples; a received sample keeps a copy of its
# payload, not a slice of the whole receive buffer; a writer tells how many readers are matched
# and how many of its samples are not acknowledged yet; a GAP for a new reader spares what the
# other readers of its receiving process still miss (Cyclone DDS applies it to all of them); a
# discovery writer sends a new Fast DDS reader its samples in order, live only once it is in sync;
# a reader joining next to another reader of its Cyclone DDS process is offered its history from
# what that reader had acknowledged shortly before.
patch_crate rustdds 0.15.1 42683a88b9dc025d7d45771b88d20846443b4901ec4b045ca78b8dd316ab616f \
  ros/patches/rustdds-0.15.1-irrelevant-undecodable-data.patch \
  ros/patches/rustdds-0.15.1-transient-local-history.patch \
  ros/patches/rustdds-0.15.1-own-received-payloads.patch \
  ros/patches/rustdds-0.15.1-writer-status.patch \
  ros/patches/rustdds-0.15.1-gaps-for-shared-readers.patch \
  ros/patches/rustdds-0.15.1-builtin-live-in-sync.patch \
  ros/patches/rustdds-0.15.1-late-reader-history.patch

# ros2-client: a Publisher waits for the acknowledgements of what it published (the node's
# shutdown), tells how many are missing and how many subscriptions are matched.
patch_crate ros2-client 0.12.1 1fe08f96d441e37bffbfa487f3feebbdc5952ee6db2edc7861592913328f7031 \
  ros/patches/ros2-client-0.12.1-publisher-status.patch
