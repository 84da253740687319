"""Classification maps over an ``Ω × V`` grid (the paper's Fig. 9), like ``bistable map``."""

from __future__ import annotations

from typing import Any, Optional, Sequence

import numpy as np

from . import _native

#: Columns of the map (the CLI map CSV's header, in order).
COLUMNS = (
    "omega",
    "velocity",
    "zeta",
    "restitution",
    "class",
    "period",
    "chaotic",
    "lyapunov",
    "snap_throughs",
    "final_well",
    "at_rest_in_second_well",
    "impacts_per_period",
    "sticking",
    "periods_simulated",
    "stopped_early",
    "wall_time_s",
)


def map(
    omega: Sequence[float],
    velocity: Sequence[float],
    client: Any = None,
    store: Optional[str] = None,
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
    """Classifies every point of the grid ``omega × velocity`` (rows ordered with ``velocity``
    outer, ``omega`` inner, as the CLI's grid) and returns a pandas DataFrame with the CLI map
    CSV's columns (:data:`COLUMNS`). Runs on ``threads`` Rust threads (0: all cores) with the GIL
    released. ``lyapunov_periods`` defaults to 300 as in ``bistable map``.

    ``client`` (a ``dask.distributed`` Client) and ``store`` are not supported yet and must be
    None.
    """
    import pandas as pd

    if client is not None or store is not None:
        raise NotImplementedError("sweep.map: 'client' and 'store' are not supported yet")
    w = np.atleast_1d(np.asarray(omega, dtype=float))
    v = np.atleast_1d(np.asarray(velocity, dtype=float))
    points = [(float(a), float(b)) for b in v for a in w]
    records = _native.classify_many(
        points,
        zeta=zeta,
        restitution=restitution,
        tol=tol,
        chatter=chatter,
        max_periods=max_periods,
        full=full,
        max_period=max_period,
        period_tol=period_tol,
        lyapunov_periods=lyapunov_periods,
        threads=threads,
    )
    df = pd.DataFrame.from_records(records, columns=list(COLUMNS))
    for c in ("period", "impacts_per_period"):
        df[c] = df[c].astype("Int64")
    return df
