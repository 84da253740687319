#!/usr/bin/env python3
"""heyoka's SIMD batch mode against its scalar mode on the model's free flight, on this machine.

The anchor figure for our own SIMD batch integrator (lanes of trajectories): how much faster does
heyoka integrate N independent trajectories in lanes of 4 or 8 than one after another?

- ODE: the free flight between impacts of ``shared/spec/model.md`` (Eq. 4),
  ``x'' + 2 zeta x' + x - 3x^2 + 2x^3 = 0`` with ``zeta = 0.02``; no plate, no impacts, no events.
  The cubic is written as products (``x*x*x``): heyoka's recurrence for ``x**3`` divides by ``x``.
- Integrators: ``heyoka.taylor_adaptive`` (scalar) and ``heyoka.taylor_adaptive_batch`` (batch size
  4 and 8; ``heyoka.recommended_simd_size()`` is 8 on AVX-512), ``tol = 1e-16`` by default (the
  project's default, ``SolverOptions::default().tol``, at which our integrator uses order 24;
  heyoka accepts it and picks order 20), default options otherwise (no compact mode, no high
  accuracy). Each integrator is built (JIT-compiled) once,
  outside the timings, and reused: a trajectory is a reset of time and state followed by one
  ``propagate_until(T)``; the batch propagates its lanes to the same ``T``.
- Trajectories: N (a multiple of 8) distinct initial states, alternately in well 1 (``x`` near 0)
  and well 2 (``x`` near 1), ``|x - well| <= 0.1``, velocity of either sign, total energy
  ``U(x) + x'^2/2`` spread over 0.5 ... 4 times the barrier energy ``U(1/2) = 1/32`` (the range where
  the damped flight crosses the barrier a few times or not at all before settling in a well, the
  sensitive range of the paper's snap-throughs), by golden-ratio sequences. Each is integrated
  over ``--periods`` natural periods (``T = periods * 2 pi``, default 200).
- Timing: ``--rounds`` rounds (default 5); each round runs every mode once over all N trajectories,
  the order of the modes rotating from round to round (modes alternate in one process, so a change
  of machine load hits them alike). One untimed warm-up pass over 8 trajectories first. Reported:
  min and median time per mode. The time is the thread's CPU time by default (``--clock cpu``):
  on a machine shared with other jobs, wall time also counts the time the process waits for a
  core, and that penalises the longer (scalar) runs more than the short batch runs; wall time
  is recorded too and can drive the figures with ``--clock wall``.
- Work unit, throughput: a *trajectory-step* is one Taylor step of one trajectory. The work is the
  sum over the N trajectories of the scalar integrator's step counts; heyoka's batch integrator
  reports its step count per lane, and the script checks that it equals the scalar count of that
  trajectory (so the modes do equal work), and that each lane's final state equals the scalar
  final state (max absolute difference printed; the run fails above ``--check-tol``, 1e-12).
  Throughput = trajectory-steps / time; ratio = scalar time / batch time. Lanes of a batch
  finish at different step counts; the idle share is reported as lane utilisation
  (sum of lane steps / (lanes x batch steps)).
- Threads: heyoka's TBB pool is limited to ``--threads`` (default 1); the integration itself is
  single-threaded in every mode.

Install (heyoka is not in ``scripts/requirements.txt``; ``bench/requirements.txt`` pins it and
``bench/ensemble.sh`` installs it): ``pip install heyoka==7.13.2`` into
``.venv`` or any venv (the wheel bundles LLVM; numpy comes with it).

Command line (markdown table on stdout; ``--json FILE`` for the numbers):

    .venv/bin/python bench/heyoka_batch.py [--quick] [--n 1024] [--periods 200] [--rounds 5] \
        [--tol 1e-16] [--lanes 4 8] [--clock cpu|wall] [--json target/bench-cache/heyoka_batch.json]

``--quick``: smoke run (64 trajectories, 50 periods, 3 rounds; about a second).
"""

from __future__ import annotations

import argparse
import datetime
import gc
import json
import math
import os
import platform
import statistics
import sys
import time

import numpy as np

ZETA = 0.02
E_BARRIER = 1.0 / 32.0
ENERGY_RANGE = (0.5, 4.0)  # total energy over the barrier energy
OFFSET = 0.1  # |x0 - well bottom| <= OFFSET


def potential(x: float) -> float:
    """``U(x) = x^2 (1 - x)^2 / 2``."""
    return 0.5 * x * x * (1.0 - x) * (1.0 - x)


