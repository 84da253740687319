//! Basins decided by recurrence: a start stops as soon as its trajectory is known to be on a
//! periodic attractor already found at this shaker point `(Ω, V)`, after the idea of
//! Attractors.jl's `AttractorsViaRecurrences` (Datseris & Wagemakers 2022), adapted to exact
//! events and to the paper's classes.
//!
//! **Known attractors.** Each periodic attractor (not rest in well 2, not aperiodic) is found
//! and classified once by the full decision of [`bistable_core::classify_from`] (period, class,
//! final well, cycle anchor), which also records its cycle: the `p` stroboscopic section points
//! (plate phase 0, state units `Δx` and `ω0·Δx`) in the order the orbit visits them.
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
//! (no capture at that point).
//!
//! **Decision.** A start is assigned to known attractor `k` when
//! [`RecurrenceOptions::hits`] (default 2, as Attractors.jl's `consecutive_attractor_steps`)
//! consecutive section points each lie within the capture radius (Euclidean distance in the
//! `(x, x')` plane) of the cycle point of `k` that the orbit visits at that section: the first
//! hit may be at any cycle point `j`, the next must be at `j + 1 (mod p)`, and so on. A start
//! that is not captured runs to today's full decision unchanged (periodicity, rest in well 2,
//! or the `max_periods` limit for aperiodic motion, with its Lyapunov exponent), and a new
//! periodic attractor it finds becomes known.
//!
//! **What a captured cell reports.** Period, final well and cycle anchor are those of `k`
//! (the anchor is that of the start that found `k`; a full decision of the cell reports its own
//! run's anchor, equal within the period tolerance, `1e-8`); the class is continuous interwell
//! when `k` crosses the barrier, else transient interwell when the run crossed the barrier
//! before it was captured and intrawell when not: the probes showed that nothing captured
//! crosses the barrier again, so this is the class the full decision reports.
//! `periods_simulated` is what the run simulated, fewer than the full decision needs.
//!
//! **Determinism.** The starts are taken in rounds, in the order given: the first
//! [`RecurrenceOptions::first_round`] starts, then each round as many starts as all rounds
//! before it together. Within a round the table of known attractors is fixed (that of the end
//! of the previous round); after it, the new periodic attractors of the round are added in the
//! order of their first start, and probed. So each cell depends only on the list of starts and
//! the options, never on the number of threads, the lane width or the order in which runs
//! complete; each lane is bit for bit the run made alone. A list given in another order (or in
//! parts, as a resumed grid or Dask tasks) may capture other cells: the labels agree with the
//! full decision as measured in `docs/sensitivity.md`, `periods_simulated` differs.
//!
//! **Where this differs from Attractors.jl.** No state-space grid: the attractors are the
//! exact cycles (section points) of the full decision, and the capture neighbourhood is a
//! probed radius per cycle point, not a grid cell. Transient cells are never labelled (no
//! `consecutive_basin_steps`): on fractal basins that would mislabel starts near the
//! boundaries. New attractors are not found by counting recurrences in unlabelled cells but by
//! the full decision, so their class, period and final well are the paper's. Rest in well 2 is
//! decided as today (it is reached within a few periods), and aperiodic (chaotic) motion is not
//! recognised by recurrence: such starts run to the limit.

use std::collections::VecDeque;
use std::f64::consts::TAU;

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

/// Settings of the recurrence decision (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RecurrenceOptions {
    /// Consecutive section points within the capture radius of a known cycle that decide a
    /// start (Attractors.jl's default: 2).
    pub hits: u32,
    /// Starts of the first round, all decided in full (the table is empty then).
    pub first_round: usize,
    /// Probes per ring of the capture-radius measurement.
    pub directions: u32,
}

impl Default for RecurrenceOptions {
    fn default() -> Self {
        Self {
            hits: 2,
            first_round: 256,
            directions: 16,
        }
    }
}

