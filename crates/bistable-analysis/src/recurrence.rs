//! Basins decided by recurrence: a start stops as soon as its trajectory is known to be on an
//! attractor already found at this shaker point `(Ω, V)`, after the idea of Attractors.jl's
//! `AttractorsViaRecurrences` (Datseris & Wagemakers 2022), adapted to exact events and to the
//! paper's classes.
//!
//! **Known attractors.** Each attractor other than rest in well 2 is found and classified once
//! by the full decision of [`bistable_core::classify_from`] (period or aperiodic, chaos, class,
//! final well, cycle anchor). A periodic one also keeps its cycle: the `p` stroboscopic section
//! points (plate phase 0, state units `Δx` and `ω0·Δx`) in the order the orbit visits them. An
//! aperiodic one keeps the cells of side [`CELL`] of the section plane that the last
//! [`APERIODIC_POINTS`] section points of its run (at most the last half of the run) occupy.
//!
//! **Capture region.** The neighbourhood of each cycle point that is known to lie in the
//! attractor's basin is measured once, by probes, in the metric of the point's [`Ellipse`]:
//! the eigenvector basis of the cycle's monodromy matrix there (shot with
//! [`bistable_core::shoot`]), in which the linearised `p`-period map shrinks every
//! displacement by the multipliers' modulus. (In the plain `(x, x')` distance a stable focus
//! sends its neighbours out along a skewed ellipse before they come in: at (1.45, 0.05) the
//! P-1 orbit's ellipse has semi-axes 4 : 1.) For each candidate radius `r` of [`PROBE_RADII`]
//! (0.1 down to 1e-4), [`RecurrenceOptions::directions`] starts on the ellipse of radius `r`
//! around the point (the ring's directions turned by a golden-ratio fraction of the spacing
//! from ring to ring), at plate phase 0, each run to the full decision. A probe *passes* when
//! it reaches the same attractor (steady state and cycle anchor, as
//! [`crate::basins::identify`] groups cells) and, unless the attractor crosses the barrier,
//! without any snap-through (class intrawell); probes below the plate (unreachable states) and
//! failed runs count as passing and failing respectively. The point's capture radius is
//! [`CAPTURE_FRACTION`] (half) of the largest `r` whose ring and every smaller ring passed, 0
//! when the smallest ring failed (no capture at that point). Probing costs `13 × directions`
//! full runs per cycle point; it is done only when the starts still to decide after the round
//! are at least [`PROBE_WORTH`] times these nominal probes, else the attractor is known with
//! radius 0 (its starts are decided in full): a few hundred starts per point are cheaper in
//! full than with probes.
//!
//! **Decision.** A start is assigned to known periodic attractor `k` when
//! [`RecurrenceOptions::hits`] (default 2, as Attractors.jl's `consecutive_attractor_steps`)
//! consecutive section points each lie within the capture radius (in its ellipse's metric) of
//! the cycle point of `k` that the orbit visits at that section: the first
//! hit may be at any cycle point `j`, the next must be at `j + 1 (mod p)`, and so on. It is
//! assigned to known aperiodic attractor `k` when [`RecurrenceOptions::aperiodic_hits`]
//! (default 500) consecutive section points lie in cells of `k`, unless those points close in
//! on a cycle (for some period `p ≤ max_period`, the distances between points `p` sections
//! apart in the newest third of the streak all lie below those in the oldest third; asked
//! when the streak reaches the count and every count sections after, over its last twice the
//! count of points): a periodic orbit can lie among an aperiodic attractor's cells, and a run
//! settling onto it stays in them; such a run goes on (to a periodic capture or its full
//! decision). A start that is not captured runs to today's full decision unchanged
//! (periodicity, rest in well 2, or the `max_periods` limit for aperiodic motion, with its
//! Lyapunov exponent), and a new attractor it finds becomes known.
//!
//! **What a captured cell reports.** Period (none for aperiodic), chaos, final well and cycle
//! anchor are those of `k` (the anchor is that of the start that found `k`; a full decision of
//! the cell reports its own run's anchor, equal within the period tolerance, `1e-8`); the class
//! is continuous interwell when `k` crosses the barrier, else transient interwell when the run
//! crossed the barrier before it was captured and intrawell when not: the probes showed that
//! nothing captured crosses the barrier again, so this is the class the full decision reports.
//! `periods_simulated` is what the run simulated, fewer than the full decision needs.
//!
//! **Determinism.** The starts are taken in rounds, in the order given: the first
//! [`RecurrenceOptions::first_round`] starts, then each round as many starts as all rounds
//! before it together. Within a round the table of known attractors is fixed (that of the end
//! of the previous round); after it, the new attractors of the round are added in the order of
//! their first start, and probed. So each cell depends only on the list of starts and the
//! options, never on the number of threads, the lane width or the order in which runs
//! complete; each lane is bit for bit the run made alone. A list given in another order (or in
//! parts, as a resumed grid or Dask tasks) may capture other cells: the labels agree with the
//! full decision as measured in `docs/sensitivity.md`, `periods_simulated` differs.
//!
//! **Where this differs from Attractors.jl.** Periodic attractors are the exact cycles
//! (section points) of the full decision, and their capture neighbourhood is a probed ellipse
//! per cycle point, shaped by the cycle's linearisation, not a grid cell; only aperiodic
//! attractors are held in cells, as Attractors.jl holds every attractor, and they need more
//! consecutive hits (500, five times the 100 `consecutive_recurrences` that Attractors.jl asks
//! to find an attractor) because nothing probes their neighbourhood and a run can take
//! hundreds of sections in its cells to settle onto a periodic orbit among them, too
//! irregularly for the settling test to see (measured in `docs/sensitivity.md`). Transient
//! cells are never labelled
//! (no `consecutive_basin_steps`): on fractal basins that mislabels starts near the
//! boundaries (measured in `docs/sensitivity.md`). New attractors are not found by
//! counting recurrences in unlabelled cells but by the full decision, so their class, period
//! and final well are the paper's. Rest in well 2 is decided as today (it is reached within a
//! few periods). Aperiodic attractors are told apart by kind and well only, as
//! [`crate::basins::identify`] groups cells.

