"""``python -m bistable_impact map``: the Fig. 9 map through :func:`bistable_impact.sweep.map`,
locally on Rust threads or on a ``dask.distributed`` scheduler (``--scheduler ADDRESS``).

Ranges are ``A:B:N`` (N evenly spaced values from A to B, both included) as in ``bistable map``;
the result is the map CSV (``--out``) or printed to stdout.
"""

from __future__ import annotations

import argparse
import math
import sys
from typing import List, Optional


def _range(text: str) -> List[float]:
    try:
        a, b, n = text.split(":")
        start, end, count = float(a), float(b), int(n)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not A:B:N")
    if not (math.isfinite(start) and math.isfinite(end)):
        raise argparse.ArgumentTypeError(f"{text!r}: A and B must be finite")
    if count < 1:
        raise argparse.ArgumentTypeError(f"{text!r}: N must be >= 1")
    if count == 1 and start != end:
        raise argparse.ArgumentTypeError(f"{text!r}: N = 1 needs A = B (a single value)")
    if count > 1 and start == end:
        raise argparse.ArgumentTypeError(f"{text!r}: A = B needs N = 1")
    from . import linspace

    return list(linspace(start, end, count))


def main(argv: Optional[List[str]] = None) -> int:
    p = argparse.ArgumentParser(prog="python -m bistable_impact")
    sub = p.add_subparsers(dest="command", required=True)
    m = sub.add_parser("map", help="response-class map over an Ω × V grid (CSV)")
    m.add_argument("--omega-range", type=_range, required=True, metavar="A:B:N")
    m.add_argument("--velocity-range", type=_range, required=True, metavar="A:B:N")
    m.add_argument("--scheduler", metavar="ADDRESS", help="dask.distributed scheduler address")
    m.add_argument("--out", metavar="FILE.csv", help="map CSV (kept results are reused)")
    m.add_argument("--threads", type=int, default=0, help="local Rust threads (0: all cores)")
    m.add_argument("--chunk", type=int, default=None,
                   help="points per Dask task (default: 16 to 256, about 8 tasks per worker thread)")
    m.add_argument("--progress", action="store_true", help="a progress line on stderr")
    m.add_argument("--zeta", type=float, default=0.02)
    m.add_argument("--restitution", type=float, default=0.85)
    m.add_argument("--tol", type=float, default=1e-16)
    m.add_argument("--chatter", choices=["accumulation", "paper"], default="accumulation")
    m.add_argument("--max-periods", type=float, default=20000.0)
    m.add_argument("--lyapunov-periods", type=int, default=300)
    from . import SENSITIVITY_DEFAULTS as sens

    for flag, kind, what in [
        ("--repeats", int, "perturbed repeats of a suspect run (0: no test)"),
        ("--efoldings", float, "transient growth (e-foldings) from which a run is repeated"),
        ("--perturbation", float, "displacement of the repeats' initial state"),
        ("--horizon", float, "natural periods over which the growth is tracked"),
        ("--repeat-periods", float, "length of an aperiodic run's repeats (natural periods)"),
        ("--lyapunov-windows", int, "further chaos verdicts of an aperiodic run"),
    ]:
        default = sens[flag[2:].replace("-", "_")]
        m.add_argument(
            flag, type=kind, default=default, help=f"sensitivity test: {what} (default {default})"
        )
    a = p.parse_args(argv)

    from . import sweep

    client = None
    if a.scheduler:
        from distributed import Client

        client = Client(a.scheduler)
    try:
        df = sweep.map(
            a.omega_range,
            a.velocity_range,
            client=client,
            store=a.out,
            chunk=a.chunk,
            threads=a.threads,
            progress=a.progress,
            zeta=a.zeta,
            restitution=a.restitution,
            tol=a.tol,
            chatter=a.chatter,
            max_periods=a.max_periods,
            lyapunov_periods=a.lyapunov_periods,
            repeats=a.repeats,
            efoldings=a.efoldings,
            perturbation=a.perturbation,
            horizon=a.horizon,
            repeat_periods=a.repeat_periods,
            lyapunov_windows=a.lyapunov_windows,
        )
    except (ValueError, RuntimeError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2 if isinstance(e, ValueError) else 1
    finally:
        if client is not None:
            client.close()
    if a.out is None:
        sweep.to_csv_frame(df).to_csv(sys.stdout, index=False)
    return 0


if __name__ == "__main__":
    sys.exit(main())
