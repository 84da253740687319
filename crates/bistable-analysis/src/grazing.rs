//! Grazing of periodic orbits, approached along one smooth side of a branch in Ω.
//!
//! At a grazing point a flight of the orbit touches the plate with zero relative velocity, so
//! the impacts per period change there. Each side has a smooth test function that vanishes at
//! the point: on the side where the flight does not touch, its **minimum gap** (the smallest
//! interior local minimum of `x − z` over the flights, units of `Δx`); on the side where it
//! does, the **impact speed** (the smallest relative velocity `|x'₋ − ż|` at an impact, units
//! of `ω0·Δx`). Both are about linear in Ω near the point; the orbits of a side are solved at
//! fixed Ω (shooting, the corrector of [`crate::arclength`] in the plane `Ω = const`), so the
//! approach works on either side of a grazing corner, where the branch turns in Ω.
//!
//! The point is located by secant steps on the test function, aimed alternately 1 % of the
//! estimated distance short of and beyond the root, until an orbit of the side (same impacts,
//! test function positive) and a failed trial aimed beyond the root (no such orbit) lie within
//! [`GRAZING_TOL`] in Ω; that bracket is the reported error. A trial short of the root that
//! fails is a failure of the corrector (near a grazing the impacting side's multipliers grow
//! like 1/speed): the step is cut. Where the approach stalls, the error is at least the
//! distance of the nearest orbit to the estimated root.

use bistable_core::shooting::eigenvalues;
use bistable_core::{Event, SimError, Simulator};

use crate::arclength::{correct, Eval};
use crate::numerics::{bisect, Mid};
use crate::Model;

/// The approach stops once the bracket in Ω is this short.
pub const GRAZING_TOL: f64 = 1e-10;
/// Samples per shaker period at which the relative velocity's sign is checked for a minimum
/// of the gap.
const GAP_SAMPLES: u32 = 256;
/// Bisection steps refining the time of a gap minimum (the interval shrinks by `2^-60`).
const REFINE: usize = 60;
/// Most orbits solved on one approach.
const MAX_SOLVES: usize = 60;
/// Largest first step in Ω from the starting orbit.
const FIRST_STEP: f64 = 4e-3;
/// Step in Ω to the second orbit that gives the first secant slope.
const SLOPE_STEP: f64 = 1e-4;
/// The trials land this fraction of the estimated distance short of and beyond the root.
const AIM: f64 = 0.01;

/// Which test function a side of the grazing point has.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Test {
    /// The side with fewer impacts: the smallest interior minimum of the gap.
    Gap,
    /// The side with more impacts: the smallest relative impact velocity.
    Speed,
}

/// The grazing measures of one orbit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Profile {
    /// Smallest interior local minimum of the gap `x − z` over the free flights (where the
    /// relative velocity turns from negative to positive), `∞` without one.
    pub min_gap: f64,
    /// Smallest relative velocity `|x'₋ − ż|` at an impact, `∞` without impacts.
    pub impact_speed: f64,
}

impl Test {
    fn value(self, p: &Profile) -> f64 {
        match self {
            Test::Gap => p.min_gap,
            Test::Speed => p.impact_speed,
        }
    }
}

/// The grazing measures of the `period`-periodic orbit through `(x, x')` (`u = (x, x', Ω)`)
/// over one period from plate phase 0.
pub fn profile(model: &Model, period: u32, u: [f64; 3]) -> Result<Profile, SimError> {
    let here = model.at(u[2], model.velocity())?;
    let mut sim = here.simulator_from(u[0].max(0.0), u[1])?;
    let n = GAP_SAMPLES * period;
    let t_end = f64::from(period) * here.shaker_period();
    let mut out = Profile {
        min_gap: f64::INFINITY,
        impact_speed: f64::INFINITY,
    };
    let mut prev = sim.clone();
    for k in 1..=n {
        let mut hit = false;
        let mut speed = f64::INFINITY;
        sim.advance_to(t_end * f64::from(k) / f64::from(n), &mut |e: &Event| {
            if let Event::Impact(i) = e {
                hit = true;
                speed = speed.min((i.v_before - i.zdot).abs());
            }
        })?;
        out.impact_speed = out.impact_speed.min(speed);
        let w = |s: &Simulator| {
            let st = s.state();
            st.v - st.zdot
        };
        if !hit && w(&prev) < 0.0 && w(&sim) >= 0.0 {
            out.min_gap = out.min_gap.min(gap_minimum(&prev, sim.time())?);
        }
        prev = sim.clone();
    }
    Ok(out)
}