use std::collections::{HashSet, VecDeque};
use std::f64::consts::TAU;
use std::sync::Arc;

use bistable_core::{
    Classification, ClassifyOptions, ClassifyRun, Event, Instant, LaneRun, ParamError, Params,
    ResponseClass, SimError, Simulator, SolverOptions, Width,
};

use crate::basins::{cell_of, same_attractor, Cell, CellTask, DecidedBy, Steady};
use crate::ensemble::{self, Run, RunSpec, Task};
use crate::orbit;
use crate::parallel::Threads;
use crate::sensitivity::Outcome;
use crate::Model;

/// Candidate capture radii, largest first, in the metric of the cycle point's [`Ellipse`] (state
/// units, `Δx` for `x` and `ω0·Δx` for `x'`, along its smaller semi-axis).
pub const PROBE_RADII: [f64; 13] = [
    0.1, 0.05, 0.03, 0.02, 0.01, 5e-3, 3e-3, 2e-3, 1e-3, 5e-4, 3e-4, 2e-4, 1e-4,
];

/// The capture radius is this fraction of the largest probed radius whose ring and every
/// smaller ring passed.
pub const CAPTURE_FRACTION: f64 = 0.5;

/// Side of the square cells of the section plane that hold an aperiodic attractor, in state
/// units.
pub const CELL: f64 = 0.01;

/// At most this many of the last section points of an aperiodic run (and at most half of its
/// sections) give the cells of its attractor.
pub const APERIODIC_POINTS: usize = 4096;

/// A new periodic attractor is probed only when the starts still to decide after the round
/// are at least this many times its own probes (else its capture radii stay 0: probing would
/// cost more than it saves).
pub const PROBE_WORTH: usize = 2;

/// Settings of the recurrence decision (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RecurrenceOptions {
    /// Consecutive section points within the capture radius of a known cycle that decide a
    /// start (Attractors.jl's default: 2).
    pub hits: u32,
    /// Consecutive section points in the cells of a known aperiodic attractor that decide a
    /// start.
    pub aperiodic_hits: u32,
    /// Starts of the first round, all decided in full (the table is empty then).
    pub first_round: usize,
    /// Probes per ring of the capture-radius measurement.
    pub directions: u32,
}

impl Default for RecurrenceOptions {
    fn default() -> Self {
        Self {
            hits: 2,
            aperiodic_hits: 500,
            first_round: 256,
            directions: 16,
        }
    }
}

impl RecurrenceOptions {
    /// Checks the settings in the order of the fields: `hits` in `[1, 1000]` (named
    /// `recurrence_hits`, as the adapters' option), `aperiodic_hits` in `[1, 100000]`,
    /// `first_round` in `[1, 1e7]`, `directions` in `[4, 256]` (named `probe_directions`).
    pub fn check(&self) -> Result<Self, ParamError> {
        let rules: [(&'static str, f64, bool, &'static str); 4] = [
            (
                "recurrence_hits",
                f64::from(self.hits),
                (1..=1000).contains(&self.hits),
                "must be in [1, 1000]",
            ),
            (
                "aperiodic_hits",
                f64::from(self.aperiodic_hits),
                (1..=100_000).contains(&self.aperiodic_hits),
                "must be in [1, 100000]",
            ),
            (
                "first_round",
                self.first_round as f64,
                (1..=10_000_000).contains(&self.first_round),
                "must be in [1, 1e7]",
            ),
            (
                "probe_directions",
                f64::from(self.directions),
                (4..=256).contains(&self.directions),
                "must be in [4, 256]",
            ),
        ];
        for (name, value, ok, rule) in rules {
            if !ok {
                return Err(ParamError { name, value, rule });
            }
        }
        Ok(*self)
    }
}

/// A periodic attractor found at this shaker point, with what the recurrence decision needs.
#[derive(Debug, Clone, PartialEq)]
pub struct KnownAttractor {
    /// Its steady state (period, well or across the barrier; never at rest or aperiodic).
    pub steady: Steady,
    /// Cycle anchor: the cycle's section point with the smallest `x`
    /// ([`bistable_core::Classification::cycle_anchor`]) in the run that found it.
    pub anchor: [f64; 2],
    /// The `p` section points `(x, x')` of the cycle at plate phase 0, in the order the orbit
    /// visits them (the one after `cycle[j]` is `cycle[(j + 1) % p]`).
    pub cycle: Vec<[f64; 2]>,
    /// Capture radius of each cycle point, in the metric of its [`Ellipse`] (0: no capture
    /// there).
    pub radii: Vec<f64>,
    /// Shape of each cycle point's capture region (circles until probed).
    pub shapes: Vec<Ellipse>,
    /// Whether the radii were probed (else they are 0: probing would not have paid).
    pub probed: bool,
    /// The start `(x0, x0')` that found it (the first in the list of starts).
    pub found_by: (f64, f64),
}

impl KnownAttractor {
    /// Whether `cell` reached this attractor.
    pub fn matches(&self, cell: &Cell) -> bool {
        same_attractor(&self.steady, Some(self.anchor), cell)
    }

    /// Whether a probe started near a cycle point passed: it reached this attractor and,
    /// unless the attractor crosses the barrier, never crossed it.
    fn captures(&self, probe: &Cell) -> bool {
        self.matches(probe)
            && (self.steady.across || probe.outcome.class == ResponseClass::Intrawell)
    }

