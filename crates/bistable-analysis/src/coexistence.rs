//! Which responses coexist: at every shaker point `(Ω, V)` of a sweep, the attractors that `K`
//! starts reach and the share of the starts each one takes (its basin fraction), decided by
//! recurrence ([`crate::recurrence`]); then the attractors matched from point to point, so that
//! one branch keeps one id across the sweep (the global continuation of Datseris, Rossi &
//! Wagemakers, Chaos 33, 073151, 2023, on the paper's classes).
//!
//! **Starts.** `K` starts `(x0, x0')` at `τ = 0` with the plate at phase 0 (where it is at
//! `z = 0`, moving up at `V`), in a box [`StartBox`]: a grid of `nx × nv` starts or `K` seeded
//! uniform random starts ([`Sampling`]). The same starts serve every point. The paper's own
//! start (at rest at `x = 0`) is decided too, in full and with `bistable map`'s sensitivity
//! test, but is not one of the `K`: it tells which attractor the paper's map reports.
//!
//! **Fractions.** The basin fraction `f = n / K` of an attractor reached by `n` of the `K`
//! starts estimates the share of the box's area (the probability that a start drawn uniformly
//! from the box reaches it); its standard error is the binomial `sqrt(f (1 − f) / K)`, exact
//! for random starts and an upper bound in practice for a grid (whose error is set by the
//! basin boundary's length and dimension). An attractor that only the paper's start reaches
//! is listed with `n = 0`.
//!
//! **Matching.** Points are visited with `Ω` inner and `V` outer. An attractor at a point is
//! matched to the attractors of the points before it in `Ω` and in `V` that have the same
//! steady state (kind, period, well or across the barrier, at rest) and an anchor within
//! `max_distance` (max-norm in the section plane; the cycle anchor of a periodic attractor,
//! the mean section point of an aperiodic one; rest needs none): closest pairs first, each
//! neighbour's branch taken at most once. An attractor left unmatched starts a new branch.
//! Branch ids count from 0 in the order branches start.

use std::sync::Arc;

use bistable_core::{
    Classification, ClassifyOptions, ClassifyRun, Event, Instant, LaneRun, ParamError, Params,
    ResponseClass, SimError, Simulator, SolverOptions, Width,
};

use crate::basins::{identify, Cell, DecidedBy, Decision, Steady};
use crate::branches::Branches;
use crate::ensemble::{self, Run, RunSpec, Task};
use crate::parallel::Threads;
use crate::progress::OnProgress;
use crate::record::Value;
use crate::recurrence::{
    reached_cell, rounds, Known, ProbePlan, Reached, RecurrenceOptions, RecurrenceRun,
    RecurrenceSpec,
};
use crate::seeds::Seed;
use crate::sensitivity::{PointTest, SensitivityOptions};
use crate::Model;

/// At most this many starts per point.
pub const MAX_STARTS: usize = 1_000_000;

/// The first round of starts at a point (all decided in full): small, so that the attractors
/// are known early among a few hundred starts.
pub const FIRST_ROUND: usize = 16;

/// The box of starts at plate phase 0, in state units (`Δx`, `ω0·Δx`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StartBox {
    /// `x0` from `x[0]` to `x[1]` (`0 <= x[0] < x[1]`: the plate is at `z = 0`).
    pub x: [f64; 2],
    /// `x0'` from `v[0]` to `v[1]` (`v[0] < v[1]`).
    pub v: [f64; 2],
}

impl Default for StartBox {
    /// `x0 ∈ [0, 1.2]` (from the plate to beyond the second well), `x0' ∈ [−0.6, 0.6]`.
    fn default() -> Self {
        Self {
            x: [0.0, 1.2],
            v: [-0.6, 0.6],
        }
    }
}

/// How the starts fill the box.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Sampling {
    /// `nx × nv` starts on a grid with the box's corners (one value: the lower edge).
    Grid {
        /// Positions.
        nx: usize,
        /// Velocities.
        nv: usize,
    },
    /// `n` uniform random starts from `seed` (SplitMix64).
    Random {
        /// Starts.
        n: usize,
        /// Seed.
        seed: u64,
    },
}

/// The starts of every point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Starts {
    /// Where.
    pub bounds: StartBox,
    /// How many and how laid out.
    pub sampling: Sampling,
}

