#!/usr/bin/env python3
"""The bistable impact oscillator with SciPy ``solve_ivp(method="DOP853", events=...)``.

This is the peer that ``bench/work_precision.py`` compares the Rust simulator against: the model of
``shared/spec/model.md`` written the way a competent SciPy user would write it.

- Free flight ``x'' + 2 zeta x' + x - 3x^2 + 2x^3 = 0`` integrated with DOP853, ``rtol = atol = tol``,
  default step-size control (no ``max_step``: the controller sees only the mass, not the plate).
- Terminal event on the gap ``x - z(t)`` with ``direction = -1``. After an impact the integration
  restarts exactly on the plate; to keep the root finder from locking onto the known root at the
  restart point, the event function is the gap divided by the time since the restart
  (``(x - z)/(t - t_n)``, equal to the rebound relative velocity at ``t_n``). It has the sign of the
  gap after the restart, so the next impact is found as usual, and it is positive at ``t_n``.
- Impact law (Eq. 5) ``x'+ = -e x'- + (1+e) zdot`` at the located root, with the mass put exactly on
  the plate (``x = z(t_n)``).
- Initial condition: impact 0 at ``t = 0`` is built into the initial state (``x' = (1+e) V``).
- Chatter: the paper's rule (model.md Sec. 3). Two impacts less than ``gap = 1e-9`` apart while the
  contact force ``N(t) = zddot + 2 zeta zdot + z - 3z^2 + 2z^3 >= 0`` -> the mass sticks to the plate;
  it is released at the first root of ``N`` where ``N`` turns negative (found by scanning ``N`` on a
  fine grid and ``brentq``). After the release the gap has a triple root at the release point; the
  event function divides it out the same way (``(x - z)/(t - t_r)^3``).

Only the integration (the loop of ``solve_ivp`` calls and impact updates) is timed.

Command line (prints a JSON summary line; ``--csv`` writes ``index,t,phase,x,v_before,v_after``):

    .venv/bin/python bench/scipy_peer.py --omega 1.75 --velocity 0.07 --t-end 1000 --tol 1e-10 \
        [--csv out.csv]
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

ZETA = 0.02
RESTITUTION = 0.85


class Result:
    """Impacts (list of tuples ``(index, t, phase, x, v_before, v_after)``), sticking intervals,
    wall time of the integration, right-hand-side evaluations, and an error message if any."""

    def __init__(self):
        self.impacts: list[tuple] = []
        self.sticks: list[tuple[float, float]] = []
        self.wall_s = 0.0
        self.nfev = 0
        self.error: str | None = None

    def impact_array(self) -> np.ndarray:
        """Impacts as an array of shape (n, 6)."""
        return np.array(self.impacts, dtype=float).reshape(-1, 6)


def simulate(
    omega: float,
    velocity: float,
    t_end: float,
    tol: float,
    zeta: float = ZETA,
    e: float = RESTITUTION,
    gap: float = 1e-9,
    max_impacts: int = 10_000_000,
) -> Result:
    """Simulates from the paper's initial condition to ``t_end``; see the module docstring."""
    amp = velocity / omega
    sin, cos = math.sin, math.cos
    two_pi = 2.0 * math.pi

    def rhs(t, y):
        x, v = y
        return [v, -2.0 * zeta * v - x + 3.0 * x * x - 2.0 * x * x * x]

    def contact_force(t):
        z = amp * sin(omega * t)
        zd = velocity * cos(omega * t)
        zdd = -velocity * omega * sin(omega * t)
        return zdd + 2.0 * zeta * zd + z - 3.0 * z * z + 2.0 * z * z * z

    res = Result()
    start = time.perf_counter()

    # Impact 0 at t = 0 is part of the initial condition.
    t0 = 0.0
    x0 = 0.0
    v0 = (1.0 + e) * velocity
    res.impacts.append((0, 0.0, 0.0, 0.0, 0.0, v0))
    pinned = 1  # order of the known root of the gap at t0 (1 after an impact, 3 after a release)
    w0 = v0 - velocity  # relative velocity at t0 (the divided gap's value there)
    last_impact_t = 0.0
    stuck = False

    while t0 < t_end:
        if stuck:
            # Riding on the plate until N turns negative: scan for the sign change, then brentq.
            h = min(two_pi / omega / 400.0, 0.01)
            a = t0
            fa = contact_force(a)
            release = None
            while a < t_end:
                b = min(a + h, t_end)
                fb = contact_force(b)
                if fa >= 0.0 and fb < 0.0:
                    release = brentq(contact_force, a, b, xtol=1e-15, rtol=4 * np.finfo(float).eps)
                    break
                a, fa = b, fb
            if release is None:
                res.sticks.append((t0, math.inf))
                break
            res.sticks.append((t0, release))
            t0 = release
            x0 = amp * sin(omega * t0)
            v0 = velocity * cos(omega * t0)
            pinned, w0 = 3, 0.0
            stuck = False
            continue

        ts, k, w_start = t0, pinned, w0

        def gap_event(t, y, ts=ts, k=k, w_start=w_start):
            s = t - ts
            if s <= 0.0:
                return w_start if k == 1 else 1.0
            return (y[0] - amp * sin(omega * t)) / s**k

        gap_event.terminal = True
        gap_event.direction = -1

        sol = solve_ivp(rhs, (t0, t_end), [x0, v0], method="DOP853", rtol=tol, atol=tol,
                        events=gap_event)
        res.nfev += sol.nfev
        if sol.status == -1:
            res.error = f"solve_ivp failed at t={sol.t[-1]}: {sol.message}"
            break
        if sol.status == 0 or len(sol.t_events[0]) == 0:
            break  # reached t_end
        te = float(sol.t_events[0][0])
        v_minus = float(sol.y_events[0][0][1])
        z = amp * sin(omega * te)
        zd = velocity * cos(omega * te)
        v_plus = -e * v_minus + (1.0 + e) * zd
        idx = len(res.impacts)
        res.impacts.append((idx, te, (omega * te / two_pi) % 1.0, z, v_minus, v_plus))
        if idx >= max_impacts:
            res.error = f"more than {max_impacts} impacts"
            break
        close = te - last_impact_t < gap
        last_impact_t = te
        t0, x0, v0 = te, z, v_plus
        pinned, w0 = 1, v_plus - zd
        if (close or w0 <= 0.0) and contact_force(te) >= 0.0:
            stuck = True
            x0, v0 = z, zd

    res.wall_s = time.perf_counter() - start
    return res


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--omega", type=float, required=True)
    ap.add_argument("--velocity", type=float, required=True)
    ap.add_argument("--t-end", type=float, required=True)
    ap.add_argument("--tol", type=float, default=1e-10)
    ap.add_argument("--gap", type=float, default=1e-9, help="paper's chatter gap")
    ap.add_argument("--csv", help="write the impacts to this CSV file")
    a = ap.parse_args(argv)
    r = simulate(a.omega, a.velocity, a.t_end, a.tol, gap=a.gap)
    if a.csv:
        with open(a.csv, "w") as f:
            f.write("index,t,phase,x,v_before,v_after\n")
            for row in r.impacts:
                f.write(f"{row[0]},{row[1]!r},{row[2]!r},{row[3]!r},{row[4]!r},{row[5]!r}\n")
    out = {"tol": a.tol, "wall_s": r.wall_s, "nfev": r.nfev, "n_impacts": len(r.impacts),
           "sticks": [[s, (e if math.isfinite(e) else None)] for s, e in r.sticks],
           "error": r.error}
    if a.csv:
        out["csv"] = a.csv
    print(json.dumps(out))
    return 0 if r.error is None else 1


if __name__ == "__main__":
    sys.exit(main())