    /// Whether `y` lies within the capture radius of cycle point `j`.
    fn within(&self, j: usize, y: [f64; 2]) -> bool {
        let r = self.radii[j];
        let c = self.cycle[j];
        r > 0.0 && self.shapes[j].norm([y[0] - c[0], y[1] - c[1]]) <= r
    }
}

/// Largest ratio of the semi-axes of a capture [`Ellipse`]; a cycle point whose monodromy
/// gives a longer one (nearly equal real multipliers) is captured in a circle.
pub const MAX_ASPECT: f64 = 10.0;

/// The shape of a cycle point's capture region: the ellipse `{c + S·u : |u| ≤ r}` around
/// cycle point `c`, whose "radius" `r` is measured in the norm `|S⁻¹·(y − c)|`. `S` is the
/// real eigenvector basis of the cycle's monodromy matrix `M` at that point (for complex
/// multipliers `λ = a ± ib` the real and imaginary parts of an eigenvector), scaled so that the
/// ellipse's smaller semi-axis is `r`: it contains the circle of radius `r`. In this norm the
/// linearised `p`-period map shrinks every displacement by the largest `|λ|` (a rotation and
/// a contraction for complex multipliers), so trajectories near the cycle approach it
/// monotonically instead of swinging out along the ellipse that circles would cut across.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ellipse {
    /// `S`, row-major: its columns map the unit circle onto the ellipse of radius 1.
    pub axes: [[f64; 2]; 2],
    /// `S⁻¹`, row-major.
    inverse: [[f64; 2]; 2],
}

impl Ellipse {
    /// The circle (`S = I`): Euclidean distance in the `(x, x')` plane.
    pub const CIRCLE: Ellipse = Ellipse {
        axes: [[1.0, 0.0], [0.0, 1.0]],
        inverse: [[1.0, 0.0], [0.0, 1.0]],
    };

    /// The ellipse of monodromy matrix `m` (row-major over `(x, x')`); the circle when `m`
    /// has no two independent real eigenvectors or complex pair (equal multipliers, a
    /// sticking orbit's `M = 0`), the semi-axes' ratio would exceed [`MAX_ASPECT`], or `m` is
    /// not finite.
    pub fn of_monodromy(m: [[f64; 2]; 2]) -> Self {
        let [(a, b), (c, _)] = bistable_core::shooting::eigenvalues(m);
        // An eigenvector of λ: (m01, λ − m00) when m01 ≠ 0, else (λ − m11, m10).
        let column = |re: f64| {
            if m[0][1].abs() >= m[1][0].abs() {
                [m[0][1], re - m[0][0]]
            } else {
                [re - m[1][1], m[1][0]]
            }
        };
        let (u, w) = if b != 0.0 {
            // a + ib: real part (m01, a − m00), imaginary part (0, b) (m01 ≠ 0 for a complex
            // pair).
            ([m[0][1], a - m[0][0]], [0.0, b])
        } else if a != c {
            (column(a), column(c))
        } else {
            return Self::CIRCLE;
        };
        let s = [[u[0], w[0]], [u[1], w[1]]];
        let det = s[0][0] * s[1][1] - s[0][1] * s[1][0];
        // Singular values of S from SᵀS: σ² = t/2 ± sqrt(t²/4 − det²), t = |S|_F².
        let t = u[0] * u[0] + u[1] * u[1] + w[0] * w[0] + w[1] * w[1];
        let root = (0.25 * t * t - det * det).max(0.0).sqrt();
        let (big, small) = ((0.5 * t + root).sqrt(), (0.5 * t - root).max(0.0).sqrt());
        if !(det.is_finite() && det != 0.0 && small > 0.0 && big <= MAX_ASPECT * small) {
            return Self::CIRCLE;
        }
        // Scaled by 1/σ_min: the smaller semi-axis of the ellipse of radius r is r.
        let k = 1.0 / small;
        let axes = [[s[0][0] * k, s[0][1] * k], [s[1][0] * k, s[1][1] * k]];
        let d = det * k * k;
        let inverse = [
            [axes[1][1] / d, -axes[0][1] / d],
            [-axes[1][0] / d, axes[0][0] / d],
        ];
        Self { axes, inverse }
    }

    /// `|S⁻¹·d|`: the "radius" of displacement `d` from the cycle point.
    pub fn norm(&self, d: [f64; 2]) -> f64 {
        let i = &self.inverse;
        (i[0][0] * d[0] + i[0][1] * d[1]).hypot(i[1][0] * d[0] + i[1][1] * d[1])
    }

    /// The point at radius `r` and angle `theta` around `c`: `c + r·S·(cos θ, sin θ)`.
    pub fn at(&self, c: [f64; 2], r: f64, theta: f64) -> [f64; 2] {
        let (cos, sin) = (theta.cos(), theta.sin());
        let s = &self.axes;
        [
            c[0] + r * (s[0][0] * cos + s[0][1] * sin),
            c[1] + r * (s[1][0] * cos + s[1][1] * sin),
        ]
    }
}

/// An aperiodic (chaotic or not) attractor found at this shaker point: the cells of side
/// [`CELL`] that the section points of the runs that found it occupy (one entry per steady
/// state: runs of one kind and well on different sets join their cells).
#[derive(Debug, Clone, PartialEq)]
pub struct KnownAperiodic {
    /// Its steady state (aperiodic, chaotic or not, in one well or across the barrier).
    pub steady: Steady,
    /// The occupied cells, `(⌊x / CELL⌋, ⌊x' / CELL⌋)`.
    pub cells: HashSet<(i64, i64)>,
    /// Mean of the section points that gave the cells.
    pub centroid: [f64; 2],
    /// The start `(x0, x0')` that found it.
    pub found_by: (f64, f64),
}

impl KnownAperiodic {
    /// Whether `cell` reached this attractor (the same steady state: aperiodic attractors are
    /// told apart by kind and well only, as [`crate::basins::identify`] groups cells).
    pub fn matches(&self, cell: &Cell) -> bool {
        same_attractor(&self.steady, None, cell)
    }

