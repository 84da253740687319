"""bistable_impact: a mass on a bistable (double-well) spring driven only by impacts with a
sinusoidally vibrating shaker plate (Nonlinear Dynamics 2022, doi 10.1007/s11071-022-07793-w).

Python adapter over the project's Rust crates (``bistable-core``: model and event-driven
integrator; ``bistable-analysis``: the paper's analyses). All quantities are nondimensional as in
the paper: time ``τ = ω0·t`` (one linear natural period is ``2π``), lengths in units of the well
distance ``Δx`` (wells at 0 and 1, barrier at 1/2), velocities in ``ω0·Δx``, energies in
``k0·Δx²``; phases are shaker phases in cycles, ``[0, 1)``.

What it offers mirrors the ``bistable`` CLI: :func:`simulate` and :class:`Simulator`;
:func:`classify`, :func:`thresholds` and :func:`sweep.map <bistable_impact.sweep.map>` (local
threads or a ``dask.distributed`` client); :func:`orbit`, :func:`continue_omega`,
:func:`atlas`, :func:`bifurcation`, :func:`energy_map` and :func:`spectrum` (module ``analyses``), which
return the subcommands' JSON keys as dicts and their CSV files as pandas DataFrames;
:func:`linspace` gives the values of the CLI's ``A:B:N`` ranges; :func:`cluster.local_cluster
<bistable_impact.cluster.local_cluster>` starts a Dask cluster with little upkeep of its own for
the sweeps.

Every argument is checked before any work: a bad value raises ``ValueError`` (a wrong type
``TypeError``) naming the argument, with the CLI's rule text; a failed simulation raises
``RuntimeError``. The package keeps the model in the FMU's ranges (``Ω`` in ``[1e-6, 1e6]`` and
``V`` in ``[0, 1e6]``, the core's ranges, as in the CLI; beyond the CLI's rules ``ζ`` in
``[0, 10]``) and caps work sizes (grids 1e7 points as the CLI, transients 1e6 shaker periods,
...; the README's Python section lists them). Computations release the GIL; Ctrl-C raises
``KeyboardInterrupt`` within about 20 ms, also inside the runs of the sweeps, the continuation
and the bifurcation data on their worker threads.
"""

from __future__ import annotations

from typing import Any, Dict, Optional, TypedDict

import numpy as np

from . import _check as check
from . import _native
from ._native import Simulator
from ._table import Table
from .analyses import atlas, bifurcation, continue_omega, energy_map, orbit, spectrum

__all__ = [
    "simulate",
    "classify",
    "thresholds",
    "orbit",
    "continue_omega",
    "atlas",
    "bifurcation",
    "energy_map",
    "spectrum",
    "linspace",
    "Simulator",
    "SimulationResult",
    "Table",
    "Outcome",
    "IMPACT_COLUMNS",
    "SENSITIVITY_DEFAULTS",
    "sweep",
    "cluster",
]

#: Default settings of the sensitivity test of :func:`classify` and :func:`sweep.map
#: <bistable_impact.sweep.map>` (``repeats, efoldings, perturbation, horizon, repeat_periods,
#: lyapunov_windows``; defined once, in ``bistable_analysis::sensitivity``).
SENSITIVITY_DEFAULTS: Dict[str, Any] = dict(_native.SENSITIVITY_DEFAULTS)
_SENS = SENSITIVITY_DEFAULTS

#: One entry of the ``outcomes`` of :func:`classify` (and of each row of :func:`sweep.map
#: <bistable_impact.sweep.map>`): a distinct outcome of the point's runs, as the objects of
#: ``bistable classify``'s JSON. ``class`` as the record's; ``period`` in shaker periods, None
#: when aperiodic; ``chaotic``; ``final_well`` 1 or 2, None for a continuous interwell
#: response (it visits both); ``count`` runs (verdicts) that reached it; ``fraction`` =
#: ``count / runs``.
Outcome = TypedDict(
    "Outcome",
    {
        "class": str,
        "period": Optional[int],
        "chaotic": bool,
        "final_well": Optional[int],
        "count": int,
        "fraction": float,
    },
)