impl Default for Starts {
    /// The default box with a 20 × 20 grid.
    fn default() -> Self {
        Self {
            bounds: StartBox::default(),
            sampling: Sampling::Grid { nx: 20, nv: 20 },
        }
    }
}

impl Starts {
    /// The number of starts `K`.
    pub fn count(&self) -> usize {
        match self.sampling {
            Sampling::Grid { nx, nv } => nx.saturating_mul(nv),
            Sampling::Random { n, .. } => n,
        }
    }

    /// Checks the box (named `start_box`: finite, not below the plate, not empty) and the
    /// number of starts (named `starts`: 1 to [`MAX_STARTS`]).
    pub fn check(&self) -> Result<Self, ParamError> {
        let StartBox { x, v } = self.bounds;
        let bad = |value: f64, rule| {
            Err(ParamError {
                name: "start_box",
                value,
                rule,
            })
        };
        if let Some(&c) = x.iter().chain(&v).find(|c| !c.is_finite()) {
            return bad(c, "must be finite");
        }
        if x[0] < 0.0 {
            return bad(
                x[0],
                "x0 must be >= 0: the plate is at z = 0 at phase 0, a start below it cannot be",
            );
        }
        if x[0] >= x[1] {
            return bad(x[1], "is empty: x0 must run from a lower to a higher value");
        }
        if v[0] >= v[1] {
            return bad(
                v[1],
                "is empty: x0' must run from a lower to a higher value",
            );
        }
        let k = self.count();
        let per_axis = match self.sampling {
            Sampling::Grid { nx, nv } => nx.min(nv),
            Sampling::Random { n, .. } => n,
        };
        if per_axis == 0 || k > MAX_STARTS {
            return Err(ParamError {
                name: "starts",
                value: k as f64,
                rule: "must be from 1 to 1e6 starts",
            });
        }
        Ok(*self)
    }

    /// The starts, in the order they are decided: a grid in the interleaved order of
    /// [`crate::sweep::interleaved`] (the first round spreads over the box), random ones as
    /// drawn.
    pub fn points(&self) -> Vec<(f64, f64)> {
        let StartBox { x, v } = self.bounds;
        let at = |r: [f64; 2], i: usize, n: usize| {
            if n > 1 {
                r[0] + (r[1] - r[0]) * i as f64 / (n - 1) as f64
            } else {
                r[0]
            }
        };
        match self.sampling {
            Sampling::Grid { nx, nv } => crate::sweep::interleaved(nx * nv)
                .map(|k| (at(x, k % nx, nx), at(v, k / nx, nv)))
                .collect(),
            Sampling::Random { n, seed } => {
                let mut state = seed;
                let mut unit = || {
                    // SplitMix64, 53 bits to [0, 1).
                    state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
                    let mut z = state;
                    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
                    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
                    (z ^ (z >> 31)) as f64 / 2f64.powi(64)
                };
                (0..n)
                    .map(|_| {
                        let a = x[0] + (x[1] - x[0]) * unit();
                        (a, v[0] + (v[1] - v[0]) * unit())
                    })
                    .collect()
            }
        }
    }
}

/// An attractor at one point, with its share of the starts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Coexisting {
    /// Its steady state.
    pub steady: Steady,
    /// The cycle anchor of a periodic attractor, the mean section point of an aperiodic one
    /// (when known; see [`crate::recurrence::KnownAperiodic`]); `None` at rest.
    pub anchor: Option<[f64; 2]>,
    /// Starts that reach it.
    pub count: usize,
    /// Of those, the starts decided by recurrence.
    pub by_recurrence: usize,
    /// Natural periods simulated by those starts together.
    pub periods_simulated: f64,
}

impl Coexisting {
    /// Basin fraction `count / starts`.
    pub fn fraction(&self, starts: usize) -> f64 {
        self.count as f64 / starts.max(1) as f64
    }

    /// Binomial standard error of the fraction, `sqrt(f (1 − f) / starts)`.
    pub fn standard_error(&self, starts: usize) -> f64 {
        let f = self.fraction(starts);
        (f * (1.0 - f) / starts.max(1) as f64).sqrt()
    }
}

