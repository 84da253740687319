"""Benchmarks of the Python package against the CLI, in one run on this machine:

* the response-class map (Fig. 9) through ``bistable_impact.sweep.map`` on a
  ``dask.distributed`` LocalCluster of 2 worker processes (1 thread each; the package's
  ``cluster.local_cluster`` with its lean settings, or with ``--dask-defaults`` Dask's own
  defaults), through ``sweep.map``
  on 2 local Rust threads, and through ``target/release/bistable map --threads 2``; rounds in
  alternating order, each result checked against the CLI's map (same class at every point);
  wall and CPU time (the CLI's from rusage of the child, the workers' from their
  ``time.process_time``, plus this process's), since wall times on a loaded machine vary; and
  what the idle cluster itself uses per wall second (event loops, heartbeats, profilers), which
  a map pays for as long as it runs, so that a slow (loaded) round pays more of it;
* the call overhead of ``simulate()`` for a 1-impact run (Ω = 1.75, V = 0.07, τ ≤ 1: only the
  impact at τ = 0): the time of the whole call against the run's own time inside Rust
  (``summary['wall_time_s']``).

    .venv/bin/python bench/python_map.py [--omega-range A:B:N] [--velocity-range A:B:N]
        [--rounds R] [--calls N] [--methods cli,dask,local] [--dask-defaults]

Prints a Markdown report (machine, load, command, tables) on stdout.
"""

from __future__ import annotations

import argparse
import os
import platform
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from typing import Dict, List, Tuple

import pandas as pd

import bistable_impact as bi

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CLI = os.path.join(ROOT, "target", "release", "bistable")


def grid(text: str) -> List[float]:
    a, b, n = text.split(":")
    return list(bi.linspace(float(a), float(b), int(n)))


def children_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def run_cli(omega_range: str, velocity_range: str, out: str) -> Tuple[float, float]:
    """Wall and CPU time (s) of `bistable map`."""
    if os.path.exists(out):
        os.remove(out)  # the CLI would resume from it
    c, t = children_cpu(), time.perf_counter()
    subprocess.run(
        [CLI, "map", "--omega-range", omega_range, "--velocity-range", velocity_range,
         "--threads", "2", "--out", out],
        check=True, capture_output=True,
    )  # fmt: skip
    return time.perf_counter() - t, children_cpu() - c


def classes(df: pd.DataFrame) -> Dict[tuple, str]:
    return dict(zip(zip(df["omega"], df["velocity"]), df["class"]))