    /// Whether `y` lies in one of the attractor's cells.
    fn holds(&self, y: [f64; 2]) -> bool {
        self.cells.contains(&cell_key(y))
    }
}

fn cell_key(y: [f64; 2]) -> (i64, i64) {
    ((y[0] / CELL).floor() as i64, (y[1] / CELL).floor() as i64)
}

/// The attractors known at a shaker point, in the order they were found.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Known {
    /// Periodic attractors (not rest in well 2).
    pub periodic: Vec<KnownAttractor>,
    /// Aperiodic attractors.
    pub aperiodic: Vec<KnownAperiodic>,
}

impl Known {
    /// Whether `cell` reached one of them.
    pub fn matches(&self, cell: &Cell) -> bool {
        self.periodic.iter().any(|k| k.matches(cell))
            || self.aperiodic.iter().any(|k| k.matches(cell))
    }

    /// The mean section point of the known aperiodic attractor that `cell` reached, if any.
    pub fn centroid_of(&self, cell: &Cell) -> Option<[f64; 2]> {
        self.aperiodic
            .iter()
            .find(|k| k.matches(cell))
            .map(|k| k.centroid)
    }

    /// Adds what a round found; the cells of an aperiodic steady state already known are
    /// joined to its entry (which keeps its centroid and first start).
    pub(crate) fn extend(&mut self, fresh: Known) {
        self.periodic.extend(fresh.periodic);
        for a in fresh.aperiodic {
            match self.aperiodic.iter_mut().find(|k| k.steady == a.steady) {
                Some(k) => k.cells.extend(a.cells),
                None => self.aperiodic.push(a),
            }
        }
    }
}

/// The rounds `(begin, end)` of a list of `n` starts: the first `first` starts, then each
/// round as many as all rounds before it together.
pub(crate) fn rounds(first: usize, n: usize) -> impl Iterator<Item = (usize, usize)> {
    let mut begin = 0;
    std::iter::from_fn(move || {
        (begin < n).then(|| {
            let len = if begin == 0 { first } else { begin };
            let end = begin.saturating_add(len).min(n);
            let r = (begin, end);
            begin = end;
            r
        })
    })
}

/// The attractors new to `known` among what a round's full decisions found (in the order of
/// their starts): a periodic cell with its cycle, an aperiodic one with its section points.
/// The periodic ones are not probed yet (radii 0). Aperiodic runs of one steady state (kind
/// and well) may lie on different sets (e.g. two chaotic bands in well 1): their cells are
/// joined into one entry per steady state, and a run whose cells the known entry lacks adds
/// them.
pub(crate) fn learn(
    known: &Known,
    found: impl IntoIterator<Item = (Cell, Vec<[f64; 2]>)>,
) -> Known {
    let mut fresh = Known::default();
    for (cell, points) in found {
        if points.is_empty() || cell.at_rest {
            continue;
        }
        let found_by = (cell.x0, cell.v0);
        if cell.outcome.period.is_some() {
            if known.matches(&cell) || fresh.matches(&cell) {
                continue;
            }
            let Some(anchor) = cell.anchor else { continue };
            fresh.periodic.push(KnownAttractor {
                steady: cell.steady(),
                anchor,
                radii: vec![0.0; points.len()],
                shapes: vec![Ellipse::CIRCLE; points.len()],
                probed: false,
                cycle: points,
                found_by,
            });
            continue;
        }
        let steady = cell.steady();
        let cells: HashSet<(i64, i64)> = points.iter().map(|&y| cell_key(y)).collect();
        if let Some(k) = fresh.aperiodic.iter_mut().find(|k| k.steady == steady) {
            k.cells.extend(cells);
            continue;
        }
        let held = |k: &KnownAperiodic| k.steady == steady && cells.is_subset(&k.cells);
        if known.aperiodic.iter().any(held) {
            continue;
        }
        let n = points.len() as f64;
        let centroid = points
            .iter()
            .fold([0.0, 0.0], |a, y| [a[0] + y[0] / n, a[1] + y[1] / n]);
        fresh.aperiodic.push(KnownAperiodic {
            steady,
            cells,
            centroid,
            found_by,
        });
    }
    fresh
}

/// The probes of the capture radii of `fresh`'s cycle points (see the module docs): their
/// starts at plate phase 0 and, for each, `(attractor, cycle point, ring)`.
pub(crate) struct ProbePlan {
    pub(crate) starts: Vec<(f64, f64)>,
    rings: Vec<(usize, usize, usize)>,
    failed: Vec<Vec<[bool; PROBE_RADII.len()]>>,
    /// Per attractor: whether it is probed.
    probed: Vec<bool>,
}

impl ProbePlan {
    /// The probes of the attractors of `fresh` whose probing pays with `left` starts still to
    /// decide: those whose nominal probes (`13 × directions` per cycle point) number at most
    /// `left / PROBE_WORTH` ([`PROBE_WORTH`]). Their cycle points get the [`Ellipse`] of their
    /// monodromy (shot at `model` from the cycle point; the circle if shooting fails), and the
    /// probes lie on those ellipses.
    pub(crate) fn new(
        model: &Model,
        fresh: &mut [KnownAttractor],
        directions: u32,
        left: usize,
    ) -> Self {
        // Probes start at plate phase 0, where the plate is at z = 0.
        const GOLDEN: f64 = 0.618_033_988_749_894_9;
        let d = f64::from(directions);
        let mut starts = Vec::new();
        let mut rings = Vec::new();
        let mut probed = vec![false; fresh.len()];
        for (a, k) in fresh.iter_mut().enumerate() {
            let nominal = k.cycle.len() * PROBE_RADII.len() * directions as usize;
            if left < PROBE_WORTH.saturating_mul(nominal) {
                continue;
            }
            probed[a] = true;
            let period = k.cycle.len() as u32;
            for (j, &c) in k.cycle.iter().enumerate() {
                let shape = orbit::shoot(model, period, (c[0], c[1]))
                    .map_or(Ellipse::CIRCLE, |o| Ellipse::of_monodromy(o.monodromy));
                k.shapes[j] = shape;
                for (i, &r) in PROBE_RADII.iter().enumerate() {
                    for n in 0..directions {
                        let theta = TAU * (f64::from(n) + GOLDEN * i as f64) / d;
                        let s = shape.at(c, r, theta);
                        if s[0] >= 0.0 {
                            starts.push((s[0], s[1]));
                            rings.push((a, j, i));
                        }
                    }
                }
            }
        }
        let failed = fresh
            .iter()
            .map(|k| vec![[false; PROBE_RADII.len()]; k.cycle.len()])
            .collect();
        Self {
            starts,
            rings,
            failed,
            probed,
        }
    }

