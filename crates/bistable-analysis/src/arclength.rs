//! Pseudo-arclength continuation of periodic orbits in Ω: follows a branch of fixed points of
//! the p-period stroboscopic map through folds, where natural continuation (one Newton solve
//! per Ω) must stop.
//!
//! Unknowns `u = (x, x', Ω)`; equations `P(x, x'; Ω) − (x, x') = 0` and the arclength condition
//! `t·(u − u_pred) = 0`, with `t` the unit tangent, the null vector of `[M − I | ∂P/∂Ω]`. `M`
//! comes from the core's variational equations (saltation matrices at impacts); `∂P/∂Ω` is a
//! central difference (the map runs from plate phase 0 to plate phase 0, so changing Ω also
//! changes its duration `2πp/Ω`).

use std::num::NonZeroU32;

use bistable_core::shooting::eigenvalues;
use bistable_core::{Event, SimError, Simulator, Sinusoid};

use crate::cycles::record_cycles;
use crate::grazing::crossing;
use crate::numerics::{self, dot, norm, sub};
use crate::orbit::Orbit;
use crate::seeds::Seed;
use crate::Model;

/// Samples per shaker period for the largest displacement of a traced orbit.
const SAMPLES: NonZeroU32 = NonZeroU32::new(128).expect("128 > 0");
/// A step that changes the impacts per period where the grazing point between cannot be
/// passed is kept only once it is at most this fraction of the largest step.
const JUMP_STEP: f64 = 1e-3;
/// A seeded orbit within this distance (max norm in `x`, `x'`) of a trace is already on it.
const COVERED: f64 = 5e-3;

/// One orbit on a traced branch.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArcPoint {
    /// `Ω`.
    pub omega: f64,
    /// Fixed point `x` at plate phase 0 (units of `Δx`).
    pub x0: f64,
    /// Its velocity `x'` (units of `ω0·Δx`).
    pub v0: f64,
    /// Floquet multipliers `(re, im)`, largest modulus first.
    pub multipliers: [(f64, f64); 2],
    /// All multipliers inside the unit circle.
    pub stable: bool,
    /// Impacts per orbit.
    pub impacts: u64,
    /// Whether the mass sticks on the orbit (then `M = 0`).
    pub sticks: bool,
    /// Largest displacement on the orbit (units of `Δx`).
    pub max_x: f64,
}

/// Settings of a trace.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArcOptions {
    /// Period in shaker periods.
    pub period: u32,
    /// Stop once Ω leaves this interval `(lo, hi)`.
    pub omega_bounds: (f64, f64),
    /// Largest step along the branch (Euclidean norm in `(x, x', Ω)`), > 0.
    pub ds_max: f64,
    /// Most points on one trace.
    pub max_points: usize,
}

impl ArcOptions {
    /// Options for tracing `period`-periodic orbits over the evenly spaced grid `omegas` (first
    /// to last, non-empty): Ω may leave the grid by half a spacing, the step along the branch
    /// is at most one spacing (0.01 for a single Ω), at most `40·max(n, 50)` points.
    pub fn for_grid(period: u32, omegas: &[f64]) -> Self {
        let n = omegas.len();
        let (first, last) = (omegas[0], omegas[n - 1]);
        let (lo, hi) = (first.min(last), first.max(last));
        let step = if n > 1 {
            ((last - first) / (n - 1) as f64).abs()
        } else {
            0.01
        };
        Self {
            period,
            omega_bounds: (lo - 0.5 * step, hi + 0.5 * step),
            ds_max: step,
            max_points: 40 * n.max(50),
        }
    }
}

/// Residual, Jacobian `[M − I | ∂P/∂Ω]`, monodromy, impacts and sticking at `u`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Eval {
    /// Residual `P(y) − y` (units of `Δx`, `ω0·Δx`).
    pub(crate) g: [f64; 2],
    jac: [[f64; 3]; 2],
    /// Monodromy matrix `M` (0 once the mass sticks).
    pub(crate) m: [[f64; 2]; 2],
    /// Impacts per orbit.
    pub(crate) impacts: u64,
    /// Whether the mass sticks on the orbit.
    pub(crate) sticks: bool,
}

