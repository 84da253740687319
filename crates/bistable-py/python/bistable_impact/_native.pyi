"""Type stubs of the Rust extension module (see the package docstring for units)."""

from typing import Any, Callable, Dict, List, Optional, Tuple, TypedDict, Union

Column = Tuple[str, str, bytes]  # name, numpy dtype without byte order ('f8' | 'i8' | 'b1'), LE data
Event = Dict[str, Any]
#: One entry of a classify record's ``outcomes`` (``bistable_impact.Outcome``).
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

#: Keys of the classify record, in order: the map CSV's columns.
COLUMNS: List[str]
COEXISTENCE_COLUMNS: List[str]
#: Most values of one grid and points of one map (the CLI's cap on ranges, 1e7).
MAX_POINTS: int
#: Most worker threads of a ``threads`` argument (1024).
MAX_THREADS: int
#: Default settings of the sensitivity test (``None`` arguments of classify/classify_many).
SENSITIVITY_DEFAULTS: Dict[str, Union[int, float]]

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
) -> Dict[str, Any]: ...
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
    repeats: Optional[int] = None,
    efoldings: Optional[float] = None,
    perturbation: Optional[float] = None,
    horizon: Optional[float] = None,
    repeat_periods: Optional[float] = None,
    lyapunov_windows: Optional[int] = None,
) -> Dict[str, Any]: ...
def classify_many(
    points: List[Tuple[float, float]],
    zeta: float = 0.02,
    restitution: float = 0.85,
    tol: float = 1e-16,
    chatter: str = "accumulation",
    max_periods: float = 20000.0,
    full: bool = False,
    max_period: int = 16,
    period_tol: float = 1e-8,
    lyapunov_periods: int = 300,
    repeats: Optional[int] = None,
    efoldings: Optional[float] = None,
    perturbation: Optional[float] = None,
    horizon: Optional[float] = None,
    repeat_periods: Optional[float] = None,
    lyapunov_windows: Optional[int] = None,
    threads: int = 0,
    lanes: int = 4,
    progress: Optional[Callable[[int, int], Any]] = None,
    on_record: Optional[Callable[[Dict[str, Any]], Any]] = None,
) -> List[Dict[str, Any]]: ...
def thresholds_of(restitution: float = 0.85, omega: Optional[float] = None) -> Dict[str, Any]: ...
def linspace(start: float, end: float, n: int) -> List[float]: ...
def outcomes_text(outcomes: List[Outcome]) -> str: ...
def outcomes_from_text(text: str, runs: int) -> List[Outcome]: ...
def kind_names() -> Dict[str, List[str]]: ...

# The analyses (see bistable_impact.analyses for the keys and units). Tables come as lists of
# Column; "orbits" tables have a separate "cycle_max" list of lists (None for arclength).
# continue_omega's "bifurcations" table has "kind" as an 'i8' code: the index in
# ("fold", "period_doubling", "neimark_sacker", "grazing", "sticking").
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
) -> Dict[str, Any]: ...
def continue_omega(
    omega: List[float],
    velocity: List[float],
    period: int = 1,
    settle: int = 2000,
    method: str = "natural",
    threads: int = 0,
    lanes: int = 4,
    zeta: float = 0.02,
    restitution: float = 0.85,
    tol: float = 1e-16,
    chatter: str = "accumulation",
) -> Dict[str, Any]: ...
# atlas's "curves" table has "kind" coded as continue_omega's "bifurcations" table; its
# "points" table codes "kind" as fold_flip, cusp, resonant_grazing, crossing (0..3).
def atlas(
    omega: List[float],
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
) -> Dict[str, List[Column]]: ...
def bifurcation(
    param: str,
    values: List[float],
    omega: Optional[float] = None,
    velocity: Optional[float] = None,
    transient: int = 500,
    record: int = 100,
    samples: int = 128,
    branch_periods: List[int] = [1, 2, 4, 8],
    threads: int = 0,
    lanes: int = 4,
    zeta: float = 0.02,
    restitution: float = 0.85,
    tol: float = 1e-16,
    chatter: str = "accumulation",
) -> Dict[str, Any]: ...
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
) -> Dict[str, Any]: ...
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
) -> Dict[str, Any]: ...