/// What coexists at one point.
#[derive(Debug, Clone, PartialEq)]
pub struct PointCoexistence {
    /// `Ω`.
    pub omega: f64,
    /// `V`.
    pub velocity: f64,
    /// The number of starts `K`.
    pub starts: usize,
    /// The attractors, largest basin first (ties: first reached in the order of the starts).
    pub attractors: Vec<Coexisting>,
    /// The cell of the paper's start (at rest at `x = 0`, plate phase 0), decided in full with
    /// `bistable map`'s sensitivity test: the outcome `bistable map` reports (the most frequent
    /// one where rounding decides).
    pub paper: Cell,
    /// Whether rounding decides the paper start's outcome (`bistable map`'s `sensitive`).
    pub paper_sensitive: bool,
    /// The attractor (index into `attractors`) that the paper's start reaches.
    pub paper_attractor: usize,
}

impl PointCoexistence {
    /// Whether the paper's start reaches a minority basin: its attractor takes less than half
    /// of the starts.
    pub fn paper_in_minority(&self) -> bool {
        2 * self.attractors[self.paper_attractor].count < self.starts
    }
}

/// Settings of a coexistence sweep.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CoexistenceOptions {
    /// The starts.
    pub starts: Starts,
    /// How each start is classified (the paper's 20,000-period limit by default; a map's 300
    /// Lyapunov periods).
    pub classify: ClassifyOptions,
    /// By recurrence (first round [`FIRST_ROUND`]) or in full.
    pub decision: Decision,
    /// The sensitivity test of the paper's start (`bistable map`'s by default).
    pub sensitivity: SensitivityOptions,
}

impl Default for CoexistenceOptions {
    fn default() -> Self {
        Self {
            starts: Starts::default(),
            classify: ClassifyOptions {
                lyapunov_periods: 300,
                ..ClassifyOptions::default()
            },
            decision: Decision::Recurrence(RecurrenceOptions {
                first_round: FIRST_ROUND,
                ..RecurrenceOptions::default()
            }),
            sensitivity: SensitivityOptions::default(),
        }
    }
}

/// Decides the starts of `options` at every `(Ω, V)` of `points` (with `model`'s damping,
/// restitution and solver), on `threads` threads of `width` lanes: each point is one task whose
/// rounds keep the lanes busy together with other points' runs. Each result goes with its
/// index to `done` on the calling thread as it completes (returning an error cancels; a point
/// that cannot be simulated gives an error). Each point's result depends only on the point and
/// `options`, never on threads, lanes or the other points. `options` must have been checked.
pub fn coexistence<E>(
    model: &Model,
    points: &[(f64, f64)],
    options: CoexistenceOptions,
    threads: Threads,
    width: Width,
    done: impl FnMut(usize, Result<PointCoexistence, SimError>) -> Result<(), E>,
) -> Result<(), E> {
    let starts: Arc<[(f64, f64)]> = options.starts.points().into();
    ensemble::run(
        points,
        threads,
        width,
        |&(w, v)| PointTask::new(model.at(w, v)?, Arc::clone(&starts), options),
        done,
    )
}

/// The runs of a point: its starts, watched for the known attractors, and plain
/// classification runs (probes, the paper's start and its sensitivity repeats).
#[derive(Clone)]
enum PointRun {
    Start(RecurrenceSpec),
    Plain(Run),
}

enum PointLane {
    Start(RecurrenceRun),
    Plain(ClassifyRun),
}

enum PointReached {
    Start(Reached),
    Plain(Classification),
}

impl LaneRun for PointLane {
    type Result = PointReached;

    fn target(&self) -> Instant {
        match self {
            PointLane::Start(r) => r.target(),
            PointLane::Plain(r) => r.target(),
        }
    }

    fn event(&mut self, e: &Event) {
        match self {
            PointLane::Start(r) => r.event(e),
            PointLane::Plain(r) => r.event(e),
        }
    }

    fn reached(&mut self, sim: &mut Simulator) -> Result<Option<PointReached>, SimError> {
        Ok(match self {
            PointLane::Start(r) => r.reached(sim)?.map(PointReached::Start),
            PointLane::Plain(r) => r.reached(sim)?.map(PointReached::Plain),
        })
    }
}

impl RunSpec for PointRun {
    type Lane = PointLane;

    fn setting(&self) -> (Params, SolverOptions) {
        match self {
            PointRun::Start(s) => s.setting(),
            PointRun::Plain(r) => r.setting(),
        }
    }

