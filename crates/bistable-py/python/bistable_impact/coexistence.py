"""Which attractors coexist over an ``Ω × V`` grid and how likely each is, like
``bistable coexistence`` (the same Rust sweep, the same table)."""

from __future__ import annotations

import sys
from typing import TYPE_CHECKING, Any, Callable, Dict, List, Optional, Sequence, Tuple, Union

if TYPE_CHECKING:  # pandas is optional (the [pandas] extra)
    import pandas as pd

from . import _check as check
from . import _native

#: Columns of the table (``bistable coexistence`` CSV header, in order; defined once, in
#: ``bistable_analysis::coexistence::COLUMNS``).
COLUMNS = tuple(_native.COEXISTENCE_COLUMNS)
_INT_COLUMNS = ("attractors", "attractor", "branch", "period", "final_well", "count",
                "decided_by_recurrence", "paper_period", "paper_final_well")  # fmt: skip
_BOOL_COLUMNS = ("chaotic", "at_rest", "paper_start", "paper_chaotic", "paper_sensitive")

Progress = Callable[[int, int], Any]


def _points_chunk(points: List[Tuple[float, float]], options: Dict[str, Any]) -> List[dict]:
    """Decides the starts at a list of points on one Rust thread (a Dask task)."""
    return _native.coexistence_points(points, threads=1, **options)


def _text_progress(done: int, total: int) -> None:
    """``progress=True``: one updating line on stderr."""
    end = "\n" if done == total else ""
    print(f"\rcoexistence: {done}/{total} points", end=end, file=sys.stderr, flush=True)


