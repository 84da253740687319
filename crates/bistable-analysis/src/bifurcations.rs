//! Bifurcation points on branches of periodic orbits continued in Ω at fixed V: every change
//! between consecutive orbits of a branch is detected, located and classified.
//!
//! Between two consecutive orbits `a`, `b` of a branch (fixed points of the `p`-period map in
//! `u = (x, x', Ω)`), a bracket of two solved orbits is shrunk: each trial orbit is predicted
//! on the chord between the bracket's ends and solved for the map's fixed-point equations in
//! the plane normal to that chord (the pseudo-arclength corrector), so the parametrisation
//! holds through folds. Then:
//!
//! * **grazing** / **sticking**: when the impacts per period (or whether the mass sticks)
//!   differ at `a` and `b`, bisection brackets the change to [`NONSMOOTH_TOL`] in `(x, x', Ω)`
//!   (re-solving the orbit at each trial); the test functions below jump there, so they are
//!   only used on the smooth pieces on either side of the bracket. Near a grazing corner the
//!   impacting side's multipliers grow without bound and the corrector may stop converging:
//!   the bracket then stays wider. A grazing point is therefore also approached along each
//!   side at fixed Ω by its own smooth test function ([`crate::grazing`]: the minimum gap of
//!   the flight that comes to touch, or the new impact's speed), which locates it to
//!   [`GRAZING_TOL`] even at a corner, where the point lies outside the chord's Ω range; the
//!   point reported is the one with the smaller error. The impact counts of
//!   orbits that stick on both sides are not compared (the chatter before sticking is
//!   truncated by the chatter rule, so its count is no grazing).
//! * on each smooth piece, a sign change of a test function of the monodromy matrix `M` is
//!   located by the Illinois variant of regula falsi to [`SMOOTH_TOL`]: **fold**
//!   `det(M − I)` (a multiplier through +1), **period doubling** `det(M + I)` (through −1),
//!   **Neimark–Sacker** `det M − 1` while the multipliers are a complex pair (their modulus
//!   through 1; with damping or `e < 1`, `det M < 1` always, so this cannot occur in the
//!   paper's model, but is checked all the same).
//!
//! A test function that changes sign twice between two orbits of the branch is not seen: the
//! detection is as fine as the branch's points. On a branch of period `p > 1`, points whose
//! orbit has a smaller period (where an arclength trace of `p`-periodic orbits runs onto the
//! orbit it doubled from) are not reported: that orbit's own branch reports them.

use std::num::NonZeroU32;

use bistable_core::shooting::eigenvalues;
use bistable_core::SimError;

use crate::arclength::{correct, period_map, ArcPoint};
use crate::branches::Branches;
use crate::continuation::Curves;
use crate::cycles::record_cycles;
use crate::grazing::{approach, Test, GRAZING_TOL};
use crate::numerics::{bisect, illinois, norm, sub, Mid};
use crate::orbit::Orbit;
use crate::parallel::{self, Threads};
use crate::progress::{OnProgress, Progress, Stage};
use crate::Model;

/// Bisection of a grazing or sticking change stops when its bracket is this short (Euclidean
/// in `(x, x', Ω)`, so Ω is known at least this well).
pub const NONSMOOTH_TOL: f64 = 1e-10;
/// Regula falsi on a smooth test function stops when its bracket is this short (as
/// [`NONSMOOTH_TOL`]).
pub const SMOOTH_TOL: f64 = 1e-12;
/// Samples per shaker period for the largest displacement of a located orbit.
const SAMPLES: NonZeroU32 = NonZeroU32::new(128).expect("128 > 0");
/// Most corrector solves spent on one root.
const MAX_SOLVES: usize = 80;
/// A `p`-periodic orbit whose section point `d | p` periods on is this close (max norm,
/// relative to `max(1, |y|)`) has the smaller period `d`.
const SMALLER_PERIOD: f64 = 1e-6;

/// What changes at a bifurcation point.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Kind {
    /// A Floquet multiplier passes through +1 (saddle-node, the branch turns in Ω).
    Fold,
    /// A multiplier passes through −1 (an orbit of twice the period is born).
    PeriodDoubling,
    /// A complex pair of multipliers crosses the unit circle (torus).
    NeimarkSacker,
    /// The impacts per period change: a flight's minimum gap reaches zero with zero relative
    /// velocity.
    Grazing,
    /// The orbit starts or stops sticking to the plate.
    Sticking,
}

