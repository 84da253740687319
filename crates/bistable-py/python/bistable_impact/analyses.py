"""The paper's analyses beyond classification, mirroring the CLI subcommands: ``orbit`` and
``continue_omega`` (``bistable orbit``, with and without ``--continue-omega``), ``atlas``,
``bifurcation``, ``energy_map`` and ``spectrum``.

Each returns a dict with the keys of the subcommand's ``--json`` output; what the subcommand
writes as CSV comes as a pandas DataFrame with the CSV's columns (flags as ``bool``), grids as
numpy arrays. Units as in the package docstring (``τ``, ``Δx``, ``ω0·Δx``, shaker cycles).
"""

from __future__ import annotations

from typing import Any, Dict, Optional, Sequence, Tuple, Union

import numpy as np

from . import _check as check
from . import _native
from ._table import Table

__all__ = ["orbit", "continue_omega", "atlas", "bifurcation", "energy_map", "spectrum"]

#: Columns of the orbits DataFrames (the CLI's ``_orbits.csv``).
ORBIT_COLUMNS = (
    "omega", "velocity", "period", "stable", "x0", "v0", "max_x", "cycle_max",
    "multiplier_1_re", "multiplier_1_im", "multiplier_2_re", "multiplier_2_im",
    "abs_multiplier", "impacts", "snap_throughs", "sticks",
)  # fmt: skip

#: Columns of ``continue_omega(method='arclength')['orbits']`` (the CLI's ``--arclength`` CSV).
ARC_COLUMNS = (
    "velocity", "trace", "index", "omega", "x0", "v0", "max_x", "stable", "multiplier_1_re",
    "multiplier_1_im", "multiplier_2_re", "multiplier_2_im", "abs_multiplier", "impacts",
)  # fmt: skip

#: Columns of ``continue_omega(...)['bifurcations']`` (the CLI's ``_bifurcations.csv``).
BIFURCATION_COLUMNS = (
    "kind", "omega", "velocity", "period", "x0", "v0", "max_x", "multiplier_1_re",
    "multiplier_1_im", "multiplier_2_re", "multiplier_2_im", "omega_error", "branch", "index",
    "impacts_before", "impacts_after", "sticks_before", "sticks_after",
)  # fmt: skip

#: Columns of :func:`atlas`'s DataFrame (the CSV of ``bistable atlas --out``).
ATLAS_COLUMNS = (
    "curve", "kind", "period", "omega", "velocity", "x0", "v0", "multiplier_1_re",
    "multiplier_1_im", "multiplier_2_re", "multiplier_2_im", "impacts",
)  # fmt: skip

#: Columns of ``atlas(..., points=True)``'s points DataFrame (the CLI's ``_points.csv``).
ATLAS_POINT_COLUMNS = (
    "kind", "omega", "velocity", "curve", "index", "other_curve", "other_index", "period",
    "x0", "v0", "multiplier_1_re", "multiplier_1_im", "multiplier_2_re", "multiplier_2_im",
    "impacts", "impacts_beyond", "error",
)  # fmt: skip

_KIND_NAMES = _native.kind_names()

#: ``kind`` of the codimension-two points, by the code the native module uses.
_POINT_KINDS = np.array(_KIND_NAMES["point"], dtype=object)

#: ``kind`` of the bifurcation points, by the code the native module uses.
_BIFURCATION_KINDS = np.array(_KIND_NAMES["bifurcation"], dtype=object)


def _bifurcations_frame(raw: Dict[str, Any]):
    """The bifurcation points as a DataFrame, ``kind`` as words."""
    df = Table(raw.pop("bifurcations")).to_pandas()
    df["kind"] = _BIFURCATION_KINDS[df["kind"].to_numpy()]
    return df


def _orbits_frame(raw: Dict[str, Any]):
    """The orbits table with its ``cycle_max`` lists, in the CSV's column order."""
    df = Table(raw.pop("orbits")).to_pandas()
    cycle_max = raw.pop("cycle_max")
    if cycle_max is not None:
        df.insert(7, "cycle_max", [np.asarray(c, dtype=float) for c in cycle_max])
    return df