/// `(P(y), M, impacts, sticks)`.
type MapResult = ([f64; 2], [[f64; 2]; 2], u64, bool);

/// `(P(y), M, impacts, sticks)` of the `p`-period map at `Ω` from `y` at plate phase 0.
pub(crate) fn period_map(
    model: &Model,
    omega: f64,
    p: u32,
    y: [f64; 2],
    variational: bool,
) -> Result<MapResult, SimError> {
    let plate = Sinusoid::new(omega, model.velocity())?;
    let mut sim = Simulator::with_state(
        model.params,
        plate.into(),
        model.opts,
        0.0,
        y[0].max(0.0),
        y[1],
    )?;
    if variational {
        sim.enable_variational();
    }
    let mut sticks = false;
    sim.advance_instant(plate.section(u64::from(p)), &mut |e: &Event| {
        sticks |= matches!(e, Event::StickStart { .. })
    })?;
    let st = sim.state();
    let m = sim.variational().unwrap_or([[0.0; 2]; 2]);
    Ok(([st.x, st.v], m, sim.stats().impacts, sticks))
}

fn evaluate(model: &Model, p: u32, u: [f64; 3]) -> Result<Eval, SimError> {
    let y = [u[0], u[1]];
    let (py, m, impacts, sticks) = period_map(model, u[2], p, y, true)?;
    let d = 1e-6 * u[2].abs().max(1.0);
    let (plus, ..) = period_map(model, u[2] + d, p, y, false)?;
    let (minus, ..) = period_map(model, u[2] - d, p, y, false)?;
    let dp = [
        (plus[0] - minus[0]) / (2.0 * d),
        (plus[1] - minus[1]) / (2.0 * d),
    ];
    Ok(Eval {
        g: [py[0] - y[0], py[1] - y[1]],
        jac: [
            [m[0][0] - 1.0, m[0][1], dp[0]],
            [m[1][0], m[1][1] - 1.0, dp[1]],
        ],
        m,
        impacts,
        sticks,
    })
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// Unit null vector of the 2×3 Jacobian, oriented along `along` (or with the sign of `dir` in
/// Ω when there is no previous tangent).
fn tangent(jac: [[f64; 3]; 2], along: Option<[f64; 3]>, dir: f64) -> Option<[f64; 3]> {
    let t = cross(jac[0], jac[1]);
    let n = norm(t);
    if !(n.is_finite() && n > 0.0) {
        return None;
    }
    let mut t = t.map(|c| c / n);
    let flip = match along {
        Some(prev) => dot(t, prev) < 0.0,
        None => t[2] * dir < 0.0,
    };
    if flip {
        t = t.map(|c| -c);
    }
    Some(t)
}

/// Newton on the augmented system from `pred`, with the arclength condition along `t` (the
/// solution lies in the plane through `pred` normal to `t`, a unit vector in `(x, x', Ω)`).
/// Returns the converged point, its evaluation and the iterations used.
pub(crate) fn correct(
    model: &Model,
    p: u32,
    pred: [f64; 3],
    t: [f64; 3],
) -> Option<([f64; 3], Eval, u32)> {
    numerics::correct(
        pred,
        t,
        |u| {
            let e = evaluate(model, p, u).ok()?;
            let scale = u[0].abs().max(u[1].abs()).max(1.0);
            let res = e.g[0].abs().max(e.g[1].abs());
            if res <= 1e-11 * scale {
                return Some((e, None));
            }
            let lin = ([e.jac[0], e.jac[1], [0.0; 3]], [e.g[0], e.g[1], 0.0]);
            Some((e, Some(lin)))
        },
        |u| u[2] > 0.0,
    )
}

fn point(model: &Model, p: u32, u: [f64; 3], e: &Eval) -> Result<ArcPoint, SimError> {
    let multipliers = eigenvalues(e.m);
    let here = model.at(u[2], model.velocity())?;
    let mut sim = here.simulator_from(u[0].max(0.0), u[1])?;
    let c = record_cycles(&mut sim, here.shaker, 0, p, SAMPLES)?;
    Ok(ArcPoint {
        omega: u[2],
        x0: u[0],
        v0: u[1],
        multipliers,
        stable: multipliers[0].0.hypot(multipliers[0].1) < 1.0,
        impacts: e.impacts,
        sticks: e.sticks,
        max_x: c.max_x.iter().copied().fold(f64::MIN, f64::max),
    })
}

/// Traces the branch through the orbit `(x0, v0)` at `Ω0` (`start = (Ω0, x0, v0)`, a fixed
/// point of the map at `model`'s V) in the direction of increasing (`dir > 0`) or decreasing Ω,
/// until Ω leaves the bounds, the step size collapses (a lost orbit, or a non-smooth point the
/// corrector cannot step over) or `max_points`. A step that changes the impacts per period
/// (neither side sticking) passes through the grazing point between (both sides approached
/// as in [`crate::grazing`]): the orbits of both sides are added, and the trace goes on along
/// the new side away from the point (at a grazing corner, back in Ω); if the point cannot be
/// located to [`crate::grazing::CROSSING_TOL`] or the impacting side's approach stops short
/// of it, the step is halved and retried (the side may fold first), and kept as it is once
/// shorter than 1e-3 of the largest step.
pub fn trace(
    model: &Model,
    start: (f64, f64, f64),
    dir: f64,
    o: ArcOptions,
) -> Result<Vec<ArcPoint>, SimError> {
    let p = o.period;
    let mut u = [start.1, start.2, start.0];
    let Ok(e) = evaluate(model, p, u) else {
        return Ok(Vec::new());
    };
    let Some(mut t) = tangent(e.jac, None, dir) else {
        return Ok(Vec::new());
    };
    let mut out = vec![point(model, p, u, &e)?];
    let mut side = (e.impacts, e.sticks);
    let ds_min = 1e-5 * o.ds_max;
    let mut ds = 0.25 * o.ds_max;
    while out.len() < o.max_points && ds >= ds_min {
        let pred = [u[0] + ds * t[0], u[1] + ds * t[1], u[2] + ds * t[2]];
        let next = correct(model, p, pred, t).and_then(|(un, e, it)| {
            let step = norm(sub(un, u));
            let tn = tangent(e.jac, Some(t), dir)?;
            // A corrector that lands far away, or a tangent that turns back, jumped branches.
            (step <= 2.0 * ds && dot(tn, t) > 0.5).then_some((un, e, it, tn))
        });
        match next {
            Some((un, e, it, mut tn)) => {
                // Impacts changed: the step crossed a grazing point (or jumped over its
                // corner onto the other side). Follow both sides up to the point, then go on
                // along the new side away from it.
                let grazed = side != (e.impacts, e.sticks) && !side.1 && !e.sticks;
                match grazed
                    .then(|| crossing(model, p, (u, side.0), (un, e.impacts)))
                    .flatten()
                {
                    Some(c) => {
                        for s in &c.orbits {
                            out.push(point(model, p, s.u, &s.eval)?);
                        }
                        tn = tangent(e.jac, None, un[2] - c.omega).unwrap_or(tn);
                    }
                    // Not passable from here: shorter steps along this side first (it may
                    // fold before the point), the jump only once they are short.
                    None if grazed && ds > JUMP_STEP * o.ds_max => {
                        ds *= 0.5;
                        continue;
                    }
                    None => {}
                }
                u = un;
                t = tn;
                side = (e.impacts, e.sticks);
                out.push(point(model, p, u, &e)?);
                if u[2] < o.omega_bounds.0 || u[2] > o.omega_bounds.1 {
                    break;
                }
                if it <= 3 {
                    ds = (1.5 * ds).min(o.ds_max);
                }
            }
            None => ds *= 0.5,
        }
    }
    Ok(out)
}

/// Whether the orbit `(x, x')` at `Ω` lies on the traced polyline (within `tol`, max norm).
pub fn covers(trace: &[ArcPoint], omega: f64, x: f64, v: f64, tol: f64) -> bool {
    trace.windows(2).any(|w| {
        let (a, b) = (w[0], w[1]);
        let (lo, hi) = (a.omega.min(b.omega), a.omega.max(b.omega));
        if omega < lo || omega > hi {
            return false;
        }
        let s = if hi > lo {
            (omega - a.omega) / (b.omega - a.omega)
        } else {
            0.5
        };
        let xi = a.x0 + s * (b.x0 - a.x0);
        let vi = a.v0 + s * (b.v0 - a.v0);
        (xi - x).abs().max((vi - v).abs()) <= tol
    })
}

/// Pseudo-arclength traces through every orbit in `found` (seed and orbit, ordered by grid
/// point; `models[seed.point]` is its model) not already on a trace, in both directions (two
/// threads), joined into one polyline each (decreasing-Ω part reversed, so each trace starts
/// at its low-Ω end unless it turns). A trace ends where it runs onto an earlier one (at the
/// first orbit within `COVERED` (5e-3) of it). Traces of a single point are dropped.
pub fn traces(
    models: &[Model],
    found: &[(Seed, Orbit)],
    o: ArcOptions,
) -> Result<Vec<Vec<ArcPoint>>, SimError> {
    let mut traces: Vec<Vec<ArcPoint>> = Vec::new();
    for (seed, orbit) in found {
        let model = &models[seed.point];
        let w = model.omega();
        let (x, v) = orbit.point();
        if traces.iter().any(|t| covers(t, w, x, v, COVERED)) {
            continue;
        }
        let start = (w, x, v);
        let (back, fwd) = std::thread::scope(|s| {
            let b = s.spawn(|| trace(model, start, -1.0, o));
            let f = trace(model, start, 1.0, o);
            (b.join().expect("trace thread"), f)
        });
        // A part that runs onto an earlier trace (another seed's branch, met at a grazing
        // corner or a fold) ends at the first orbit it shares with it, so that no stretch of a
        // branch is drawn or counted twice.
        let joined = |a: &ArcPoint| {
            traces
                .iter()
                .any(|t| covers(t, a.omega, a.x0, a.v0, COVERED))
        };
        let until_joined = |mut part: Vec<ArcPoint>| {
            if let Some(i) = part.iter().skip(1).position(joined) {
                part.truncate(i + 2);
            }
            part
        };
        let mut back = until_joined(back?);
        back.reverse();
        back.extend(until_joined(fwd?).into_iter().skip(1));
        if back.len() > 1 {
            traces.push(back);
        }
    }
    Ok(traces)
}

/// Number of turning points of Ω (folds) along a trace; a turn where the impacts per period
/// change is a grazing corner, not a fold.
pub fn folds(t: &[ArcPoint]) -> usize {
    t.windows(3)
        .filter(|w| (w[1].omega - w[0].omega) * (w[2].omega - w[1].omega) < 0.0)
        .filter(|w| w[0].impacts == w[1].impacts && w[1].impacts == w[2].impacts)
        .count()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tangent_of_a_jacobian() {
        let t = tangent([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], None, -1.0).unwrap();
        assert_eq!(t, [0.0, 0.0, -1.0]);
    }

    #[test]
    fn grid_options_and_folds() {
        let o = ArcOptions::for_grid(1, &[2.0, 1.5, 1.0]);
        assert_eq!(o.omega_bounds, (0.75, 2.25));
        assert_eq!((o.ds_max, o.max_points), (0.5, 2000));
        assert_eq!(ArcOptions::for_grid(2, &[1.0]).ds_max, 0.01);
        let at = |omega| ArcPoint {
            omega,
            x0: 0.0,
            v0: 0.0,
            multipliers: [(0.5, 0.0); 2],
            stable: true,
            impacts: 1,
            sticks: false,
            max_x: 0.1,
        };
        let t: Vec<ArcPoint> = [1.0, 1.2, 1.1, 1.0, 1.3].map(at).to_vec();
        assert_eq!(folds(&t), 2);
        // A turn where the impacts per period change is a grazing corner.
        let mut corner = t.clone();
        corner[2].impacts = 2;
        corner[3].impacts = 2;
        assert_eq!(folds(&corner), 0);
        assert!(covers(&t, 1.15, 0.0, 0.0, 1e-9) && !covers(&t, 1.4, 0.0, 0.0, 1e-9));
    }
}