    /// Takes the outcome of probe `n`.
    pub(crate) fn probed(&mut self, fresh: &[KnownAttractor], n: usize, r: Result<Cell, SimError>) {
        let (a, j, i) = self.rings[n];
        if !r.is_ok_and(|c| fresh[a].captures(&c)) {
            self.failed[a][j][i] = true;
        }
    }

    /// Sets the capture radii of `fresh` from the probes' outcomes.
    pub(crate) fn set_radii(self, fresh: &mut [KnownAttractor]) {
        for ((k, failed), probed) in fresh.iter_mut().zip(self.failed).zip(self.probed) {
            if !probed {
                continue;
            }
            k.probed = true;
            for (radius, rings) in k.radii.iter_mut().zip(failed) {
                *radius = PROBE_RADII
                    .iter()
                    .zip(rings)
                    .rev()
                    .take_while(|(_, f)| !f)
                    .last()
                    .map_or(0.0, |(r, _)| r * CAPTURE_FRACTION);
            }
        }
    }
}

/// The cells of `starts` decided by recurrence (see the module docs), on `threads` threads of
/// `width` lanes; each result goes with its index to `done` on the calling thread as it
/// completes (returning an error cancels). Returns the known attractors at the end, in the
/// order they were found. `ro` must have passed [`RecurrenceOptions::check`].
#[allow(clippy::too_many_arguments)]
pub fn classify_starts<E>(
    model: &Model,
    phase: f64,
    co: ClassifyOptions,
    ro: RecurrenceOptions,
    starts: &[(f64, f64)],
    threads: Threads,
    width: Width,
    mut done: impl FnMut(usize, Result<Cell, SimError>) -> Result<(), E>,
) -> Result<Known, E> {
    let mut known = Arc::new(Known::default());
    for (begin, end) in rounds(ro.first_round, starts.len()) {
        // What the round's full decisions found, by index in the round.
        let mut found: Vec<Option<(Cell, Vec<[f64; 2]>)>> = vec![None; end - begin];
        let table = &known;
        ensemble::run(
            &starts[begin..end],
            threads,
            width,
            |&start| RecurrenceCell::new(model, phase, co, start, Arc::clone(table), ro),
            |i, r| {
                let cell = r.map(|(cell, points)| {
                    if !points.is_empty() {
                        found[i] = Some((cell, points));
                    }
                    cell
                });
                done(begin + i, cell)
            },
        )?;
        let mut fresh = learn(&known, found.into_iter().flatten());
        let mut plan = ProbePlan::new(
            model,
            &mut fresh.periodic,
            ro.directions,
            starts.len() - end,
        );
        if !plan.starts.is_empty() {
            let outcome: Result<(), std::convert::Infallible> = ensemble::run(
                &plan.starts.clone(),
                threads,
                width,
                |&(x0, v0)| CellTask::new(model, 0.0, x0, v0, co),
                |n, r| {
                    plan.probed(&fresh.periodic, n, r);
                    Ok(())
                },
            );
            let Ok(()) = outcome;
            plan.set_radii(&mut fresh.periodic);
        }
        let mut table = Known::clone(&known);
        table.extend(fresh);
        known = Arc::new(table);
    }
    Ok(Arc::unwrap_or_clone(known))
}

/// Which known attractor captured a run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Capture {
    /// Periodic attractor `k` of [`Known::periodic`].
    Periodic(usize),
    /// Aperiodic attractor `k` of [`Known::aperiodic`].
    Aperiodic(usize),
}

/// A run decided by recurrence or in full.
pub(crate) enum Reached {
    /// The full decision, with the cycle's section points when periodic (not at rest), the
    /// last section points when aperiodic (see [`APERIODIC_POINTS`]).
    Full(Classification, Vec<[f64; 2]>),
    /// Captured by a known attractor.
    Captured {
        by: Capture,
        snap_throughs: u64,
        periods_simulated: f64,
    },
}

/// A classification run that also watches its section points for a known attractor.
pub(crate) struct RecurrenceRun {
    inner: ClassifyRun,
    known: Arc<Known>,
    hits: u32,
    aperiodic_hits: u32,
    /// The periodic attractor, the cycle point expected at the next section and the hits so
    /// far.
    streak: Option<(usize, usize, u32)>,
    /// The aperiodic attractor whose cells the last sections were in, and how many.
    cells_streak: Option<(usize, u32)>,
    /// The last section points (at most `keep`).
    recent: VecDeque<[f64; 2]>,
    keep: usize,
    /// The classification's longest period (`ClassifyOptions::max_period`).
    max_period: usize,
    sections: u64,
    period_len: f64,
}

