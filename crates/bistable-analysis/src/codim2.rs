//! Codimension-two points of an atlas: the points of its fold and period-doubling curves
//! ([`crate::twoparam`]) where a second condition holds.
//!
//! * **fold–flip** (multipliers `+1` and `−1` at once): on a fold curve `det(M + I)` changes
//!   sign, on a period-doubling curve `det(M − I)` does. With `ζ > 0` or `e < 1`,
//!   `0 < det M < 1`, so the other multiplier is `det M ∈ (0, 1)` on a fold curve and
//!   `−det M ∈ (−1, 0)` on a period-doubling curve: the paper's model has none (checked all
//!   the same).
//! * **cusp**: on a fold curve the quadratic coefficient of the fold's normal form
//!   `a = ½·⟨p, D²P(q, q)⟩` changes sign (`q`, `p`: right and left null vectors of `M − I`
//!   with `|q| = 1`, `⟨p, q⟩ = 1`, `q` oriented continuously along the curve; `D²P(q, q)` is
//!   the central difference of `M·q` along `q`, step [`CUSP_STEP`]). There the two folds of a
//!   hysteresis loop meet and the curve's projection on `(Ω, V)` turns back.
//! * **resonant grazing**: a curve ends inside its bounds because the impacts per period
//!   change (the fold or period-doubling curve meets a grazing curve). The end is located by
//!   bisection along the curve: a trial is on the curve's side when the corrector converges
//!   there with the curve's impacts and sticking; the reported point is the last such trial.
//! * **crossing**: two curves (or one with itself) intersect in `(Ω, V)`: segments of their
//!   polylines that intersect, refined by Newton in the two curves' parameters.
//!
//! Positions along a curve are its pseudo-arclength parameter `s` from a curve point `w_k`:
//! trial points are solved on the hyperplane `t·(w − w_k) = s` (`t`: the unit tangent at
//! `w_k`), so `s` is a distance in `(x, x', Ω, V)`. Sign changes between consecutive curve
//! points are located by the Illinois variant of regula falsi, ends by bisection, both to a
//! bracket of [`S_TOL`] in `s` (so `Ω` and `V` are known at least that well). A sign change
//! twice between two curve points is not seen.

use bistable_core::shooting::eigenvalues;

use crate::arclength::period_map;
use crate::bifurcations::det_shifted;
use crate::numerics::{bisect, dot, illinois, norm, solve, sub, Mid};
use crate::twoparam::{tangent, Atlas, CurveOptions, CurvePoint, System, Value};
use crate::Model;

/// Brackets in the curve parameter `s` are shrunk to this length.
pub const S_TOL: f64 = 1e-10;
/// Step (in `(x, x')`) of the central difference of `M·q` along `q`.
pub const CUSP_STEP: f64 = 1e-5;
/// A curve's end whose orbit is this close to the plate at plate phase 0 (`|x0|`, units of
/// `Δx`; the plate is at 0 then) is an impact crossing the stroboscopic section, where the
/// section's impact count and state jump: no grazing, not reported.
pub const SECTION_CONTACT: f64 = 1e-4;
/// Most trial points spent on one root or end.
const MAX_TRIALS: usize = 100;
/// Newton on a crossing stops when its step in `s` is this short.
const CROSSING_STEP: f64 = 1e-12;
/// Two points of curves that cross this close in `(x, x')` are the same orbit on the same
/// curve (a self-crossing at a cusp's tip is none).
const SAME_ORBIT: f64 = 1e-6;

/// What holds at a codimension-two point.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PointKind {
    /// Multipliers `+1` and `−1`: a fold curve meets a period-doubling curve of the same orbit.
    FoldFlip,
    /// The fold's quadratic coefficient vanishes: two folds meet.
    Cusp,
    /// The curve ends where the impacts per period change (it meets a grazing curve).
    ResonantGrazing,
    /// Two curves intersect in `(Ω, V)` (not necessarily at the same orbit).
    Crossing,
}

impl PointKind {
    /// Every kind, in the order of the plots' legends.
    pub const ALL: [PointKind; 4] = [
        PointKind::FoldFlip,
        PointKind::Cusp,
        PointKind::ResonantGrazing,
        PointKind::Crossing,
    ];