def print_simulate(n: int, calls: List[float], inside: List[float]) -> None:
    med_call, med_in = statistics.median(calls), statistics.median(inside)
    print(f"`simulate(1.75, 0.07, t_end=1.0)` (1 impact), {n} calls after 200 warm-up:\n")
    print("| quantity | median | 10 % | 90 % |")
    print("|---|---|---|---|")
    q = lambda xs, f: sorted(xs)[int(f * (len(xs) - 1))]  # noqa: E731
    print(f"| whole call | {1e6 * med_call:.1f} µs | {1e6 * q(calls, 0.1):.1f} µs | "
          f"{1e6 * q(calls, 0.9):.1f} µs |")
    print(f"| the run inside Rust (`summary['wall_time_s']`) | {1e6 * med_in:.1f} µs | "
          f"{1e6 * q(inside, 0.1):.1f} µs | {1e6 * q(inside, 0.9):.1f} µs |")
    print(f"| overhead (median difference) | {1e6 * (med_call - med_in):.1f} µs | | |")


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--omega-range", default="0.2:3.5:60")
    p.add_argument("--velocity-range", default="0.001:0.2:40")
    p.add_argument("--rounds", type=int, default=2)
    p.add_argument("--calls", type=int, default=2000)
    p.add_argument("--chunk", type=int, default=None,
                   help="points per Dask task (default: sweep.map's choice)")
    p.add_argument("--no-map", action="store_true", help="only the simulate() overhead")
    p.add_argument("--idle-seconds", type=float, default=10.0,
                   help="how long the idle cluster's own CPU use is measured")
    p.add_argument("--methods", default="cli,dask,local",
                   help="which maps to time (comma-separated; cli is always run, as reference)")
    p.add_argument("--dask-defaults", action="store_true",
                   help="a LocalCluster with Dask's default settings instead of "
                        "bistable_impact.cluster.local_cluster (LEAN_CONFIG)")
    a = p.parse_args()
    methods = ["cli"] + [m for m in ("dask", "local") if m in a.methods.split(",")]
    from distributed import Client, LocalCluster

    w, v = grid(a.omega_range), grid(a.velocity_range)
    load0 = os.getloadavg()
    times: Dict[str, List[float]] = {"cli": [], "dask": [], "local": []}
    cpu: Dict[str, List[float]] = {"cli": [], "dask": [], "local": []}
    tmp = tempfile.mkdtemp()
    ref_path = os.path.join(tmp, "cli.csv")
    t = time.perf_counter()
    rounds = 0 if a.no_map else a.rounds
    start = LocalCluster if a.dask_defaults else bi.cluster.local_cluster
    cluster = start(n_workers=2 if rounds else 0, threads_per_worker=1, processes=True,
                    dashboard_address=None)  # fmt: skip
    client = Client(cluster)
    client.run(lambda: __import__("bistable_impact"))  # import in the workers before timing
    startup = time.perf_counter() - t
    # What the cluster costs doing nothing (event loops, heartbeats, the workers' profilers):
    # CPU seconds of the workers and of this process (client and scheduler) per wall second.
    idle = 0.0
    if rounds and "dask" in methods:
        before, c, t = client.run(time.process_time), time.process_time(), time.perf_counter()
        time.sleep(a.idle_seconds)
        after = client.run(time.process_time)
        idle = (sum(after[k] - before[k] for k in before) + time.process_time() - c) / (
            time.perf_counter() - t)
    mismatches = 0
    try:
        for r in range(rounds):
            order = methods if r % 2 == 0 else methods[::-1]
            for what in order:
                if what == "cli":
                    wall, used = run_cli(a.omega_range, a.velocity_range, ref_path)
                    times["cli"].append(wall)
                    cpu["cli"].append(used)
                    continue
                c = time.process_time()
                if what == "dask":
                    workers = client.run(time.process_time)
                    t = time.perf_counter()
                    df = bi.sweep.map(w, v, client=client, chunk=a.chunk)
                    times[what].append(time.perf_counter() - t)
                    after = client.run(time.process_time)
                    used = sum(after[k] - workers[k] for k in workers)
                else:
                    t = time.perf_counter()
                    df = bi.sweep.map(w, v, threads=2)
                    times[what].append(time.perf_counter() - t)
                    used = 0.0
                cpu[what].append(used + time.process_time() - c)
                if os.path.exists(ref_path):
                    ref = classes(pd.read_csv(ref_path))
                    got = classes(df)
                    mismatches += sum(got[k] != ref[k] for k in ref)
    finally:
        client.close()
        cluster.close()

    # simulate() overhead for a 1-impact run.
    calls, inside = [], []
    for _ in range(200):
        bi.simulate(1.75, 0.07, t_end=1.0)  # warm-up
    for _ in range(a.calls):
        t = time.perf_counter()
        r = bi.simulate(1.75, 0.07, t_end=1.0)
        calls.append(time.perf_counter() - t)
        inside.append(r.summary["wall_time_s"])
    assert len(r.impacts) == 1
    load1 = os.getloadavg()

    n = len(w) * len(v)
    print("## Python package (`bistable_impact`)\n")
    print(f"- machine: {platform.machine()}, {os.cpu_count()} cores; "
          f"{platform.platform()}; Python {platform.python_version()}")
    print(f"- load average (1 min) {load0[0]:.2f} before, {load1[0]:.2f} after")
    print(f"- command: `.venv/bin/python bench/python_map.py --omega-range {a.omega_range} "
          f"--velocity-range {a.velocity_range} --rounds {a.rounds} --calls {a.calls}"
          f" --methods {','.join(methods)}{' --no-map' if a.no_map else ''}"
          f"{' --dask-defaults' if a.dask_defaults else ''}`\n")
    if a.no_map:
        print_simulate(a.calls, calls, inside)
        return 0
    cli_best = min(times["cli"])
    print(f"Map of {len(w)} × {len(v)} = {n} points (Ω {a.omega_range}, V {a.velocity_range}, "
          f"defaults of `bistable map`), {a.rounds} round(s) in alternating order; the class of "
          f"every point compared with the CLI's map: {mismatches} differences.\n")
    print("| run | wall per round (s) | best (s) | points/s (best) | best vs CLI | CPU per round (s) "
          "| least CPU vs CLI |")
    print("|---|---|---|---|---|---|---|")
    names = {
        "cli": "`bistable map --threads 2`",
        "dask": f"`sweep.map(client=...)`, LocalCluster 2 processes × 1 thread "
                f"({'Dask defaults' if a.dask_defaults else '`cluster.local_cluster`'}), chunk {a.chunk or 'auto'}",
        "local": "`sweep.map(threads=2)` (Rust threads in-process)",
    }
    for k in methods:
        best = min(times[k])
        least = min(cpu[k])
        print(f"| {names[k]} | {', '.join(f'{x:.2f}' for x in times[k])} | {best:.2f} | "
              f"{n / best:.1f} | {100 * (best / cli_best - 1):+.1f} % | "
              f"{', '.join(f'{x:.2f}' for x in cpu[k])} | "
              f"{100 * (least / min(cpu['cli']) - 1):+.1f} % |")
    print(f"\nLocalCluster start-up (not in the times above): {startup:.2f} s.\n")
    if "dask" in methods:
        least = min(range(len(cpu["dask"])), key=lambda i: cpu["dask"][i])
        work = cpu["dask"][least] - idle * times["dask"][least]
        print(f"The idle cluster used {idle:.3f} CPU s per wall s ({a.idle_seconds:.0f} s measured "
              f"before the rounds); the least-CPU Dask round less that over its wall time: "
              f"{work:.2f} s, {100 * (work / min(cpu['cli']) - 1):+.1f} % against the CLI.\n")
    print_simulate(a.calls, calls, inside)
    return 0


if __name__ == "__main__":
    sys.exit(main())