/// The gap at the minimum between `from`'s time and `to`, where the relative velocity turns
/// from negative to positive (no impact in between): bisection on its sign.
fn gap_minimum(from: &Simulator, to: f64) -> Result<f64, SimError> {
    let at = |t: f64| -> Result<Simulator, SimError> {
        let mut s = from.clone();
        s.advance_to(t, &mut |_: &Event| {})?;
        Ok(s)
    };
    let mut failed = None;
    let (lo, hi) = bisect(
        (from.time(), to),
        0.0,
        REFINE,
        |lo, hi| hi - lo,
        |&lo, &hi| {
            let mid = 0.5 * (lo + hi);
            if !(mid > lo && mid < hi) {
                return Mid::Stop;
            }
            match at(mid).map(|s| s.state()) {
                Ok(st) if st.v - st.zdot < 0.0 => Mid::Lo(mid),
                Ok(_) => Mid::Hi(mid),
                Err(e) => {
                    failed = Some(e);
                    Mid::Stop
                }
            }
        },
    );
    if let Some(e) = failed {
        return Err(e);
    }
    Ok(at(0.5 * (lo + hi))?.state().gap())
}

/// An orbit solved on an approach.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Solved {
    /// `(x, x', Ω)`.
    pub(crate) u: [f64; 3],
    /// Its evaluation (monodromy, impacts, sticking).
    pub(crate) eval: Eval,
    /// The side's test function.
    pub(crate) value: f64,
}

impl Solved {
    /// Floquet multipliers, largest modulus first.
    pub(crate) fn multipliers(&self) -> [(f64, f64); 2] {
        eigenvalues(self.eval.m)
    }
}

/// An approach to a grazing point along one side.
#[derive(Debug, Clone)]
pub(crate) struct Approach {
    /// The orbits of the side solved on the way, in order of Ω towards the point (the last is
    /// the nearest; the first is the starting orbit).
    pub(crate) path: Vec<Solved>,
    /// `Ω` at the point: the secant root of the last two orbits, inside the final bracket.
    pub(crate) omega: f64,
    /// Length in Ω of the final bracket (an orbit of the side and a failed trial beyond), at
    /// least the distance of the nearest orbit to the estimated root (twice that where no
    /// trial beyond failed; where the test function reached its round-off, twice its value
    /// over the last slope), and at least the nearest orbit's residual over that slope.
    pub(crate) error: f64,
}

/// The `period`-periodic orbit at `omega` from the prediction `y`, if it is one of the side
/// (`impacts` per period, no sticking, test function positive) within `reach` of `y`.
fn solve(
    model: &Model,
    period: u32,
    test: Test,
    impacts: u64,
    omega: f64,
    y: [f64; 2],
    reach: f64,
) -> Option<Solved> {
    let (u, eval, _) = correct(model, period, [y[0], y[1], omega], [0.0, 0.0, 1.0])?;
    let near = (u[0] - y[0]).hypot(u[1] - y[1]) <= reach;
    if !near || eval.impacts != impacts || eval.sticks {
        return None;
    }
    let value = test.value(&profile(model, period, u).ok()?);
    (value.is_finite() && value > 0.0).then_some(Solved { u, eval, value })
}

