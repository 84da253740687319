//! The steady state seen per shaker cycle: the largest displacement in each cycle, the phases
//! of the impacts, and the stroboscopic section points (plate phase 0), for bifurcation
//! diagrams, orbit seeds and orbit analysis.

use std::num::NonZeroU32;

use bistable_core::{Event, SimError, Simulator, Sinusoid};

use crate::parallel::{self, Threads};
use crate::progress::{OnProgress, Progress, Stage};
use crate::Model;

/// What [`record_cycles`] saw.
#[derive(Debug, Clone, Default)]
pub struct Cycles {
    /// Largest `x` in each shaker cycle (units of `Δx`).
    pub max_x: Vec<f64>,
    /// Impacts as `(cycle, phase in cycles ∈ [0, 1))`; cycles count from 0 at the first
    /// recorded one.
    pub impacts: Vec<(u32, f64)>,
    /// `(x, x')` at the start of each cycle and at the end of the last (one more than cycles).
    pub sections: Vec<(f64, f64)>,
}

/// Records `cycles` shaker cycles of `sim`, which must stand at the section instant
/// `plate.section(first)`. The maximum of `x` in a cycle comes from `samples`
/// dense-output samples per cycle, refined by the cubic Hermite interpolant of `(x, x')` on
/// each interval where `x'` changes sign from + to − with no impact in between (error
/// `O(h⁴)`). Samples sit at the same plate phases in every cycle, so a periodic response
/// repeats exactly.
pub fn record_cycles(
    sim: &mut Simulator,
    plate: Sinusoid,
    first: u64,
    cycles: u32,
    samples: NonZeroU32,
) -> Result<Cycles, SimError> {
    let samples = samples.get();
    let h = plate.period() / f64::from(samples);
    let mut out = Cycles::default();
    let st = sim.state();
    out.sections.push((st.x, st.v));
    let (mut x0, mut v0) = (st.x, st.v);
    for c in 0..cycles {
        let start = plate.section(first + u64::from(c));
        let mut best = x0;
        for j in 1..=samples {
            let target = if j == samples {
                plate.section(first + u64::from(c) + 1)
            } else {
                start + f64::from(j) * h
            };
            let mut kinks = false;
            sim.advance_instant(target, &mut |e: &Event| match e {
                Event::Impact(i) => {
                    kinks = true;
                    out.impacts.push((c, i.phase.unwrap_or(f64::NAN)));
                }
                Event::StickStart { .. } | Event::StickEnd { .. } => kinks = true,
                Event::SnapThrough { .. } => {}
            })?;
            let s = sim.state();
            best = best.max(s.x);
            if !kinks && v0 > 0.0 && s.v < 0.0 {
                best = best.max(hermite_max(x0, v0, s.x, s.v, h));
            }
            (x0, v0) = (s.x, s.v);
        }
        out.max_x.push(best);
        out.sections.push((x0, v0));
    }
    Ok(out)
}

/// The largest value of the cubic Hermite interpolant of `x(0) = x0, x'(0) = v0, x(h) = x1,
/// x'(h) = v1` (with `v0 > 0 > v1`) on `[0, h]`.
fn hermite_max(x0: f64, v0: f64, x1: f64, v1: f64, h: f64) -> f64 {
    // p(s) = a s³ + b s² + c s + d on s ∈ [0, 1].
    let c = h * v0;
    let b = 3.0 * (x1 - x0) - h * (2.0 * v0 + v1);
    let a = 2.0 * (x0 - x1) + h * (v0 + v1);
    let p = |s: f64| ((a * s + b) * s + c) * s + x0;
    // p'(s) = 3a s² + 2b s + c goes from c > 0 at 0 to h·v1 < 0 at 1: one root in between;
    // bisection is exact enough and never fails.
    let dp = |s: f64| (3.0 * a * s + 2.0 * b) * s + c;
    let (mut lo, mut hi) = (0.0, 1.0);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if dp(mid) > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    p(0.5 * (lo + hi)).max(x0).max(x1)
}

