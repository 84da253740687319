//! Bifurcation data (the paper's Fig. 6/8): along a grid of models (one control parameter
//! varied), the recorded steady state of each point, its period, and the branches of periodic
//! orbits seeded from the attractors and continued along the grid.

use std::num::NonZeroU32;

use bistable_core::{SimError, Width};

use crate::branches::{self, Branches};
use crate::cycles::{steady_cycles_over, Cycles};
use crate::parallel::Threads;
use crate::period::{detect_period, distinct, MAX_PERIOD, PERIOD_TOL};
use crate::progress::OnProgress;
use crate::seeds::{seeds_from, Seed};
use crate::Model;

/// What to record at each point.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BifurcationOptions {
    /// Shaker periods skipped as transient.
    pub transient: u32,
    /// Shaker periods recorded after the transient.
    pub record: u32,
    /// Dense-output samples per shaker period for the maximum of `x`.
    pub samples: NonZeroU32,
    /// Periods (shaker periods) of the orbit branches to find; empty: no branches.
    pub branch_periods: Vec<u32>,
    /// Trajectories per thread in SIMD lanes for the recorded runs (the data is the same for
    /// every width).
    pub width: Width,
}

/// The bifurcation data along a grid.
#[derive(Debug, Clone)]
pub struct Bifurcation {
    /// The recorded steady state at each grid point.
    pub points: Vec<Cycles>,
    /// The period of each point's steady state in shaker periods (`None`: none up to 16).
    pub periods: Vec<Option<usize>>,
    /// One entry per branch period, in the order of `branch_periods`.
    pub branches: Vec<Branches>,
}

/// What is reported about one point of the grid.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointSummary {
    /// Ω of the point.
    pub omega: f64,
    /// V of the point.
    pub velocity: f64,
    /// Period of the recorded response in shaker periods (`None`: none up to 16).
    pub period: Option<usize>,
    /// Distinct values of max x over the recorded cycles (to [`DISTINCT_TOL`]).
    pub distinct_max_x: usize,
    /// Impacts per recorded shaker period.
    pub impacts_per_cycle: f64,
}

/// Two per-cycle maxima closer than this count as one value in [`PointSummary`].
pub const DISTINCT_TOL: f64 = 1e-6;

impl Bifurcation {
    /// The summary of every point, for the grid `models` the data was computed on with
    /// `record` recorded shaker periods.
    pub fn point_summaries(&self, models: &[Model], record: u32) -> Vec<PointSummary> {
        models
            .iter()
            .zip(&self.points)
            .zip(&self.periods)
            .map(|((m, c), &period)| PointSummary {
                omega: m.omega(),
                velocity: m.velocity(),
                period,
                distinct_max_x: distinct(&c.max_x, DISTINCT_TOL),
                impacts_per_cycle: c.impacts.len() as f64 / f64::from(record),
            })
            .collect()
    }
}

/// Records every point of `models` (in parallel, `o.width` runs per thread in SIMD lanes), detects the periods, then seeds and
/// continues the orbit branches.
pub fn compute<E: From<SimError>>(
    models: &[Model],
    o: &BifurcationOptions,
    threads: Threads,
    progress: &mut OnProgress<'_, E>,
) -> Result<Bifurcation, E> {
    let points = steady_cycles_over(
        models,
        o.transient,
        o.record,
        o.samples,
        threads,
        o.width,
        progress,
    )?;
    let periods: Vec<Option<usize>> = points
        .iter()
        .map(|c| detect_period(&c.sections, MAX_PERIOD, PERIOD_TOL))
        .collect();
    let branches = if o.branch_periods.is_empty() {
        Vec::new()
    } else {
        let seeds: Vec<Seed> = points
            .iter()
            .zip(&periods)
            .enumerate()
            .flat_map(|(i, (c, &p))| seeds_from(i, &c.sections, p, &o.branch_periods))
            .collect();
        branches::build(models, &o.branch_periods, &seeds, threads, progress)?
    };
    Ok(Bifurcation {
        points,
        periods,
        branches,
    })
}