impl Kind {
    /// Every kind, in the order of the plots' legends.
    pub const ALL: [Kind; 5] = [
        Kind::Fold,
        Kind::PeriodDoubling,
        Kind::NeimarkSacker,
        Kind::Grazing,
        Kind::Sticking,
    ];

    /// The kind as one word: `fold`, `period_doubling`, `neimark_sacker`, `grazing`,
    /// `sticking`.
    pub fn name(self) -> &'static str {
        match self {
            Kind::Fold => "fold",
            Kind::PeriodDoubling => "period_doubling",
            Kind::NeimarkSacker => "neimark_sacker",
            Kind::Grazing => "grazing",
            Kind::Sticking => "sticking",
        }
    }

    /// The test function of a smooth kind at multipliers `λ`: `det(M − I)`, `det(M + I)` or
    /// `det M − 1` (`None` for the non-smooth kinds).
    fn test(self, lambda: [(f64, f64); 2]) -> Option<f64> {
        match self {
            Kind::Fold => Some(det_shifted(lambda, -1.0)),
            Kind::PeriodDoubling => Some(det_shifted(lambda, 1.0)),
            Kind::NeimarkSacker => Some(det(lambda) - 1.0),
            Kind::Grazing | Kind::Sticking => None,
        }
    }
}

/// `det M` of a real 2×2 matrix with eigenvalues `λ` (`λ1·λ2`, real for a real matrix).
fn det(lambda: [(f64, f64); 2]) -> f64 {
    lambda[0].0 * lambda[1].0 - lambda[0].1 * lambda[1].1
}

/// `det(M + s·I) = 1 + s·tr M + det M` of a real 2×2 matrix with eigenvalues `λ`, `s` = ±1:
/// the fold's test function with `s = −1`, the period doubling's with `s = +1`.
pub(crate) fn det_shifted(lambda: [(f64, f64); 2], s: f64) -> f64 {
    1.0 + s * (lambda[0].0 + lambda[1].0) + det(lambda)
}

/// One orbit of a branch, as the locator sees it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BranchPoint {
    /// `Ω`.
    pub omega: f64,
    /// Fixed point `x` at plate phase 0 (units of `Δx`).
    pub x0: f64,
    /// Its velocity `x'` (units of `ω0·Δx`).
    pub v0: f64,
    /// Floquet multipliers `(re, im)`, largest modulus first.
    pub multipliers: [(f64, f64); 2],
    /// Impacts per orbit.
    pub impacts: u64,
    /// Whether the mass sticks on the orbit.
    pub sticks: bool,
}

impl From<&ArcPoint> for BranchPoint {
    fn from(a: &ArcPoint) -> Self {
        Self {
            omega: a.omega,
            x0: a.x0,
            v0: a.v0,
            multipliers: a.multipliers,
            impacts: a.impacts,
            sticks: a.sticks,
        }
    }
}

impl From<&Orbit> for BranchPoint {
    fn from(o: &Orbit) -> Self {
        let p = &o.orbit;
        Self {
            omega: p.omega,
            x0: p.x0,
            v0: p.v0,
            multipliers: p.multipliers,
            impacts: p.impacts,
            sticks: p.sticks,
        }
    }
}

impl BranchPoint {
    fn u(&self) -> [f64; 3] {
        [self.x0, self.v0, self.omega]
    }
}

/// A located bifurcation point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BifurcationPoint {
    /// What changes.
    pub kind: Kind,
    /// `Ω` at the point.
    pub omega: f64,
    /// `V` of the branch.
    pub velocity: f64,
    /// Period of the branch's orbits in shaker periods.
    pub period: u32,
    /// Fixed point `x` at plate phase 0 of the orbit at the point (grazing: the solved orbit
    /// nearest it on the side it was approached from, normally the one with fewer impacts,
    /// or after a bisection, as for sticking: the orbit at the end of the final bracket on the
    /// side of `before`).
    pub x0: f64,
    /// Its velocity `x'`.
    pub v0: f64,
    /// Floquet multipliers `(re, im)` of that orbit, largest modulus first.
    pub multipliers: [(f64, f64); 2],
    /// Largest displacement on that orbit (units of `Δx`, sampled 128 times per shaker
    /// period; NaN if its simulation failed).
    pub max_x: f64,
    /// Bound on the error of `omega`: the distance in `(x, x', Ω)` of the final bracket's
    /// orbits (smooth kinds: regula falsi, at most [`SMOOTH_TOL`] when it converged; sticking:
    /// bisection, at most [`NONSMOOTH_TOL`] when it converged; grazing: the final bracket in Ω
    /// of the test function's approach, at most [`GRAZING_TOL`] when it converged, or the
    /// bisection's where that is smaller).
    pub omega_error: f64,
    /// Which branch of the caller's list the point is on.
    pub branch: usize,
    /// The point lies between orbits `index` and `index + 1` of that branch.
    pub index: usize,
    /// Impacts per period of the orbits on the side of orbit `index`.
    pub impacts_before: u64,
    /// ... and on the side of orbit `index + 1`.
    pub impacts_after: u64,
    /// Whether the orbits on the side of orbit `index` stick.
    pub sticks_before: bool,
    /// ... and on the side of orbit `index + 1`.
    pub sticks_after: bool,
}

