"""Classification maps over an ``Ω × V`` grid (the paper's Fig. 9), like ``bistable map``."""

from __future__ import annotations

import os
import sys
from typing import TYPE_CHECKING, Any, Callable, Dict, List, Optional, Sequence, Tuple, Union

if TYPE_CHECKING:  # pandas is optional (the [pandas] extra)
    import pandas as pd


from . import _check as check
from . import _native

#: Columns of the map (the CLI map CSV's header, in order; defined once, in
#: ``bistable_analysis::record::COLUMNS``).
COLUMNS = tuple(_native.COLUMNS)
_SENS = _native.SENSITIVITY_DEFAULTS

Point = Tuple[float, float]
#: Finished points of a local sweep written to the store at a time.
_STORE_BATCH = 64
Progress = Callable[[int, int], Any]


def _classify_chunk(points: List[Point], options: Dict[str, Any]) -> List[Dict[str, Any]]:
    """Classifies a list of points on one Rust thread (a Dask task)."""
    return _native.classify_many(points, threads=1, **options)


def _text_progress(done: int, total: int) -> None:
    """``progress=True``: one updating line on stderr."""
    end = "\n" if done == total else ""
    print(f"\rmap: {done}/{total} points", end=end, file=sys.stderr, flush=True)


class _Store:
    """The map CSV that keeps results: rows are appended (and flushed to disk) as chunks
    finish, so a crashed or interrupted sweep keeps them; the file is rewritten in grid order
    at the end."""

    def __init__(self, path: str, zeta: float, restitution: float):
        import pandas as pd

        self.path = path
        self.done: Dict[Point, Dict[str, Any]] = {}
        if os.path.exists(path) and os.path.getsize(path) > 0:
            old = pd.read_csv(path)
            if list(old.columns) != list(COLUMNS):
                raise ValueError(
                    f"store {path!r} does not have the map columns {','.join(COLUMNS)}"
                )
            same = (old["zeta"] == zeta) & (old["restitution"] == restitution)
            for rec in old[same].to_dict("records"):
                rec = {k: (None if pd.isna(x) else x) for k, x in rec.items()}
                rec["outcomes"] = _native.outcomes_from_text(rec["outcomes"], int(rec["runs"]))
                self.done[(rec["omega"], rec["velocity"])] = rec
        else:
            with open(path, "w") as f:
                f.write(",".join(COLUMNS) + "\n")

    def append(self, records: List[Dict[str, Any]]) -> None:
        import pandas as pd

        if not records:
            return
        rows = to_csv_frame(pd.DataFrame.from_records(records, columns=list(COLUMNS)))
        with open(self.path, "a", newline="") as f:
            rows.to_csv(f, header=False, index=False)
            f.flush()
            os.fsync(f.fileno())