    fn begin(&self) -> Result<(PointLane, Simulator), SimError> {
        Ok(match self {
            PointRun::Start(s) => {
                let (r, sim) = s.begin()?;
                (PointLane::Start(r), sim)
            }
            PointRun::Plain(p) => {
                let (r, sim) = p.begin()?;
                (PointLane::Plain(r), sim)
            }
        })
    }
}

/// What a point's run was asked for.
enum Role {
    /// Start `i` of the box.
    Start(usize),
    /// Probe `n` of the plan.
    Probe(usize),
    /// Run `j` of the paper start's sensitivity test.
    Paper(usize),
}

/// One point: its starts in rounds, the table of known attractors, the probes of each round's
/// new periodic attractors.
struct PointTask {
    model: Model,
    starts: Arc<[(f64, f64)]>,
    co: ClassifyOptions,
    ro: RecurrenceOptions,
    recurrence: bool,
    known: Arc<Known>,
    rounds: Vec<(usize, usize)>,
    round: usize,
    roles: Vec<Role>,
    cells: Vec<Option<Cell>>,
    found: Vec<(usize, Cell, Vec<[f64; 2]>)>,
    probing: Option<(Known, ProbePlan)>,
    /// Round and probe runs not yet done.
    open: usize,
    /// The paper's start with `bistable map`'s sensitivity test, and its runs asked so far.
    paper: Option<PointTest>,
    paper_asked: usize,
}

impl PointTask {
    fn new(
        model: Model,
        starts: Arc<[(f64, f64)]>,
        options: CoexistenceOptions,
    ) -> Result<Self, SimError> {
        let (ro, recurrence) = match options.decision {
            Decision::Recurrence(ro) => (ro, true),
            Decision::Full => (RecurrenceOptions::default(), false),
        };
        let first = if recurrence {
            ro.first_round
        } else {
            starts.len()
        };
        Ok(Self {
            model,
            co: options.classify,
            ro,
            recurrence,
            known: Arc::new(Known::default()),
            rounds: rounds(first, starts.len()).collect(),
            round: 0,
            roles: Vec::new(),
            cells: vec![None; starts.len()],
            found: Vec::new(),
            probing: None,
            open: 0,
            paper: Some(PointTest::new(
                &model,
                options.classify,
                options.sensitivity,
            )),
            paper_asked: 0,
            starts,
        })
    }

    /// Runs of the paper start's test, numbered on.
    fn paper_runs(&mut self, runs: Vec<Run>) -> Vec<PointRun> {
        runs.into_iter()
            .map(|r| {
                self.roles.push(Role::Paper(self.paper_asked));
                self.paper_asked += 1;
                PointRun::Plain(r)
            })
            .collect()
    }

    /// The runs of round `self.round`.
    fn round_runs(&mut self) -> Result<Vec<PointRun>, SimError> {
        let Some(&(begin, end)) = self.rounds.get(self.round) else {
            return Ok(Vec::new());
        };
        let mut runs = Vec::with_capacity(end - begin);
        for i in begin..end {
            let spec = RecurrenceSpec::new(
                &self.model,
                0.0,
                self.co,
                self.starts[i],
                Arc::clone(&self.known),
                self.ro,
            )?;
            self.roles.push(Role::Start(i));
            runs.push(PointRun::Start(spec));
        }
        self.open = runs.len();
        Ok(runs)
    }

    /// The round is over: learns its attractors, probes them when that pays, or goes on.
    fn end_round(&mut self) -> Result<Vec<PointRun>, SimError> {
        let (_, end) = self.rounds[self.round];
        let mut found = std::mem::take(&mut self.found);
        found.sort_by_key(|f| f.0);
        let mut fresh =
            crate::recurrence::learn(&self.known, found.into_iter().map(|f| (f.1, f.2)));
        // Without recurrence nothing is probed.
        let left = if self.recurrence {
            self.starts.len() - end
        } else {
            0
        };
        let plan = ProbePlan::new(&self.model, &mut fresh.periodic, self.ro.directions, left);
        if self.recurrence && !plan.starts.is_empty() {
            let runs: Vec<PointRun> = plan
                .starts
                .iter()
                .map(|&(x0, v0)| {
                    crate::basins::CellTask::new(&self.model, 0.0, x0, v0, self.co)
                        .map(|t| PointRun::Plain(t.run()))
                })
                .collect::<Result<_, _>>()?;
            for n in 0..runs.len() {
                self.roles.push(Role::Probe(n));
            }
            self.open = runs.len();
            self.probing = Some((fresh, plan));
            return Ok(runs);
        }
        self.next_round(fresh)
    }