/// The simulator after `periods` shaker periods from the paper's initial condition, standing
/// at the section instant `model.shaker.section(periods)` (plate phase 0).
pub fn settled(model: &Model, periods: u32) -> Result<Simulator, SimError> {
    let mut sim = model.simulator()?;
    sim.advance_instant(
        model.shaker.section(u64::from(periods)),
        &mut |_: &Event| {},
    )?;
    Ok(sim)
}

/// Runs the paper's initial condition for `transient` shaker periods, then records `cycles`
/// with `samples` samples per cycle (see [`record_cycles`]).
pub fn steady_cycles(
    model: &Model,
    transient: u32,
    cycles: u32,
    samples: NonZeroU32,
) -> Result<Cycles, SimError> {
    let mut sim = settled(model, transient)?;
    record_cycles(
        &mut sim,
        model.shaker,
        u64::from(transient),
        cycles,
        samples,
    )
}

/// [`steady_cycles`] at every model (in parallel, on `threads`), in the order of `models`;
/// reports [`Stage::Simulating`] progress. The first simulation error stops the run.
pub fn steady_cycles_over<E: From<SimError>>(
    models: &[Model],
    transient: u32,
    cycles: u32,
    samples: NonZeroU32,
    threads: Threads,
    progress: &mut OnProgress<'_, E>,
) -> Result<Vec<Cycles>, E> {
    let total = models.len();
    let mut out: Vec<Option<Cycles>> = vec![None; total];
    let mut finished = 0;
    parallel::run(
        models,
        threads,
        |m| steady_cycles(m, transient, cycles, samples),
        |i, c| {
            out[i] = Some(c?);
            finished += 1;
            progress(Progress {
                stage: Stage::Simulating,
                done: finished,
                total,
            })
        },
    )?;
    Ok(out.into_iter().flatten().collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::period::distinct;
    use bistable_core::{Params, SolverOptions};

    #[test]
    fn hermite_max_is_exact_for_a_cubic() {
        // x(t) = 1 − (t − 0.3)²·(1 + t) on [0, 1]: maximum 1 at t = 0.3.
        let x = |t: f64| 1.0 - (t - 0.3) * (t - 0.3) * (1.0 + t);
        let v = |t: f64| -2.0 * (t - 0.3) * (1.0 + t) - (t - 0.3) * (t - 0.3);
        let m = hermite_max(x(0.0), v(0.0), x(1.0), v(1.0), 1.0);
        assert!((m - 1.0).abs() < 1e-14, "{m}");
    }

    #[test]
    fn max_per_cycle_of_a_period_one_response_repeats() {
        let model = Model::new(
            Params::new(0.02, 0.85).unwrap(),
            Sinusoid::new(1.75, 0.07).unwrap(),
            SolverOptions::default(),
        );
        let n = |k| NonZeroU32::new(k).unwrap();
        let c = steady_cycles(&model, 600, 6, n(128)).unwrap();
        assert_eq!(c.max_x.len(), 6);
        assert_eq!(c.sections.len(), 7);
        assert_eq!(distinct(&c.max_x, 1e-9), 1, "{:?}", c.max_x);
        // One impact per cycle, at the same phase.
        assert_eq!(c.impacts.len(), 6);
        assert_eq!(
            distinct(&c.impacts.iter().map(|i| i.1).collect::<Vec<_>>(), 1e-9),
            1
        );
        // The refined maximum beats the plain samples by a little, never by much.
        let coarse = steady_cycles(&model, 600, 1, n(16)).unwrap().max_x[0];
        assert!(c.max_x[0] >= coarse - 1e-9 && c.max_x[0] - coarse < 1e-3);
        assert!(
            (coarse - c.max_x[0]).abs() < 1e-6,
            "{coarse} vs {}",
            c.max_x[0]
        );
    }
}
