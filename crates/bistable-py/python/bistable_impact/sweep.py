"""Classification maps over an ``Ω × V`` grid (the paper's Fig. 9), like ``bistable map``."""

from __future__ import annotations

import os
from typing import Any, Optional, Sequence

import numpy as np

from . import _native

#: Columns of the map (the CLI map CSV's header, in order; defined once, in
#: ``bistable_analysis::record::COLUMNS``).
COLUMNS = tuple(_native.COLUMNS)


def _classify_chunk(points, options):
    """Classifies a list of points on one Rust thread (a Dask task)."""
    return _native.classify_many(points, threads=1, **options)


def map(
    omega: Sequence[float],
    velocity: Sequence[float],
    client: Any = None,
    store: Optional[str] = None,
    chunk: int = 16,
    threads: int = 0,
    zeta: float = 0.02,
    restitution: float = 0.85,
    tol: float = 1e-16,
    chatter: str = "accumulation",
    max_periods: float = 20000.0,
    full: bool = False,
    max_period: int = 16,
    period_tol: float = 1e-8,
    lyapunov_periods: int = 300,
):
    """Classifies every point of the grid ``omega × velocity`` (:func:`bistable_impact.classify`
    at each ``(Ω, V)``) and returns a pandas DataFrame with the CLI map CSV's columns
    (:data:`COLUMNS`), one row per point, ordered with ``velocity`` outer and ``omega`` inner as
    the CLI's grid. ``lyapunov_periods`` defaults to 300 as in ``bistable map``.

    Args:
        omega, velocity: the grid's values of ``Ω`` (> 0) and ``V`` (>= 0).
        client: a ``dask.distributed`` Client: the points go to its workers in tasks of
            ``chunk`` points (each on one thread); without it, ``threads`` Rust threads in this
            process (0: all cores), with the GIL released.
        store: a CSV file (the map CSV's columns) that keeps results: points already in it (same ``zeta``
            and ``restitution``) are not computed again, and it is rewritten with the whole grid.
        chunk: points per Dask task (>= 1).
        Other arguments: as for :func:`bistable_impact.classify`.
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
        full=full,
        max_period=max_period,
        period_tol=period_tol,
        lyapunov_periods=lyapunov_periods,
    )
    w = np.atleast_1d(np.asarray(omega, dtype=float))
    v = np.atleast_1d(np.asarray(velocity, dtype=float))
    points = [(float(a), float(b)) for b in v for a in w]
    _native.classify_many([], **options)  # checks the options before any work is sent
    done = {}
    if store is not None and os.path.exists(store):
        old = pd.read_csv(store)
        if list(old.columns) != list(COLUMNS):
            raise ValueError(f"store {store!r} does not have the map columns {','.join(COLUMNS)}")
        same = (old["zeta"] == zeta) & (old["restitution"] == restitution)
        for rec in old[same].to_dict("records"):
            rec = {k: (None if pd.isna(x) else x) for k, x in rec.items()}
            done[(rec["omega"], rec["velocity"])] = rec
    todo = [p for p in points if p not in done]
    if client is None:
        records = _native.classify_many(todo, threads=threads, **options)
    else:
        chunks = [todo[i : i + chunk] for i in range(0, len(todo), chunk)]
        futures = client.map(_classify_chunk, chunks, options=options, pure=False)
        records = [r for part in client.gather(futures) for r in part]
    for rec in records:
        done[(rec["omega"], rec["velocity"])] = rec
    df = pd.DataFrame.from_records([done[p] for p in points], columns=list(COLUMNS))
    for c in ("period", "impacts_per_period", "snap_throughs", "final_well"):
        df[c] = df[c].astype("Int64")
    for c in ("chaotic", "at_rest_in_second_well", "sticking", "stopped_early"):
        df[c] = df[c].astype(bool)
    if store is not None:
        df.to_csv(store, index=False)
    return df


# Basins of attraction (`bistable basins`), kept in their own module.
from .basins import basins  # noqa: E402,F401
