//! Two-parameter curves: a located fold or period-doubling point of a `p`-periodic orbit
//! continued in `(Ω, V)`.
//!
//! Unknowns `w = (x, x', Ω, V)`; equations `P(x, x'; Ω, V) − (x, x') = 0` (the orbit) and
//! `h = det(M − I) = 0` (fold) or `det(M + I) = 0` (period doubling), with `M` the monodromy
//! matrix from the variational equations; pseudo-arclength in `w` with the tangent the null
//! vector of the 3×4 Jacobian (`M − I` exactly, the other entries by central differences).
//! A curve ends where the impacts per period or sticking change (the conditions are not
//! smooth there), where the corrector fails at a step 1e-4 of the largest, outside the bounds
//! or after `max_points`.

use bistable_core::shooting::eigenvalues;
use bistable_core::SimError;

use crate::arclength::period_map;
use crate::bifurcations::{BifurcationPoint, Kind};
use crate::numerics::{self, dot, norm, solve, sub};
use crate::Model;

/// Relative step of the central differences.
const FD: f64 = 1e-6;
/// Newton on the augmented system stops at this max-norm of `(P(y) − y, h)`.
const RESIDUAL: f64 = 1e-11;

/// One point of a two-parameter curve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CurvePoint {
    /// `Ω`.
    pub omega: f64,
    /// `V` (units of `ω0·Δx`).
    pub velocity: f64,
    /// Fixed point `x` at plate phase 0 (units of `Δx`).
    pub x0: f64,
    /// Its velocity `x'` (units of `ω0·Δx`).
    pub v0: f64,
    /// Floquet multipliers `(re, im)`, largest modulus first (one at +1 or −1).
    pub multipliers: [(f64, f64); 2],
    /// Impacts per orbit.
    pub impacts: u64,
}

/// Settings of a two-parameter curve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CurveOptions {
    /// Stop once Ω leaves `(lo, hi)`.
    pub omega_bounds: (f64, f64),
    /// Stop once V leaves `(lo, hi)` (`lo >= 0`).
    pub velocity_bounds: (f64, f64),
    /// Largest step along the curve (Euclidean in `(x, x', Ω, V)`), > 0.
    pub ds_max: f64,
    /// Most points in each direction from the start.
    pub max_points: usize,
}

/// Why a curve cannot start.
#[derive(Debug, Clone, PartialEq)]
pub enum CurveError {
    /// Only folds and period doublings have a curve here.
    Kind(Kind),
    /// The start does not solve the augmented system (residual reached).
    Start(f64),
    /// A simulation failed.
    Sim(SimError),
}

impl std::fmt::Display for CurveError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CurveError::Kind(k) => write!(
                f,
                "only fold and period_doubling points can be continued, not {}",
                k.name()
            ),
            CurveError::Start(r) => write!(
                f,
                "the start point does not solve the bifurcation condition (residual {r:e})"
            ),
            CurveError::Sim(e) => e.fmt(f),
        }
    }
}

impl std::error::Error for CurveError {}

impl From<SimError> for CurveError {
    fn from(e: SimError) -> Self {
        CurveError::Sim(e)
    }
}

/// The augmented system of one curve.
pub(crate) struct System<'a> {
    model: &'a Model,
    pub(crate) period: u32,
    /// +1 for a fold (`det(M − I)`), −1 for a period doubling (`det(M + I)`).
    pub(crate) sign: f64,
}

/// `Φ(w) = (P(y) − y, h)` with `M`, impacts and sticking.
pub(crate) type Value = ([f64; 3], [[f64; 2]; 2], u64, bool);

impl<'a> System<'a> {
    /// The system of the curves of `kind` (fold or period doubling) of `period`-periodic
    /// orbits (`model`: any model of the run's ζ and e).
    pub(crate) fn new(model: &'a Model, kind: Kind, period: u32) -> Result<Self, CurveError> {
        let sign = match kind {
            Kind::Fold => 1.0,
            Kind::PeriodDoubling => -1.0,
            k => return Err(CurveError::Kind(k)),
        };
        Ok(Self {
            model,
            period,
            sign,
        })
    }

    /// The model at `(Ω, V)`.
    pub(crate) fn model_at(&self, omega: f64, velocity: f64) -> Result<Model, SimError> {
        Ok(self.model.at(omega, velocity)?)
    }

    pub(crate) fn value(&self, w: [f64; 4]) -> Result<Value, SimError> {
        let m = self.model.at(w[2], w[3])?;
        let (py, mm, impacts, sticks) = period_map(&m, w[2], self.period, [w[0], w[1]], true)?;
        let s = self.sign;
        let h = (mm[0][0] - s) * (mm[1][1] - s) - mm[0][1] * mm[1][0];
        Ok(([py[0] - w[0], py[1] - w[1], h], mm, impacts, sticks))
    }