class Simulator:
    """A stateful simulator of the model (nondimensional units, see the package docstring).

    ``Simulator(omega, velocity, zeta=0.02, restitution=0.85, tol=1e-16,
    chatter='accumulation', t0=0.0, x0=0.0, v0=0.0)``: the mass at ``x0`` (``Δx``, not below
    the plate) with velocity ``v0`` (``ω0·Δx``) at time ``t0``; the defaults are the paper's
    initial condition. Picklable (through :meth:`checkpoint`).

    Limits (``ValueError`` naming the argument beyond them, ``TypeError`` for what is not a
    real number): ``omega`` in ``[1e-6, 1e6]``, ``velocity`` in ``[0, 1e6]``, ``zeta`` in
    ``[0, 10]``; times within the clock range ``max(Ω, 1)·|t − origin| < 2^52`` (the origin
    of the shaker's sinusoid: 0, or the time of the last :meth:`set_sinusoid`).
    """

    def __init__(
        self,
        omega: float,
        velocity: float,
        zeta: float = 0.02,
        restitution: float = 0.85,
        tol: float = 1e-16,
        chatter: str = "accumulation",
        t0: float = 0.0,
        x0: float = 0.0,
        v0: float = 0.0,
    ) -> None: ...
    def advance_to(
        self, t: float, callback: Optional[Callable[[Event], Any]] = None
    ) -> Union[List[Event], bool]:
        """Advances to time ``t`` (>= the current time). Without ``callback``: returns the
        events on the way as dicts (``kind``: ``'impact'`` with ``index, t, phase, x, v_before,
        v_after, zdot, delta_k``; ``'stick_start'`` with ``t, x, cause, impacts``;
        ``'stick_end'`` with ``t, x, v``; ``'snap_through'`` with ``t, v, to_well``). With
        ``callback``: calls it with each event in time order (the GIL is taken for the call
        only); returning ``False`` stops the advance at that event, an exception stops it and
        propagates; returns whether ``t`` was reached.

        ``t`` must be finite and within the clock range. Ctrl-C raises ``KeyboardInterrupt``
        within about 20 ms (the simulator stays usable where it stopped). Without
        ``callback`` at most 1e7 events are returned: beyond, ``RuntimeError`` (the simulator
        stays at the last event)."""
        ...
    def state(self) -> Dict[str, Any]:
        """``t, x, v, z, zdot, mode ('free'|'sticking'), well (1|2), kinetic_energy,
        potential_energy`` now (dense output; observing never changes the run)."""
        ...
    @property
    def time(self) -> float:
        """Current time ``τ``."""
        ...
    def stats(self) -> Dict[str, int]:
        """Work counters ``steps, impacts, sticks, snap_throughs``."""
        ...
    def set_sinusoid(self, omega: float, velocity: float) -> None:
        """Switches the shaker to ``(omega, velocity)`` now, continuing plate position and
        phase."""
        ...
    def checkpoint(self) -> bytes:
        """The complete state in a versioned, checksummed byte format; a simulator restored
        from it continues bit for bit like this one."""
        ...
    @staticmethod
    def from_checkpoint(data: bytes) -> "Simulator":
        """Restores a simulator; ``ValueError`` naming ``'data'`` for bytes that are not a
        valid checkpoint, and for a checkpoint whose state no run can reach (a time, position,
        velocity or energy that is not finite, a time beyond the clock range, parameters
        outside the limits of :class:`Simulator`)."""
        ...
    def __reduce__(self) -> Tuple[Any, Tuple[bytes]]: ...

def basin_cells(
    omega: float,
    velocity: float,
    phase: float,
    starts: List[Tuple[float, float]],
    zeta: float = 0.02,
    restitution: float = 0.85,
    tol: float = 1e-16,
    chatter: str = "accumulation",
    max_periods: float = 2000.0,
    lyapunov_periods: int = 300,
    threads: int = 0,
    lanes: int = 4,
    full_decision: bool = False,
    recurrence_hits: int = 2,
    aperiodic_hits: int = 500,
    check_only: bool = False,
) -> List[Dict[str, Any]]: ...

def basin_attractors(
    cells: List[Dict[str, Any]],
) -> Tuple[List[Dict[str, Any]], List[int]]: ...

def basin_uncertainty_starts(grid: Dict[str, Any]) -> List[Tuple[float, float]]:
    """``grid``: omega, velocity, phase, zeta, restitution, tol, chatter, cells, samples,
    x_first, x_last, nx."""
    ...
def basin_uncertainty(
    grid: Dict[str, Any], reached: List[Dict[str, Any]]
) -> Tuple[List[Dict[str, Any]], Optional[float]]: ...

def coexistence_points(
    points: List[Tuple[float, float]],
    start_box: Tuple[float, float, float, float] = (0.0, 1.2, -0.6, 0.6),
    grid: Optional[Tuple[int, int]] = None,
    random: Optional[Tuple[int, int]] = None,
    zeta: float = 0.02,
    restitution: float = 0.85,
    tol: float = 1e-16,
    chatter: str = "accumulation",
    max_periods: float = 20000.0,
    lyapunov_periods: int = 300,
    full_decision: bool = False,
    recurrence_hits: int = 2,
    aperiodic_hits: int = 500,
    threads: int = 0,
    lanes: int = 4,
    progress: Optional[Callable[[int, int], Any]] = None,
    check_only: bool = False,
) -> List[Dict[str, Any]]: ...

def coexistence_table(
    points: List[Dict[str, Any]],
    omegas: List[float],
    velocities: List[float],
    match_distance: float = 0.2,
    start_box: Tuple[float, float, float, float] = (0.0, 1.2, -0.6, 0.6),
    grid: Optional[Tuple[int, int]] = None,
    random: Optional[Tuple[int, int]] = None,
    zeta: float = 0.02,
    restitution: float = 0.85,
    tol: float = 1e-16,
    chatter: str = "accumulation",
    max_periods: float = 20000.0,
    lyapunov_periods: int = 300,
    full_decision: bool = False,
    recurrence_hits: int = 2,
    aperiodic_hits: int = 500,
) -> List[Dict[str, Any]]: ...
