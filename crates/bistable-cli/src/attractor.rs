//! The steady state seen per shaker cycle: the largest displacement in each cycle, the phases
//! of the impacts, and the stroboscopic section points (plate phase 0), for bifurcation
//! diagrams, orbit seeds and spectra.

use bistable_core::{Event, Simulator, Sinusoid};

use crate::common::Model;
use crate::error::CliError;

/// What [`record_cycles`] saw.
#[derive(Debug, Clone, Default)]
pub struct Cycles {
    /// Largest `x` in each shaker cycle.
    pub max_x: Vec<f64>,
    /// Impacts as `(cycle, phase in cycles)`.
    pub impacts: Vec<(u32, f64)>,
    /// `(x, x')` at the start of each cycle and at the end of the last (one more than cycles).
    pub sections: Vec<(f64, f64)>,
}

/// Records `cycles` shaker cycles of `sim`, which must stand at the section instant
/// `plate.section(first)`. The maximum of `x` in a cycle comes from `samples` dense-output
/// samples per cycle, refined by the cubic Hermite interpolant of `(x, x')` on each interval
/// where `x'` changes sign from + to − with no impact in between (error `O(h⁴)`). Samples sit
/// at the same plate phases in every cycle, so a periodic response repeats exactly.
pub fn record_cycles(
    sim: &mut Simulator,
    plate: Sinusoid,
    first: u64,
    cycles: u32,
    samples: u32,
) -> Result<Cycles, CliError> {
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

/// Runs the paper's initial condition for `transient` shaker periods, then records `cycles`.
pub fn steady_cycles(
    model: &Model,
    transient: u32,
    cycles: u32,
    samples: u32,
) -> Result<Cycles, CliError> {
    let mut sim = model.simulator()?;
    sim.advance_instant(
        model.shaker.section(u64::from(transient)),
        &mut |_: &Event| {},
    )?;
    record_cycles(
        &mut sim,
        model.shaker,
        u64::from(transient),
        cycles,
        samples,
    )
}

/// Smallest `p <= max_p` with which the last `2p + 4` section points repeat to `tol`
/// (relative to `max(1, |y|)`); `None` if there is none.
pub fn detect_period(sections: &[(f64, f64)], max_p: usize, tol: f64) -> Option<usize> {
    let n = sections.len();
    (1..=max_p).find(|&p| {
        let need = 3 * p + 4;
        n >= need
            && (n - (2 * p + 4)..n).all(|i| {
                let (a, b) = (sections[i], sections[i - p]);
                let scale = a.0.abs().max(a.1.abs()).max(1.0);
                (a.0 - b.0).abs().max((a.1 - b.1).abs()) <= tol * scale
            })
    })
}

/// Number of distinct values, counting values within `tol·max(1, |x|)` of their sorted
/// neighbour as one.
pub fn distinct(values: &[f64], tol: f64) -> usize {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    v.sort_by(f64::total_cmp);
    v.windows(2)
        .filter(|w| w[1] - w[0] > tol * w[1].abs().max(1.0))
        .count()
        + usize::from(!v.is_empty())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hermite_max_is_exact_for_a_cubic() {
        // x(t) = 1 − (t − 0.3)²·(1 + t) on [0, 1]: maximum 1 at t = 0.3.
        let x = |t: f64| 1.0 - (t - 0.3) * (t - 0.3) * (1.0 + t);
        let v = |t: f64| -2.0 * (t - 0.3) * (1.0 + t) - (t - 0.3) * (t - 0.3);
        let m = hermite_max(x(0.0), v(0.0), x(1.0), v(1.0), 1.0);
        assert!((m - 1.0).abs() < 1e-14, "{m}");
    }

    #[test]
    fn periods_and_distinct_values() {
        let p2: Vec<(f64, f64)> = (0..40)
            .map(|i| if i % 2 == 0 { (0.1, 0.2) } else { (0.3, -0.1) })
            .collect();
        assert_eq!(detect_period(&p2, 16, 1e-9), Some(2));
        let drift: Vec<(f64, f64)> = (0..40).map(|i| (0.1 + 1e-3 * f64::from(i), 0.0)).collect();
        assert_eq!(detect_period(&drift, 16, 1e-9), None);
        assert_eq!(distinct(&[0.1, 0.1 + 1e-12, 0.2, 0.3, 0.2], 1e-9), 3);
        assert_eq!(distinct(&[], 1e-9), 0);
    }

    #[test]
    fn max_per_cycle_of_a_period_one_response_repeats() {
        let model = crate::common::Model::new(
            &crate::common::ModelArgs {
                zeta: 0.02,
                restitution: 0.85,
                tol: 1e-16,
                chatter: crate::common::Chatter::Accumulation,
                json: false,
            },
            1.75,
            0.07,
        )
        .unwrap();
        let c = steady_cycles(&model, 600, 6, 128).unwrap();
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
        let coarse = steady_cycles(&model, 600, 1, 16).unwrap().max_x[0];
        assert!(c.max_x[0] >= coarse - 1e-9 && c.max_x[0] - coarse < 1e-3);
        assert!(
            (coarse - c.max_x[0]).abs() < 1e-6,
            "{coarse} vs {}",
            c.max_x[0]
        );
    }
}