    /// The kind as one word: `fold_flip`, `cusp`, `resonant_grazing`, `crossing`.
    pub fn name(self) -> &'static str {
        match self {
            PointKind::FoldFlip => "fold_flip",
            PointKind::Cusp => "cusp",
            PointKind::ResonantGrazing => "resonant_grazing",
            PointKind::Crossing => "crossing",
        }
    }
}

/// A located codimension-two point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Codim2Point {
    /// What holds there.
    pub kind: PointKind,
    /// `Ω`.
    pub omega: f64,
    /// `V` (units of `ω0·Δx`).
    pub velocity: f64,
    /// The curve (index in the atlas) the point lies on.
    pub curve: usize,
    /// The point lies between points `index` and `index + 1` of `curve` (resonant grazing:
    /// beyond its end point `index`).
    pub index: usize,
    /// A crossing: the other curve and the index of its segment (`None` for the other kinds).
    pub other: Option<(usize, usize)>,
    /// Fixed point `x` at plate phase 0 of the orbit of `curve` there (units of `Δx`).
    pub x0: f64,
    /// Its velocity `x'` (units of `ω0·Δx`).
    pub v0: f64,
    /// Its Floquet multipliers `(re, im)`, largest modulus first.
    pub multipliers: [(f64, f64); 2],
    /// Impacts per orbit on `curve` there.
    pub impacts: u64,
    /// Resonant grazing: impacts per orbit just beyond the end; the other kinds: `impacts`.
    pub impacts_beyond: u64,
    /// Bound on the error in the curve parameter `s` (Euclidean in `(x, x', Ω, V)`): the
    /// final bracket (fold–flip, cusp, resonant grazing) or Newton step (crossing), at most
    /// [`S_TOL`] resp. `1e-12` when converged; a crossing Newton could not refine: the
    /// longer of the two polyline segments.
    pub error: f64,
}

fn w_of(c: &CurvePoint) -> [f64; 4] {
    [c.x0, c.v0, c.omega, c.velocity]
}

/// A curve parameterised from one of its points `w`: trial points on the hyperplanes
/// `t·(u − w) = s`.
struct Chart<'a> {
    sys: &'a System<'a>,
    w: [f64; 4],
    /// Unit tangent at `w`.
    t: [f64; 4],
}

impl<'a> Chart<'a> {
    /// The chart at the curve point `w`, its tangent oriented along `along`.
    fn new(sys: &'a System<'a>, w: [f64; 4], along: [f64; 4]) -> Option<Self> {
        let (_, jac, _) = sys.jacobian(w).ok()?;
        Some(Self {
            sys,
            w,
            t: tangent(jac, along)?,
        })
    }

    /// The point at `s`, its value and its unit tangent (oriented along `t`).
    fn at(&self, s: f64) -> Option<([f64; 4], Value, [f64; 4])> {
        let pred = [0, 1, 2, 3].map(|k| self.w[k] + s * self.t[k]);
        let (w, v, jac) = self.sys.correct(pred, self.t)?;
        Some((w, v, tangent(jac, self.t)?))
    }

    /// `s` of the curve point `u` (on a hyperplane of this chart).
    fn s_of(&self, u: [f64; 4]) -> f64 {
        dot(self.t, sub(u, self.w))
    }
}

/// The other test function on a curve of `sign` (+1: fold, −1: period doubling) at
/// multipliers `λ`: `det(M + sign·I)`, the period doubling's on a fold curve and the fold's on
/// a period-doubling curve.
fn other_test(lambda: [(f64, f64); 2], sign: f64) -> f64 {
    det_shifted(lambda, sign)
}