impl RecurrenceRun {
    /// Takes section point `y`: the attractor that captures the run, if any.
    fn recur(&mut self, y: [f64; 2]) -> Option<Capture> {
        if let Some(a) = self.recur_periodic(y) {
            return Some(Capture::Periodic(a));
        }
        self.recur_aperiodic(y).map(Capture::Aperiodic)
    }

    fn recur_periodic(&mut self, y: [f64; 2]) -> Option<usize> {
        let known = &self.known.periodic;
        if let Some((a, j, n)) = self.streak.take() {
            let k = &known[a];
            if k.within(j, y) {
                if n + 1 >= self.hits {
                    return Some(a);
                }
                self.streak = Some((a, (j + 1) % k.cycle.len(), n + 1));
                return None;
            }
        }
        for (a, k) in known.iter().enumerate() {
            if let Some(j) = (0..k.cycle.len()).find(|&j| k.within(j, y)) {
                if self.hits <= 1 {
                    return Some(a);
                }
                self.streak = Some((a, (j + 1) % k.cycle.len(), 1));
                return None;
            }
        }
        None
    }

    fn recur_aperiodic(&mut self, y: [f64; 2]) -> Option<usize> {
        let known = &self.known.aperiodic;
        let streak = match self.cells_streak.take() {
            Some((a, n)) if known[a].holds(y) => Some((a, n + 1)),
            _ => known.iter().position(|k| k.holds(y)).map(|a| (a, 1)),
        };
        // A streak is asked whether it settles when it reaches `aperiodic_hits`, and again
        // every `aperiodic_hits` sections while it goes on, over its last `2 × aperiodic_hits`
        // points at most (a run settling for thousands of sections costs a check per
        // `aperiodic_hits` sections, not per section).
        let hits = self.aperiodic_hits;
        match streak {
            Some((a, n))
                if n >= hits
                    && (n - hits).is_multiple_of(hits)
                    && !settling(
                        &self.recent,
                        n.min(hits.saturating_mul(2)) as usize,
                        self.max_period,
                    ) =>
            {
                Some(a)
            }
            s => {
                self.cells_streak = s;
                None
            }
        }
    }
}

/// Whether the last `n` of `points` (section points, oldest first) close in on a cycle: for
/// some period `p` up to `max_period`, the distances `|y_k − y_(k−p)|` of the newest third of
/// them all lie below those of the oldest third (thirds of at least 6 points). A run that
/// settles onto a periodic orbit lying among an aperiodic attractor's cells does so (its
/// distances shrink by the multipliers' modulus to the power `p` each section). A chaotic run
/// does now and then, while it shadows an unstable cycle, the less the longer the window (on
/// the Hénon map 29 % of 20-point windows, none of 990 100-point windows).
fn settling(points: &VecDeque<[f64; 2]>, n: usize, max_period: usize) -> bool {
    const SETTLING_THIRD: usize = 6;
    (1..=max_period).any(|p| {
        let w = n.min(points.len().saturating_sub(p));
        let third = w / 3;
        if third < SETTLING_THIRD {
            return false;
        }
        let last = points.len() - 1;
        let d = |j: usize| {
            let (a, b) = (points[last - j], points[last - j - p]);
            (a[0] - b[0]).hypot(a[1] - b[1])
        };
        let newest = (0..third).map(d).fold(0.0, f64::max);
        let oldest = (w - third..w).map(d).fold(f64::INFINITY, f64::min);
        newest < oldest
    })
}

impl LaneRun for RecurrenceRun {
    type Result = Reached;

    fn target(&self) -> Instant {
        self.inner.target()
    }

    fn event(&mut self, e: &Event) {
        self.inner.event(e);
    }

    fn reached(&mut self, sim: &mut Simulator) -> Result<Option<Reached>, SimError> {
        if self.inner.at_sections() {
            self.sections += 1;
            let (x, v, _, _) = sim.mass();
            if self.recent.len() == self.keep {
                self.recent.pop_front();
            }
            self.recent.push_back([x, v]);
            if let Some(by) = self.recur([x, v]) {
                return Ok(Some(Reached::Captured {
                    by,
                    snap_throughs: sim.stats().snap_throughs,
                    periods_simulated: self.sections as f64 * self.period_len / TAU,
                }));
            }
        }
        Ok(self.inner.reached(sim)?.map(|c| {
            let last = match c.period {
                _ if c.at_rest_in_second_well => 0,
                Some(p) => p as usize,
                None => self.recent.len().min((self.sections / 2) as usize),
            };
            let points = self
                .recent
                .iter()
                .skip(self.recent.len() - last)
                .copied()
                .collect();
            Reached::Full(c, points)
        }))
    }
}

/// The run of a start, watched for the attractors of `known`.
#[derive(Clone)]
pub(crate) struct RecurrenceSpec {
    run: Run,
    known: Arc<Known>,
    ro: RecurrenceOptions,
}

impl RecurrenceSpec {
    /// The run of start `(x0, x0')` at plate phase `phase`, watched for `known`.
    pub(crate) fn new(
        model: &Model,
        phase: f64,
        co: ClassifyOptions,
        start: (f64, f64),
        known: Arc<Known>,
        ro: RecurrenceOptions,
    ) -> Result<Self, SimError> {
        let run = CellTask::new(model, phase, start.0, start.1, co)?.run();
        Ok(Self { run, known, ro })
    }

    /// The cell of the start's result, and the section points of a full decision (see
    /// [`Reached::Full`]; empty when captured).
    pub(crate) fn cell(&self, result: Reached) -> (Cell, Vec<[f64; 2]>) {
        reached_cell(self.run.start, &self.known, result)
    }
}

