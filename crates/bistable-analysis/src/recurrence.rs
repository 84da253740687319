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
//! **Capture radius.** The neighbourhood of each cycle point that is known to lie in the
//! attractor's basin is measured once, by probes: for each candidate radius `r` of
//! [`PROBE_RADII`] (0.1 down to 1e-4), [`RecurrenceOptions::directions`] starts on the circle
//! of radius `r` around the point (the ring's directions turned by a golden-ratio fraction of
//! the spacing from ring to ring), at plate phase 0, each run to the full decision. A probe
//! *passes* when it reaches the same attractor (steady state and cycle anchor, as
//! [`crate::basins::identify`] groups cells) and, unless the attractor crosses the barrier,
//! without any snap-through (class intrawell); probes below the plate (unreachable states) and
//! failed runs count as passing and failing respectively. The point's capture radius is half
//! the largest `r` whose ring and every smaller ring passed, 0 when the smallest ring failed
//! (no capture at that point). Probing costs `13 × directions` full runs per cycle point; it is
//! done only when the starts still to decide after the round are at least [`PROBE_WORTH`]
//! times the probes, else the attractor is known with radius 0 (its starts are decided in
//! full): a few hundred starts per point are cheaper in full than with probes.
//!
//! **Decision.** A start is assigned to known periodic attractor `k` when
//! [`RecurrenceOptions::hits`] (default 2, as Attractors.jl's `consecutive_attractor_steps`)
//! consecutive section points each lie within the capture radius (Euclidean distance in the
//! `(x, x')` plane) of the cycle point of `k` that the orbit visits at that section: the first
//! hit may be at any cycle point `j`, the next must be at `j + 1 (mod p)`, and so on. It is
//! assigned to known aperiodic attractor `k` when [`RecurrenceOptions::aperiodic_hits`]
//! (default 20) consecutive section points lie in cells of `k`. A start that is not captured
//! runs to today's full decision unchanged (periodicity, rest in well 2, or the `max_periods`
//! limit for aperiodic motion, with its Lyapunov exponent), and a new attractor it finds
//! becomes known.
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
//! (section points) of the full decision, and their capture neighbourhood is a probed radius
//! per cycle point, not a grid cell; only aperiodic attractors are held in cells, as
//! Attractors.jl holds every attractor, and they need more consecutive hits (20, not 2)
//! because nothing probes their neighbourhood. Transient cells are never labelled (no
//! `consecutive_basin_steps`): on fractal basins that would mislabel starts near the
//! boundaries. New attractors are not found by counting recurrences in unlabelled cells but by
//! the full decision, so their class, period and final well are the paper's. Rest in well 2 is
//! decided as today (it is reached within a few periods). Aperiodic attractors are told apart
//! by kind and well only, as [`crate::basins::identify`] groups cells.

use std::collections::{HashSet, VecDeque};
use std::f64::consts::TAU;
use std::sync::Arc;

use bistable_core::{
    Classification, ClassifyOptions, ClassifyRun, Event, Instant, LaneRun, ParamError, Params,
    ResponseClass, SimError, Simulator, SolverOptions, Width,
};

use crate::basins::{cell_of, same_attractor, Cell, CellTask, DecidedBy, Steady};
use crate::ensemble::{self, Run, RunSpec, Task};
use crate::parallel::Threads;
use crate::sensitivity::Outcome;
use crate::Model;

/// Candidate capture radii, largest first, in state units (`Δx` for `x`, `ω0·Δx` for `x'`).
pub const PROBE_RADII: [f64; 13] = [
    0.1, 0.05, 0.03, 0.02, 0.01, 5e-3, 3e-3, 2e-3, 1e-3, 5e-4, 3e-4, 2e-4, 1e-4,
];

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
            aperiodic_hits: 20,
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
    /// Capture radius of each cycle point (same units; 0: no capture there).
    pub radii: Vec<f64>,
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
        let (dx, dv) = (y[0] - c[0], y[1] - c[1]);
        r > 0.0 && dx * dx + dv * dv <= r * r
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
    /// decide: those whose probes number at most `left / PROBE_WORTH` ([`PROBE_WORTH`]).
    pub(crate) fn new(fresh: &[KnownAttractor], directions: u32, left: usize) -> Self {
        // Probes start at plate phase 0, where the plate is at z = 0.
        const GOLDEN: f64 = 0.618_033_988_749_894_9;
        let d = f64::from(directions);
        let mut starts = Vec::new();
        let mut rings = Vec::new();
        let mut probed = vec![false; fresh.len()];
        for (a, k) in fresh.iter().enumerate() {
            let mut own = Vec::new();
            for (j, c) in k.cycle.iter().enumerate() {
                for (i, r) in PROBE_RADII.iter().enumerate() {
                    for n in 0..directions {
                        let theta = TAU * (f64::from(n) + GOLDEN * i as f64) / d;
                        let s = (c[0] + r * theta.cos(), c[1] + r * theta.sin());
                        if s.0 >= 0.0 {
                            own.push((s, (a, j, i)));
                        }
                    }
                }
            }
            if !own.is_empty() && left >= PROBE_WORTH.saturating_mul(own.len()) {
                probed[a] = true;
                for (s, ring) in own {
                    starts.push(s);
                    rings.push(ring);
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
                    .map_or(0.0, |(r, _)| r / 2.0);
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
        let mut plan = ProbePlan::new(&fresh.periodic, ro.directions, starts.len() - end);
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
        match streak {
            Some((a, n)) if n >= self.aperiodic_hits => Some(a),
            s => {
                self.cells_streak = s;
                None
            }
        }
    }
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