    fn next_round(&mut self, fresh: Known) -> Result<Vec<PointRun>, SimError> {
        let mut table = Known::clone(&self.known);
        table.extend(fresh);
        self.known = Arc::new(table);
        self.round += 1;
        self.round_runs()
    }
}

impl Task for PointTask {
    type Run = PointRun;
    type Output = PointCoexistence;

    fn start(&mut self) -> Result<Vec<PointRun>, SimError> {
        let first = self.paper.as_mut().expect("the test").start()?;
        let mut runs = self.paper_runs(first);
        runs.extend(self.round_runs()?);
        Ok(runs)
    }

    fn run_done(&mut self, i: usize, result: PointReached) -> Result<Vec<PointRun>, SimError> {
        match (&self.roles[i], result) {
            (&Role::Start(s), PointReached::Start(r)) => {
                let (cell, points) = reached_cell(self.starts[s], &self.known, r);
                if !points.is_empty() {
                    self.found.push((s, cell, points));
                }
                self.cells[s] = Some(cell);
            }
            (&Role::Paper(j), PointReached::Plain(c)) => {
                let more = self.paper.as_mut().expect("the test").run_done(j, c)?;
                return Ok(self.paper_runs(more));
            }
            (&Role::Probe(n), PointReached::Plain(c)) => {
                let (fresh, plan) = self.probing.as_mut().expect("probing");
                let (x0, v0) = plan.starts[n];
                let cell = crate::basins::cell_of(x0, v0, &c);
                plan.probed(&fresh.periodic, n, Ok(cell));
            }
            _ => unreachable!("a run's result is of the kind it was asked for"),
        }
        self.open -= 1;
        if self.open > 0 {
            return Ok(Vec::new());
        }
        match self.probing.take() {
            Some((mut fresh, plan)) => {
                plan.set_radii(&mut fresh.periodic);
                self.next_round(fresh)
            }
            None => self.end_round(),
        }
    }

    fn finish(self) -> PointCoexistence {
        let cells: Vec<Cell> = self
            .cells
            .into_iter()
            .map(|c| c.expect("decided"))
            .collect();
        let box_cells = &cells[..];
        let (c, sensitivity) = self.paper.expect("the test").finish();
        let paper = crate::basins::cell_of(0.0, 0.0, &c);
        let (found, index) = identify(box_cells);
        let mut attractors: Vec<Coexisting> = found
            .iter()
            .map(|a| Coexisting {
                steady: a.steady,
                anchor: a.anchor,
                count: a.cells,
                by_recurrence: 0,
                periods_simulated: 0.0,
            })
            .collect();
        for (c, &k) in box_cells.iter().zip(&index) {
            let a = &mut attractors[k];
            a.by_recurrence += usize::from(c.decided_by == DecidedBy::Recurrence);
            a.periods_simulated += c.periods_simulated;
            if a.anchor.is_none() {
                a.anchor = self.known.centroid_of(c);
            }
        }
        let paper_attractor = match crate::basins::attractor_of(&found, &paper) {
            Some(k) => k,
            None => {
                attractors.push(Coexisting {
                    steady: paper.steady(),
                    anchor: paper.anchor.or_else(|| self.known.centroid_of(&paper)),
                    count: 0,
                    by_recurrence: 0,
                    periods_simulated: 0.0,
                });
                attractors.len() - 1
            }
        };
        PointCoexistence {
            omega: self.model.omega(),
            velocity: self.model.velocity(),
            starts: box_cells.len(),
            attractors,
            paper,
            paper_sensitive: sensitivity.sensitive,
            paper_attractor,
        }
    }
}