impl RecurrenceOptions {
    /// Checks the settings in the order of the fields: `hits` in `[1, 1000]` (named
    /// `recurrence_hits`, as the adapters' option), `first_round` in `[1, 1e7]`, `directions`
    /// in `[4, 256]` (named `probe_directions`).
    pub fn check(&self) -> Result<Self, ParamError> {
        let rules: [(&'static str, f64, bool, &'static str); 3] = [
            (
                "recurrence_hits",
                f64::from(self.hits),
                (1..=1000).contains(&self.hits),
                "must be in [1, 1000]",
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
) -> Result<Vec<KnownAttractor>, E> {
    let mut known: Vec<KnownAttractor> = Vec::new();
    let mut begin = 0;
    while begin < starts.len() {
        let len = if begin == 0 { ro.first_round } else { begin };
        let end = begin.saturating_add(len).min(starts.len());
        // The cycles of the round's periodic full decisions, by index in the round.
        let mut cycles: Vec<Option<(Cell, Vec<[f64; 2]>)>> = vec![None; end - begin];
        let table = &known;
        ensemble::run(
            &starts[begin..end],
            threads,
            width,
            |&(x0, v0)| RecurrenceCell::new(model, phase, co, (x0, v0), table, ro.hits),
            |i, r| {
                let cell = r.map(|(cell, cycle)| {
                    if !cycle.is_empty() {
                        cycles[i] = Some((cell, cycle));
                    }
                    cell
                });
                done(begin + i, cell)
            },
        )?;
        let mut fresh: Vec<KnownAttractor> = Vec::new();
        for (cell, cycle) in cycles.into_iter().flatten() {
            if known.iter().chain(&fresh).any(|k| k.matches(&cell)) {
                continue;
            }
            let Some(anchor) = cell.anchor else { continue };
            fresh.push(KnownAttractor {
                steady: cell.steady(),
                anchor,
                radii: vec![0.0; cycle.len()],
                cycle,
                found_by: (cell.x0, cell.v0),
            });
        }
        probe(model, co, ro.directions, &mut fresh, threads, width);
        known.extend(fresh);
        begin = end;
    }
    Ok(known)
}

/// Measures the capture radius of every cycle point of `fresh` (see the module docs).
fn probe(
    model: &Model,
    co: ClassifyOptions,
    directions: u32,
    fresh: &mut [KnownAttractor],
    threads: Threads,
    width: Width,
) {
    if fresh.is_empty() {
        return;
    }
    // Probes start at plate phase 0, where the plate is at z = 0.
    const GOLDEN: f64 = 0.618_033_988_749_894_9;
    let d = f64::from(directions);
    let mut starts = Vec::new();
    let mut rings = Vec::new();
    for (a, k) in fresh.iter().enumerate() {
        for (j, c) in k.cycle.iter().enumerate() {
            for (i, r) in PROBE_RADII.iter().enumerate() {
                for n in 0..directions {
                    let theta = TAU * (f64::from(n) + GOLDEN * i as f64) / d;
                    let s = (c[0] + r * theta.cos(), c[1] + r * theta.sin());
                    if s.0 >= 0.0 {
                        starts.push(s);
                        rings.push((a, j, i));
                    }
                }
            }
        }
    }
    let mut failed: Vec<Vec<[bool; PROBE_RADII.len()]>> = fresh
        .iter()
        .map(|k| vec![[false; PROBE_RADII.len()]; k.cycle.len()])
        .collect();
    let outcome: Result<(), std::convert::Infallible> = ensemble::run(
        &starts,
        threads,
        width,
        |&(x0, v0)| CellTask::new(model, 0.0, x0, v0, co),
        |n, r| {
            let (a, j, i) = rings[n];
            if !r.is_ok_and(|c| fresh[a].captures(&c)) {
                failed[a][j][i] = true;
            }
            Ok(())
        },
    );
    let Ok(()) = outcome;
    for (k, failed) in fresh.iter_mut().zip(failed) {
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

/// A run decided by recurrence or in full.
enum Reached {
    /// The full decision, with the cycle's section points when periodic (not at rest).
    Full(Classification, Vec<[f64; 2]>),
    /// Captured by known attractor `attractor`.
    Captured {
        attractor: usize,
        snap_throughs: u64,
        periods_simulated: f64,
    },
}

/// A classification run that also watches its section points for a known attractor.
struct RecurrenceRun<'a> {
    inner: ClassifyRun,
    known: &'a [KnownAttractor],
    hits: u32,
    /// The attractor, the cycle point expected at the next section and the hits so far.
    streak: Option<(usize, usize, u32)>,
    /// The last section points (at most `max_period`).
    recent: VecDeque<[f64; 2]>,
    keep: usize,
    sections: u64,
    period_len: f64,
}

impl RecurrenceRun<'_> {
    /// Takes section point `y`: the attractor that captures the run, if any.
    fn recur(&mut self, y: [f64; 2]) -> Option<usize> {
        if let Some((a, j, n)) = self.streak.take() {
            let k = &self.known[a];
            if k.within(j, y) {
                if n + 1 >= self.hits {
                    return Some(a);
                }
                self.streak = Some((a, (j + 1) % k.cycle.len(), n + 1));
                return None;
            }
        }
        for (a, k) in self.known.iter().enumerate() {
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
}

impl LaneRun for RecurrenceRun<'_> {
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
            if let Some(attractor) = self.recur([x, v]) {
                return Ok(Some(Reached::Captured {
                    attractor,
                    snap_throughs: sim.stats().snap_throughs,
                    periods_simulated: self.sections as f64 * self.period_len / TAU,
                }));
            }
        }
        Ok(self.inner.reached(sim)?.map(|c| {
            let cycle = match c.period {
                Some(p) if !c.at_rest_in_second_well => {
                    let p = p as usize;
                    self.recent
                        .iter()
                        .skip(self.recent.len() - p)
                        .copied()
                        .collect()
                }
                _ => Vec::new(),
            };
            Reached::Full(c, cycle)
        }))
    }
}

/// The run of a start, watched for the known attractors of `known`.
struct RecurrenceSpec<'a> {
    run: Run,
    known: &'a [KnownAttractor],
    hits: u32,
}

impl<'a> RunSpec for RecurrenceSpec<'a> {
    type Lane = RecurrenceRun<'a>;