/// The fold's quadratic coefficient `a = ½·⟨p, D²P(q, q)⟩` at the fold-curve point `w` with
/// monodromy `mm`, and `q` (oriented along `q_ref` when given).
fn cusp_coefficient(
    sys: &System<'_>,
    w: [f64; 4],
    mm: [[f64; 2]; 2],
    q_ref: Option<[f64; 2]>,
) -> Option<(f64, [f64; 2])> {
    let a = [[mm[0][0] - 1.0, mm[0][1]], [mm[1][0], mm[1][1] - 1.0]];
    let longer = |u: [f64; 2], v: [f64; 2]| if dot(u, u) >= dot(v, v) { u } else { v };
    // q is normal to the rows of M − I, p to its columns.
    let r = longer(a[0], a[1]);
    let n = dot(r, r).sqrt();
    if n.is_nan() || n <= 0.0 {
        return None;
    }
    let mut q = [-r[1] / n, r[0] / n];
    if q_ref.is_some_and(|g| dot(g, q) < 0.0) {
        q = [-q[0], -q[1]];
    }
    let c = longer([a[0][0], a[1][0]], [a[0][1], a[1][1]]);
    let p = [-c[1], c[0]];
    let pq = dot(p, q);
    let m = sys.model_at(w[2], w[3]).ok()?;
    let h = CUSP_STEP;
    let map = |e: f64| {
        period_map(
            &m,
            w[2],
            sys.period,
            [w[0] + e * q[0], w[1] + e * q[1]],
            true,
        )
    };
    let (plus, minus) = (map(h).ok()?, map(-h).ok()?);
    if (plus.2, plus.3) != (minus.2, minus.3) {
        return None;
    }
    let dm = |i: usize| {
        ((plus.1[i][0] - minus.1[i][0]) * q[0] + (plus.1[i][1] - minus.1[i][1]) * q[1]) / (2.0 * h)
    };
    let a2 = 0.5 * dot(p, [dm(0), dm(1)]) / pq;
    a2.is_finite().then_some((a2, q))
}

/// The root of `f` between the curve parameters of `a` and `b` (`f(a)·f(b) < 0`) by the
/// Illinois variant of regula falsi to [`S_TOL`]: the last trial and the final bracket's
/// length (`None` if `f` fails).
fn root(f: impl Fn(f64) -> Option<f64>, a: (f64, f64), b: (f64, f64)) -> Option<(f64, f64)> {
    illinois(a, b, S_TOL, MAX_TRIALS, s_len, |&lo, &hi, g| {
        let s = lo + g * (hi - lo);
        f(s).map(|v| (s, v))
    })
}

/// Length of a bracket in the curve parameter.
fn s_len(a: &f64, b: &f64) -> f64 {
    (b - a).abs()
}

fn located(
    kind: PointKind,
    curve: usize,
    index: usize,
    (w, v): ([f64; 4], &Value),
    error: f64,
) -> Codim2Point {
    Codim2Point {
        kind,
        omega: w[2],
        velocity: w[3],
        curve,
        index,
        other: None,
        x0: w[0],
        v0: w[1],
        multipliers: eigenvalues(v.1),
        impacts: v.2,
        impacts_beyond: v.2,
        error,
    }
}

/// The fold–flip points and cusps on curve `k` of system `sys`.
fn sign_changes(sys: &System<'_>, k: usize, curve: &[CurvePoint], out: &mut Vec<Codim2Point>) {
    let fold = sys.sign > 0.0;
    let g: Vec<f64> = curve
        .iter()
        .map(|c| other_test(c.multipliers, sys.sign))
        .collect();
    // The cusp coefficient and q at every point of a fold curve.
    let mut cusp: Vec<Option<(f64, [f64; 2])>> = Vec::new();
    if fold {
        let mut q_ref = None;
        for c in curve {
            let w = w_of(c);
            let a = sys
                .value(w)
                .ok()
                .and_then(|v| cusp_coefficient(sys, w, v.1, q_ref));
            if let Some((_, q)) = a {
                q_ref = Some(q);
            }
            cusp.push(a);
        }
    }
    for j in 0..curve.len().saturating_sub(1) {
        let (w0, w1) = (w_of(&curve[j]), w_of(&curve[j + 1]));
        let along = sub(w1, w0);
        let chart = || Chart::new(sys, w0, along);
        if g[j] * g[j + 1] < 0.0 {
            if let Some(c) = chart() {
                let s1 = c.s_of(w1);
                let f = |s: f64| {
                    c.at(s)
                        .map(|(_, v, _)| other_test(eigenvalues(v.1), sys.sign))
                };
                if let Some((s, err)) = root(f, (0.0, g[j]), (s1, g[j + 1])) {
                    if let Some((w, v, _)) = c.at(s) {
                        out.push(located(PointKind::FoldFlip, k, j, (w, &v), err));
                    }
                }
            }
        }
        if let (Some(Some((a0, q0))), Some(Some((a1, _)))) = (cusp.get(j), cusp.get(j + 1)) {
            if a0 * a1 < 0.0 {
                let Some(c) = chart() else { continue };
                let s1 = c.s_of(w1);
                let f = |s: f64| {
                    let (w, v, _) = c.at(s)?;
                    cusp_coefficient(sys, w, v.1, Some(*q0)).map(|(a, _)| a)
                };
                if let Some((s, err)) = root(f, (0.0, *a0), (s1, *a1)) {
                    if let Some((w, v, _)) = c.at(s) {
                        out.push(located(PointKind::Cusp, k, j, (w, &v), err));
                    }
                }
            }
        }
    }
}