def orbit(
    omega: float,
    velocity: float,
    period: int = 1,
    guess: Optional[Tuple[float, float]] = None,
    settle: int = 2000,
    zeta: float = 0.02,
    restitution: float = 0.85,
    tol: float = 1e-16,
    chatter: str = "accumulation",
) -> Dict[str, Any]:
    """A periodic orbit by shooting, as ``bistable orbit --json``: Newton's method on the map
    over ``period`` shaker periods from plate phase 0 to plate phase 0, with the monodromy
    matrix ``M`` from the variational equations.

    Returns the CLI's keys: ``omega, velocity, period, x0, v0`` (fixed point at plate phase 0,
    ``Δx`` and ``ω0·Δx``), ``multipliers`` (list of ``{re, im, abs}``, largest first),
    ``max_abs_multiplier, stable`` (all ``|λ| < 1``), ``floquet_exponent`` (``ln|λ|max/(pT)``
    per unit of ``τ``), ``impacts, sticks, snap_throughs, max_x, cycle_max`` (largest ``x`` of
    each cycle, ascending), ``iterations, residual, monodromy`` (2×2 numpy array),
    ``det_monodromy, det_identity`` (``e^(2·impacts)·exp(−2ζpT)``), ``det_relative_error``
    (None when the orbit sticks), ``guess, guess_source, distance_to_guess``.

    Args:
        omega, velocity: the shaker (``Ω`` in ``[1e-6, 1e6]``, ``V`` in ``[0, 1e6]``).
        period: period of the orbit in shaker periods, ``[1, 64]``.
        guess: ``(x, x')`` at plate phase 0 to start Newton from; default: the section point
            after ``settle`` shaker periods from the paper's initial condition.
        settle: shaker periods simulated for the default guess, ``[0, 1e6]``.
        zeta, restitution, tol, chatter: the model and solver, as for
            :func:`bistable_impact.simulate`.

    ``floquet_exponent`` is None when the largest multiplier is 0 (an orbit that sticks).
    Ctrl-C raises ``KeyboardInterrupt``.

    Raises:
        ValueError: a bad argument (named). RuntimeError: Newton failed (``no P-periodic orbit
        found from (x, v): ...``) or the simulation failed.

    Example (the stable period-2 orbit of the paper's Fig. 6 at ``Ω = 2.2``)::

        >>> import bistable_impact as bi
        >>> o = bi.orbit(2.2, 0.07, period=2)
        >>> o["stable"], o["impacts"], [round(m["abs"], 4) for m in o["multipliers"]]
        (True, 2, [0.6445, 0.6445])
    """
    m = check.model(omega=omega, velocity=velocity, zeta=zeta, restitution=restitution, tol=tol)
    d = _native.orbit(
        period=check.integer("period", period, 1, 64),
        guess=None if guess is None else check.pair("guess", guess),
        settle=check.integer("settle", settle, 0, check.MAX_TRANSIENT),
        chatter=check.text("chatter", chatter),
        **m,
    )
    d["monodromy"] = np.asarray(d["monodromy"], dtype=float)
    return d