#: Columns of :attr:`SimulationResult.impacts` (the CLI's impacts CSV header).
IMPACT_COLUMNS = ("index", "t", "phase", "x", "v_before", "v_after", "delta_k")


class SimulationResult:
    """What :func:`simulate` returns.

    Attributes:
        impacts: :class:`Table` with ``index, t, phase, x, v_before, v_after, delta_k``, one row
            per impact in time order (index 0 is the impact at ``τ = 0``); ``t`` time units,
            ``phase`` shaker cycles ``[0, 1)``, ``x`` position of mass and plate (``Δx``),
            velocities ``ω0·Δx`` (``v_after = −e·v_before + (1+e)·ż``), ``delta_k`` the kinetic
            energy change ``½(v_after² − v_before²)`` (``k0·Δx²``).
        sticking: :class:`Table` ``start, end, x_start, x_end`` per sticking interval (the mass
            rides on the plate); an interval still open at the end has ``end = x_end = NaN``.
        snaps: :class:`Table` ``t, v, to_well`` per crossing of the barrier ``x = 1/2``
            (``to_well`` 1: ``x < 1/2``, 2: ``x > 1/2``).
        trace: :class:`Table` ``t, x, v, z, zdot`` sampled at ``τ = k·trace_dt`` from the dense
            output, or ``None`` without ``trace_dt``.
        final_state: dict ``t, x, v, z, zdot, mode ('free'|'sticking'), well, kinetic_energy,
            potential_energy`` at the end.
        summary: dict of the run (the CLI's ``simulate --json`` keys that apply, plus
            ``started_at``/``finished_at``: Unix time in s of the computation).
    """

    def __init__(self, raw: Dict[str, Any]):
        self.impacts = Table(raw["impacts"])
        self.sticking = Table(raw["sticking"])
        self.snaps = Table(raw["snaps"])
        self.trace = None if raw["trace"] is None else Table(raw["trace"])
        self.final_state: Dict[str, Any] = raw["final_state"]
        self.summary: Dict[str, Any] = raw["summary"]

    def __repr__(self) -> str:
        s = self.summary
        return (
            f"SimulationResult(omega={s['omega']}, velocity={s['velocity']}, "
            f"t_end={s['t_end']}, impacts={len(self.impacts)}, "
            f"sticking={len(self.sticking)}, snaps={len(self.snaps)})"
        )


