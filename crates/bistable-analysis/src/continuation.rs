//! Branches of periodic orbits of one period continued in Ω at fixed V (the paper's Fig. 11a):
//! seeded from simulated attractors at every grid point, then followed by natural continuation
//! on the grid or by pseudo-arclength continuation through folds.

use std::num::NonZeroU32;

use bistable_core::{SimError, Width};

use crate::arclength::{self, ArcOptions, ArcPoint};
use crate::branches::{self, Branches};
use crate::cycles::steady_cycles_over;
use crate::parallel::Threads;
use crate::period::{detect_period, MAX_PERIOD, PERIOD_TOL};
use crate::progress::OnProgress;
use crate::seeds::{seeds_from, Seed};
use crate::Model;

/// Samples per shaker period of the seeding simulations (only their sections are used).
const SEED_SAMPLES: NonZeroU32 = NonZeroU32::new(16).expect("16 > 0");

/// How the orbits are followed in Ω.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Method {
    /// One Newton solve per grid point from the neighbour's orbit; stops at folds.
    Natural,
    /// Pseudo-arclength continuation in `(x, x', Ω)`; turns at folds.
    Arclength,
}

/// The continued orbits at one V.
#[derive(Debug, Clone)]
pub enum Curves {
    /// Natural continuation: the orbits at the grid points and their links.
    Natural(Branches),
    /// Pseudo-arclength traces, each a polyline of orbits.
    Arclength(Vec<Vec<ArcPoint>>),
}

/// Counts of the continued orbits at one V.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CurvesSummary {
    /// Orbits (natural: at the grid points; arclength: points of the traces).
    pub orbits: usize,
    /// The stable ones.
    pub stable: usize,
    /// Smallest and largest Ω with an orbit (`None` without orbits).
    pub omega_min: Option<f64>,
    /// See `omega_min`.
    pub omega_max: Option<f64>,
    /// Arclength only: the number of traces.
    pub traces: Option<usize>,
    /// Arclength only: turning points in Ω along the traces.
    pub folds: Option<usize>,
}

impl Curves {
    /// The counts of these curves, continued over the grid `omegas` (natural continuation:
    /// `omega_min`/`omega_max` are the first and last grid values with an orbit).
    pub fn summary(&self, omegas: &[f64]) -> CurvesSummary {
        match self {
            Curves::Natural(b) => {
                let covered: Vec<f64> = b
                    .slots
                    .iter()
                    .zip(omegas)
                    .filter(|(s, _)| !s.is_empty())
                    .map(|(_, &w)| w)
                    .collect();
                CurvesSummary {
                    orbits: b.len(),
                    stable: b.stable(),
                    omega_min: covered.first().copied(),
                    omega_max: covered.last().copied(),
                    traces: None,
                    folds: None,
                }
            }
            Curves::Arclength(traces) => {
                let pts = || traces.iter().flatten();
                CurvesSummary {
                    orbits: pts().count(),
                    stable: pts().filter(|p| p.stable).count(),
                    omega_min: pts().map(|p| p.omega).reduce(f64::min),
                    omega_max: pts().map(|p| p.omega).reduce(f64::max),
                    traces: Some(traces.len()),
                    folds: Some(traces.iter().map(|t| arclength::folds(t)).sum()),
                }
            }
        }
    }
}

/// Continues the `period`-periodic orbits over the grid `models` (one V, Ω evenly spaced,
/// non-empty). At every grid point the paper's initial condition runs `settle` shaker periods,
/// then `4·max(p, 16) + 8` are recorded; the recorded attractor seeds the orbit (itself, or if
/// its period is a multiple of `period`, the orbit it doubled from).
/// The seeding runs take `width` lanes per thread (the seeds are the same for every width).
pub fn continue_orbits<E: From<SimError>>(
    models: &[Model],
    period: u32,
    settle: u32,
    method: Method,
    threads: Threads,
    width: Width,
    progress: &mut OnProgress<'_, E>,
) -> Result<Curves, E> {
    let record = 4 * period.max(16) + 8;
    let seeds: Vec<Seed> = steady_cycles_over(
        models,
        settle,
        record,
        SEED_SAMPLES,
        threads,
        width,
        progress,
    )?
    .iter()
    .enumerate()
    .flat_map(|(i, c)| {
        let attractor = detect_period(&c.sections, MAX_PERIOD, PERIOD_TOL);
        seeds_from(i, &c.sections, attractor, &[period])
    })
    .collect();
    Ok(match method {
        Method::Natural => {
            let mut b = branches::build(models, &[period], &seeds, threads, progress)?;
            Curves::Natural(b.remove(0))
        }
        Method::Arclength => {
            let found = branches::solve_seeds(models, &seeds, threads, progress)?;
            let omegas: Vec<f64> = models.iter().map(Model::omega).collect();
            let o = ArcOptions::for_grid(period, &omegas);
            Curves::Arclength(arclength::traces(models, &found, o)?)
        }
    })
}