def map(
    omega: Sequence[float],
    velocity: Sequence[float],
    client: Any = None,
    store: Optional[str] = None,
    chunk: Optional[int] = None,
    threads: int = 0,
    lanes: int = 4,
    progress: Union[bool, Progress] = False,
    zeta: float = 0.02,
    restitution: float = 0.85,
    tol: float = 1e-16,
    chatter: str = "accumulation",
    max_periods: float = 20000.0,
    full: bool = False,
    max_period: int = 16,
    period_tol: float = 1e-8,
    lyapunov_periods: int = 300,
    repeats: int = _SENS["repeats"],
    efoldings: float = _SENS["efoldings"],
    perturbation: float = _SENS["perturbation"],
    horizon: float = _SENS["horizon"],
    repeat_periods: float = _SENS["repeat_periods"],
    lyapunov_windows: int = _SENS["lyapunov_windows"],
) -> "pd.DataFrame":
    """Classifies every point of the grid ``omega × velocity`` (:func:`bistable_impact.classify`
    at each ``(Ω, V)``) and returns a pandas DataFrame with the CLI map CSV's columns
    (:data:`COLUMNS`), one row per point, ordered with ``velocity`` outer and ``omega`` inner as
    the CLI's grid. ``lyapunov_periods`` defaults to 300 as in ``bistable map``.

    Column types: floats; ``period``, ``impacts_per_period``, ``snap_throughs``,
    ``final_well`` and ``runs`` as ``Int64`` (``<NA>`` for None); flags as ``bool``;
    ``class`` and ``sensitivity_trigger`` as text; ``outcomes`` as the list of dicts of
    :func:`bistable_impact.classify` (:data:`bistable_impact.Outcome`). The CSV files (``store``,
    :func:`to_csv_frame`) hold ``outcomes`` as the CLI's text; :func:`read_csv` reads them.

    Example::

        >>> import bistable_impact as bi
        >>> df = bi.sweep.map([0.85], [0.11, 0.15], threads=1)
        >>> df[["velocity", "class", "period", "final_well"]].values.tolist()
        [[0.11, 'intrawell', 4, 1], [0.15, 'transient_interwell', 1, 2]]
        >>> df["outcomes"][1]
        [{'class': 'transient_interwell', 'period': 1, 'chaotic': False, 'final_well': 2, 'count': 1, 'fraction': 1.0}]

    Args:
        omega, velocity: the grid's values of ``Ω`` and ``V`` (as for
            :func:`bistable_impact.classify`; at most 1e7 points in all).
        client: a ``dask.distributed`` Client: the points go to its workers in tasks of
            ``chunk`` points (each on one thread); tasks lost with a worker are run again by
            Dask, and each point's result is taken once. Without a client, ``threads`` Rust
            threads in this process (``[0, 1024]``, 0: all cores), with the GIL released;
            Ctrl-C (``KeyboardInterrupt``) stops the sweep, also the points in progress.
        store: a CSV file (the map CSV's columns) that keeps results: points already in it
            (same ``zeta`` and ``restitution``; the other options are not recorded in the
            file: resume with the same ones) are not computed again; finished points are
            appended to it as the sweep goes (with a client each task's rows when it is back,
            without one every 64 points and when the sweep stops, also by Ctrl-C or an
            error), so a crashed or interrupted sweep resumes with only the missing points;
            at the end it is rewritten with the whole grid.
        chunk: points per Dask task, ``[1, 1e7]``; ``None`` (the default) takes 16 to 256,
            as many as give each worker thread about 8 tasks.
        lanes: trajectories each thread (or Dask task) advances together in SIMD lanes: 1
            (one at a time), 4 or 8. The results are the same for every width; 4 is the
            fastest on the machines measured (``docs/benchmarks.md``).
        progress: ``True`` for a progress line on stderr, or a callable ``f(done, total)``
            (points) called after each point (no client) or each finished task (client).
        Other arguments: as for :func:`bistable_impact.classify`.
    """
    import pandas as pd

    chunk = check.chunk(chunk)
    threads = check.threads(threads)
    client = check.client(client)
    store = check.path("store", store)
    report: Optional[Progress] = _text_progress if progress is True else (progress or None)
    if report is not None and not callable(report):
        raise TypeError(f"'progress' must be a bool or a callable, not {type(progress).__name__}")
    options = check.classify_options(dict(
        zeta=zeta,
        restitution=restitution,
        tol=tol,
        chatter=chatter,
        max_periods=max_periods,
        full=full,
        max_period=max_period,
        period_tol=period_tol,
        lyapunov_periods=lyapunov_periods,
        repeats=repeats,
        efoldings=efoldings,
        perturbation=perturbation,
        horizon=horizon,
        repeat_periods=repeat_periods,
        lyapunov_windows=lyapunov_windows,
    ))
    options["lanes"] = check.lanes(lanes)
    w, v = check.reals("omega", omega), check.reals("velocity", velocity)
    check.grid(("omega", "velocity"), w, v)
    points = [(a, b) for b in v for a in w]
    _native.classify_many([], **options)  # checks the options before any work is sent
    kept = _Store(store, zeta, restitution) if store is not None else None
    done: Dict[Point, Dict[str, Any]] = dict(kept.done) if kept else {}
    todo = [p for p in points if p not in done]
    if client is None:
        pending: List[Dict[str, Any]] = []

        def on_record(rec: Dict[str, Any]) -> None:
            done[(rec["omega"], rec["velocity"])] = rec
            if kept:
                pending.append(rec)
                if len(pending) >= _STORE_BATCH:
                    kept.append(pending)
                    pending.clear()

        try:
            _native.classify_many(
                todo, threads=threads, progress=report, on_record=on_record, **options
            )
        finally:
            if kept:  # also after Ctrl-C or an error: the finished points are kept
                kept.append(pending)
    elif todo:
        from distributed import as_completed

        chunks = check.tasks(todo, chunk, client)
        futures = client.map(_classify_chunk, chunks, options=options, pure=False)
        finished = 0
        for fut in as_completed(futures):
            part = fut.result()
            if kept:
                kept.append(part)
            for rec in part:
                done[(rec["omega"], rec["velocity"])] = rec
            finished += len(part)
            if report is not None:
                report(finished, len(todo))
    df = pd.DataFrame.from_records([done[p] for p in points], columns=list(COLUMNS))
    for c in ("period", "impacts_per_period", "snap_throughs", "final_well", "runs"):
        df[c] = df[c].astype("Int64")
    for c in ("chaotic", "at_rest_in_second_well", "sticking", "stopped_early", "sensitive",
              "at_rest"):
        df[c] = df[c].astype(bool)
    if store is not None:
        to_csv_frame(df).to_csv(store, index=False)
    return df


def to_csv_frame(df: "pd.DataFrame") -> "pd.DataFrame":
    """A copy of a :func:`map` DataFrame in the form of the map CSV (``bistable map --out``):
    the ``outcomes`` lists as their text ``class:period:well=fraction`` joined by ``;``. Write
    it with ``to_csv(path, index=False)``; :func:`read_csv` reads such a file back."""
    out = df.copy()
    out["outcomes"] = [_native.outcomes_text(list(o)) for o in df["outcomes"]]
    return out


def read_csv(path: Union[str, "os.PathLike[str]"]) -> "pd.DataFrame":
    """A map CSV (``bistable map --out``, a ``store`` of :func:`map`) as the DataFrame
    :func:`map` returns: integer columns as ``Int64`` (empty cells ``<NA>``), flags as
    ``bool``, ``outcomes`` as lists of dicts (:data:`bistable_impact.Outcome`). Raises
    ``ValueError`` for a file without the map columns or with an unreadable ``outcomes``."""
    import pandas as pd

    path = check.path("path", path)
    if path is None:
        raise TypeError("'path' must be a path (str or os.PathLike), not None")
    df = pd.read_csv(path)
    if list(df.columns) != list(COLUMNS):
        raise ValueError(f"{path!r} does not have the map columns {','.join(COLUMNS)}")
    df["outcomes"] = [
        _native.outcomes_from_text(str(t), int(n)) for t, n in zip(df["outcomes"], df["runs"])
    ]
    for c in ("period", "impacts_per_period", "snap_throughs", "final_well", "runs"):
        df[c] = df[c].astype("Int64")
    for c in ("chaotic", "at_rest_in_second_well", "sticking", "stopped_early", "sensitive",
              "at_rest"):
        df[c] = df[c].astype(bool)
    return df


# Basins of attraction (`bistable basins`), kept in their own module.
from .basins import basin_uncertainty, basins  # noqa: E402,F401

# Which attractors coexist (`bistable coexistence`), kept in its own module.
from .coexistence import coexistence  # noqa: E402,F401