/// The cell of start `(x0, x0')` whose run watched for `known` gave `result`, and the section
/// points of a full decision (see [`Reached::Full`]; empty when captured).
pub(crate) fn reached_cell(
    (x0, v0): (f64, f64),
    known: &Known,
    result: Reached,
) -> (Cell, Vec<[f64; 2]>) {
    match result {
        Reached::Full(c, points) => (cell_of(x0, v0, &c), points),
        Reached::Captured {
            by,
            snap_throughs,
            periods_simulated,
        } => {
            let (steady, anchor) = match by {
                Capture::Periodic(a) => {
                    let k = &known.periodic[a];
                    (k.steady, Some(k.anchor))
                }
                Capture::Aperiodic(a) => (known.aperiodic[a].steady, None),
            };
            let class = if steady.across {
                ResponseClass::ContinuousInterwell
            } else if snap_throughs > 0 {
                ResponseClass::TransientInterwell
            } else {
                ResponseClass::Intrawell
            };
            let cell = Cell {
                x0,
                v0,
                outcome: Outcome {
                    class,
                    period: steady.period,
                    chaotic: steady.chaotic,
                    final_well: steady.well,
                },
                anchor,
                at_rest: false,
                periods_simulated,
                decided_by: DecidedBy::Recurrence,
            };
            (cell, Vec::new())
        }
    }
}

impl RunSpec for RecurrenceSpec {
    type Lane = RecurrenceRun;

    fn setting(&self) -> (Params, SolverOptions) {
        self.run.setting()
    }

    fn begin(&self) -> Result<(RecurrenceRun, Simulator), SimError> {
        let (inner, sim) = self.run.begin()?;
        let keep = (self.run.co.max_period as usize).max(APERIODIC_POINTS);
        Ok((
            RecurrenceRun {
                inner,
                known: Arc::clone(&self.known),
                hits: self.ro.hits,
                aperiodic_hits: self.ro.aperiodic_hits,
                streak: None,
                cells_streak: None,
                recent: VecDeque::new(),
                keep,
                max_period: self.run.co.max_period as usize,
                sections: 0,
                period_len: self.run.plate.period(),
            },
            sim,
        ))
    }
}

/// A basin cell decided by recurrence, as a [`Task`]: its cell, and the section points of a
/// full decision (see [`Reached::Full`]).
struct RecurrenceCell {
    spec: Option<RecurrenceSpec>,
    result: Option<(Cell, Vec<[f64; 2]>)>,
}

impl RecurrenceCell {
    fn new(
        model: &Model,
        phase: f64,
        co: ClassifyOptions,
        start: (f64, f64),
        known: Arc<Known>,
        ro: RecurrenceOptions,
    ) -> Result<Self, SimError> {
        Ok(Self {
            spec: Some(RecurrenceSpec::new(model, phase, co, start, known, ro)?),
            result: None,
        })
    }
}

impl Task for RecurrenceCell {
    type Run = RecurrenceSpec;
    type Output = (Cell, Vec<[f64; 2]>);

    fn start(&mut self) -> Result<Vec<RecurrenceSpec>, SimError> {
        Ok(self.spec.iter().cloned().collect())
    }

    fn run_done(&mut self, _: usize, result: Reached) -> Result<Vec<RecurrenceSpec>, SimError> {
        let spec = self.spec.take().expect("the cell's run was asked for");
        self.result = Some(spec.cell(result));
        Ok(Vec::new())
    }