/// A solved orbit of the interval: its position `s` along it (0 at `a`, the chord length at
/// `b`, interpolated for trial orbits: used only to order the points found), `u`, multipliers,
/// impacts and sticking.
#[derive(Debug, Clone, Copy)]
struct Solved {
    s: f64,
    u: [f64; 3],
    multipliers: [(f64, f64); 2],
    impacts: u64,
    sticks: bool,
}

impl Solved {
    /// As [`side`].
    fn side(&self) -> (u64, bool) {
        (if self.sticks { 0 } else { self.impacts }, self.sticks)
    }
}

/// The orbits of one interval of a branch, each solved in the plane normal to the chord of
/// the current bracket.
struct Chord<'a> {
    model: &'a Model,
    period: u32,
}

impl Chord<'_> {
    /// The orbit a fraction `f` of the way from `lo` to `hi` (solved orbits): predicted on
    /// their chord, corrected in the plane normal to it; `None` when the corrector fails or
    /// lands further from the prediction than the chord is long (on another part of the
    /// branch). Its `s` is interpolated from theirs.
    fn at(&self, lo: &Solved, hi: &Solved, f: f64) -> Option<Solved> {
        let d = sub(hi.u, lo.u);
        let len = norm(d);
        if !(len.is_finite() && len > 0.0) {
            return None;
        }
        let pred = [0, 1, 2].map(|k| lo.u[k] + f * d[k]);
        let s = lo.s + f * (hi.s - lo.s);
        let near = |u: [f64; 3]| norm(sub(u, pred)) <= len;
        correct(self.model, self.period, pred, d.map(|c| c / len))
            .filter(|(u, ..)| near(*u))
            .map(|(u, e, _)| Solved {
                s,
                u,
                multipliers: eigenvalues(e.m),
                impacts: e.impacts,
                sticks: e.sticks,
            })
    }

    /// The orbit near the fraction `f` from `lo` to `hi`, or if none is found there, at
    /// a quarter of the bracket nearer either end.
    fn near(&self, lo: &Solved, hi: &Solved, f: f64) -> Option<Solved> {
        [f, 0.5 * f, 0.5 * (1.0 + f)]
            .into_iter()
            .find_map(|g| self.at(lo, hi, g))
    }

    /// Bisects between `lo` and `hi` (different impacts or sticking) to [`NONSMOOTH_TOL`];
    /// the final bracket, shorter only as far as the corrector converged.
    fn bisect(&self, lo: Solved, hi: Solved) -> (Solved, Solved) {
        bisect(
            (lo, hi),
            NONSMOOTH_TOL,
            MAX_SOLVES,
            dist,
            |lo, hi| match self.near(lo, hi, 0.5) {
                Some(mid) if mid.side() == lo.side() => Mid::Lo(mid),
                Some(mid) => Mid::Hi(mid),
                None => Mid::Stop,
            },
        )
    }

    /// The root of `kind`'s test function between `lo` and `hi` (of opposite signs) by the
    /// Illinois method to [`SMOOTH_TOL`]: the last orbit solved and the length of the final
    /// bracket in `(x, x', Ω)`.
    fn root(&self, kind: Kind, lo: Solved, hi: Solved) -> Option<(Solved, f64)> {
        let f = |p: &Solved| kind.test(p.multipliers).unwrap_or(f64::NAN);
        illinois(
            (lo, f(&lo)),
            (hi, f(&hi)),
            SMOOTH_TOL,
            MAX_SOLVES,
            dist,
            |lo, hi, g| {
                let p = self.near(lo, hi, g)?;
                (p.side() == lo.side()).then(|| (p, f(&p)))
            },
        )
    }
}