def initial_states(n: int) -> np.ndarray:
    """N distinct initial states ``(x, x')``, shape (n, 2); see the module docstring."""
    golden = (math.sqrt(5.0) - 1.0) / 2.0
    root2 = math.sqrt(2.0) - 1.0
    lo, hi = ENERGY_RANGE
    out = np.empty((n, 2))
    for i in range(n):
        well = float(i % 2)
        sign = 1.0 if (i // 2) % 2 == 0 else -1.0
        energy = E_BARRIER * (lo + (hi - lo) * ((0.5 + i * golden) % 1.0))
        x0 = well + OFFSET * (2.0 * ((0.5 + i * root2) % 1.0) - 1.0)
        out[i] = (x0, sign * math.sqrt(2.0 * (energy - potential(x0))))
    return out


def free_flight(hy, zeta: float):
    """The free-flight system for heyoka (cubic as products)."""
    x, v = hy.make_vars("x", "v")
    return [(x, v), (v, -2.0 * zeta * v - x + 3.0 * x * x - 2.0 * x * x * x)]


class Scalar:
    """``taylor_adaptive``: the trajectories one after another."""

    def __init__(self, hy, system, tol: float):
        self.lanes = 1
        self.name = "scalar"
        self.ta = hy.taylor_adaptive(system, [0.0, 0.0], tol=tol)
        self.order = self.ta.order

    def run(self, y0: np.ndarray, t_end: float) -> tuple[int, int, np.ndarray, np.ndarray, float]:
        """Integrates every row of ``y0`` to ``t_end``; returns (wall ns, thread CPU ns, final
        states, steps per trajectory, lane utilisation)."""
        ta = self.ta
        n = len(y0)
        final = np.empty((n, 2))
        steps = np.empty(n, dtype=np.int64)
        res = [None] * n
        c0, t0 = time.thread_time_ns(), time.perf_counter_ns()
        for i in range(n):
            ta.time = 0.0
            ta.state[:] = y0[i]
            res[i] = ta.propagate_until(t_end)
            final[i] = ta.state
        wall, cpu = time.perf_counter_ns() - t0, time.thread_time_ns() - c0
        for i, r in enumerate(res):
            if "time_limit" not in str(r[0]):
                raise RuntimeError(f"scalar trajectory {i}: outcome {r[0]}")
            steps[i] = r[3]
        return wall, cpu, final, steps, 1.0


class Batch:
    """``taylor_adaptive_batch``: the trajectories in lanes, ``lanes`` at a time."""

    def __init__(self, hy, system, tol: float, lanes: int):
        self.lanes = lanes
        self.name = f"batch {lanes}"
        self.tb = hy.taylor_adaptive_batch(system, np.zeros((2, lanes)), tol=tol)
        self.order = self.tb.order

    def run(self, y0: np.ndarray, t_end: float) -> tuple[int, int, np.ndarray, np.ndarray, float]:
        """As :meth:`Scalar.run`; ``len(y0)`` must be a multiple of the lanes."""
        tb, b = self.tb, self.lanes
        n = len(y0)
        final = np.empty((n, 2))
        steps = np.empty(n, dtype=np.int64)
        starts = [np.ascontiguousarray(y0[j : j + b].T) for j in range(0, n, b)]
        res = [None] * len(starts)
        c0, t0 = time.thread_time_ns(), time.perf_counter_ns()
        for k, s in enumerate(starts):
            tb.set_time(0.0)
            tb.state[:] = s
            tb.propagate_until(t_end)
            res[k] = tb.propagate_res
            final[k * b : (k + 1) * b] = tb.state.T
        wall, cpu = time.perf_counter_ns() - t0, time.thread_time_ns() - c0
        batch_steps = 0
        for k, lanes in enumerate(res):
            for j, r in enumerate(lanes):
                if "time_limit" not in str(r[0]):
                    raise RuntimeError(f"{self.name}: trajectory {k * b + j}: outcome {r[0]}")
                steps[k * b + j] = r[3]
            batch_steps += max(r[3] for r in lanes)
        return wall, cpu, final, steps, float(steps.sum()) / (b * batch_steps)


def cpu_model() -> str:
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    p = argparse.ArgumentParser(
        description="heyoka taylor_adaptive_batch (lanes of 4 and 8) against taylor_adaptive "
        "(scalar) on the bistable oscillator's free flight: throughput in trajectory-steps per "
        "second and batch/scalar ratios, modes alternated in one run. Markdown table on stdout.",
        epilog="Needs heyoka (pip install heyoka==7.13.2). Example: .venv/bin/python "
        "bench/heyoka_batch.py --json target/bench-cache/heyoka_batch.json",
    )
    p.add_argument("--n", type=int, default=1024, help="trajectories, a multiple of 8 (default 1024)")
    p.add_argument("--periods", type=float, default=200.0,
                   help="natural periods (2 pi each) per trajectory (default 200)")
    p.add_argument("--rounds", type=int, default=5, help="timed rounds, modes alternated (default 5)")
    p.add_argument("--tol", type=float, default=1e-16, help="heyoka tolerance (default 1e-16)")
    p.add_argument("--lanes", type=int, nargs="+", default=[4, 8], help="batch sizes (default 4 8)")
    p.add_argument("--zeta", type=float, default=ZETA, help=f"damping ratio (default {ZETA})")
    p.add_argument("--threads", type=int, default=1,
                   help="heyoka's TBB thread limit (default 1; integration is single-threaded)")
    p.add_argument("--check-tol", type=float, default=1e-12,
                   help="largest allowed |batch lane final state - scalar final state| (default 1e-12)")
    p.add_argument("--clock", choices=["cpu", "wall"], default="cpu",
                   help="time behind throughput and ratios: the thread's CPU time (default; robust "
                   "to preemption on a shared machine) or wall time; both are recorded")
    p.add_argument("--json", metavar="FILE", help="write the configuration and numbers as JSON")
    p.add_argument("--quick", action="store_true",
                   help="smoke run: 64 trajectories, 50 periods, 3 rounds (overrides --n, --periods, --rounds)")
    a = p.parse_args(argv)
    if a.quick:
        a.n, a.periods, a.rounds = 64, 50.0, 3
    if any(b < 2 for b in a.lanes):
        p.error("--lanes: batch sizes must be at least 2")
    if a.n <= 0 or a.n % math.lcm(8, *a.lanes) != 0:
        p.error(f"--n must be a positive multiple of {math.lcm(8, *a.lanes)}")
    if a.rounds < 1 or a.periods <= 0:
        p.error("--rounds and --periods must be positive")
    return a


def main(argv: list[str] | None = None) -> int:
    a = parse_args(argv)
    try:
        import heyoka as hy
    except ImportError:
        print("heyoka is not installed in this Python: pip install heyoka==7.13.2", file=sys.stderr)
        return 2
    hy.set_nthreads(a.threads)

    t_end = a.periods * 2.0 * math.pi
    y0 = initial_states(a.n)
    system = free_flight(hy, a.zeta)

    t0 = time.perf_counter()
    modes = [Scalar(hy, system, a.tol)] + [Batch(hy, system, a.tol, b) for b in a.lanes]
    compile_s = time.perf_counter() - t0
    load_before = os.getloadavg()

    for m in modes:  # warm-up: touch the compiled code and the buffers
        m.run(y0[:8], t_end)

    walls = {m.name: [] for m in modes}
    cpus = {m.name: [] for m in modes}
    finals, steps, util = {}, {}, {}
    gc_was = gc.isenabled()
    gc.disable()
    try:
        for r in range(a.rounds):
            for k in range(len(modes)):
                m = modes[(k + r) % len(modes)]
                wall, cpu, fin, st, u = m.run(y0, t_end)
                walls[m.name].append(wall * 1e-9)
                cpus[m.name].append(cpu * 1e-9)
                if m.name in finals:  # deterministic: every round gives the same answers
                    if not (np.array_equal(fin, finals[m.name]) and np.array_equal(st, steps[m.name])):
                        raise RuntimeError(f"{m.name}: round {r} differs from round 0")
                else:
                    finals[m.name], steps[m.name], util[m.name] = fin, st, u
    finally:
        if gc_was:
            gc.enable()
    load_after = os.getloadavg()

    ref = modes[0].name
    work = int(steps[ref].sum())
    timed = cpus if a.clock == "cpu" else walls  # the clock behind throughput and ratios
    t_ref_min, t_ref_med = min(timed[ref]), statistics.median(timed[ref])
    results = []
    ok = True
    for m in modes:
        t = timed[m.name]
        tmin, tmed = min(t), statistics.median(t)
        diff = float(np.max(np.abs(finals[m.name] - finals[ref])))
        step_mismatch = int(np.count_nonzero(steps[m.name] != steps[ref]))
        if diff > a.check_tol or step_mismatch:
            ok = False
        results.append({
            "mode": m.name,
            "lanes": m.lanes,
            "order": m.order,
            "wall_s": walls[m.name],
            "cpu_s": cpus[m.name],
            "wall_min_s": min(walls[m.name]),
            "wall_median_s": statistics.median(walls[m.name]),
            "cpu_min_s": min(cpus[m.name]),
            "cpu_median_s": statistics.median(cpus[m.name]),
            "clock": a.clock,
            # from the selected clock; "min" = from the least time (best round)
            "traj_steps_per_s_min": work / tmin,
            "traj_steps_per_s_median": work / tmed,
            "ratio_vs_scalar_min": t_ref_min / tmin,
            "ratio_vs_scalar_median": t_ref_med / tmed,
            "max_final_state_diff": diff,
            "trajectories_with_other_step_count": step_mismatch,
            "lane_utilisation": util[m.name],
        })

    env = {
        "date_utc": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M:%S"),
        "heyoka": hy.__version__,
        "numpy": np.__version__,
        "python": platform.python_version(),
        "cpu": cpu_model(),
        "cpus": os.cpu_count(),
        "recommended_simd_size": hy.recommended_simd_size(),
        "heyoka_threads": hy.get_nthreads(),
        "loadavg_before": load_before,
        "loadavg_after": load_after,
        "compile_s": compile_s,
    }
    config = {
        "n": a.n, "periods": a.periods, "t_end": t_end, "rounds": a.rounds, "tol": a.tol,
        "zeta": a.zeta, "lanes": a.lanes, "quick": a.quick,
        "energy_over_barrier": list(ENERGY_RANGE), "offset_from_well": OFFSET,
        "trajectory_steps": work,
        "steps_per_trajectory": {"min": int(steps[ref].min()), "mean": work / a.n,
                                 "max": int(steps[ref].max())},
        "check_tol": a.check_tol,
        "clock": a.clock,
    }

    print(f"## heyoka {hy.__version__}: batch vs scalar, free flight (zeta = {a.zeta})\n")
    print(f"{a.n} trajectories x {a.periods:g} natural periods (tau = {t_end:.6g}), "
          f"tol {a.tol:g} (order {modes[0].order}), {a.rounds} rounds alternated; "
          f"{work} trajectory-steps per mode "
          f"({config['steps_per_trajectory']['min']}..{config['steps_per_trajectory']['max']} "
          f"per trajectory). {env['cpu']}, {env['cpus']} CPUs, load {load_before[0]:.2f} -> "
          f"{load_after[0]:.2f}; JIT {compile_s:.2f} s (not timed).\n")
    other = "wall" if a.clock == "cpu" else "cpu"
    print(f"Times: {a.clock} time (thread CPU time if cpu) drives throughput and ratios; "
          f"{other} min shown for comparison.\n")
    print(f"| mode | {a.clock} min (s) | {a.clock} median (s) | {other} min (s) "
          "| M traj-steps/s (min) | M traj-steps/s (median) "
          "| x scalar (min) | x scalar (median) | lane use | max final diff |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for r in results:
        print(f"| {r['mode']} | {r[a.clock + '_min_s']:.4f} | {r[a.clock + '_median_s']:.4f} "
              f"| {r[other + '_min_s']:.4f} "
              f"| {r['traj_steps_per_s_min'] / 1e6:.2f} | {r['traj_steps_per_s_median'] / 1e6:.2f} "
              f"| {r['ratio_vs_scalar_min']:.2f} | {r['ratio_vs_scalar_median']:.2f} "
              f"| {r['lane_utilisation']:.3f} | {r['max_final_state_diff']:.1e} |")
    maxdiff = max(r["max_final_state_diff"] for r in results)
    mism = sum(r["trajectories_with_other_step_count"] for r in results)
    print(f"\nEqual work: max |batch lane final state - scalar final state| = {maxdiff:.3e} "
          f"(limit {a.check_tol:g}); trajectories whose batch step count differs from scalar: {mism}. "
          f"{'OK' if ok else 'FAILED'}")

    if a.json:
        d = os.path.dirname(os.path.abspath(a.json))
        os.makedirs(d, exist_ok=True)
        with open(a.json, "w") as f:
            json.dump({"config": config, "environment": env, "results": results,
                       "max_final_state_diff": maxdiff, "ok": ok}, f, indent=2)
            f.write("\n")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
