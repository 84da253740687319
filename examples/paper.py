"""Figures of the paper through the Python package ``bistable_impact`` (Nonlinear Dynamics 2022,
doi 10.1007/s11071-022-07793-w), drawn with matplotlib:

* Fig. 3: the shaker phase of the second impact against ``Ω`` at ``V = 0.07`` (the first impact
  is at ``τ = 0``, phase 0); the paper reports 0.0507 at ``Ω = 1.75`` and 0.5943 at ``Ω = 2.5``.
* Fig. 6: the bifurcation diagram against ``Ω`` at ``V = 0.07`` (largest displacement of each
  recorded shaker cycle, impact phases, periodic-orbit branches).
* Fig. 9: the map of response classes over ``Ω × V`` with the thresholds of Eq. 16–18.

    python examples/paper.py OUT_DIR [--reduced] [--map-size 300x200] [--scheduler ADDRESS]

writes ``fig3_second_impact_phase.png``, ``fig6_bifurcation.png``, ``fig9_map.png`` and the data
behind them (``fig3_second_impact_phase.csv``, ``fig6_bifurcation.csv``, ``fig6_orbits.csv``,
``fig9_map.csv``) to ``OUT_DIR``. ``--reduced`` uses small grids (seconds instead of minutes);
``--scheduler`` runs the map on a ``dask.distributed`` scheduler.
"""

from __future__ import annotations

import argparse
import os
from dataclasses import dataclass
from typing import Any, Dict, List, Optional, Tuple

import numpy as np

import bistable_impact as bi

V_PAPER = 0.07


@dataclass(frozen=True)
class Sizes:
    """Grid sizes and run lengths of the three figures."""

    fig3_points: int
    fig6_points: int
    fig6_transient: int
    fig6_record: int
    map_shape: Tuple[int, int]
    map_max_periods: float


FULL = Sizes(661, 141, 500, 100, (60, 40), 20000.0)
REDUCED = Sizes(67, 15, 200, 20, (12, 8), 2000.0)

#: Fig. 3's Ω range, Fig. 6's, and Fig. 9's Ω and V ranges (as the CLI's demo).
FIG3_OMEGA = (0.2, 3.5)
FIG6_OMEGA = (2.0, 2.7)
FIG9_OMEGA = (0.2, 3.5)
FIG9_VELOCITY = (0.005, 0.2)


def second_impact_phase(omega: float, velocity: float = V_PAPER) -> float:
    """The shaker phase (cycles) of the impact after the one at ``τ = 0``; NaN if none comes
    within 200 natural periods."""
    sim = bi.Simulator(omega, velocity)
    found: List[float] = []

    def on_event(e: Dict[str, Any]) -> Optional[bool]:
        if e["kind"] == "impact" and e["index"] == 1:
            found.append(e["phase"])
            return False  # stop the advance here
        return None

    sim.advance_to(200 * 2 * np.pi, on_event)
    return found[0] if found else float("nan")


def fig3(out: str, sizes: Sizes) -> None:
    import matplotlib.pyplot as plt
    import pandas as pd

    omegas = bi.linspace(*FIG3_OMEGA, sizes.fig3_points)
    phases = np.array([second_impact_phase(w) for w in omegas])
    pd.DataFrame({"omega": omegas, "phase": phases}).to_csv(
        os.path.join(out, "fig3_second_impact_phase.csv"), index=False
    )
    fig, ax = plt.subplots(figsize=(8, 5))
    ax.plot(omegas, phases, ".", ms=4, label="simulated")
    ax.plot([1.75, 2.5], [0.0507, 0.5943], "rx", ms=10, label="paper (Sec. 5)")
    ax.set_xlabel("shaker frequency ratio Ω")
    ax.set_ylabel("phase of the second impact (shaker cycles)")
    ax.set_ylim(0, 1)
    ax.set_title(f"Second impact after the first at τ = 0, V = {V_PAPER}")
    ax.legend()
    fig.savefig(os.path.join(out, "fig3_second_impact_phase.png"), dpi=120)
    plt.close(fig)