/// Distance of two solved orbits in `(x, x', Ω)`.
fn dist(a: &Solved, b: &Solved) -> f64 {
    norm(sub(b.u, a.u))
}

/// Whether a point on the way from `a` to `b` may hold a bifurcation: a change of impacts or
/// sticking, or a sign change of a test function.
fn changes(a: &BranchPoint, b: &BranchPoint) -> bool {
    side(a) != side(b) || smooth_kinds(a.multipliers, b.multipliers).next().is_some()
}

/// What must agree on both sides of a smooth stretch: the impacts per period and sticking.
/// Orbits that stick on both sides count as one side whatever their impacts: the number of
/// chatter impacts before the mass settles on the plate changes with the chatter rule's
/// truncation, not with a grazing flight.
fn side(p: &BranchPoint) -> (u64, bool) {
    (if p.sticks { 0 } else { p.impacts }, p.sticks)
}

/// The smooth kinds whose test functions have opposite signs at `la` and `lb`.
fn smooth_kinds(la: [(f64, f64); 2], lb: [(f64, f64); 2]) -> impl Iterator<Item = Kind> {
    [Kind::Fold, Kind::PeriodDoubling, Kind::NeimarkSacker]
        .into_iter()
        .filter(move |k| {
            let (fa, fb) = (k.test(la), k.test(lb));
            matches!((fa, fb), (Some(x), Some(y)) if x * y < 0.0)
        })
}

/// Whether the `period`-periodic orbit at `u` has a smaller period.
fn smaller_period(model: &Model, period: u32, u: [f64; 3]) -> bool {
    let y = [u[0], u[1]];
    let scale = y[0].abs().max(y[1].abs()).max(1.0);
    (1..period).filter(|&d| period.is_multiple_of(d)).any(|d| {
        match period_map(model, u[2], d, y, false) {
            Ok((py, ..)) => (py[0] - y[0]).abs().max((py[1] - y[1]).abs()) < SMALLER_PERIOD * scale,
            Err(_) => false,
        }
    })
}

/// The bifurcation points between the consecutive orbits `a` and `b` of a branch of
/// `period`-periodic orbits at `model`'s V (`model`: any model of the branch; Ω comes from the
/// orbits), in the order met from `a` to `b`. `branch` and `index` label them.
pub fn between(
    model: &Model,
    period: u32,
    a: &BranchPoint,
    b: &BranchPoint,
    branch: usize,
    index: usize,
) -> Vec<BifurcationPoint> {
    let (ua, ub) = (a.u(), b.u());
    let len = norm(sub(ub, ua));
    if !(len.is_finite() && len > 0.0 && changes(a, b)) {
        return Vec::new();
    }
    let chord = Chord { model, period };
    let end = |p: &BranchPoint, s: f64| Solved {
        s,
        u: p.u(),
        multipliers: p.multipliers,
        impacts: p.impacts,
        sticks: p.sticks,
    };
    let (sa, sb) = (end(a, 0.0), end(b, len));
    let point =
        |kind: Kind, at: &Solved, err: f64, before: &Solved, after: &Solved| BifurcationPoint {
            kind,
            omega: at.u[2],
            velocity: model.velocity(),
            period,
            x0: at.u[0],
            v0: at.u[1],
            multipliers: at.multipliers,
            max_x: f64::NAN,
            omega_error: err,
            branch,
            index,
            impacts_before: before.impacts,
            impacts_after: after.impacts,
            sticks_before: before.sticks,
            sticks_after: after.sticks,
        };
    // The smooth pieces, and the non-smooth change between them.
    let mut pieces = vec![(sa, sb)];
    let mut out = Vec::new();
    if sa.side() != sb.side() {
        let (lo, hi) = chord.bisect(sa, sb);
        let kind = if lo.sticks != hi.sticks {
            Kind::Sticking
        } else {
            Kind::Grazing
        };
        let mid = Solved {
            u: [0, 1, 2].map(|k| 0.5 * (lo.u[k] + hi.u[k])),
            ..lo
        };
        // The change lies on the branch between the bracket's orbits, so Ω is known to their
        // distance (also where Ω hardly differs: the branch can turn at a grazing corner).
        let err = (hi.u[2] - lo.u[2]).abs().max(dist(&lo, &hi));
        let p = match grazing_point(model, period, &sa, &sb) {
            // Located by its test functions, where they did better than the bisection.
            Some(g) if kind == Kind::Grazing && g.error < err => BifurcationPoint {
                omega: g.omega,
                ..point(kind, &g.at, g.error, &lo, &hi)
            },
            _ => BifurcationPoint {
                omega: mid.u[2],
                ..point(kind, &lo, err, &lo, &hi)
            },
        };
        out.push((mid.s, p));
        pieces = vec![(sa, lo), (hi, sb)];
    }
    for (lo, hi) in pieces {
        if lo.side() != hi.side() {
            continue;
        }
        for kind in smooth_kinds(lo.multipliers, hi.multipliers) {
            let Some((at, err)) = chord.root(kind, lo, hi) else {
                continue;
            };
            // The modulus of a real pair through 1 is no Neimark–Sacker bifurcation.
            if kind == Kind::NeimarkSacker && at.multipliers[0].1 == 0.0 {
                continue;
            }
            out.push((at.s, point(kind, &at, err, &lo, &hi)));
        }
    }
    out.retain(|(_, p)| period == 1 || !smaller_period(model, period, [p.x0, p.v0, p.omega]));
    out.sort_by(|x, y| x.0.total_cmp(&y.0));
    out.into_iter()
        .map(|(_, mut p)| {
            p.max_x = max_x(model, period, [p.x0, p.v0, p.omega]).unwrap_or(f64::NAN);
            p
        })
        .collect()
}