def continue_omega(
    omega: Sequence[float],
    velocity: Union[float, Sequence[float]],
    period: int = 1,
    settle: int = 2000,
    method: str = "natural",
    threads: int = 0,
    lanes: int = 4,
    zeta: float = 0.02,
    restitution: float = 0.85,
    tol: float = 1e-16,
    chatter: str = "accumulation",
) -> Dict[str, Any]:
    """Branches of ``period``-periodic orbits continued in ``Ω`` for each ``V``, as ``bistable
    orbit --continue-omega ... --json`` (the paper's Fig. 11a). At every ``Ω`` a simulation of
    ``settle`` shaker periods seeds the orbits, which are continued point to point in both
    directions (``method='natural'``) or followed through folds by pseudo-arclength
    continuation in ``(x, x', Ω)`` (``method='arclength'``, step at most the grid spacing).

    Returns the CLI's JSON keys ``period, method ('natural'|'pseudo-arclength'), omega_range
    ('A:B:N'), branches`` (per ``V``: ``velocity, orbits, stable, omega_min, omega_max,
    traces, folds``; the last two None for natural continuation), ``orbits``: a DataFrame
    with the CLI's ``--out`` CSV columns (:data:`ORBIT_COLUMNS`, one row per orbit, for natural
    continuation; :data:`ARC_COLUMNS`, one row per trace point, for arclength), and
    ``bifurcations``: a DataFrame with the columns of the CLI's ``_bifurcations.csv``
    (:data:`BIFURCATION_COLUMNS`), one row per bifurcation point located between consecutive
    orbits of a branch: ``kind`` (``'fold'``: a Floquet multiplier through +1,
    ``'period_doubling'``: through −1, ``'neimark_sacker'``: a complex pair through the unit
    circle, ``'grazing'``: the impacts per period change, ``'sticking'``: sticking starts or
    stops), ``omega`` and its error bound ``omega_error`` (1e-12 for the smooth kinds, located
    by regula falsi on ``det(M − I)``, ``det(M + I)``, ``det M − 1``; 1e-10 for grazing and
    sticking, by bisection, when converged), the orbit there (``x0, v0, max_x``, multipliers),
    the ``branch`` and ``index`` of the interval, and the impacts and sticking on either side.
    Natural continuation stops at folds, so folds are found with ``method='arclength'``.

    Args:
        omega: the grid of ``Ω`` (in ``[1e-6, 1e6]``), evenly spaced (e.g. :func:`bistable_impact.linspace`).
        velocity: one ``V`` or several.
        period: ``[1, 64]`` shaker periods.
        settle: shaker periods simulated at every ``Ω`` for the seeds, ``[0, 1e6]``.
        method: ``'natural'`` or ``'arclength'``.
        threads: worker threads, ``[0, 1024]`` (0: all cores); the GIL is released, Ctrl-C
            stops the run. ``len(omega)·len(velocity) <= 1e7``.
        lanes: seeding simulations each thread advances together in SIMD lanes: 1 (one at a
            time), 4 or 8; the results are the same for every width.
        zeta, restitution, tol, chatter: as for :func:`bistable_impact.simulate`.
    """
    ws, vs = check.reals("omega", omega), check.reals("velocity", velocity)
    check.grid(("omega", "velocity"), ws, vs)
    m = check.model(zeta=zeta, restitution=restitution, tol=tol)
    d = _native.continue_omega(
        ws,
        vs,
        period=check.integer("period", period, 1, 64),
        settle=check.integer("settle", settle, 0, check.MAX_TRANSIENT),
        method=method,
        threads=check.threads(threads),
        lanes=check.lanes(lanes),
        chatter=check.text("chatter", chatter),
        **m,
    )
    d["orbits"] = _orbits_frame(d)
    d["bifurcations"] = _bifurcations_frame(d)
    return d


