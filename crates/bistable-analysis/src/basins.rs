//! Basins of attraction over a grid of initial states `(x0, x0')` at a given plate phase, for
//! one shaker point `(Ω, V)`: every cell is classified from its own start (the core's
//! [`bistable_core::classify_from`]), cells that reach the same attractor are grouped and the
//! attractors numbered by basin size, and the fractal character of the basin boundaries is
//! measured by the uncertainty exponent of Grebogi, McDonald, Ott and Yorke (1983).
//!
//! An attractor is identified by what the steady state is — rest in well 2, a periodic orbit
//! of period `p` in one well or across the barrier, chaotic or aperiodic motion in one well or
//! across — and, when periodic, by its cycle's section point with the smallest `x`
//! ([`bistable_core::Classification::cycle_anchor`]): coexisting orbits of the same period
//! (e.g. low- and high-energy P-1 in well 1) are told apart by it. Whether the transient
//! crossed the barrier (intrawell against transient interwell) is not part of the attractor;
//! each cell keeps its class.
//!
//! Uncertainty exponent: a start is *ε-uncertain* when the start displaced by `±ε` in `x0`
//! reaches another attractor. The fraction `f(ε)` of uncertain starts among sampled cells
//! scales like `ε^α` for small `ε`; `α` is fitted by least squares on `ln f` against `ln ε`,
//! and `2 − α` is the box-counting dimension of the basin boundary in the `(x0, x0')` plane
//! (`α = 1`: smooth boundaries; `α < 1`: fractal).
//!
//! How each start is decided ([`Decision`]): in full (every start runs until the period
//! repeats, the mass rests in well 2 or the run reaches its limit), or by recurrence
//! ([`crate::recurrence`]: a start stops once it is known to be on a periodic attractor
//! already found at this point; the default of `bistable basins`).

use bistable_core::{
    Classification, ClassifyOptions, ParamError, ResponseClass, SimError, Sinusoid, Tracking, Well,
    Width,
};

use crate::ensemble::{self, run_alone, Run, Task};
use crate::parallel::Threads;
use crate::recurrence::{self, Known, RecurrenceOptions};
use crate::sensitivity::Outcome;
use crate::Model;

/// Where the plate is at the start (`τ = 0`) of every cell: phase in cycles.
pub fn plate_at(model: &Model, phase: f64) -> Result<(f64, f64), ParamError> {
    let s = shaker_at(model, phase)?;
    let a = s.angle(bistable_core::Instant::new(0.0));
    Ok((
        model.velocity() / model.omega() * a.sin(),
        model.velocity() * a.cos(),
    ))
}

fn shaker_at(model: &Model, phase: f64) -> Result<Sinusoid, ParamError> {
    if !(phase.is_finite() && (0.0..1.0).contains(&phase)) {
        return Err(ParamError {
            name: "phase",
            value: phase,
            rule: "must be in [0, 1) (cycles)",
        });
    }
    Sinusoid::new(model.omega(), model.velocity())?.with_origin(
        bistable_core::Instant::new(0.0),
        std::f64::consts::TAU * phase,
        0.0,
    )
}

/// What one start reaches.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cell {
    /// Start position.
    pub x0: f64,
    /// Start velocity.
    pub v0: f64,
    /// The outcome.
    pub outcome: Outcome,
    /// Cycle anchor of a periodic outcome (see the module docs); `None` at rest.
    pub anchor: Option<[f64; 2]>,
    /// At rest in well 2.
    pub at_rest: bool,
    /// Natural periods simulated.
    pub periods_simulated: f64,
    /// How the outcome was decided.
    pub decided_by: DecidedBy,
}

/// How a cell's outcome was decided.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum DecidedBy {
    /// The full decision of its own run ([`bistable_core::classify_from`]).
    Full,
    /// Captured by a known periodic attractor ([`crate::recurrence`]).
    Recurrence,
}

impl DecidedBy {
    /// `full` or `recurrence`.
    pub fn name(self) -> &'static str {
        match self {
            DecidedBy::Full => "full",
            DecidedBy::Recurrence => "recurrence",
        }
    }
}

/// How the starts of a grid are decided.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Decision {
    /// Every start runs to the full decision.
    Full,
    /// By recurrence onto the periodic attractors found so far ([`crate::recurrence`]).
    Recurrence(RecurrenceOptions),
}

