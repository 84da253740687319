#!/usr/bin/env python3
"""Points of a `bistable map` grid whose label changes with the integrator tolerance.

Usage: scripts/sensitive-flips.py MAP_1e-16.csv MAP_1e-15.csv MAP_1e-14.csv > FLIPS.csv

The maps are the same grid computed with `--tol 1e-16`, `1e-15` and `1e-14` (and otherwise
the same options). A point's label is (class, period, chaotic, final_well,
at_rest_in_second_well); a point flips when its three labels are not all equal. Prints omega,
velocity and the three labels (`class/period/chaotic/well/rest`) as CSV, in grid order.
"""
import csv
import sys


def load(path):
    with open(path) as f:
        return {(r["omega"], r["velocity"]): r for r in csv.DictReader(f)}


def label(r):
    return "/".join(
        r[k] for k in ("class", "period", "chaotic", "final_well", "at_rest_in_second_well")
    )


def main(paths):
    maps = [load(p) for p in paths]
    keys = sorted(maps[0], key=lambda k: (float(k[0]), float(k[1])))
    w = csv.writer(sys.stdout, lineterminator="\n")
    w.writerow(["omega", "velocity"] + [f"label_{i}" for i in range(len(maps))])
    for k in keys:
        labels = [label(m[k]) for m in maps]
        if len(set(labels)) > 1:
            w.writerow([k[0], k[1]] + labels)


if __name__ == "__main__":
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    main(sys.argv[1:])