/// The branch id of every attractor of every point (see the module docs): `points[ia + na·ib]`
/// is the point at the `ia`-th `Ω` and `ib`-th `V` of an `na × nb` grid (`None`: not computed;
/// it breaks the matching there). Returns, per point, the ids in the order of its attractors,
/// and the number of branches.
pub fn match_branches(
    na: usize,
    points: &[Option<&PointCoexistence>],
    max_distance: f64,
) -> (Vec<Vec<usize>>, usize) {
    let mut ids: Vec<Vec<usize>> = points
        .iter()
        .map(|p| vec![usize::MAX; p.map_or(0, |p| p.attractors.len())])
        .collect();
    let mut branches = 0;
    for k in 0..points.len() {
        let Some(p) = points[k] else { continue };
        let mut neighbours = Vec::new();
        if na > 0 && k % na > 0 {
            neighbours.push(k - 1);
        }
        if k >= na {
            neighbours.push(k - na);
        }
        // Candidate pairs (distance, attractor here, branch there).
        let mut pairs: Vec<(f64, usize, usize)> = Vec::new();
        for &n in &neighbours {
            let Some(q) = points[n] else { continue };
            for (a, here) in p.attractors.iter().enumerate() {
                for (b, there) in q.attractors.iter().enumerate() {
                    if here.steady != there.steady {
                        continue;
                    }
                    let d = match (here.anchor, there.anchor) {
                        _ if here.steady.at_rest => 0.0,
                        (Some(x), Some(y)) => (x[0] - y[0]).abs().max((x[1] - y[1]).abs()),
                        _ => continue,
                    };
                    if d <= max_distance {
                        pairs.push((d, a, ids[n][b]));
                    }
                }
            }
        }
        pairs.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)).then(x.2.cmp(&y.2)));
        let mut taken = Vec::new();
        for (_, a, branch) in pairs {
            if ids[k][a] == usize::MAX && !taken.contains(&branch) {
                ids[k][a] = branch;
                taken.push(branch);
            }
        }
        for id in ids[k].iter_mut().filter(|id| **id == usize::MAX) {
            *id = branches;
            branches += 1;
        }
    }
    (ids, branches)
}

/// Names of the columns of a coexistence table, one row per point and attractor: the CSV of
/// `bistable coexistence` and the DataFrame of the Python package (see [`row`]).
pub const COLUMNS: [&str; 29] = [
    "omega",
    "velocity",
    "zeta",
    "restitution",
    "box",
    "starts",
    "decision",
    "attractors",
    "attractor",
    "branch",
    "label",
    "class",
    "period",
    "chaotic",
    "final_well",
    "at_rest",
    "anchor_x",
    "anchor_v",
    "count",
    "fraction",
    "fraction_se",
    "decided_by_recurrence",
    "periods_simulated",
    "paper_start",
    "paper_class",
    "paper_period",
    "paper_chaotic",
    "paper_final_well",
    "paper_sensitive",
];

/// What every row of a table records of the sweep's settings (a resumed table must agree).
#[derive(Debug, Clone, PartialEq)]
pub struct TableSettings {
    /// Damping ratio.
    pub zeta: f64,
    /// Coefficient of restitution.
    pub restitution: f64,
    /// The box, `X0:X1;V0:V1`.
    pub start_box: String,
    /// The starts, `NXxNV` or `random:K:SEED`.
    pub starts: String,
    /// `recurrence` or `full`.
    pub decision: &'static str,
}

impl TableSettings {
    /// The settings of a sweep with `model`'s damping and restitution and `o`.
    pub fn new(model: &Model, o: &CoexistenceOptions) -> Self {
        let b = o.starts.bounds;
        Self {
            zeta: model.params.zeta(),
            restitution: model.restitution(),
            start_box: format!("{}:{};{}:{}", b.x[0], b.x[1], b.v[0], b.v[1]),
            starts: match o.starts.sampling {
                Sampling::Grid { nx, nv } => format!("{nx}x{nv}"),
                Sampling::Random { n, seed } => format!("random:{n}:{seed}"),
            },
            decision: match o.decision {
                Decision::Full => "full",
                Decision::Recurrence(_) => "recurrence",
            },
        }
    }
}

/// The class of an attractor's steady state: `rest` (rest in well 2), `continuous_interwell`
/// (it crosses the barrier) or `intrawell` (it stays in its final well; a start that reaches
/// it is intrawell or transient interwell by its transient).
pub fn steady_class(s: &Steady) -> &'static str {
    if s.at_rest {
        "rest"
    } else if s.across {
        ResponseClass::ContinuousInterwell.name()
    } else {
        ResponseClass::Intrawell.name()
    }
}