def atlas(
    omega: Sequence[float],
    velocity: float,
    velocity_bounds: Tuple[float, float],
    period: int = 1,
    method: str = "natural",
    ds: float = 0.005,
    max_points: int = 200,
    settle: int = 2000,
    threads: int = 0,
    lanes: int = 4,
    zeta: float = 0.02,
    restitution: float = 0.85,
    tol: float = 1e-16,
    chatter: str = "accumulation",
    points: bool = False,
):
    """Fold and period-doubling curves in ``(Ω, V)``, as ``bistable atlas --out``: the
    ``period``-periodic orbits are continued over ``omega`` at ``velocity`` (as
    :func:`continue_omega`), the bifurcation points on them located, and every fold
    (``det(M − I) = 0``) and period doubling (``det(M + I) = 0``) continued in ``(Ω, V)`` by
    pseudo-arclength continuation of the shooting system extended by that condition. A curve
    ends where ``Ω`` leaves the range of ``omega``, ``V`` leaves ``velocity_bounds``, the
    impacts per period change, the step collapses, or after ``max_points`` points each way; a
    point already on a traced curve starts no second one.

    Returns a DataFrame with the columns of the CLI's CSV (:data:`ATLAS_COLUMNS`), one row per
    curve point: ``curve`` (its number), ``kind`` (``'fold'`` or ``'period_doubling'``),
    ``period``, ``omega``, ``velocity``, the fixed point ``x0, v0`` at plate phase 0, the
    multipliers (one at +1 or −1) and ``impacts`` per orbit; each curve from its low-``V`` end.

    With ``points=True``, returns ``(curves, points)``: ``points`` is a DataFrame with the
    columns of the CLI's ``<stem>_points.csv`` (:data:`ATLAS_POINT_COLUMNS`), one row per
    codimension-two point on the curves: ``kind`` (``'fold_flip'``: multipliers +1 and −1 at
    once, none in this model since ``0 < det M < 1``; ``'cusp'``: the fold's normal-form
    coefficient vanishes, two folds meet; ``'resonant_grazing'``: the curve ends where the
    impacts per period change, ``impacts`` → ``impacts_beyond``; ``'crossing'``: two curves
    meet in ``(Ω, V)``, ``other_curve`` and ``other_index`` name the other, −1 for the other
    kinds), ``omega``, ``velocity``, the ``curve`` and the ``index`` of its segment, the
    orbit there (``x0, v0``, multipliers) and ``error``, the bound on the error along the
    curve (≤ 1e-10 when converged; see ``docs/bifurcations.md``).

    Args:
        omega: the grid of ``Ω`` (in ``[1e-6, 1e6]``) the branches are continued over.
        velocity: ``V`` of the branches (in ``[0, 1e6]``).
        velocity_bounds: ``(lo, hi)`` with ``0 <= lo < velocity < hi``.
        period: ``[1, 64]`` shaker periods.
        method: ``'natural'`` or ``'arclength'`` (through folds; needed for folds).
        ds: largest step along a curve (> 0), Euclidean in ``(x, x', Ω, V)``.
        max_points: most points of a curve each way from its start (>= 1).
        settle, threads, lanes, zeta, restitution, tol, chatter: as for
            :func:`continue_omega`.
        points: also return the codimension-two points.

    Raises:
        ValueError: a bad argument (named). RuntimeError: a simulation failed or a curve could
        not start.
    """
    ws = check.reals("omega", omega)
    m = check.model(velocity=velocity, zeta=zeta, restitution=restitution, tol=tol)
    rows = _native.atlas(
        ws,
        velocity_bounds=check.pair("velocity_bounds", velocity_bounds),
        period=check.integer("period", period, 1, 64),
        method=check.text("method", method),
        ds=check.real("ds", ds),
        max_points=check.integer("max_points", max_points, 1, 1_000_000),
        settle=check.integer("settle", settle, 0, check.MAX_TRANSIENT),
        threads=check.threads(threads),
        lanes=check.lanes(lanes),
        chatter=check.text("chatter", chatter),
        **m,
    )
    df = Table(rows["curves"]).to_pandas()
    df["kind"] = _BIFURCATION_KINDS[df["kind"].to_numpy()]
    if not points:
        return df
    pts = Table(rows["points"]).to_pandas()
    pts["kind"] = _POINT_KINDS[pts["kind"].to_numpy()]
    return df, pts


#: ``kind`` values of the bifurcation data, by the code the native module uses.
_KINDS = np.array(["max_x", "impact_phase"], dtype=object)