impl Cell {
    /// The steady state, without the transient's class: `(continuous interwell, period,
    /// chaotic, final well (None when continuous), at rest)`.
    pub fn steady(&self) -> Steady {
        let o = &self.outcome;
        Steady {
            across: o.class == ResponseClass::ContinuousInterwell,
            period: o.period,
            chaotic: o.chaotic,
            well: o.final_well,
            at_rest: self.at_rest,
        }
    }
}

/// A steady state (the part of an outcome that belongs to the attractor).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Steady {
    /// The orbit crosses the barrier (continuous interwell).
    pub across: bool,
    /// Period in shaker periods (`None`: aperiodic).
    pub period: Option<u32>,
    /// Chaotic.
    pub chaotic: bool,
    /// The well it stays in (`None` when `across`).
    pub well: Option<Well>,
    /// At rest in well 2.
    pub at_rest: bool,
}

impl Steady {
    /// E.g. `P-1 in well 1`, `rest in well 2`, `chaotic across the barrier`.
    pub fn label(&self) -> String {
        if self.at_rest {
            return "rest in well 2".into();
        }
        let kind = crate::period::label(self.period, self.chaotic);
        match self.well {
            Some(w) if !self.across => format!("{kind} in well {}", w.number()),
            _ => format!("{kind} across the barrier"),
        }
    }
}

/// Classifies the start `(x0, x0')` at plate phase `phase` (cycles).
pub fn basin_cell(
    model: &Model,
    phase: f64,
    x0: f64,
    v0: f64,
    co: ClassifyOptions,
) -> Result<Cell, SimError> {
    run_alone(CellTask::new(model, phase, x0, v0, co)?)
}

/// A basin cell as a [`Task`]: one classification run from its start.
pub(crate) struct CellTask {
    run: Run,
    result: Option<Classification>,
}

impl CellTask {
    pub(crate) fn new(
        model: &Model,
        phase: f64,
        x0: f64,
        v0: f64,
        co: ClassifyOptions,
    ) -> Result<Self, SimError> {
        Ok(Self {
            run: Run {
                params: model.params,
                plate: shaker_at(model, phase)?,
                opts: model.opts,
                co,
                start: (x0, v0),
                track: Tracking::default(),
            },
            result: None,
        })
    }

    /// The cell's run.
    pub(crate) fn run(&self) -> Run {
        self.run
    }
}

impl Task for CellTask {
    type Run = Run;
    type Output = Cell;

    fn start(&mut self) -> Result<Vec<Run>, SimError> {
        Ok(vec![self.run])
    }

    fn run_done(&mut self, _: usize, result: Classification) -> Result<Vec<Run>, SimError> {
        self.result = Some(result);
        Ok(Vec::new())
    }

    fn finish(self) -> Cell {
        let c = self.result.expect("the cell's run is done");
        let (x0, v0) = self.run.start;
        cell_of(x0, v0, &c)
    }
}

/// The cell of the start `(x0, x0')` whose run gave `c` (decided in full).
pub(crate) fn cell_of(x0: f64, v0: f64, c: &Classification) -> Cell {
    Cell {
        x0,
        v0,
        outcome: Outcome::of(c),
        anchor: if c.at_rest_in_second_well {
            None
        } else {
            c.cycle_anchor
        },
        at_rest: c.at_rest_in_second_well,
        periods_simulated: c.periods_simulated,
        decided_by: DecidedBy::Full,
    }
}

/// Relative tolerance within which two cycle anchors are the same orbit.
pub const ANCHOR_TOL: f64 = 1e-5;

/// An attractor found in a basin grid.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Attractor {
    /// Its steady state.
    pub steady: Steady,
    /// Cycle anchor (periodic outcomes).
    pub anchor: Option<[f64; 2]>,
    /// Cells in its basin.
    pub cells: usize,
}

impl Attractor {
    fn matches(&self, c: &Cell) -> bool {
        same_attractor(&self.steady, self.anchor, c)
    }
}