/// The values of the row of attractor `k` of `p`, in the order of [`COLUMNS`]: `branch` its
/// id from 0 (written from 1; `None` while not matched), `label` its [`Steady::label`].
/// Attractors are numbered from 1, largest basin first.
pub fn row<'a>(
    p: &PointCoexistence,
    k: usize,
    branch: Option<usize>,
    t: &'a TableSettings,
    label: &'a str,
) -> [Value<'a>; 29] {
    let a = &p.attractors[k];
    let st = &a.steady;
    let paper = &p.paper.outcome;
    let int = |v: Option<u64>| v.map_or(Value::Null, Value::I);
    [
        Value::F(p.omega),
        Value::F(p.velocity),
        Value::F(t.zeta),
        Value::F(t.restitution),
        Value::S(&t.start_box),
        Value::S(&t.starts),
        Value::S(t.decision),
        Value::I(p.attractors.len() as u64),
        Value::I(k as u64 + 1),
        int(branch.map(|b| b as u64 + 1)),
        Value::S(label),
        Value::S(steady_class(st)),
        int(st.period.map(u64::from)),
        Value::Bool(st.chaotic),
        int(st.well.map(|w| u64::from(w.number()))),
        Value::Bool(st.at_rest),
        a.anchor.map_or(Value::Null, |x| Value::F(x[0])),
        a.anchor.map_or(Value::Null, |x| Value::F(x[1])),
        Value::I(a.count as u64),
        Value::F(a.fraction(p.starts)),
        Value::F(a.standard_error(p.starts)),
        Value::I(a.by_recurrence as u64),
        Value::F(a.periods_simulated),
        Value::Bool(k == p.paper_attractor),
        Value::S(paper.class.name()),
        int(paper.period.map(u64::from)),
        Value::Bool(paper.chaotic),
        int(paper.final_well.map(|w| u64::from(w.number()))),
        Value::Bool(p.paper_sensitive),
    ]
}

/// Longest period whose orbit branches [`orbit_branches`] continues.
pub const MAX_BRANCH_PERIOD: u32 = 16;