    fn setting(&self) -> (Params, SolverOptions) {
        self.run.setting()
    }

    fn begin(&self) -> Result<(RecurrenceRun<'a>, Simulator), SimError> {
        let (inner, sim) = self.run.begin()?;
        let keep = self.run.co.max_period as usize;
        Ok((
            RecurrenceRun {
                inner,
                known: self.known,
                hits: self.hits,
                streak: None,
                recent: VecDeque::with_capacity(keep),
                keep,
                sections: 0,
                period_len: self.run.plate.period(),
            },
            sim,
        ))
    }
}

/// A basin cell decided by recurrence, as a [`Task`]: its cell, and the cycle's section points
/// of a periodic full decision (empty otherwise).
struct RecurrenceCell<'a> {
    spec: Option<RecurrenceSpec<'a>>,
    start: (f64, f64),
    known: &'a [KnownAttractor],
    result: Option<Reached>,
}

impl<'a> RecurrenceCell<'a> {
    fn new(
        model: &Model,
        phase: f64,
        co: ClassifyOptions,
        start: (f64, f64),
        known: &'a [KnownAttractor],
        hits: u32,
    ) -> Result<Self, SimError> {
        let run = CellTask::new(model, phase, start.0, start.1, co)?.run();
        Ok(Self {
            spec: Some(RecurrenceSpec { run, known, hits }),
            start,
            known,
            result: None,
        })
    }
}

impl<'a> Task for RecurrenceCell<'a> {
    type Run = RecurrenceSpec<'a>;
    type Output = (Cell, Vec<[f64; 2]>);

    fn start(&mut self) -> Result<Vec<RecurrenceSpec<'a>>, SimError> {
        Ok(self.spec.take().into_iter().collect())
    }

    fn run_done(&mut self, _: usize, result: Reached) -> Result<Vec<RecurrenceSpec<'a>>, SimError> {
        self.result = Some(result);
        Ok(Vec::new())
    }

    fn finish(self) -> (Cell, Vec<[f64; 2]>) {
        let (x0, v0) = self.start;
        match self.result.expect("the cell's run is done") {
            Reached::Full(c, cycle) => (cell_of(x0, v0, &c), cycle),
            Reached::Captured {
                attractor,
                snap_throughs,
                periods_simulated,
            } => {
                let k = &self.known[attractor];
                let class = if k.steady.across {
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
                        period: k.steady.period,
                        chaotic: false,
                        final_well: k.steady.well,
                    },
                    anchor: Some(k.anchor),
                    at_rest: false,
                    periods_simulated,
                    decided_by: DecidedBy::Recurrence,
                };
                (cell, Vec::new())
            }
        }
    }
}