/// A grazing point between orbits `a` and `b` of a branch.
struct Grazed {
    /// `Ω` at the point.
    omega: f64,
    /// Bound on its error (the final bracket of the approach it comes from).
    error: f64,
    /// The orbit of that approach nearest the point.
    at: Solved,
}

/// The grazing point between `a` and `b` (different impacts, neither sticks), approached
/// along each side at fixed Ω ([`grazing::approach`]: the minimum gap on the side with
/// fewer impacts, the impact speed on the other): the minimum-gap side's estimate while it
/// converged to [`GRAZING_TOL`] or has the smaller error, else the other's. `None` when
/// neither approach succeeds.
fn grazing_point(model: &Model, period: u32, a: &Solved, b: &Solved) -> Option<Grazed> {
    if a.sticks || b.sticks {
        return None;
    }
    let (few, many) = if a.impacts < b.impacts {
        (a, b)
    } else {
        (b, a)
    };
    let gap = approach(model, period, few.u, Test::Gap);
    let speed = approach(model, period, many.u, Test::Speed);
    let g = match (gap, speed) {
        (Some(g), Some(s)) => {
            if g.error <= GRAZING_TOL || g.error <= s.error {
                g
            } else {
                s
            }
        }
        (Some(g), None) => g,
        (None, s) => s?,
    };
    let n = g.path.last()?;
    Some(Grazed {
        omega: g.omega,
        error: g.error,
        at: Solved {
            s: 0.5 * (a.s + b.s),
            u: n.u,
            multipliers: n.multipliers(),
            impacts: n.eval.impacts,
            sticks: n.eval.sticks,
        },
    })
}

/// Largest displacement on the `period`-periodic orbit through `(x, x')` at `Ω` (`u`).
fn max_x(model: &Model, period: u32, u: [f64; 3]) -> Result<f64, SimError> {
    let here = model.at(u[2], model.velocity())?;
    let mut sim = here.simulator_from(u[0].max(0.0), u[1])?;
    let c = record_cycles(&mut sim, here.shaker, 0, period, SAMPLES)?;
    Ok(c.max_x.iter().copied().fold(f64::MIN, f64::max))
}

/// One branch to search: a model at its V, its period and its orbits in order along it.
#[derive(Debug, Clone)]
pub struct Branch {
    /// Any model at the branch's V (Ω comes from the orbits).
    pub model: Model,
    /// Period in shaker periods.
    pub period: u32,
    /// The orbits in order along the branch.
    pub points: Vec<BranchPoint>,
}

impl Branch {
    /// The polylines of natural continuation `b` over the grid `models` (one V), one branch
    /// each (orbits by increasing Ω). A `p`-periodic orbit has `p` section points, each a
    /// fixed point of the `p`-period map; each orbit is represented by the one nearest to
    /// that of the orbit before it, so that consecutive points follow one fixed point.
    pub fn from_natural(models: &[Model], b: &Branches) -> Vec<Branch> {
        b.paths()
            .into_iter()
            .map(|path| {
                let mut points: Vec<BranchPoint> = Vec::with_capacity(path.len());
                for &n in &path {
                    let o = b.orbit(n);
                    let mut p = BranchPoint::from(o);
                    if let Some(prev) = points.last() {
                        let d = |&(x, v): &(f64, f64)| (x - prev.x0).hypot(v - prev.v0);
                        if let Some(&(x, v)) =
                            o.sections.iter().min_by(|a, c| d(a).total_cmp(&d(c)))
                        {
                            (p.x0, p.v0) = (x, v);
                        }
                    }
                    points.push(p);
                }
                Branch {
                    model: models[path[0].0],
                    period: b.period,
                    points,
                }
            })
            .collect()
    }