/// The branches of periodic orbits along a line of points (`models[i]` the model of
/// `points[i]`): shot from the anchor of every periodic attractor found there (period at most
/// [`MAX_BRANCH_PERIOD`]) and continued along the line both ways ([`crate::branches::build`]),
/// so that unstable orbits between the stable ones are drawn too. One [`Branches`] per period
/// found, shortest first.
pub fn orbit_branches<E>(
    models: &[Model],
    points: &[&PointCoexistence],
    threads: Threads,
    progress: &mut OnProgress<'_, E>,
) -> Result<Vec<Branches>, E> {
    let mut seeds = Vec::new();
    for (i, p) in points.iter().enumerate() {
        for a in &p.attractors {
            if let (Some(period), Some(anchor), false) =
                (a.steady.period, a.anchor, a.steady.at_rest)
            {
                if period <= MAX_BRANCH_PERIOD {
                    seeds.push(Seed {
                        point: i,
                        period,
                        guess: (anchor[0], anchor[1]),
                    });
                }
            }
        }
    }
    let mut periods: Vec<u32> = seeds.iter().map(|s| s.period).collect();
    periods.sort_unstable();
    periods.dedup();
    crate::branches::build(models, &periods, &seeds, threads, progress)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sensitivity::Outcome;
    use bistable_core::{ResponseClass, Well};

    #[test]
    fn starts_fill_the_box_and_bad_boxes_are_named() {
        let s = Starts {
            bounds: StartBox {
                x: [0.0, 1.0],
                v: [-1.0, 1.0],
            },
            sampling: Sampling::Grid { nx: 3, nv: 2 },
        };
        let mut p = s.points();
        p.sort_by(|a, b| a.partial_cmp(b).unwrap());
        assert_eq!(
            p,
            vec![
                (0.0, -1.0),
                (0.0, 1.0),
                (0.5, -1.0),
                (0.5, 1.0),
                (1.0, -1.0),
                (1.0, 1.0)
            ]
        );
        let r = Starts {
            sampling: Sampling::Random { n: 1000, seed: 7 },
            ..s
        };
        let p = r.points();
        assert_eq!(p, r.points(), "seeded");
        assert!(p
            .iter()
            .all(|&(x, v)| (0.0..1.0).contains(&x) && (-1.0..1.0).contains(&v)));
        // Uniform: a quarter of the starts in each quadrant, within 5 standard errors.
        let q = p.iter().filter(|&&(x, v)| x < 0.5 && v < 0.0).count() as f64;
        assert!(
            (q - 250.0).abs() < 5.0 * (1000.0f64 * 0.25 * 0.75).sqrt(),
            "{q}"
        );
        let named = |b: StartBox, sampling| {
            Starts {
                bounds: b,
                sampling,
            }
            .check()
            .unwrap_err()
            .name
        };
        let g = Sampling::Grid { nx: 2, nv: 2 };
        let below = StartBox {
            x: [-0.1, 1.0],
            v: [0.0, 1.0],
        };
        assert_eq!(named(below, g), "start_box");
        let empty = StartBox {
            x: [0.5, 0.5],
            v: [0.0, 1.0],
        };
        assert_eq!(named(empty, g), "start_box");
        let ok = StartBox::default();
        assert_eq!(named(ok, Sampling::Grid { nx: 0, nv: 5 }), "starts");
        assert_eq!(named(ok, Sampling::Random { n: 0, seed: 1 }), "starts");
        assert_eq!(
            named(
                ok,
                Sampling::Random {
                    n: 1_000_001,
                    seed: 1
                }
            ),
            "starts"
        );
        assert!(Starts::default().check().is_ok());
    }

    fn attractor(period: Option<u32>, anchor: Option<[f64; 2]>, count: usize) -> Coexisting {
        Coexisting {
            steady: Steady {
                across: false,
                period,
                chaotic: false,
                well: Some(Well::One),
                at_rest: false,
            },
            anchor,
            count,
            by_recurrence: 0,
            periods_simulated: 0.0,
        }
    }

    fn point(attractors: Vec<Coexisting>) -> PointCoexistence {
        let paper = Cell {
            x0: 0.0,
            v0: 0.0,
            outcome: Outcome {
                class: ResponseClass::Intrawell,
                period: Some(1),
                chaotic: false,
                final_well: Some(Well::One),
            },
            anchor: None,
            at_rest: false,
            periods_simulated: 1.0,
            decided_by: DecidedBy::Full,
        };
        PointCoexistence {
            omega: 1.0,
            velocity: 0.1,
            starts: 10,
            attractors,
            paper,
            paper_sensitive: false,
            paper_attractor: 0,
        }
    }

    #[test]
    fn branches_follow_the_nearest_anchor_of_the_same_kind() {
        // 3 × 1 points along Ω: two P-1 orbits that swap basin ranks, and a P-2 that appears.
        let p0 = point(vec![
            attractor(Some(1), Some([0.1, 0.0]), 6),
            attractor(Some(1), Some([0.5, 0.0]), 4),
        ]);
        let p1 = point(vec![
            attractor(Some(1), Some([0.52, 0.0]), 7),
            attractor(Some(1), Some([0.12, 0.0]), 3),
        ]);
        let p2 = point(vec![
            attractor(Some(2), Some([0.52, 0.0]), 5),
            attractor(Some(1), Some([0.14, 0.0]), 5),
        ]);
        let pts = [Some(&p0), Some(&p1), Some(&p2)];
        let (ids, n) = match_branches(3, &pts, 0.2);
        assert_eq!(ids, vec![vec![0, 1], vec![1, 0], vec![2, 0]]);
        assert_eq!(n, 3);
        // Beyond the distance, or across a point not computed, a new branch starts.
        let (ids, n) = match_branches(3, &pts, 0.01);
        assert_eq!((ids[1].clone(), n), (vec![2, 3], 6));
        let (ids, _) = match_branches(3, &[Some(&p0), None, Some(&p2)], 0.2);
        assert_eq!(ids[2], vec![2, 3]);
        // On a 2 × 2 grid the point above matches its neighbour below too.
        let (ids, n) = match_branches(2, &[Some(&p0), Some(&p1), Some(&p1), Some(&p0)], 0.2);
        assert_eq!(ids, vec![vec![0, 1], vec![1, 0], vec![1, 0], vec![0, 1]]);
        assert_eq!(n, 2);
    }

    #[test]
    fn fractions_and_their_errors() {
        let a = attractor(Some(1), None, 25);
        assert_eq!(a.fraction(100), 0.25);
        assert!((a.standard_error(100) - (0.25f64 * 0.75 / 100.0).sqrt()).abs() < 1e-16);
        assert_eq!(attractor(Some(1), None, 0).standard_error(100), 0.0);
        let mut p = point(vec![a, attractor(Some(2), None, 75)]);
        p.starts = 100;
        assert!(p.paper_in_minority());
        p.paper_attractor = 1;
        assert!(!p.paper_in_minority());
    }
}