/// Approaches the grazing point of the side of the orbit `start` (`(x, x', Ω)`, a solved
/// `period`-periodic orbit that does not stick) whose test function is `test`; `None` if its
/// test function cannot be evaluated or no second orbit of the side is found near it.
pub(crate) fn approach(
    model: &Model,
    period: u32,
    start: [f64; 3],
    test: Test,
) -> Option<Approach> {
    let (u0, eval0, _) = correct(model, period, start, [0.0, 0.0, 1.0])?;
    if eval0.sticks {
        return None;
    }
    let impacts = eval0.impacts;
    let v0 = test.value(&profile(model, period, u0).ok()?);
    if !(v0.is_finite() && v0 > 0.0) {
        return None;
    }
    let first = Solved {
        u: u0,
        eval: eval0,
        value: v0,
    };
    let y0 = [u0[0], u0[1]];
    let second = [1.0, -1.0].into_iter().find_map(|sign| {
        let w = u0[2] + sign * SLOPE_STEP * u0[2].max(1.0);
        solve(model, period, test, impacts, w, y0, 0.01)
    })?;
    // The orbits in the order solved, and the path towards the point.
    let mut solved = vec![first, second];
    let mut beyond: Option<f64> = None;
    let mut step = FIRST_STEP * u0[2].max(1.0);
    let mut root = u0[2];
    let mut aim_short = true;
    let mut stalled = None;
    let mut last_slope = f64::NAN;
    for _ in 0..MAX_SOLVES {
        let (a, b) = (solved[solved.len() - 1], solved[solved.len() - 2]);
        let slope = (a.value - b.value) / (a.u[2] - b.u[2]);
        root = a.u[2] - a.value / slope;
        if !root.is_finite() || a.u[2] == b.u[2] {
            // The test function is at its round-off: both orbits are within their values
            // over the last slope of the point.
            root = a.u[2];
            stalled = Some(2.0 * a.value.max(b.value) / last_slope.abs());
            break;
        }
        last_slope = slope;
        if let Some(w) = beyond {
            if (a.u[2] - w).abs() <= GRAZING_TOL {
                break;
            }
            // Keep the estimate inside the bracket.
            if (root - w) * (a.u[2] - w) <= 0.0 {
                root = 0.5 * (a.u[2] + w);
            }
        }
        let d = a.u[2] - root;
        // Alternately just short of and just beyond the root; far from it, bounded steps.
        let mut trial = if aim_short {
            root + AIM * d
        } else {
            root - AIM * d
        };
        let far = (trial - a.u[2]).abs() > step;
        let aimed_beyond = !far && !aim_short;
        if far {
            trial = a.u[2] - step.copysign(d);
        } else {
            aim_short = !aim_short;
        }
        let dw = trial - a.u[2];
        let dy = [0, 1].map(|k| (a.u[k] - b.u[k]) / (a.u[2] - b.u[2]));
        let pred = [a.u[0] + dy[0] * dw, a.u[1] + dy[1] * dw];
        let reach = 2.0 * dw.abs() * dy[0].hypot(dy[1]).max(1.0) + 1e-9;
        match solve(model, period, test, impacts, trial, pred, reach) {
            Some(s) => {
                solved.push(s);
                if far {
                    step *= 2.0;
                }
            }
            None if aimed_beyond => beyond = Some(trial),
            // Short of the root no orbit of the side was found: the corrector failed.
            None => {
                step = 0.25 * dw.abs();
                aim_short = true;
            }
        }
    }
    let a = solved[solved.len() - 1];
    // The orbit's own residual moves the test function by about as much.
    let floor = a.eval.g[0].abs().max(a.eval.g[1].abs()) / last_slope.abs();
    let error = match (stalled, beyond) {
        (Some(e), _) => e,
        (None, Some(w)) => (a.u[2] - w).abs().max((a.u[2] - root).abs()),
        (None, None) => 2.0 * (a.u[2] - root).abs(),
    }
    .max(if floor.is_finite() { floor } else { 0.0 });
    // From the start towards the point: the orbits no farther from it than the start, the
    // farthest first (the start stays first among equals).
    let from_root = |s: &Solved| (s.u[2] - root).abs();
    let d0 = (u0[2] - root).abs();
    let mut path: Vec<Solved> = solved.into_iter().filter(|s| from_root(s) <= d0).collect();
    path.sort_by(|p, q| from_root(q).total_cmp(&from_root(p)));
    Some(Approach {
        path,
        omega: root,
        error,
    })
}

