"""Basins of attraction over a grid of starts ``(x0, x0')`` at one plate phase, like
``bistable basins`` (the same Rust classification of every cell, the same attractors)."""

from __future__ import annotations

from typing import Any, Optional, Sequence

from . import _check as check
from . import _native

#: Columns of the cells' DataFrame (``bistable basins`` CSV columns without the model's).
CELL_COLUMNS = (
    "x0",
    "v0",
    "class",
    "period",
    "chaotic",
    "final_well",
    "anchor_x",
    "anchor_v",
    "at_rest_in_second_well",
    "periods_simulated",
    "decided_by",
)


def _cells_chunk(starts, omega, velocity, phase, options):
    """Classifies a list of starts on one Rust thread (a Dask task)."""
    return _native.basin_cells(omega, velocity, phase, starts, threads=1, **options)


def _classify_starts(omega, velocity, phase, starts, options, client, chunk, threads):
    """The cells of ``starts``: on ``threads`` Rust threads here, or on a Dask ``client`` in
    tasks of ``chunk`` starts; the options, the phase and every start (not below the plate) are
    checked before any work."""
    _native.basin_cells(omega, velocity, phase, starts, check_only=True, **options)
    if client is None:
        return _native.basin_cells(omega, velocity, phase, starts, threads=threads, **options)
    parts = check.tasks(starts, chunk, client)
    futures = client.map(
        _cells_chunk,
        parts,
        omega=omega,
        velocity=velocity,
        phase=phase,
        options=options,
        pure=False,
    )
    return [c for part in client.gather(futures) for c in part]


def _arguments(
    omega, velocity, phase, client, chunk, threads, lanes, zeta, restitution, tol, chatter,
    max_periods, lyapunov_periods,
):  # fmt: skip
    """The arguments :func:`basins` and :func:`basin_uncertainty` share, converted:
    ``(omega, velocity, phase)``, the classification options and ``(client, chunk, threads)``
    (their values are checked by the native module before any work)."""
    names = ("omega", "velocity", "phase")
    shaker = tuple(check.real(k, v) for k, v in zip(names, (omega, velocity, phase)))
    options = dict(
        zeta=check.real("zeta", zeta),
        restitution=check.real("restitution", restitution),
        tol=check.real("tol", tol),
        chatter=check.text("chatter", chatter),
        max_periods=check.real("max_periods", max_periods),
        lyapunov_periods=check.integer(
            "lyapunov_periods", lyapunov_periods, 1, check.MAX_LYAPUNOV_PERIODS
        ),
        lanes=check.lanes(lanes),
    )
    where = (
        check.client(client),
        check.chunk(chunk),
        check.threads(threads),
    )
    return shaker, options, where


def basins(
    omega: float,
    velocity: float,
    x0: Sequence[float],
    v0: Sequence[float],
    phase: float = 0.0,
    client: Any = None,
    chunk: Optional[int] = None,
    threads: int = 0,
    lanes: int = 4,
    zeta: float = 0.02,
    restitution: float = 0.85,
    tol: float = 1e-16,
    chatter: str = "accumulation",
    max_periods: float = 2000.0,
    lyapunov_periods: int = 300,
    full_decision: bool = False,
    recurrence_hits: int = 2,
    aperiodic_hits: int = 500,
):
    """Classifies every start of the grid ``x0 × v0`` at plate phase ``phase`` (cycles) for the
    shaker point ``(omega, velocity)``, as ``bistable basins`` does, and groups the starts by
    the attractor they reach.

    By default a start stops once ``recurrence_hits`` consecutive section points lie within
    the probed capture radius of a periodic attractor already found, or ``aperiodic_hits``
    consecutive section points lie in the cells of an aperiodic (chaotic) one (``decided_by``
    is then ``'recurrence'``; see ``docs/sensitivity.md``); ``full_decision=True`` decides
    every start in full. The starts are taken in rounds in the CLI's interleaved grid order, so the cells
    are those of ``bistable basins`` for the same grid; with a Dask ``client`` each task makes
    its own rounds (the same labels up to the measured agreement, other ``periods_simulated``).

    Returns ``(cells, attractors)``: a pandas DataFrame of the cells (:data:`CELL_COLUMNS` and
    ``attractor``, the attractor's number from 1), ordered with ``v0`` outer and ``x0`` inner as
    the CLI's grid, and a list of dicts, one per attractor, largest basin first (``number``,
    ``label``, ``period``, ``chaotic``, ``final_well``, ``anchor``, ``cells``, ``fraction``...).
    :func:`basin_uncertainty` measures the uncertainty exponent of the result.

    Args:
        x0, v0: the grid's start positions (not below the plate at ``phase``) and velocities
            (at most 1e7 starts in all).
        client: a ``dask.distributed`` Client: the starts go to its workers in tasks of
            ``chunk`` starts (each on one thread; ``None``: 16 to 256, about 8 tasks per
            worker thread, as for :func:`bistable_impact.sweep.map`); without it, ``threads``
            Rust threads here.
        lanes: trajectories each thread (or Dask task) advances together in SIMD lanes: 1, 4
            or 8 (the cells are the same for every width).
        Other arguments: as for ``bistable basins``.
    """
    import pandas as pd

    shaker, options, where = _arguments(
        omega, velocity, phase, client, chunk, threads, lanes, zeta, restitution, tol, chatter,
        max_periods, lyapunov_periods,
    )  # fmt: skip
    options["full_decision"] = full_decision
    options["recurrence_hits"] = check.integer("recurrence_hits", recurrence_hits, 1, 1000)
    options["aperiodic_hits"] = check.integer("aperiodic_hits", aperiodic_hits, 1, 100000)
    xs, vs = check.reals("x0", x0), check.reals("v0", v0)
    check.grid(("x0", "v0"), xs, vs)
    starts = [(a, b) for b in vs for a in xs]
    cells = _classify_starts(*shaker, starts, options, *where)
    attractors, index = _native.basin_attractors(cells)
    df = pd.DataFrame.from_records(cells, columns=list(CELL_COLUMNS))
    df["attractor"] = index
    for c in ("period", "final_well"):
        df[c] = df[c].astype("Int64")
    return df, attractors