    /// The branches of `curves`, the continuation of `period`-periodic orbits over the grid
    /// `models` (one V): [`Branch::from_natural`] or [`Branch::from_traces`] as the method was.
    pub fn from_curves(models: &[Model], period: u32, curves: &Curves) -> Vec<Branch> {
        match curves {
            Curves::Natural(b) => Self::from_natural(models, b),
            Curves::Arclength(t) => Self::from_traces(&models[0], period, t),
        }
    }

    /// The pseudo-arclength `traces` of `period`-periodic orbits at `model`'s V, one branch
    /// each.
    pub fn from_traces(model: &Model, period: u32, traces: &[Vec<ArcPoint>]) -> Vec<Branch> {
        traces
            .iter()
            .map(|t| Branch {
                model: *model,
                period,
                points: t.iter().map(BranchPoint::from).collect(),
            })
            .collect()
    }
}

/// Locates every bifurcation point on `branches` (the intervals with a change, in parallel on
/// `threads`), ordered by branch and position along it; a point found again (same kind,
/// period, Ω and orbit) is reported once. Reports [`Stage::Locating`] progress;
/// an error of `progress` cancels.
pub fn locate<E>(
    branches: &[Branch],
    threads: Threads,
    progress: &mut OnProgress<'_, E>,
) -> Result<Vec<BifurcationPoint>, E> {
    let items: Vec<(usize, usize)> = branches
        .iter()
        .enumerate()
        .flat_map(|(k, b)| {
            b.points
                .windows(2)
                .enumerate()
                .filter(|(_, w)| changes(&w[0], &w[1]))
                .map(move |(i, _)| (k, i))
        })
        .collect();
    let total = items.len();
    let found = parallel::map(
        &items,
        threads,
        |&(k, i)| {
            let b = &branches[k];
            between(&b.model, b.period, &b.points[i], &b.points[i + 1], k, i)
        },
        |done| {
            progress(Progress {
                stage: Stage::Locating,
                done,
                total,
            })
        },
    )?;
    let mut out: Vec<BifurcationPoint> = Vec::new();
    for p in found.into_iter().flatten() {
        if !out.iter().any(|q| same_point(q, &p)) {
            out.push(p);
        }
    }
    Ok(out)
}

/// Whether `p` and `q` are one point found twice (on branches sharing an interval, or on
/// copies of an orbit): same kind, period and V, Ω within their error bounds (and 1e-9),
/// fixed points within 1e-6.
fn same_point(p: &BifurcationPoint, q: &BifurcationPoint) -> bool {
    p.kind == q.kind
        && p.period == q.period
        && p.velocity == q.velocity
        && (p.omega - q.omega).abs() <= p.omega_error.max(q.omega_error).max(1e-9)
        && (p.x0 - q.x0).abs().max((p.v0 - q.v0).abs()) <= 1e-6
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn test_functions_and_names() {
        // λ = −1.05 and −0.6: det(M + I) < 0, det(M − I) > 0.
        let l = [(-1.05, 0.0), (-0.6, 0.0)];
        assert!(Kind::PeriodDoubling.test(l).unwrap() < 0.0);
        assert!(Kind::Fold.test(l).unwrap() > 0.0);
        let before = [(-0.95, 0.0), (-0.6, 0.0)];
        let kinds: Vec<Kind> = smooth_kinds(before, l).collect();
        assert_eq!(kinds, vec![Kind::PeriodDoubling]);
        // A complex pair 0.9 ± 0.5i has modulus² 1.06: det M − 1 > 0.
        let ns = Kind::NeimarkSacker.test([(0.9, 0.5), (0.9, -0.5)]).unwrap();
        assert!((ns - 0.06).abs() < 1e-12);
        assert_eq!(Kind::PeriodDoubling.name(), "period_doubling");
        assert!(Kind::Grazing.test(l).is_none());
    }
}