/// Whether `c` reached the attractor of steady state `steady` and cycle anchor `anchor`: the
/// same steady state and anchors within [`ANCHOR_TOL`] (relative to `max(1, |anchor|)`).
pub(crate) fn same_attractor(steady: &Steady, anchor: Option<[f64; 2]>, c: &Cell) -> bool {
    *steady == c.steady()
        && match (anchor, c.anchor) {
            (Some(a), Some(b)) => {
                let d = (a[0] - b[0]).abs().max((a[1] - b[1]).abs());
                d <= ANCHOR_TOL * a[0].abs().max(a[1].abs()).max(1.0)
            }
            (None, None) => true,
            _ => false,
        }
}

/// The attractors reached by `cells`, largest basin first (ties: first reached), and each
/// cell's attractor index into that list.
pub fn identify(cells: &[Cell]) -> (Vec<Attractor>, Vec<usize>) {
    let mut found: Vec<Attractor> = Vec::new();
    let mut raw = Vec::with_capacity(cells.len());
    for c in cells {
        let i = match found.iter().position(|a| a.matches(c)) {
            Some(i) => i,
            None => {
                found.push(Attractor {
                    steady: c.steady(),
                    anchor: c.anchor,
                    cells: 0,
                });
                found.len() - 1
            }
        };
        found[i].cells += 1;
        raw.push(i);
    }
    let mut order: Vec<usize> = (0..found.len()).collect();
    order.sort_by_key(|&i| std::cmp::Reverse(found[i].cells));
    let mut rank = vec![0; found.len()];
    for (r, &i) in order.iter().enumerate() {
        rank[i] = r;
    }
    let attractors = order.iter().map(|&i| found[i]).collect();
    (attractors, raw.into_iter().map(|i| rank[i]).collect())
}

/// The attractor of `cell` in `attractors`, if it is one of them.
pub fn attractor_of(attractors: &[Attractor], cell: &Cell) -> Option<usize> {
    attractors.iter().position(|a| a.matches(cell))
}

/// One point of the uncertainty-exponent measurement.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Uncertain {
    /// Displacement `ε` of the start in `x0`.
    pub epsilon: f64,
    /// Sampled starts.
    pub samples: usize,
    /// Starts whose `±ε` neighbours reach another attractor.
    pub uncertain: usize,
}

impl Uncertain {
    /// `uncertain / samples`.
    pub fn fraction(&self) -> f64 {
        self.uncertain as f64 / self.samples.max(1) as f64
    }
}

/// Displacements `ε` of the uncertainty measurement for a grid of `n` start positions from
/// `x_first` to `x_last`: their mean spacing (for a single position, 1 % of `max(|x0|, 1)`)
/// and that divided by 4, 16, 64 and 256.
pub fn uncertainty_epsilons(x_first: f64, x_last: f64, n: usize) -> Vec<f64> {
    let step = if n > 1 {
        ((x_last - x_first) / (n - 1) as f64).abs()
    } else {
        1e-2 * x_first.abs().max(1.0)
    };
    (0..5).map(|j| step / 4f64.powi(j)).collect()
}

/// `n` of the grid's `cells` (in grid order, with their attractor `index`), spread over the
/// whole grid, for the uncertainty measurement.
pub fn uncertainty_samples(cells: &[Cell], index: &[usize], n: usize) -> Vec<(Cell, usize)> {
    crate::sweep::interleaved(cells.len())
        .take(n.min(cells.len()))
        .map(|i| (cells[i], index[i]))
        .collect()
}

/// The neighbour starts of the measurement, `(ε index, sample index, x0)`: each sample's `x0`
/// displaced by `+ε`, and by `−ε` unless that is below the plate (at `plate_x`); the velocity
/// is the sample's.
pub fn uncertainty_starts(
    samples: &[(Cell, usize)],
    epsilons: &[f64],
    plate_x: f64,
) -> Vec<(usize, usize, f64)> {
    let mut starts = Vec::new();
    for (k, &eps) in epsilons.iter().enumerate() {
        for (i, (c, _)) in samples.iter().enumerate() {
            starts.push((k, i, c.x0 + eps));
            if c.x0 - eps >= plate_x {
                starts.push((k, i, c.x0 - eps));
            }
        }
    }
    starts
}

