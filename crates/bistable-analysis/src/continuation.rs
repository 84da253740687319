//! Branches of periodic orbits of one period continued in Ω at fixed V (the paper's Fig. 11a):
//! seeded from simulated attractors at every grid point, then followed by natural continuation
//! on the grid or by pseudo-arclength continuation through folds.

use std::num::NonZeroU32;

use bistable_core::SimError;

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

/// Continues the `period`-periodic orbits over the grid `models` (one V, Ω evenly spaced,
/// non-empty). At every grid point the paper's initial condition runs `settle` shaker periods,
/// then `4·max(p, 16) + 8` are recorded; the recorded attractor seeds the orbit (itself, or if
/// its period is a multiple of `period`, the orbit it doubled from).
pub fn continue_orbits<E: From<SimError>>(
    models: &[Model],
    period: u32,
    settle: u32,
    method: Method,
    threads: Threads,
    progress: &mut OnProgress<'_, E>,
) -> Result<Curves, E> {
    let record = 4 * period.max(16) + 8;
    let seeds: Vec<Seed> =
        steady_cycles_over(models, settle, record, SEED_SAMPLES, threads, progress)?
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