def bifurcation(
    param: str,
    values: Sequence[float],
    omega: Optional[float] = None,
    velocity: Optional[float] = None,
    transient: int = 500,
    record: int = 100,
    samples: int = 128,
    branch_periods: Sequence[int] = (1, 2, 4, 8),
    threads: int = 0,
    lanes: int = 4,
    zeta: float = 0.02,
    restitution: float = 0.85,
    tol: float = 1e-16,
    chatter: str = "accumulation",
) -> Dict[str, Any]:
    """Bifurcation data against ``Ω`` (``param='omega'``, at fixed ``velocity``) or ``V``
    (``param='velocity'``, at fixed ``omega``), as ``bistable bifurcation --json --out``
    (the paper's Fig. 6/8). At each value the paper's initial condition runs ``transient``
    shaker periods, then ``record`` periods are recorded: the largest ``x`` of each cycle and
    the phase of every impact. Periodic-orbit branches of ``branch_periods`` are found by
    shooting from the attractors and continued along the grid.

    Returns the CLI's JSON keys ``param, range ('A:B:N'), transient, record, points`` (per
    value: ``omega, velocity, period`` (None: none up to 16), ``distinct_max_x,
    impacts_per_cycle``), ``branches`` (per period: ``period, orbits, stable, links``),
    ``wall_time_s`` (s), and the CSVs as DataFrames: ``data`` (``omega, velocity, kind
    ('max_x'|'impact_phase'), cycle, value``: ``x`` in ``Δx`` or phase in cycles; cycles count
    from 0 at the end of the transient) and ``orbits`` (:data:`ORBIT_COLUMNS`).

    Args:
        param: ``'omega'`` or ``'velocity'``.
        values: the values of the control parameter (``Ω`` in ``[1e-6, 1e6]`` or ``V`` in
            ``[0, 1e6]``; at most 1e7 values).
        omega, velocity: the fixed parameter (the other one, if given, must be a valid value).
        transient, record: shaker periods skipped (``[0, 1e6]``) and recorded (``record >= 1``,
            ``record·len(values) <= 1e8``).
        samples: dense-output samples per shaker period for the maxima, ``[8, 4096]``.
        branch_periods: periods of the orbit branches (each ``[1, 64]``, at most 64 of them);
            empty: none.
        threads: worker threads, ``[0, 1024]`` (0: all cores); the GIL is released, Ctrl-C
            stops the run.
        lanes: recorded simulations each thread advances together in SIMD lanes: 1 (one at a
            time), 4 or 8; the results are the same for every width.
        zeta, restitution, tol, chatter: as for :func:`bistable_impact.simulate`.
    """
    if isinstance(branch_periods, (str, bytes)) or not hasattr(branch_periods, "__len__"):
        raise TypeError("'branch_periods' must be a sequence of integers")
    if len(branch_periods) > check.MAX_BRANCHES:
        shown = f"<{len(branch_periods)} values>"
        raise check.invalid("branch_periods", shown, "at most 64 periods")
    m = check.model(zeta=zeta, restitution=restitution, tol=tol)
    d = _native.bifurcation(
        param,
        check.reals("values", values),
        omega=check.optional_real("omega", omega),
        velocity=check.optional_real("velocity", velocity),
        transient=check.integer("transient", transient, 0, check.MAX_TRANSIENT),
        record=check.integer("record", record, 1, 100_000_000),
        samples=check.integer("samples", samples, 8, check.MAX_CYCLE_SAMPLES),
        branch_periods=[check.integer("branch_periods", p, 1, 64) for p in branch_periods],
        threads=check.threads(threads),
        lanes=check.lanes(lanes),
        chatter=check.text("chatter", chatter),
        **m,
    )
    data = Table(d.pop("data")).to_pandas()
    data["kind"] = _KINDS[data["kind"].to_numpy()]
    d["data"] = data
    d["orbits"] = _orbits_frame(d)
    return d