/// The ends of curve `k` inside the bounds of `o` where the impacts per period change.
///
/// From the end point, trials along the curve are bisected to [`S_TOL`] between the last one
/// the corrector solves on the curve's side (same impacts and sticking) and the first it does
/// not. The corrector's finite differences fail once their stencil straddles the grazing, so
/// the change itself is then located on the tangent line from that last trial `u`: the impacts
/// of the period map at `u + σ·t` are bisected in `σ`. The tangent line leaves the curve by
/// about `κ·σ²` (`κ`: the curve's curvature from its last two tangents), which with the
/// brackets bounds the error. Ends at an impact at the section ([`SECTION_CONTACT`]) are left
/// out; the multipliers reported are those of `u`.
fn grazing_ends(
    sys: &System<'_>,
    k: usize,
    curve: &[CurvePoint],
    o: CurveOptions,
    out: &mut Vec<Codim2Point>,
) {
    let n = curve.len();
    if n < 2 {
        return;
    }
    let inside = |x: f64, (lo, hi): (f64, f64)| x > lo && x < hi;
    for (end, prev) in [(0, 1), (n - 1, n - 2)] {
        let (c, p) = (&curve[end], &curve[prev]);
        if !(inside(c.omega, o.omega_bounds) && inside(c.velocity, o.velocity_bounds)) {
            continue;
        }
        let (w, wp) = (w_of(c), w_of(p));
        let Ok(v_end) = sys.value(w) else { continue };
        let side = (v_end.2, v_end.3);
        let (Some(chart), Some(before)) = (
            Chart::new(sys, w, sub(w, wp)),
            Chart::new(sys, wp, sub(w, wp)),
        ) else {
            continue;
        };
        let good = |s: f64| chart.at(s).filter(|(_, v, _)| (v.2, v.3) == side);
        // The first trial off the curve's side, doubling from 1e-6 of the largest step.
        let (mut lo, mut u, mut v_u) = (0.0, w, v_end);
        let mut hi = None;
        let mut s = 1e-6 * o.ds_max;
        while s <= o.ds_max {
            match good(s) {
                Some(g) => (lo, u, v_u) = (s, g.0, g.1),
                None => {
                    hi = Some(s);
                    break;
                }
            }
            s *= 2.0;
        }
        let Some(hi) = hi else { continue };
        if u[0].abs() <= SECTION_CONTACT {
            continue;
        }
        let (lo, hi) = bisect((lo, hi), S_TOL, MAX_TRIALS, s_len, |&lo, &hi| {
            let mid = 0.5 * (lo + hi);
            match good(mid) {
                Some(g) => {
                    (u, v_u) = (g.0, g.1);
                    Mid::Lo(mid)
                }
                None => Mid::Hi(mid),
            }
        });
        // The impacts along the tangent line from u.
        let impacts_at = |sigma: f64| {
            let b = [0, 1, 2, 3].map(|i| u[i] + sigma * chart.t[i]);
            let m = sys.model_at(b[2], b[3]).ok()?;
            let r = period_map(&m, b[2], sys.period, [b[0], b[1]], false).ok()?;
            Some((r.2, r.3))
        };
        let (mut same, mut sigma) = (0.0, S_TOL);
        let mut far = None;
        while sigma <= o.ds_max {
            match impacts_at(sigma) {
                Some(r) if r == side => same = sigma,
                Some((impacts, sticks)) if sticks == side.1 => {
                    far = Some((sigma, impacts));
                    break;
                }
                _ => break,
            }
            sigma *= 2.0;
        }
        let Some((far, mut beyond)) = far else {
            continue;
        };
        let (same, far) = bisect((same, far), S_TOL, MAX_TRIALS, s_len, |&same, &far| {
            let mid = 0.5 * (same + far);
            match impacts_at(mid) {
                Some(r) if r == side => Mid::Lo(mid),
                Some((impacts, sticks)) if sticks == side.1 => {
                    beyond = impacts;
                    Mid::Hi(mid)
                }
                _ => Mid::Stop,
            }
        });
        let at = [0, 1, 2, 3].map(|i| u[i] + same * chart.t[i]);
        let kappa = norm(sub(chart.t, before.t)) / chart.s_of(w).abs().max(norm(sub(w, wp)));
        let error = (hi - lo) + (far - same) + kappa * far * far;
        let mut q = located(PointKind::ResonantGrazing, k, end, (at, &v_u), error);
        q.impacts_beyond = beyond;
        out.push(q);
    }
}