    /// `Φ(w)`, its 3×4 Jacobian, `M`, impacts and sticking.
    #[allow(clippy::type_complexity)]
    pub(crate) fn jacobian(
        &self,
        w: [f64; 4],
    ) -> Result<([f64; 3], [[f64; 4]; 3], Value), SimError> {
        let v = self.value(w)?;
        let mut jac = [[0.0; 4]; 3];
        for k in 0..4 {
            let d = FD * w[k].abs().max(if k < 2 { 0.1 } else { 1.0 }).max(1e-3);
            let (mut plus, mut minus) = (w, w);
            plus[k] += d;
            minus[k] -= d;
            let (fp, ..) = self.value(plus)?;
            let (fm, ..) = self.value(minus)?;
            for (r, row) in jac.iter_mut().enumerate() {
                row[k] = (fp[r] - fm[r]) / (2.0 * d);
            }
        }
        // The orbit's rows in x and x' exactly: M − I.
        let mm = v.1;
        jac[0][0] = mm[0][0] - 1.0;
        jac[0][1] = mm[0][1];
        jac[1][0] = mm[1][0];
        jac[1][1] = mm[1][1] - 1.0;
        Ok((v.0, jac, v))
    }

    /// Newton from `pred` with the arclength condition `t·(w − pred) = 0`: the point, its
    /// value and its Jacobian.
    #[allow(clippy::type_complexity)]
    pub(crate) fn correct(
        &self,
        pred: [f64; 4],
        t: [f64; 4],
    ) -> Option<([f64; 4], Value, [[f64; 4]; 3])> {
        numerics::correct(
            pred,
            t,
            |w| {
                let (f, jac, v) = self.jacobian(w).ok()?;
                if f.iter().all(|c| c.abs() <= RESIDUAL) {
                    return Some(((v, jac), None));
                }
                Some((
                    (v, jac),
                    Some(([jac[0], jac[1], jac[2], [0.0; 4]], [f[0], f[1], f[2], 0.0])),
                ))
            },
            |w| w[2] > 0.0 && w[3] >= 0.0,
        )
        .map(|(w, (v, jac), _)| (w, v, jac))
    }
}

/// Unit null vector of the 3×4 Jacobian, oriented along `along` (its product with it
/// positive).
pub(crate) fn tangent(jac: [[f64; 4]; 3], along: [f64; 4]) -> Option<[f64; 4]> {
    let t = solve([jac[0], jac[1], jac[2], along], [0.0, 0.0, 0.0, 1.0])?;
    let n = norm(t);
    (n.is_finite() && n > 0.0).then(|| t.map(|c| c / n))
}

fn curve_point(w: [f64; 4], v: &Value) -> CurvePoint {
    CurvePoint {
        omega: w[2],
        velocity: w[3],
        x0: w[0],
        v0: w[1],
        multipliers: eigenvalues(v.1),
        impacts: v.2,
    }
}

/// Continues the fold or period-doubling point `start` (located on a branch at `model`'s
/// parameters; `model`: any model of that branch) in `(Ω, V)`: the curve from its low-V end
/// to its high-V end (or as far as it goes each way), the start among its points.
pub fn continue_point(
    model: &Model,
    start: &BifurcationPoint,
    o: CurveOptions,
) -> Result<Vec<CurvePoint>, CurveError> {
    let sys = System::new(model, start.kind, start.period)?;
    // Polish the start at its V (the arclength condition fixes V).
    let w0 = [start.x0, start.v0, start.omega, start.velocity];
    let Some((w0, v0, jac0)) = sys.correct(w0, [0.0, 0.0, 0.0, 1.0]) else {
        let r = sys
            .value(w0)
            .map(|(f, ..)| f.iter().fold(0.0_f64, |a, c| a.max(c.abs())))?;
        return Err(CurveError::Start(r));
    };
    let side = (v0.2, v0.3);
    let mut halves: Vec<Vec<CurvePoint>> = Vec::new();
    for dir in [-1.0, 1.0] {
        let mut pts = Vec::new();
        let Some(mut t) = tangent(jac0, [0.0, 0.0, 0.0, dir]) else {
            halves.push(pts);
            continue;
        };
        let mut w = w0;
        let mut ds = 0.25 * o.ds_max;
        while pts.len() < o.max_points && ds >= 1e-4 * o.ds_max {
            let pred = [0, 1, 2, 3].map(|k| w[k] + ds * t[k]);
            let next = sys.correct(pred, t).and_then(|(wn, v, jac)| {
                let step = norm(sub(wn, w));
                let tn = tangent(jac, t)?;
                let turn = dot(tn, t);
                (step <= 2.0 * ds && turn > 0.5 && (v.2, v.3) == side).then_some((wn, v, tn))
            });
            match next {
                Some((wn, v, tn)) => {
                    w = wn;
                    t = tn;
                    pts.push(curve_point(w, &v));
                    let inside = |x: f64, (lo, hi): (f64, f64)| x > lo && x < hi;
                    if !(inside(w[2], o.omega_bounds) && inside(w[3], o.velocity_bounds)) {
                        break;
                    }
                    ds = (1.5 * ds).min(o.ds_max);
                }
                None => ds *= 0.5,
            }
        }
        halves.push(pts);
    }
    let mut out: Vec<CurvePoint> = halves[0].iter().rev().copied().collect();
    out.push(curve_point(w0, &v0));
    out.extend(halves[1].iter().copied());
    Ok(out)
}