/// The uncertainty fraction at each `ε` from the cells the neighbour `starts` reached (in the
/// order of `starts`): a sample is uncertain when a neighbour reaches another attractor.
/// Without samples, none (nothing was measured).
pub fn count_uncertain(
    attractors: &[Attractor],
    samples: &[(Cell, usize)],
    epsilons: &[f64],
    starts: &[(usize, usize, f64)],
    reached: &[Cell],
) -> Vec<Uncertain> {
    if samples.is_empty() {
        return Vec::new();
    }
    let mut uncertain = vec![vec![false; samples.len()]; epsilons.len()];
    for (&(k, i, _), cell) in starts.iter().zip(reached) {
        if attractor_of(attractors, cell) != Some(samples[i].1) {
            uncertain[k][i] = true;
        }
    }
    epsilons
        .iter()
        .zip(uncertain)
        .map(|(&epsilon, u)| Uncertain {
            epsilon,
            samples: samples.len(),
            uncertain: u.iter().filter(|&&b| b).count(),
        })
        .collect()
}

/// The uncertainty fraction at each `epsilon` over the sampled cells (each with its attractor
/// index), classifying the neighbour starts ([`uncertainty_starts`]) on `threads` threads of
/// `width` lanes, `progress(done, total)` after each (returning an error cancels).
#[allow(clippy::too_many_arguments)]
pub fn uncertainty<E>(
    model: &Model,
    phase: f64,
    co: ClassifyOptions,
    attractors: &[Attractor],
    samples: &[(Cell, usize)],
    epsilons: &[f64],
    plate_x: f64,
    threads: Threads,
    width: Width,
    mut progress: impl FnMut(usize, usize) -> Result<(), E>,
) -> Result<Result<Vec<Uncertain>, SimError>, E> {
    let starts = uncertainty_starts(samples, epsilons, plate_x);
    let total = starts.len();
    let mut results: Vec<Option<Result<Cell, SimError>>> = vec![None; total];
    let mut finished = 0;
    ensemble::run(
        &starts,
        threads,
        width,
        |&(_, i, x0)| CellTask::new(model, phase, x0, samples[i].0.v0, co),
        |k, r| {
            results[k] = Some(r);
            finished += 1;
            progress(finished, total)
        },
    )?;
    let reached: Result<Vec<Cell>, SimError> = results.into_iter().flatten().collect();
    Ok(reached.map(|r| count_uncertain(attractors, samples, epsilons, &starts, &r)))
}

/// Least-squares slope of `ln f` against `ln ε` over the points with `f > 0` (the uncertainty
/// exponent `α`), `None` with fewer than two such points.
pub fn uncertainty_exponent(points: &[Uncertain]) -> Option<f64> {
    let xy: Vec<(f64, f64)> = points
        .iter()
        .filter(|p| p.uncertain > 0)
        .map(|p| (p.epsilon.ln(), p.fraction().ln()))
        .collect();
    if xy.len() < 2 {
        return None;
    }
    let n = xy.len() as f64;
    let (mx, my) = (
        xy.iter().map(|p| p.0).sum::<f64>() / n,
        xy.iter().map(|p| p.1).sum::<f64>() / n,
    );
    let sxx: f64 = xy.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = xy.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    (sxx > 0.0).then(|| sxy / sxx)
}

