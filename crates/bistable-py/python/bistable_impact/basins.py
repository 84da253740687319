"""Basins of attraction over a grid of starts ``(x0, x0')`` at one plate phase, like
``bistable basins`` (the same Rust classification of every cell, the same attractors)."""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np

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
)


def _cells_chunk(starts, omega, velocity, phase, options):
    """Classifies a list of starts on one Rust thread (a Dask task)."""
    return _native.basin_cells(omega, velocity, phase, starts, threads=1, **options)


def basins(
    omega: float,
    velocity: float,
    x0: Sequence[float],
    v0: Sequence[float],
    phase: float = 0.0,
    client: Any = None,
    chunk: int = 64,
    threads: int = 0,
    zeta: float = 0.02,
    restitution: float = 0.85,
    tol: float = 1e-16,
    chatter: str = "accumulation",
    max_periods: float = 2000.0,
    lyapunov_periods: int = 300,
):
    """Classifies every start of the grid ``x0 × v0`` at plate phase ``phase`` (cycles) for the
    shaker point ``(omega, velocity)``, as ``bistable basins`` does, and groups the starts by
    the attractor they reach.

    Returns ``(cells, attractors)``: a pandas DataFrame of the cells (:data:`CELL_COLUMNS` and
    ``attractor``, the attractor's number from 1), ordered with ``v0`` outer and ``x0`` inner as
    the CLI's grid, and a list of dicts, one per attractor, largest basin first (``number``,
    ``label``, ``period``, ``chaotic``, ``final_well``, ``anchor``, ``cells``, ``fraction``...).
    The uncertainty exponent is computed by the CLI only.

    Args:
        x0, v0: the grid's start positions (not below the plate at ``phase``) and velocities.
        client: a ``dask.distributed`` Client: the starts go to its workers in tasks of
            ``chunk`` starts (each on one thread); without it, ``threads`` Rust threads here.
        Other arguments: as for ``bistable basins``.
    """
    import pandas as pd

    if not (isinstance(chunk, int) and chunk >= 1):
        raise ValueError(f"invalid value {chunk!r} for 'chunk': must be an integer >= 1")
    options = dict(
        zeta=zeta,
        restitution=restitution,
        tol=tol,
        chatter=chatter,
        max_periods=max_periods,
        lyapunov_periods=lyapunov_periods,
    )
    xs = np.atleast_1d(np.asarray(x0, dtype=float))
    vs = np.atleast_1d(np.asarray(v0, dtype=float))
    starts = [(float(a), float(b)) for b in vs for a in xs]
    # Checks the options, the phase and every start (not below the plate) before any work.
    _native.basin_cells(omega, velocity, phase, starts, check_only=True, **options)
    if client is None:
        cells = _native.basin_cells(omega, velocity, phase, starts, threads=threads, **options)
    else:
        parts = [starts[i : i + chunk] for i in range(0, len(starts), chunk)]
        futures = client.map(
            _cells_chunk,
            parts,
            omega=omega,
            velocity=velocity,
            phase=phase,
            options=options,
            pure=False,
        )
        cells = [c for part in client.gather(futures) for c in part]
    attractors, index = _native.basin_attractors(cells)
    df = pd.DataFrame.from_records(cells, columns=list(CELL_COLUMNS))
    df["attractor"] = index
    for c in ("period", "final_well"):
        df[c] = df[c].astype("Int64")
    return df, attractors