    fn finish(self) -> (Cell, Vec<[f64; 2]>) {
        self.result.expect("the cell's run is done")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `n` section points `y_k = c + λ1^k·u + λ2^k·w` of a run closing in on a fixed point `c`
    /// with real multipliers `λ1`, `λ2`, oldest first.
    fn closing_in(n: usize, l1: f64, l2: f64) -> VecDeque<[f64; 2]> {
        let (c, u, w) = ([0.013, 0.062], [0.01, 0.004], [-0.003, 0.008]);
        (0..n)
            .map(|k| {
                let (a, b) = (l1.powi(k as i32), l2.powi(k as i32));
                [c[0] + a * u[0] + b * w[0], c[1] + a * u[1] + b * w[1]]
            })
            .collect()
    }

    #[test]
    fn runs_closing_in_on_a_cycle_are_settling() {
        // The P-1 orbit at (0.927, 0.065) flips with multipliers −0.989 and −0.557: slowly.
        assert!(settling(&closing_in(40, -0.989, -0.557), 20, 16));
        // A focus (modulus 0.78, turning 1.9 rad a section) on a 4 : 1 ellipse, whose plain
        // distances rise and fall from section to section.
        let focus: VecDeque<[f64; 2]> = (0..40)
            .map(|k| {
                let (r, t) = (0.02 * 0.78_f64.powi(k), 1.9 * f64::from(k));
                [0.15 + 4.0 * r * t.cos(), -0.13 + r * t.sin()]
            })
            .collect();
        assert!(settling(&focus, 20, 16));
        // A P-2 orbit closing in: only p = 2 (and its multiples) repeat.
        let p2: VecDeque<[f64; 2]> = closing_in(40, 0.9, 0.5)
            .iter()
            .enumerate()
            .map(|(k, y)| {
                if k % 2 == 0 {
                    *y
                } else {
                    [y[0] + 0.05, y[1] - 0.02]
                }
            })
            .collect();
        assert!(settling(&p2, 20, 16));
        // Too few points to tell: not settling.
        assert!(!settling(&closing_in(3, 0.5, 0.5), 20, 16));
    }

    #[test]
    fn chaotic_runs_are_held_back_for_a_few_sections_at_most() {
        // On the Hénon map's chaotic attractor (a = 1.4, b = 0.3) a short streak looks settling
        // now and then (the run shadows an unstable cycle for a while); as the streak goes on,
        // the window grows and the run is let go. Streaks of the default length hardly ever.
        let mut y = [0.1, 0.1];
        let history: Vec<[f64; 2]> = (0..12_000)
            .map(|_| {
                y = [1.0 - 1.4 * y[0] * y[0] + y[1], 0.3 * y[0]];
                y
            })
            .collect();
        let default = RecurrenceOptions::default().aperiodic_hits as usize;
        for (hits, most_held, most_mean) in [(20, 0.4, 2.0), (default, 0.01, 0.1)] {
            let delays: Vec<usize> = (100..10_000)
                .step_by(10)
                .map(|k0| {
                    (hits..2000)
                        .find(|&n| {
                            !settling(&history[k0 - 40..k0 + n].iter().copied().collect(), n, 16)
                        })
                        .unwrap()
                        - hits
                })
                .collect();
            let n = delays.len() as f64;
            let held = delays.iter().filter(|&&d| d > 0).count() as f64 / n;
            let mean = delays.iter().sum::<usize>() as f64 / n;
            let longest = *delays.iter().max().unwrap();
            eprintln!("Hénon, {hits} hits: {held} held back, mean delay {mean}, longest {longest}");
            assert!(
                held <= most_held && mean <= most_mean && longest < 40,
                "{hits} hits: {held} held back, mean delay {mean}, longest {longest}"
            );
        }
    }

    fn apply(m: [[f64; 2]; 2], d: [f64; 2]) -> [f64; 2] {
        [
            m[0][0] * d[0] + m[0][1] * d[1],
            m[1][0] * d[0] + m[1][1] * d[1],
        ]
    }

    /// `S·R·S⁻¹` for `S` with columns `u`, `w`.
    fn similar(u: [f64; 2], w: [f64; 2], r: [[f64; 2]; 2]) -> [[f64; 2]; 2] {
        let s = [[u[0], w[0]], [u[1], w[1]]];
        let det = s[0][0] * s[1][1] - s[0][1] * s[1][0];
        let inv = [
            [s[1][1] / det, -s[0][1] / det],
            [-s[1][0] / det, s[0][0] / det],
        ];
        let mut sr = [[0.0; 2]; 2];
        let mut m = [[0.0; 2]; 2];
        for i in 0..2 {
            for j in 0..2 {
                sr[i][j] = (0..2).map(|k| s[i][k] * r[k][j]).sum();
            }
        }
        for i in 0..2 {
            for j in 0..2 {
                m[i][j] = (0..2).map(|k| sr[i][k] * inv[k][j]).sum();
            }
        }
        m
    }

    fn directions() -> impl Iterator<Item = [f64; 2]> {
        (0..64).map(|n| {
            let t = TAU * f64::from(n) / 64.0 + 0.1;
            [0.7 * t.cos(), 0.7 * t.sin()]
        })
    }

    #[test]
    fn the_ellipse_norm_shrinks_by_the_multipliers_modulus_and_holds_the_circle() {
        // Complex multipliers 0.78·e^{±i·1.9} in a skewed basis (the P-1 orbit at (1.45, 0.05)
        // has this kind of monodromy, semi-axes about 4:1), and real ones 0.6 and -0.2.
        let (q, phi) = (0.78_f64, 1.9_f64);
        let rotation = [
            [q * phi.cos(), q * phi.sin()],
            [-q * phi.sin(), q * phi.cos()],
        ];
        let cases = [
            (similar([1.0, 0.3], [0.2, -1.5], rotation), q),
            (
                similar([1.0, 0.8], [0.1, 1.0], [[0.6, 0.0], [0.0, -0.2]]),
                0.6,
            ),
        ];
        for (m, modulus) in cases {
            let e = Ellipse::of_monodromy(m);
            assert_ne!(e, Ellipse::CIRCLE, "{m:?}");
            for d in directions() {
                let (before, after) = (e.norm(d), e.norm(apply(m, d)));
                // |S⁻¹ M d| = |R S⁻¹ d|: the modulus for a rotation-contraction, at most the
                // largest |λ| for a diagonal R.
                assert!(after <= modulus * before * (1.0 + 1e-12), "{m:?} {d:?}");
                if modulus == q {
                    assert!((after - q * before).abs() <= 1e-12 * before, "{m:?} {d:?}");
                }
                // The ellipse of radius r holds the circle of radius r: |S⁻¹ d| ≤ |d|.
                assert!(before <= d[0].hypot(d[1]) * (1.0 + 1e-12), "{m:?} {d:?}");
                // Ring points lie at their radius.
                let theta = d[1].atan2(d[0]);
                let p = e.at([0.3, -0.1], 0.05, theta);
                assert!((e.norm([p[0] - 0.3, p[1] + 0.1]) - 0.05).abs() < 1e-15);
            }
            // Its smaller semi-axis is the radius: some direction has |S⁻¹ d| = |d|.
            let widest = directions()
                .map(|d| e.norm(d) / d[0].hypot(d[1]))
                .fold(0.0, f64::max);
            assert!(widest > 0.999, "{widest}");
        }
    }

    #[test]
    fn degenerate_monodromies_give_the_circle() {
        let circle = |m| Ellipse::of_monodromy(m) == Ellipse::CIRCLE;
        // A sticking orbit (M = 0), equal multipliers (defective or not), NaN.
        assert!(circle([[0.0, 0.0], [0.0, 0.0]]));
        assert!(circle([[0.5, 1.0], [0.0, 0.5]]));
        assert!(circle([[0.5, 0.0], [0.0, 0.5]]));
        assert!(circle([[f64::NAN, 0.0], [0.0, 0.5]]));
        // Nearly equal real multipliers: eigenvectors nearly parallel, semi-axes beyond
        // MAX_ASPECT.
        assert!(circle(similar(
            [1.0, 0.0],
            [1.0, 1e-3],
            [[0.5, 0.0], [0.0, 0.4]]
        )));
        // A diagonal monodromy: its eigenvectors are the axes, the circle.
        let e = Ellipse::of_monodromy([[0.5, 0.0], [0.0, 0.2]]);
        assert!((e.norm([0.3, 0.4]) - 0.5).abs() < 1e-15);
    }
}