def coexistence(
    omega: Sequence[float],
    velocity: Sequence[float],
    box: Tuple[float, float, float, float] = (0.0, 1.2, -0.6, 0.6),
    starts: Union[int, Tuple[int, int]] = (20, 20),
    seed: int = 1,
    client: Any = None,
    chunk: Optional[int] = None,
    threads: int = 0,
    lanes: int = 4,
    progress: Union[bool, Progress] = False,
    zeta: float = 0.02,
    restitution: float = 0.85,
    tol: float = 1e-16,
    chatter: str = "accumulation",
    max_periods: float = 20000.0,
    lyapunov_periods: int = 300,
    full_decision: bool = False,
    recurrence_hits: int = 2,
    aperiodic_hits: int = 500,
    match_distance: float = 0.2,
) -> "pd.DataFrame":
    """Which attractors coexist at every point of the grid ``omega × velocity`` and how likely
    each is, as ``bistable coexistence`` computes it: the starts of ``box`` are classified at
    each point (decided by recurrence onto the attractors already found there), the attractors
    they reach are listed with their basin fraction and its standard error, and the attractors
    of neighbouring points are matched into branches (one id across the grid).

    Returns a pandas DataFrame with the CLI CSV's columns (:data:`COLUMNS`), one row per point
    and attractor, ordered with ``velocity`` outer and ``omega`` inner as the CLI's file, and
    equal to it value for value. Integer columns (``attractor``, ``branch``, ``period``,
    ``count``...) are ``Int64`` (``<NA>`` for none), flags ``bool``. ``fraction`` is the share
    of the starts that reach the attractor, ``fraction_se`` its binomial standard error
    ``sqrt(f (1 - f) / K)``; ``paper_start`` marks the attractor that the paper's start (at
    rest at ``x = 0``, the start of :func:`bistable_impact.sweep.map`) reaches, and the
    ``paper_*`` columns give that start's own class, period, chaos and final well, and
    whether rounding decides them, as :func:`bistable_impact.sweep.map` reports them. See
    ``docs/coexistence.md``.

    Example::

        >>> import bistable_impact as bi
        >>> df = bi.sweep.coexistence([1.45], [0.05], starts=(8, 8), max_periods=2000, threads=1)
        >>> df[["label", "count"]].values.tolist()[:2]
        [['rest in well 2', 32], ['P-1 in well 1', 30]]

    Args:
        omega, velocity: the grid's values of ``Ω`` and ``V`` (at most 1e7 points in all).
        box: ``(x0 from, x0 to, x0' from, x0' to)`` of the starts at plate phase 0 (x0 from
            >= 0: the plate is at z = 0 then), units ``Δx`` and ``ω0·Δx``.
        starts: ``(nx, nv)``, a grid over the box with its corners, or ``K``, that many
            uniform random starts drawn from ``seed``; at most 1e6.
        client: a ``dask.distributed`` Client: the points go to its workers in tasks of
            ``chunk`` points (each on one thread; each point's result depends only on the
            point, so the table is the same as without a client). Without it, ``threads``
            Rust threads here (0: all cores), with the GIL released; Ctrl-C stops the sweep.
        chunk: points per Dask task, ``[1, 1e7]``; ``None``: 16 to 256, about 8 tasks per
            worker thread.
        lanes: trajectories each thread advances together in SIMD lanes: 1, 4 or 8 (the
            results are the same).
        progress: ``True`` for a progress line on stderr, or a callable ``f(done, total)``
            (points) called after each point (no client) or each finished task (client).
        max_periods, lyapunov_periods: how far a start runs at most (natural periods) and over
            how many shaker periods the Lyapunov exponent of an aperiodic one is averaged.
        full_decision: decide every start in full (no recurrence).
        recurrence_hits, aperiodic_hits: consecutive section points that capture a start on a
            known periodic attractor (within its probed radius) or a known aperiodic one (in
            its cells, unless they close in on a cycle).
        match_distance: largest anchor distance of two attractors matched into one branch.
        Other arguments: as for :func:`bistable_impact.classify`.
    """
    import pandas as pd

    if isinstance(starts, bool):
        raise TypeError("'starts' must be an int or a pair of ints, not bool")
    if isinstance(starts, int):
        layout: Dict[str, Any] = dict(
            random=(check.integer("starts", starts, 0, 10**6 + 1),
                    check.integer("seed", seed, 0, 2**64 - 1)),
        )  # fmt: skip
    else:
        try:
            nx, nv = starts
        except (TypeError, ValueError):
            raise TypeError("'starts' must be an int or a pair of ints") from None
        n = 10**6 + 1
        layout = dict(grid=(check.integer("starts", nx, 0, n), check.integer("starts", nv, 0, n)))
    try:
        b = tuple(check.real("box", x) for x in box)
    except TypeError:
        raise TypeError("'box' must be four numbers (x0 from, x0 to, x0' from, x0' to)") from None
    if len(b) != 4:
        raise TypeError("'box' must be four numbers (x0 from, x0 to, x0' from, x0' to)")
    options: Dict[str, Any] = dict(
        start_box=b,
        **check.model(zeta=zeta, restitution=restitution, tol=tol, chatter=chatter),
        max_periods=check.real("max_periods", max_periods),
        lyapunov_periods=check.integer(
            "lyapunov_periods", lyapunov_periods, 1, check.MAX_LYAPUNOV_PERIODS
        ),
        full_decision=bool(full_decision),
        recurrence_hits=check.integer("recurrence_hits", recurrence_hits, 1, 1000),
        aperiodic_hits=check.integer("aperiodic_hits", aperiodic_hits, 1, 100000),
        **layout,
    )
    distance = check.real("match_distance", match_distance)
    chunk = check.chunk(chunk)
    threads = check.threads(threads)
    client = check.client(client)
    lanes = check.lanes(lanes)
    report: Optional[Progress] = _text_progress if progress is True else (progress or None)
    if report is not None and not callable(report):
        raise TypeError(f"'progress' must be a bool or a callable, not {type(progress).__name__}")
    w, v = check.reals("omega", omega), check.reals("velocity", velocity)
    check.grid(("omega", "velocity"), w, v)
    points = [(a, c) for c in v for a in w]
    _native.coexistence_points(points, check_only=True, lanes=lanes, **options)
    if client is None:
        results = _native.coexistence_points(
            points, threads=threads, lanes=lanes, progress=report, **options
        )
    else:
        from distributed import as_completed

        chunks = check.tasks(points, chunk, client)
        futures = client.map(
            _points_chunk, chunks, options=dict(options, lanes=lanes), pure=False
        )
        results, finished = [], 0
        for fut in as_completed(futures):
            part = fut.result()
            results.extend(part)
            finished += len(part)
            if report is not None:
                report(finished, len(points))
    rows = _native.coexistence_table(results, w, v, match_distance=distance, **options)
    df = pd.DataFrame.from_records(rows, columns=list(COLUMNS))
    for c in _INT_COLUMNS:
        df[c] = df[c].astype("Int64")
    for c in _BOOL_COLUMNS:
        df[c] = df[c].astype(bool)
    return df


def read_csv(path: Any) -> "pd.DataFrame":
    """A ``bistable coexistence`` CSV as the DataFrame :func:`coexistence` returns (the same
    column types). Raises ``ValueError`` for a file without the coexistence columns."""
    import pandas as pd

    path = check.path("path", path)
    if path is None:
        raise TypeError("'path' must be a path (str or os.PathLike), not None")
    df = pd.read_csv(path, keep_default_na=False, na_values=[""])
    if list(df.columns) != list(COLUMNS):
        raise ValueError(f"{path!r} does not have the coexistence columns {','.join(COLUMNS)}")
    for c in _INT_COLUMNS:
        df[c] = df[c].astype("Int64")
    for c in _BOOL_COLUMNS:
        df[c] = df[c].astype(bool)
    return df