def basin_uncertainty(
    omega: float,
    velocity: float,
    x0: Sequence[float],
    cells: Any,
    phase: float = 0.0,
    samples: int = 400,
    client: Any = None,
    chunk: Optional[int] = None,
    threads: int = 0,
    lanes: int = 4,
    zeta: float = 0.02,
    restitution: float = 0.85,
    tol: float = 1e-16,
    chatter: str = "accumulation",
    max_periods: float = 2000.0,
    lyapunov_periods: int = 300,
):
    """The uncertainty exponent of the basins (Grebogi, McDonald, Ott & Yorke 1983), measured
    as ``bistable basins`` measures it: ``samples`` cells spread over the grid, each
    *ε-uncertain* when its start displaced by ``±ε`` in ``x0`` reaches another attractor, at
    ``ε`` = the grid's ``x0`` spacing divided by 1, 4, 16, 64 and 256; ``α`` is the
    least-squares slope of ``ln f(ε)`` against ``ln ε`` (``α = 1``: smooth boundaries,
    ``α < 1``: fractal, of box-counting dimension ``2 − α``).

    Args:
        omega, velocity, phase, x0: as given to :func:`basins` for ``cells``.
        cells: the cells DataFrame that :func:`basins` returned for the grid ``x0 × v0``.
        samples: cells sampled, ``[0, 1e7]`` (at most all of them).
        client, chunk, threads, lanes: where and how the displaced starts are classified,
            as in :func:`basins`.
        Other arguments: the model and classification options given to :func:`basins`.

    Returns ``(fractions, alpha)``: a pandas DataFrame with ``epsilon, samples, uncertain,
    fraction``, one row per ``ε`` (largest first), and ``α`` (``None`` when fewer than two
    fractions are above zero), the ``uncertainty`` and ``uncertainty_exponent`` of
    ``bistable basins --json``.
    """
    import pandas as pd

    shaker, options, where = _arguments(
        omega, velocity, phase, client, chunk, threads, lanes, zeta, restitution, tol, chatter,
        max_periods, lyapunov_periods,
    )  # fmt: skip
    samples = check.integer("samples", samples, 0, check.MAX_POINTS)
    xs = check.reals("x0", x0)
    # `decided_by` says how a cell was decided, not what it reached: not needed here.
    needed = [c for c in CELL_COLUMNS if c != "decided_by"]
    if not (hasattr(cells, "columns") and set(needed) <= set(cells.columns)):
        raise check.invalid(
            "cells",
            type(cells).__name__,
            f"must be the cells DataFrame of basins() (columns {', '.join(needed)})",
        )
    model = {k: options[k] for k in ("zeta", "restitution", "tol", "chatter")}
    records = [
        {k: (None if pd.isna(v) else v.item() if hasattr(v, "item") else v) for k, v in r.items()}
        for r in cells[needed].to_dict("records")
    ]
    grid = dict(
        model,
        omega=shaker[0],
        velocity=shaker[1],
        phase=shaker[2],
        cells=records,
        samples=samples,
        x_first=float(xs[0]),
        x_last=float(xs[-1]),
        nx=len(xs),
    )
    starts = _native.basin_uncertainty_starts(grid)
    # The displaced starts are decided in full, as by `bistable basins`.
    reached = _classify_starts(*shaker, starts, dict(options, full_decision=True), *where)
    fractions, alpha = _native.basin_uncertainty(grid, reached)
    columns = ["epsilon", "samples", "uncertain", "fraction"]
    return pd.DataFrame.from_records(fractions, columns=columns), alpha