def energy_map(
    restitution: float = 0.85,
    u_range: Optional[Tuple[float, float]] = None,
    nx: int = 360,
    ny: int = 300,
    omega: Optional[float] = None,
    velocity: Optional[float] = None,
    periods: float = 200.0,
    zeta: float = 0.02,
    tol: float = 1e-16,
    chatter: str = "accumulation",
) -> Dict[str, Any]:
    """The kinetic energy change of an impact normalised by the first impact's (Eq. 13),
    ``ΔK/ΔK0 = (((1+e)·cos φ − e·u)² − u²)/(1+e)²`` with ``u = x'₋/V``, on the grid that
    ``bistable energy-map`` draws; with ``omega`` and ``velocity`` also the impacts of a run
    from the paper's initial condition over ``periods`` natural periods (its ``--overlay``).

    Returns ``restitution``, ``u_range`` ``(lo, hi)``, ``phase`` (``nx`` cell centres of
    ``φ/2π`` in ``[0, 1)``, cycles), ``u`` (``ny`` cell centres), ``ratio`` (``nx × ny``
    array of ``ΔK/ΔK0``, NaN where no contact is possible, ``u > cos φ``), ``max_abs`` (largest
    ``|ratio|``, at least 1) and ``impacts`` (DataFrame ``phase, u, time_fraction``, or None).

    Args:
        restitution: ``e`` in ``[0, 1)``.
        u_range: ``(lo, hi)`` of ``u``; default: up to 1.5 and down to below the neutral line
            ``u = −(1+e)/(1−e)·cos φ`` at ``φ = 0`` (with impacts: below the lowest one).
        nx, ny: cells along the phase and along ``u`` (the CLI draws 360 × 300;
            ``nx·ny <= 1e7``).
        omega, velocity: the overlaid run (``Ω`` in ``[1e-6, 1e6]``, ``V`` in ``(0, 1e6]``;
            both or neither).
        periods: natural periods of the overlaid run (> 0, ``periods·max(omega, 1) <= 1e7``).
        zeta, tol, chatter: the overlaid run's model, as for :func:`bistable_impact.simulate`
            (checked also without the overlay).
    """
    d = _native.energy_map(
        check.real("restitution", restitution),
        u_range=None if u_range is None else check.pair("u_range", u_range),
        nx=check.integer("nx", nx, 1, check.MAX_POINTS),
        ny=check.integer("ny", ny, 1, check.MAX_POINTS),
        omega=check.optional_real("omega", omega),
        velocity=check.optional_real("velocity", velocity),
        periods=check.real("periods", periods),
        zeta=check.real("zeta", zeta),
        tol=check.real("tol", tol),
        chatter=check.text("chatter", chatter),
    )
    d["phase"] = Table(d["phase"])["phase"]
    d["u"] = Table(d["u"])["u"]
    d["ratio"] = Table(d["ratio"])["ratio"].reshape(d.pop("shape"))
    if d["impacts"] is not None:
        d["impacts"] = Table(d["impacts"]).to_pandas()
    return d


def spectrum(
    omega: float,
    velocity: float,
    transient: int = 500,
    record: int = 1024,
    samples: int = 64,
    max_freq: float = 5.0,
    zeta: float = 0.02,
    restitution: float = 0.85,
    tol: float = 1e-16,
    chatter: str = "accumulation",
) -> Dict[str, Any]:
    """The amplitude spectrum of the steady-state displacement ``x(τ)``, as ``bistable
    spectrum --json --out``: ``transient`` shaker periods skipped, ``x`` sampled ``samples``
    times per shaker period over ``record`` periods, mean removed, Hann window, FFT.

    Returns the CLI's JSON keys ``omega, velocity, transient, record, samples_per_period,
    period`` (on the stroboscopic section, None: none up to 16), ``spectral_flatness``
    (geometric over arithmetic mean of the power up to ``max_freq``: near 0 for lines),
    ``peak_freq_over_omega, peak_amplitude`` (``Δx``) and ``spectrum``: a DataFrame
    ``freq_over_omega, amplitude`` (frequency in units of ``Ω``, amplitude of a sinusoid at it
    in ``Δx``), one row per FFT bin up to the Nyquist frequency ``samples/2``.

    Args:
        omega, velocity: the shaker.
        transient: shaker periods skipped, ``[0, 1e6]``.
        record: shaker periods sampled (>= 8; resolution ``Ω/record``).
        samples: samples per shaker period (>= 4; ``record·samples <= 2^26``).
        max_freq: highest frequency (units of ``Ω``, > 0) of the flatness.
        zeta, restitution, tol, chatter: as for :func:`bistable_impact.simulate`.

    Example (a period-2 response: lines at multiples of ``Ω/2``)::

        >>> import bistable_impact as bi
        >>> sp = bi.spectrum(2.2, 0.07)
        >>> sp["period"], sp["spectrum"].columns.tolist()
        (2, ['freq_over_omega', 'amplitude'])
    """
    m = check.model(omega=omega, velocity=velocity, zeta=zeta, restitution=restitution, tol=tol)
    d = _native.spectrum(
        transient=check.integer("transient", transient, 0, check.MAX_TRANSIENT),
        record=check.integer("record", record, 8, 1 << 26),
        samples=check.integer("samples", samples, 4, 1 << 26),
        max_freq=check.real("max_freq", max_freq),
        chatter=check.text("chatter", chatter),
        **m,
    )
    d["spectrum"] = Table(d["spectrum"]).to_pandas()
    return d