/// Largest error in Ω of the minimum-gap side's approach for a continuation to pass through
/// the grazing point it located.
pub const CROSSING_TOL: f64 = 1e-8;

/// The impact-speed side's approach must end this fraction of its start's distance (in Ω)
/// from the point for a continuation to pass through it.
const SPEED_REACH: f64 = 0.01;

/// A branch continued through a grazing point.
#[derive(Debug, Clone)]
pub(crate) struct Crossing {
    /// `Ω` at the point (from the minimum-gap side).
    pub(crate) omega: f64,
    /// The orbits from the first side's towards the point, then the second side's away from
    /// it (neither end orbit).
    pub(crate) orbits: Vec<Solved>,
}

/// The way from orbit `a` (`(x, x', Ω)`, `impacts_a` per period) through the grazing point to
/// orbit `b` of the same branch (`impacts_b ≠ impacts_a`, neither sticks): both sides
/// approached ([`approach`]). `None` unless the minimum-gap side located the point to
/// [`CROSSING_TOL`] and the impact-speed side came within [`SPEED_REACH`] of its start's
/// distance to it (short of that its corrector failed, or the side has a fold between, which
/// an approach at fixed Ω cannot pass).
pub(crate) fn crossing(
    model: &Model,
    period: u32,
    a: ([f64; 3], u64),
    b: ([f64; 3], u64),
) -> Option<Crossing> {
    let test = |p: u64, q: u64| if p < q { Test::Gap } else { Test::Speed };
    let ga = approach(model, period, a.0, test(a.1, b.1))?;
    let gb = approach(model, period, b.0, test(b.1, a.1))?;
    let (gap, speed) = if a.1 < b.1 { (&ga, &gb) } else { (&gb, &ga) };
    if gap.error.is_nan() || gap.error > CROSSING_TOL {
        return None;
    }
    // The impact-speed side must have come at least 99 % of the way to the point (not stalled
    // where its corrector failed, nor walked off to a fold of its side).
    let to_point = |s: &Solved| (s.u[2] - gap.omega).abs();
    let (first, last) = (&speed.path[0], speed.path.last()?);
    if to_point(last) > SPEED_REACH * to_point(first) {
        return None;
    }
    let mut orbits: Vec<Solved> = ga.path[1..].to_vec();
    orbits.extend(gb.path[1..].iter().rev());
    Some(Crossing {
        omega: gap.omega,
        orbits,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use bistable_core::{Params, Sinusoid, SolverOptions};

    #[test]
    fn test_functions_pick_their_measure() {
        let p = Profile {
            min_gap: 1e-3,
            impact_speed: 0.03,
        };
        assert_eq!(Test::Gap.value(&p), 1e-3);
        assert_eq!(Test::Speed.value(&p), 0.03);
        // The P-1 orbit at Ω = 0.85, V = 0.05: one impact, and a flight that comes within
        // 8.5e-4 of the plate (measured 8.4777e-4; its grazing is near Ω = 0.8408).
        let m = Model::new(
            Params::paper(),
            Sinusoid::new(0.85, 0.05).unwrap(),
            SolverOptions::default(),
        );
        let (u, e, _) = correct(&m, 1, [0.026169, 0.051992, 0.85], [0.0, 0.0, 1.0]).unwrap();
        assert_eq!(e.impacts, 1);
        let p = profile(&m, 1, u).unwrap();
        assert!((p.min_gap - 8.4777e-4).abs() < 1e-7, "{p:?}");
        assert!(p.impact_speed > 0.02, "{p:?}");
    }
}