def simulate(
    omega: float,
    velocity: float,
    t_end: Optional[float] = None,
    periods: Optional[float] = None,
    zeta: float = 0.02,
    restitution: float = 0.85,
    tol: float = 1e-16,
    chatter: str = "accumulation",
    trace_dt: Optional[float] = None,
) -> SimulationResult:
    """Simulates from the paper's initial condition (mass at rest at ``x = 0``, ``τ = 0``, where
    the plate ``z = (V/Ω)·sin(Ωτ)`` meets it moving up: impact 0 at ``τ = 0``).

    Args:
        omega: shaker frequency ratio ``Ω = Ω̂/ω0``, ``[1e-6, 1e6]``.
        velocity: shaker velocity amplitude ``V = V̂/(ω0·Δx)``, ``[0, 1e6]``.
        t_end: end time ``τ`` (time units, > 0); exactly one of ``t_end`` and ``periods``.
        periods: number of natural periods ``N``, i.e. up to ``τ = 2π·N``.
        zeta: damping ratio ``ζ``, ``[0, 10]``.
        restitution: coefficient of restitution ``e`` in ``[0, 1]``.
        tol: local error tolerance of the Taylor integrator, in ``[1e-18, 1e-3]``.
        chatter: ``'accumulation'`` (predicted accumulation point, default) or ``'paper'``
            (sticking when two impacts are less than ``1e-9`` apart).
        trace_dt: sampling interval of :attr:`SimulationResult.trace` (time units, > 0; at
            most 1e8 rows).

    At most 1e7 events (impacts, sticking intervals, barrier crossings) are returned: a run
    with more raises ``RuntimeError`` (use :class:`Simulator` with a callback). Ctrl-C raises
    ``KeyboardInterrupt``.

    Example (the paper's baseline case, 200 natural periods)::

        >>> import bistable_impact as bi
        >>> r = bi.simulate(1.75, 0.07, periods=200)
        >>> r
        SimulationResult(omega=1.75, velocity=0.07, t_end=1256.6370614359173, impacts=349, sticking=0, snaps=0)
        >>> r.impacts["t"][:3].round(6).tolist(), r.final_state["well"]
        ([0.0, 3.772532, 9.291869], 1)
    """
    m = check.model(omega=omega, velocity=velocity, zeta=zeta, restitution=restitution, tol=tol)
    return SimulationResult(
        _native.simulate(
            m["omega"],
            m["velocity"],
            t_end=check.optional_real("t_end", t_end),
            periods=check.optional_real("periods", periods),
            zeta=m["zeta"],
            restitution=m["restitution"],
            tol=m["tol"],
            chatter=check.text("chatter", chatter),
            trace_dt=check.optional_real("trace_dt", trace_dt),
        )
    )


def classify(
    omega: float,
    velocity: float,
    zeta: float = 0.02,
    restitution: float = 0.85,
    tol: float = 1e-16,
    chatter: str = "accumulation",
    max_periods: float = 20000.0,
    full: bool = False,
    max_period: int = 16,
    period_tol: float = 1e-8,
    lyapunov_periods: int = 2000,
    repeats: int = _SENS["repeats"],
    efoldings: float = _SENS["efoldings"],
    perturbation: float = _SENS["perturbation"],
    horizon: float = _SENS["horizon"],
    repeat_periods: float = _SENS["repeat_periods"],
    lyapunov_windows: int = _SENS["lyapunov_windows"],
) -> Dict[str, Any]:
    """The response class at ``(Ω, V)`` from the paper's initial condition, with the final-state
    sensitivity test, as ``bistable classify`` prints it: a dict with the CLI's JSON keys
    ``omega, velocity, zeta, restitution, class
    ('intrawell'|'transient_interwell'|'continuous_interwell'), period (shaker periods or None),
    chaotic, lyapunov (per unit of τ, or None), snap_throughs, final_well (1|2),
    at_rest_in_second_well, impacts_per_period, sticking, periods_simulated (natural periods),
    stopped_early, wall_time_s (s)`` and the sensitivity test's ``sensitive, runs,
    majority_fraction, outcomes, sensitivity_trigger, efoldings, efoldings_threshold`` and
    ``at_rest`` (the steady state is the mass at rest: at the second equilibrium, or on the
    plate without ever leaving it, e.g. ``V = 0``: class ``'intrawell'``, period 1, no
    impacts, ``sticking`` True).

    Sensitivity: a run whose transient amplified an infinitesimal perturbation by at least
    ``e**efoldings`` before its class was decided (tracked over the first ``horizon`` natural
    periods), one decided later, and one still aperiodic at the end are repeated ``repeats``
    times (tolerance ×10 and ×100, and starts displaced by ``perturbation``; repeats of an
    aperiodic run last ``repeat_periods`` natural periods), and an aperiodic run's chaos verdict
    on ``lyapunov_windows`` further windows of the run itself. ``sensitive`` is True when these
    do not all reach the same outcome (class, period, chaos, final well): double precision
    cannot decide such a point. The result is the most frequent outcome; ``outcomes`` lists
    each distinct outcome, most frequent first, as a dict (:data:`Outcome`: ``class, period,
    chaotic, final_well, count, fraction``; the map CSV writes them as the text
    ``class:period:well=fraction`` joined by ``;``). ``repeats=0`` turns the test off (a
    single run). See ``docs/sensitivity.md``.

    Example (a point that no double-precision run can decide: a chaotic transient ends at rest
    in well 2 or on the continuous interwell P-1 orbit, depending on rounding)::

        >>> import bistable_impact as bi
        >>> r = bi.classify(0.85, 0.13)
        >>> r["class"], r["sensitive"], r["runs"]
        ('transient_interwell', True, 9)
        >>> [(o["class"], o["period"], o["final_well"], o["count"]) for o in r["outcomes"]]
        [('transient_interwell', 1, 2, 5), ('continuous_interwell', 1, None, 4)]
        >>> r["outcomes"][0]["fraction"] == 5 / 9 == r["majority_fraction"]
        True

    Args (besides the model's, see :func:`simulate`):
        max_periods: longest run in natural periods, ``[1, 1e8]``.
        full: always run ``max_periods`` (no early stop).
        max_period: largest period looked for, in shaker periods, ``[1, 64]``.
        period_tol: relative agreement that counts as periodic, ``(0, 1e-3]``.
        lyapunov_periods: shaker periods averaged for the Lyapunov exponent, ``[1, 1e6]``.
        repeats: perturbed repeats of a suspect run, ``[0, 64]`` (0: no test).
        efoldings: transient growth (natural log of the amplification) from which a decided
            run is suspect, ``(0, 700]``.
        perturbation: displacement of the repeats' initial state ``(x0, x0')``,
            ``(0, 1e-3]``.
        horizon: natural periods over which the growth is tracked, ``[1, 1e8]``.
        repeat_periods: length of the repeats of an aperiodic run in natural periods,
            ``[1, 1e8]``.
        lyapunov_windows: further Lyapunov windows of an aperiodic run, ``[0, 1024]``.

    The defaults are those of ``bistable classify`` (:data:`SENSITIVITY_DEFAULTS`).
    """
    options = check.classify_options(
        dict(
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
        )
    )
    return _native.classify(check.real("omega", omega), check.real("velocity", velocity), **options)