def fig6(out: str, sizes: Sizes) -> None:
    import matplotlib.pyplot as plt

    omegas = bi.linspace(*FIG6_OMEGA, sizes.fig6_points)
    b = bi.bifurcation(
        "omega",
        omegas,
        velocity=V_PAPER,
        transient=sizes.fig6_transient,
        record=sizes.fig6_record,
    )
    data, orbits = b["data"], b["orbits"]
    data.to_csv(os.path.join(out, "fig6_bifurcation.csv"), index=False)
    orbits.assign(cycle_max=[";".join(map(repr, c)) for c in orbits["cycle_max"]]).to_csv(
        os.path.join(out, "fig6_orbits.csv"), index=False
    )
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(9, 8), sharex=True)
    mx = data[data["kind"] == "max_x"]
    top.plot(mx["omega"], mx["value"], "k.", ms=2, zorder=3, label="simulated (max x per cycle)")
    for period, colour in zip((1, 2, 4, 8), ("C0", "C1", "C2", "C3")):
        o = orbits[orbits["period"] == period]
        for stable, marker in ((True, "o"), (False, "x")):
            sel = o[o["stable"] == stable]
            xs = np.repeat(sel["omega"].to_numpy(), [len(c) for c in sel["cycle_max"]])
            ys = np.concatenate(list(sel["cycle_max"])) if len(sel) else []
            top.plot(xs, ys, marker, color=colour, ms=3, alpha=0.6, zorder=2,
                     mfc="none" if not stable else colour,
                     label=f"orbit, period {period}, {'stable' if stable else 'unstable'}")
    top.set_ylabel("max displacement x (Δx)")
    top.legend(fontsize=7, ncol=2)
    ph = data[data["kind"] == "impact_phase"]
    bottom.plot(ph["omega"], ph["value"], "k.", ms=2)
    bottom.set_ylabel("impact phase (cycles)")
    bottom.set_xlabel("shaker frequency ratio Ω")
    top.set_title(f"Bifurcation diagram, V = {V_PAPER} (Fig. 6)")
    fig.savefig(os.path.join(out, "fig6_bifurcation.png"), dpi=120)
    plt.close(fig)


CLASSES = ("intrawell", "transient_interwell", "continuous_interwell")


def fig9(out: str, sizes: Sizes, client: Any = None) -> None:
    import matplotlib.pyplot as plt
    from matplotlib.colors import ListedColormap

    nw, nv = sizes.map_shape
    omegas = bi.linspace(*FIG9_OMEGA, nw)
    velocities = bi.linspace(*FIG9_VELOCITY, nv)
    df = bi.sweep.map(omegas, velocities, client=client, max_periods=sizes.map_max_periods)
    bi.sweep.to_csv_frame(df).to_csv(os.path.join(out, "fig9_map.csv"), index=False)  # the CLI CSV form
    code = df["class"].map({c: i for i, c in enumerate(CLASSES)}).to_numpy().reshape(nv, nw)
    fig, ax = plt.subplots(figsize=(9, 6))
    dw, dv = (omegas[1] - omegas[0]) / 2, (velocities[1] - velocities[0]) / 2
    ax.imshow(
        code,
        origin="lower",
        aspect="auto",
        interpolation="nearest",
        extent=(omegas[0] - dw, omegas[-1] + dw, velocities[0] - dv, velocities[-1] + dv),
        cmap=ListedColormap(["#9ecae1", "#fdae6b", "#d62728"]),
        vmin=-0.5,
        vmax=2.5,
    )
    t = bi.thresholds()
    ax.axhline(t["single_impact"], color="k", ls="--", lw=1, label="single impact (Eq. 16)")
    ax.axhline(t["interwell"], color="k", ls=":", lw=1, label="interwell (Eq. 17)")
    ax.plot(omegas, [bi.thresholds(omega=w)["quasi_static"] for w in omegas], "k-.", lw=1,
            label="quasi-static V = Ω/2 (Eq. 18)")
    ax.set_ylim(velocities[0] - dv, velocities[-1] + dv)
    for i, c in enumerate(CLASSES):
        ax.plot([], [], "s", color=["#9ecae1", "#fdae6b", "#d62728"][i], label=c)
    ax.legend(fontsize=8, loc="upper left")
    ax.set_xlabel("shaker frequency ratio Ω")
    ax.set_ylabel("shaker velocity amplitude V (ω0·Δx)")
    ax.set_title(f"Response classes, {nw} × {nv} grid (Fig. 9)")
    fig.savefig(os.path.join(out, "fig9_map.png"), dpi=120)
    plt.close(fig)


def main(argv: Optional[List[str]] = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("out", help="directory for the PNGs and their data")
    p.add_argument("--reduced", action="store_true", help="small grids (a quick check)")
    p.add_argument("--map-size", metavar="NWxNV", help="Fig. 9 grid, e.g. 300x200 (the paper's)")
    p.add_argument("--scheduler", metavar="ADDRESS", help="dask.distributed scheduler for Fig. 9")
    a = p.parse_args(argv)
    import matplotlib

    matplotlib.use("Agg")
    sizes = REDUCED if a.reduced else FULL
    if a.map_size:
        nw, nv = (int(n) for n in a.map_size.lower().split("x"))
        sizes = Sizes(**{**sizes.__dict__, "map_shape": (nw, nv)})
    os.makedirs(a.out, exist_ok=True)
    fig3(a.out, sizes)
    fig6(a.out, sizes)
    client = None
    if a.scheduler:
        from distributed import Client

        client = Client(a.scheduler)
    try:
        fig9(a.out, sizes, client)
    finally:
        if client is not None:
            client.close()
    for name in ("fig3_second_impact_phase.png", "fig6_bifurcation.png", "fig9_map.png"):
        print(os.path.join(a.out, name))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