/// Classifies every start of `starts` as `decision` says, on `threads` threads of `width`
/// lanes ([`ensemble::run`]; the cells are the same for every width and number of threads);
/// each result goes with its index to `done` on the calling thread as it completes (returning
/// an error cancels). Returns the known attractors of a recurrence decision
/// ([`recurrence::classify_starts`]; none for [`Decision::Full`]). By recurrence the starts
/// are taken in rounds in the order given: give them in an order that spreads over the grid
/// early ([`crate::sweep::interleaved`]), so that the first round finds the attractors.
#[allow(clippy::too_many_arguments)]
pub fn classify_starts<E>(
    model: &Model,
    phase: f64,
    co: ClassifyOptions,
    decision: Decision,
    starts: &[(f64, f64)],
    threads: Threads,
    width: Width,
    done: impl FnMut(usize, Result<Cell, SimError>) -> Result<(), E>,
) -> Result<Known, E> {
    match decision {
        Decision::Full => ensemble::run(
            starts,
            threads,
            width,
            |&(x0, v0)| CellTask::new(model, phase, x0, v0, co),
            done,
        )
        .map(|()| Known::default()),
        Decision::Recurrence(ro) => {
            recurrence::classify_starts(model, phase, co, ro, starts, threads, width, done)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use bistable_core::{Params, SolverOptions};

    fn model(w: f64, v: f64) -> Model {
        Model::new(
            Params::paper(),
            Sinusoid::new(w, v).unwrap(),
            SolverOptions::default(),
        )
    }

    #[test]
    fn the_paper_start_reaches_the_paper_outcome() {
        // From (0, 0) at phase 0 the cell is the paper's initial condition.
        let m = model(0.85, 0.11);
        let c = basin_cell(&m, 0.0, 0.0, 0.0, ClassifyOptions::default()).unwrap();
        assert_eq!(c.outcome.class, ResponseClass::Intrawell);
        assert_eq!(c.outcome.period, Some(4));
        let r = bistable_core::classify(m.params, m.shaker, m.opts, ClassifyOptions::default())
            .unwrap();
        assert_eq!(c.anchor, r.cycle_anchor);
        assert_eq!(c.periods_simulated, r.periods_simulated);
    }

    #[test]
    fn starts_below_the_plate_and_bad_phases_are_refused() {
        let m = model(1.45, 0.05);
        let (z, zd) = plate_at(&m, 0.25).unwrap();
        // At a quarter cycle the plate is at its top, V/Ω, at rest.
        assert!(
            (z - 0.05 / 1.45).abs() < 1e-15 && zd.abs() < 1e-15,
            "{z} {zd}"
        );
        let e = basin_cell(&m, 0.25, z - 1e-3, 0.0, ClassifyOptions::default()).unwrap_err();
        assert!(e.to_string().contains("x0"), "{e}");
        assert!(plate_at(&m, 1.0).is_err() && plate_at(&m, f64::NAN).is_err());
    }

    #[test]
    fn uncertainty_plan_follows_the_grid_and_the_plate() {
        let e = uncertainty_epsilons(0.0, 1.2, 10);
        assert_eq!(e.len(), 5);
        for (j, &x) in e.iter().enumerate() {
            assert!(
                (x - 1.2 / 9.0 / 4f64.powi(j as i32)).abs() < 1e-16,
                "{j}: {x}"
            );
        }
        assert_eq!(uncertainty_epsilons(1.2, 0.0, 10), e);
        assert_eq!(uncertainty_epsilons(-3.0, -3.0, 1)[0], 0.03);
        assert_eq!(uncertainty_epsilons(0.5, 0.5, 1)[0], 0.01);
        let cell = |x0: f64| Cell {
            x0,
            v0: 0.25,
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
        let samples = [(cell(0.0), 0), (cell(0.5), 1)];
        // At x0 = 0 on a plate at 0 only x0 + ε; at 0.5 both.
        let s = uncertainty_starts(&samples, &[0.1, 0.01], 0.0);
        assert_eq!(
            s,
            vec![
                (0, 0, 0.1),
                (0, 1, 0.6),
                (0, 1, 0.4),
                (1, 0, 0.01),
                (1, 1, 0.51),
                (1, 1, 0.49)
            ]
        );
        let (attractors, _) = identify(&[cell(0.0), cell(0.5)]);
        let mut other = cell(0.4);
        other.at_rest = true;
        let reached = [
            cell(0.1),
            cell(0.6),
            other,
            cell(0.01),
            cell(0.51),
            cell(0.49),
        ];
        let idx = [(samples[0].0, 0), (samples[1].0, 0)];
        let u = count_uncertain(&attractors, &idx, &[0.1, 0.01], &s, &reached);
        assert_eq!((u[0].uncertain, u[1].uncertain, u[0].samples), (1, 0, 2));
        assert!(count_uncertain(&attractors, &[], &[0.1], &[], &[]).is_empty());
    }

    #[test]
    fn exponent_of_a_power_law() {
        let pts: Vec<Uncertain> = [1e-2, 1e-3, 1e-4]
            .iter()
            .map(|&e: &f64| Uncertain {
                epsilon: e,
                samples: 1_000_000,
                uncertain: (1_000_000.0 * 3.0 * e.powf(0.4)).round() as usize,
            })
            .collect();
        let a = uncertainty_exponent(&pts).unwrap();
        assert!((a - 0.4).abs() < 1e-4, "{a}");
        assert_eq!(uncertainty_exponent(&pts[..1]), None);
    }
}