def thresholds(restitution: float = 0.85, omega: Optional[float] = None) -> Dict[str, Any]:
    """The shaker velocity thresholds of Eq. 16–18 (``V`` in units of ``ω0·Δx``), as
    ``bistable thresholds --json``: ``restitution``, ``single_impact = 1/(4(1+e))``,
    ``interwell = (1−e)/(2(1+e))``, ``omega`` and ``quasi_static = Ω/2`` (None without omega).

    Args:
        restitution: ``e`` in ``[0, 1)``.
        omega: ``Ω`` (> 0), for the quasi-static threshold.

    Example::

        >>> import bistable_impact as bi
        >>> t = bi.thresholds(0.85, omega=0.2)
        >>> round(t["single_impact"], 6), round(t["interwell"], 6), t["quasi_static"]
        (0.135135, 0.040541, 0.1)
    """
    return _native.thresholds_of(
        check.real("restitution", restitution), check.optional_real("omega", omega)
    )


def linspace(start: float, end: float, n: int) -> np.ndarray:
    """``n`` evenly spaced values from ``start`` to ``end``, both included exactly: the values
    of the CLI's ``A:B:N`` ranges (one formula, ``bistable_analysis::grid``), with its limits:
    finite ends, ``n`` in ``[1, 1e7]``.

    Example::

        >>> import bistable_impact as bi
        >>> bi.linspace(0.0, 1.0, 5).tolist()
        [0.0, 0.25, 0.5, 0.75, 1.0]
    """
    n = check.integer("n", n, 1, check.MAX_POINTS)
    values = _native.linspace(check.real("start", start), check.real("end", end), n)
    return np.array(values, dtype=float)


from . import cluster  # noqa: E402
from . import sweep  # noqa: E402  (uses the functions above)