/// A located point this close (Euclidean in `(x, x', Ω, V)`) to a curve already traced is on
/// it (see [`trace_all`]).
pub const ON_CURVE: f64 = 1e-4;

/// Curves of an atlas, each with the point it was started from.
pub type Atlas = Vec<(BifurcationPoint, Vec<CurvePoint>)>;

/// The atlas of `points` (located on branches at one V, e.g. by
/// [`crate::bifurcations::locate`]): every fold and period doubling among them, in their order,
/// with its curve continued by [`continue_point`] (`model`: any model of the run's ζ and e).
/// A point on a curve already traced of its kind and period (within [`ON_CURVE`]: a curve that
/// turns in V meets the branches' V twice) starts no second curve; the other kinds are left
/// out. The error gives the kind and Ω of the point whose curve could not start.
pub fn trace_all(
    model: &Model,
    points: Vec<BifurcationPoint>,
    o: CurveOptions,
) -> Result<Atlas, (Kind, f64, CurveError)> {
    let mut all: Vec<(BifurcationPoint, Vec<CurvePoint>)> = Vec::new();
    for s in points {
        if !matches!(s.kind, Kind::Fold | Kind::PeriodDoubling)
            || all
                .iter()
                .any(|(t, c)| t.kind == s.kind && t.period == s.period && covers(c, &s, ON_CURVE))
        {
            continue;
        }
        match continue_point(model, &s, o) {
            Ok(c) => all.push((s, c)),
            Err(e) => return Err((s.kind, s.omega, e)),
        }
    }
    Ok(all)
}

/// Whether the bifurcation point `p` lies on `curve` (within `tol` of one of its segments,
/// Euclidean in `(x, x', Ω, V)`), with the same kind and period as `curve` was traced for:
/// a second start on a curve already traced (one that turns in V meets V again).
pub fn covers(curve: &[CurvePoint], p: &BifurcationPoint, tol: f64) -> bool {
    let u = [p.x0, p.v0, p.omega, p.velocity];
    let w = |c: &CurvePoint| [c.x0, c.v0, c.omega, c.velocity];
    curve.windows(2).any(|seg| {
        let (a, b) = (w(&seg[0]), w(&seg[1]));
        let d: [f64; 4] = [0, 1, 2, 3].map(|k| b[k] - a[k]);
        let l2: f64 = d.iter().map(|c| c * c).sum();
        let s = if l2 > 0.0 {
            ((0..4).map(|k| (u[k] - a[k]) * d[k]).sum::<f64>() / l2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (0..4)
            .map(|k| (u[k] - a[k] - s * d[k]).powi(2))
            .sum::<f64>()
            .sqrt()
            <= tol
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tangent_of_a_jacobian() {
        let t = tangent(
            [
                [1.0, 0.0, 0.0, 0.0],
                [0.0, 1.0, 0.0, 0.0],
                [0.0, 0.0, 1.0, -1.0],
            ],
            [0.0, 0.0, 0.0, 1.0],
        )
        .unwrap();
        let h = 0.5_f64.sqrt();
        assert!(
            (t[2] - h).abs() < 1e-15 && (t[3] - h).abs() < 1e-15,
            "{t:?}"
        );
    }

    #[test]
    fn a_point_on_a_traced_curve_is_covered() {
        let at = |omega: f64, velocity: f64| CurvePoint {
            omega,
            velocity,
            x0: 0.1,
            v0: 0.0,
            multipliers: [(-1.0, 0.0), (0.5, 0.0)],
            impacts: 1,
        };
        let curve = [at(2.0, 0.06), at(2.1, 0.07)];
        let p = |omega, velocity| BifurcationPoint {
            kind: Kind::PeriodDoubling,
            omega,
            velocity,
            period: 1,
            x0: 0.1,
            v0: 0.0,
            multipliers: [(-1.0, 0.0), (0.5, 0.0)],
            max_x: 0.2,
            omega_error: 0.0,
            branch: 0,
            index: 0,
            impacts_before: 1,
            impacts_after: 1,
            sticks_before: false,
            sticks_after: false,
        };
        assert!(covers(&curve, &p(2.05, 0.065), 1e-9));
        assert!(!covers(&curve, &p(2.05, 0.066), 1e-4));
        assert!(!covers(&curve, &p(2.2, 0.08), 1e-4));
    }
}