/// Where segments `a0–a1` and `b0–b1` meet: the fractions `(α, β) ∈ [0, 1)²` along them.
fn intersect(a0: (f64, f64), a1: (f64, f64), b0: (f64, f64), b1: (f64, f64)) -> Option<(f64, f64)> {
    let (da, db) = ((a1.0 - a0.0, a1.1 - a0.1), (b1.0 - b0.0, b1.1 - b0.1));
    let den = da.0 * db.1 - da.1 * db.0;
    if den == 0.0 {
        return None;
    }
    let r = (b0.0 - a0.0, b0.1 - a0.1);
    let alpha = (r.0 * db.1 - r.1 * db.0) / den;
    let beta = (r.0 * da.1 - r.1 * da.0) / den;
    ((0.0..1.0).contains(&alpha) && (0.0..1.0).contains(&beta)).then_some((alpha, beta))
}

/// `d(Ω, V)/ds` of a chart's curve at a point with unit tangent `tn`.
fn velocity_in_plane(chart: &Chart<'_>, tn: [f64; 4]) -> [f64; 2] {
    let d = dot(chart.t, tn);
    [tn[2] / d, tn[3] / d]
}

/// A solved point of a curve with its value.
type Solved = ([f64; 4], Value);

/// The crossing of the segments `(i, a)` and `(j, b)` refined by Newton in the two curves'
/// parameters: the points on each curve and the last step (`None` if Newton fails).
fn refine_crossing(
    (ca, sa0): (&Chart<'_>, f64),
    (cb, sb0): (&Chart<'_>, f64),
) -> Option<(Solved, [f64; 4], f64)> {
    let (mut sa, mut sb) = (sa0, sb0);
    for _ in 0..20 {
        let (wa, va, ta) = ca.at(sa)?;
        let (wb, _, tb) = cb.at(sb)?;
        let (da, db) = (velocity_in_plane(ca, ta), velocity_in_plane(cb, tb));
        let r = [wa[2] - wb[2], wa[3] - wb[3]];
        // da·δa − db·δb = −r
        let [step_a, step_b] = solve([[da[0], -db[0]], [da[1], -db[1]]], [-r[0], -r[1]])?;
        sa += step_a;
        sb += step_b;
        let step = step_a.abs().max(step_b.abs());
        if step <= CROSSING_STEP {
            let (wa, va) = ca.at(sa).map(|(w, v, _)| (w, v)).unwrap_or((wa, va));
            let wb = cb.at(sb).map(|(w, ..)| w).unwrap_or(wb);
            return Some(((wa, va), wb, step));
        }
    }
    None
}

/// The crossings of the curves of `atlas` in `(Ω, V)`.
fn crossings(model: &Model, atlas: &Atlas, out: &mut Vec<Codim2Point>) {
    let plane = |c: &CurvePoint| (c.omega, c.velocity);
    for (i, (si, ci)) in atlas.iter().enumerate() {
        for (j, (sj, cj)) in atlas.iter().enumerate().skip(i) {
            for a in 0..ci.len().saturating_sub(1) {
                let first_b = if i == j { a + 2 } else { 0 };
                for b in first_b..cj.len().saturating_sub(1) {
                    let Some((alpha, beta)) = intersect(
                        plane(&ci[a]),
                        plane(&ci[a + 1]),
                        plane(&cj[b]),
                        plane(&cj[b + 1]),
                    ) else {
                        continue;
                    };
                    let systems = (
                        System::new(model, si.kind, si.period),
                        System::new(model, sj.kind, sj.period),
                    );
                    let (Ok(sys_a), Ok(sys_b)) = systems else {
                        continue;
                    };
                    let chart = |sys, c: &[CurvePoint], k: usize| {
                        let (w0, w1) = (w_of(&c[k]), w_of(&c[k + 1]));
                        let ch = Chart::new(sys, w0, sub(w1, w0))?;
                        let s1 = ch.s_of(w1);
                        Some((ch, s1))
                    };
                    let refined = match (chart(&sys_a, ci, a), chart(&sys_b, cj, b)) {
                        (Some((ca, la)), Some((cb, lb))) => {
                            refine_crossing((&ca, alpha * la), (&cb, beta * lb))
                        }
                        _ => None,
                    };
                    let p = match refined {
                        Some(((wa, va), wb, step)) => {
                            let same = (wa[0] - wb[0]).hypot(wa[1] - wb[1]) < SAME_ORBIT;
                            if i == j && same {
                                continue;
                            }
                            located(PointKind::Crossing, i, a, (wa, &va), step)
                        }
                        None => {
                            // The polyline's intersection, with the orbit of the segment's
                            // start.
                            let (p0, p1) = (&ci[a], &ci[a + 1]);
                            let len = |c: &[CurvePoint], k: usize| {
                                let (u, v) = (w_of(&c[k]), w_of(&c[k + 1]));
                                norm(sub(u, v))
                            };
                            Codim2Point {
                                kind: PointKind::Crossing,
                                omega: p0.omega + alpha * (p1.omega - p0.omega),
                                velocity: p0.velocity + alpha * (p1.velocity - p0.velocity),
                                curve: i,
                                index: a,
                                other: None,
                                x0: p0.x0,
                                v0: p0.v0,
                                multipliers: p0.multipliers,
                                impacts: p0.impacts,
                                impacts_beyond: p0.impacts,
                                error: len(ci, a).max(len(cj, b)),
                            }
                        }
                    };
                    out.push(Codim2Point {
                        other: Some((j, b)),
                        ..p
                    });
                }
            }
        }
    }
}

/// The codimension-two points of `atlas` (as [`crate::twoparam::trace_all`] gives it, with
/// the options `o` it was traced with; `model`: any model of the run's ζ and e): per curve,
/// its fold–flip points and cusps in the curve's order and its resonant-grazing ends (low-V
/// end first), then the crossings (by the first curve and segment).
pub fn points(model: &Model, atlas: &Atlas, o: CurveOptions) -> Vec<Codim2Point> {
    let mut out = Vec::new();
    for (k, (start, curve)) in atlas.iter().enumerate() {
        let Ok(sys) = System::new(model, start.kind, start.period) else {
            continue;
        };
        sign_changes(&sys, k, curve, &mut out);
        grazing_ends(&sys, k, curve, o, &mut out);
    }
    crossings(model, atlas, &mut out);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn segments_intersect_once() {
        let (a, b) = intersect((0.0, 0.0), (2.0, 2.0), (0.0, 2.0), (2.0, 0.0)).unwrap();
        assert!((a - 0.5).abs() < 1e-15 && (b - 0.5).abs() < 1e-15);
        assert!(intersect((0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)).is_none());
        assert!(intersect((0.0, 0.0), (1.0, 1.0), (2.0, 0.0), (3.0, -1.0)).is_none());
    }

    #[test]
    fn the_other_test_function_is_det_m_plus_or_minus_i() {
        // M = diag(1, −1): det(M + I) = det(M − I) = 0; diag(0.5, 0.2): 1.8 and 0.4.
        assert_eq!(other_test([(1.0, 0.0), (-1.0, 0.0)], 1.0), 0.0);
        assert!((other_test([(0.5, 0.0), (0.2, 0.0)], 1.0) - 1.8).abs() < 1e-15);
        assert!((other_test([(0.5, 0.0), (0.2, 0.0)], -1.0) - 0.4).abs() < 1e-15);
    }
}
