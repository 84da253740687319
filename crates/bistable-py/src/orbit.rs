//! `orbit` (one periodic orbit by shooting), `continue_omega` (branches of orbits continued
//! in Ω) and `atlas` (their folds and period doublings continued in (Ω, V)), as `bistable
//! orbit` without and with `--continue-omega` and `bistable atlas`.

use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use bistable_analysis::arclength::ArcPoint;
use bistable_analysis::bifurcations::{locate, BifurcationPoint, Branch, Kind};
use bistable_analysis::branches::Branches;
use bistable_analysis::codim2::{self, Codim2Point, PointKind};
use bistable_analysis::continuation::{continue_orbits, Curves, Method};
use bistable_analysis::cycles::settled;
use bistable_analysis::orbit::{shoot, summarise};
use bistable_analysis::twoparam::{trace_all, Atlas, CurveOptions};
use bistable_analysis::Model;

use crate::common::{
    check_signals, invalid_text, lanes as lanes_arg, model, released, sim_err, table,
    threads as threads_arg, Col, Stop,
};

/// Checks an orbit period (shaker periods), as the CLI's `--period`.
pub(crate) fn check_period(name: &str, p: u32) -> PyResult<u32> {
    if (1..=64).contains(&p) {
        Ok(p)
    } else {
        Err(invalid_text(name, p, "must be in [1, 64]"))
    }
}

/// One periodic orbit (see `bistable_impact.orbit`).
#[pyfunction]
#[pyo3(signature = (omega, velocity, period=1, guess=None, settle=2000, zeta=0.02,
    restitution=0.85, tol=1e-16, chatter="accumulation"))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn orbit<'py>(
    py: Python<'py>,
    omega: f64,
    velocity: f64,
    period: u32,
    guess: Option<(f64, f64)>,
    settle: u32,
    zeta: f64,
    restitution: f64,
    tol: f64,
    chatter: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let period = check_period("period", period)?;
    let m = model(py, omega, velocity, zeta, restitution, tol, chatter)?;
    let (guess, source) = match guess {
        Some((x, v)) if x.is_finite() && v.is_finite() => ((x, v), "guess".to_string()),
        Some((x, v)) => {
            return Err(invalid_text(
                "guess",
                format!("({x}, {v})"),
                "must be two finite numbers",
            ))
        }
        None => {
            let st = released(
                py,
                || settled(&m, settle).map(|s| s.state()),
                |e| sim_err(py, &e),
            )?;
            (
                (st.x, st.v),
                format!(
                    "section point after {settle} shaker periods from the paper's initial condition"
                ),
            )
        }
    };
    let orbit = released(
        py,
        || shoot(&m, period, guess),
        |e| {
            pyo3::exceptions::PyRuntimeError::new_err(format!(
                "no {period}-periodic orbit found from ({}, {}): {e}",
                guess.0, guess.1
            ))
        },
    )?;
    let s = released(py, || summarise(&m, orbit, guess), |e| sim_err(py, &e))?;
    let d = PyDict::new(py);
    d.set_item("omega", omega)?;
    d.set_item("velocity", velocity)?;
    d.set_item("period", orbit.periods)?;
    d.set_item("x0", orbit.x0)?;
    d.set_item("v0", orbit.v0)?;
    let mults = PyList::empty(py);
    for &(re, im) in &orbit.multipliers {
        let md = PyDict::new(py);
        md.set_item("re", re)?;
        md.set_item("im", im)?;
        md.set_item("abs", re.hypot(im))?;
        mults.append(md)?;
    }
    d.set_item("multipliers", mults)?;
    d.set_item("max_abs_multiplier", s.max_abs_multiplier)?;
    d.set_item("stable", orbit.stable)?;
    // ln 0 = −∞ for an orbit whose largest multiplier is 0 (one that sticks): None.
    let floquet = Some(s.floquet_exponent).filter(|f| f.is_finite());
    d.set_item("floquet_exponent", floquet)?;
    d.set_item("impacts", orbit.impacts)?;
    d.set_item("sticks", orbit.sticks)?;
    d.set_item("snap_throughs", orbit.snap_throughs)?;
    d.set_item("max_x", orbit.max_x)?;
    d.set_item("cycle_max", s.cycle_max)?;
    d.set_item("iterations", orbit.iterations)?;
    d.set_item("residual", orbit.residual)?;
    d.set_item("monodromy", orbit.monodromy.map(|r| r.to_vec()).to_vec())?;
    d.set_item("det_monodromy", s.det_monodromy)?;
    d.set_item("det_identity", orbit.det_identity)?;
    d.set_item("det_relative_error", s.det_relative_error)?;
    d.set_item("guess", guess)?;
    d.set_item("guess_source", source)?;
    d.set_item("distance_to_guess", s.distance_to_guess)?;
    Ok(d)
}

/// The orbits of `branches`, one row each: the columns of the CLI's orbits CSV as a table
/// (`stable`, `sticks` as bools) and the per-cycle maxima of each row (the CSV's `cycle_max`).
pub(crate) fn orbit_rows<'py>(
    py: Python<'py>,
    branches: &[Branches],
) -> PyResult<(Bound<'py, PyList>, Bound<'py, PyList>)> {
    let mut c: [Col; 15] = Default::default();
    let cycle_max = PyList::empty(py);
    for o in branches.iter().flat_map(|b| b.slots.iter().flatten()) {
        let p = &o.orbit;
        c[0].f(p.omega);
        c[1].f(p.velocity);
        c[2].i(i64::from(p.periods));
        c[3].b(p.stable);
        c[4].f(p.x0);
        c[5].f(p.v0);
        c[6].f(o.cycle_max.last().copied().unwrap_or(p.max_x));
        c[7].f(p.multipliers[0].0);
        c[8].f(p.multipliers[0].1);
        c[9].f(p.multipliers[1].0);
        c[10].f(p.multipliers[1].1);
        c[11].f(o.abs_multiplier());
        c[12].i(p.impacts as i64);
        c[13].i(p.snap_throughs as i64);
        c[14].b(p.sticks);
        cycle_max.append(o.cycle_max.clone())?;
    }
    let names = [
        ("omega", "f8"),
        ("velocity", "f8"),
        ("period", "i8"),
        ("stable", "b1"),
        ("x0", "f8"),
        ("v0", "f8"),
        ("max_x", "f8"),
        ("multiplier_1_re", "f8"),
        ("multiplier_1_im", "f8"),
        ("multiplier_2_re", "f8"),
        ("multiplier_2_im", "f8"),
        ("abs_multiplier", "f8"),
        ("impacts", "i8"),
        ("snap_throughs", "i8"),
        ("sticks", "b1"),
    ];
    let cols = names.into_iter().zip(c).map(|((n, t), c)| (n, t, c));
    Ok((table(py, cols.collect())?, cycle_max))
}

/// The points of pseudo-arclength traces at `velocity`, one row each: the columns of the CLI's
/// `--arclength` CSV.
fn arc_rows(all: &[(f64, Vec<Vec<ArcPoint>>)]) -> Vec<(&'static str, &'static str, Col)> {
    let mut c: [Col; 14] = Default::default();
    for (v, traces) in all {
        for (k, t) in traces.iter().enumerate() {
            for (i, a) in t.iter().enumerate() {
                let m = a.multipliers;
                c[0].f(*v);
                c[1].i(k as i64);
                c[2].i(i as i64);
                c[3].f(a.omega);
                c[4].f(a.x0);
                c[5].f(a.v0);
                c[6].f(a.max_x);
                c[7].b(a.stable);
                c[8].f(m[0].0);
                c[9].f(m[0].1);
                c[10].f(m[1].0);
                c[11].f(m[1].1);
                c[12].f(m[0].0.hypot(m[0].1));
                c[13].i(a.impacts as i64);
            }
        }
    }
    let names = [
        ("velocity", "f8"),
        ("trace", "i8"),
        ("index", "i8"),
        ("omega", "f8"),
        ("x0", "f8"),
        ("v0", "f8"),
        ("max_x", "f8"),
        ("stable", "b1"),
        ("multiplier_1_re", "f8"),
        ("multiplier_1_im", "f8"),
        ("multiplier_2_re", "f8"),
        ("multiplier_2_im", "f8"),
        ("abs_multiplier", "f8"),
        ("impacts", "i8"),
    ];
    names
        .into_iter()
        .zip(c)
        .map(|((n, t), c)| (n, t, c))
        .collect()
}

/// The bifurcation points, one row each: the columns of the CLI's `_bifurcations.csv`, with
/// `kind` as its index in `Kind::ALL` (the Python side names it).
fn bifurcation_rows(points: &[BifurcationPoint]) -> Vec<(&'static str, &'static str, Col)> {
    let mut c: [Col; 18] = Default::default();
    for p in points {
        let m = p.multipliers;
        let kind = Kind::ALL.iter().position(|&k| k == p.kind).unwrap_or(0);
        c[0].i(kind as i64);
        c[1].f(p.omega);
        c[2].f(p.velocity);
        c[3].i(i64::from(p.period));
        c[4].f(p.x0);
        c[5].f(p.v0);
        c[6].f(p.max_x);
        c[7].f(m[0].0);
        c[8].f(m[0].1);
        c[9].f(m[1].0);
        c[10].f(m[1].1);
        c[11].f(p.omega_error);
        c[12].i(p.branch as i64);
        c[13].i(p.index as i64);
        c[14].i(p.impacts_before as i64);
        c[15].i(p.impacts_after as i64);
        c[16].b(p.sticks_before);
        c[17].b(p.sticks_after);
    }
    let names = [
        ("kind", "i8"),
        ("omega", "f8"),
        ("velocity", "f8"),
        ("period", "i8"),
        ("x0", "f8"),
        ("v0", "f8"),
        ("max_x", "f8"),
        ("multiplier_1_re", "f8"),
        ("multiplier_1_im", "f8"),
        ("multiplier_2_re", "f8"),
        ("multiplier_2_im", "f8"),
        ("omega_error", "f8"),
        ("branch", "i8"),
        ("index", "i8"),
        ("impacts_before", "i8"),
        ("impacts_after", "i8"),
        ("sticks_before", "b1"),
        ("sticks_after", "b1"),
    ];
    names
        .into_iter()
        .zip(c)
        .map(|((n, t), c)| (n, t, c))
        .collect()
}

/// The continuation method named by `method` (`'natural'` or `'arclength'`) and its name in
/// summaries.
fn method_arg(method: &str) -> PyResult<(Method, &'static str)> {
    match method {
        "natural" => Ok((Method::Natural, "natural")),
        "arclength" => Ok((Method::Arclength, "pseudo-arclength")),
        other => Err(invalid_text(
            "method",
            other,
            "must be 'natural' or 'arclength'",
        )),
    }
}

/// Orbits continued in Ω (see `bistable_impact.continue_omega`).
#[pyfunction]
#[pyo3(signature = (omega, velocity, period=1, settle=2000, method="natural", threads=0,
    lanes=4, zeta=0.02, restitution=0.85, tol=1e-16, chatter="accumulation"))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn continue_omega<'py>(
    py: Python<'py>,
    omega: Vec<f64>,
    velocity: Vec<f64>,
    period: u32,
    settle: u32,
    method: &str,
    threads: usize,
    lanes: usize,
    zeta: f64,
    restitution: f64,
    tol: f64,
    chatter: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let period = check_period("period", period)?;
    let (method, method_name) = method_arg(method)?;
    if omega.is_empty() {
        return Err(invalid_text("omega", "[]", "must have at least one value"));
    }
    if velocity.is_empty() {
        return Err(invalid_text(
            "velocity",
            "[]",
            "must have at least one value",
        ));
    }
    let threads = threads_arg(threads)?;
    let width = lanes_arg(lanes)?;
    let mut grids: Vec<Vec<Model>> = Vec::new();
    for &v in &velocity {
        let ms = omega
            .iter()
            .map(|&w| model(py, w, v, zeta, restitution, tol, chatter))
            .collect::<PyResult<Vec<_>>>()?;
        grids.push(ms);
    }
    let results: Vec<(Curves, Vec<BifurcationPoint>)> = released(
        py,
        || {
            grids
                .iter()
                .map(|ms| {
                    let c =
                        continue_orbits(ms, period, settle, method, threads, width, &mut |_| {
                            check_signals()
                        })?;
                    let on = Branch::from_curves(ms, period, &c);
                    let found = locate(&on, threads, &mut |_| check_signals())?;
                    Ok((c, found))
                })
                .collect::<Result<Vec<_>, Stop>>()
        },
        |e| e.into_py(py),
    )?;
    let found: Vec<BifurcationPoint> = results.iter().flat_map(|r| r.1.clone()).collect();
    let curves: Vec<Curves> = results.into_iter().map(|r| r.0).collect();

    let out = PyDict::new(py);
    out.set_item("period", period)?;
    out.set_item("method", method_name)?;
    out.set_item(
        "omega_range",
        format!("{}:{}:{}", omega[0], omega[omega.len() - 1], omega.len()),
    )?;
    let branches = PyList::empty(py);
    for (&v, c) in velocity.iter().zip(&curves) {
        let s = c.summary(&omega);
        let b = PyDict::new(py);
        b.set_item("velocity", v)?;
        b.set_item("orbits", s.orbits)?;
        b.set_item("stable", s.stable)?;
        b.set_item("omega_min", s.omega_min)?;
        b.set_item("omega_max", s.omega_max)?;
        b.set_item("traces", s.traces)?;
        b.set_item("folds", s.folds)?;
        branches.append(b)?;
    }
    out.set_item("branches", branches)?;
    out.set_item("bifurcations", table(py, bifurcation_rows(&found))?)?;
    match method {
        Method::Natural => {
            let all: Vec<Branches> = curves
                .into_iter()
                .filter_map(|c| match c {
                    Curves::Natural(b) => Some(b),
                    Curves::Arclength(_) => None,
                })
                .collect();
            let (rows, cycle_max) = orbit_rows(py, &all)?;
            out.set_item("orbits", rows)?;
            out.set_item("cycle_max", cycle_max)?;
        }
        Method::Arclength => {
            let all: Vec<(f64, Vec<Vec<ArcPoint>>)> = velocity
                .iter()
                .zip(curves)
                .filter_map(|(&v, c)| match c {
                    Curves::Arclength(t) => Some((v, t)),
                    Curves::Natural(_) => None,
                })
                .collect();
            out.set_item("orbits", table(py, arc_rows(&all))?)?;
            out.set_item("cycle_max", py.None())?;
        }
    }
    Ok(out)
}

/// The curves of an atlas, one row per point: the columns of `bistable atlas --out`, with
/// `kind` as its index in `Kind::ALL` (the Python side names it).
fn atlas_rows(all: &Atlas) -> Vec<(&'static str, &'static str, Col)> {
    let mut c: [Col; 12] = Default::default();
    for (k, (s, curve)) in all.iter().enumerate() {
        let kind = Kind::ALL.iter().position(|&q| q == s.kind).unwrap_or(0);
        for q in curve {
            let m = q.multipliers;
            c[0].i(k as i64);
            c[1].i(kind as i64);
            c[2].i(i64::from(s.period));
            c[3].f(q.omega);
            c[4].f(q.velocity);
            c[5].f(q.x0);
            c[6].f(q.v0);
            c[7].f(m[0].0);
            c[8].f(m[0].1);
            c[9].f(m[1].0);
            c[10].f(m[1].1);
            c[11].i(q.impacts as i64);
        }
    }
    let names = [
        ("curve", "i8"),
        ("kind", "i8"),
        ("period", "i8"),
        ("omega", "f8"),
        ("velocity", "f8"),
        ("x0", "f8"),
        ("v0", "f8"),
        ("multiplier_1_re", "f8"),
        ("multiplier_1_im", "f8"),
        ("multiplier_2_re", "f8"),
        ("multiplier_2_im", "f8"),
        ("impacts", "i8"),
    ];
    names
        .into_iter()
        .zip(c)
        .map(|((n, t), c)| (n, t, c))
        .collect()
}

/// The codimension-two points of an atlas, one row per point: the columns of `bistable atlas`'s
/// `_points.csv`, with `kind` as its index in `PointKind::ALL` (the Python side names it) and
/// `other_curve`, `other_index` −1 where the CSV leaves them empty.
fn point_rows(all: &Atlas, points: &[Codim2Point]) -> Vec<(&'static str, &'static str, Col)> {
    let mut c: [Col; 17] = Default::default();
    for p in points {
        let kind = PointKind::ALL
            .iter()
            .position(|&q| q == p.kind)
            .unwrap_or(0);
        let m = p.multipliers;
        let (other, other_index) = p.other.map_or((-1, -1), |(a, b)| (a as i64, b as i64));
        c[0].i(kind as i64);
        c[1].f(p.omega);
        c[2].f(p.velocity);
        c[3].i(p.curve as i64);
        c[4].i(p.index as i64);
        c[5].i(other);
        c[6].i(other_index);
        c[7].i(i64::from(all[p.curve].0.period));
        c[8].f(p.x0);
        c[9].f(p.v0);
        c[10].f(m[0].0);
        c[11].f(m[0].1);
        c[12].f(m[1].0);
        c[13].f(m[1].1);
        c[14].i(p.impacts as i64);
        c[15].i(p.impacts_beyond as i64);
        c[16].f(p.error);
    }
    let names = [
        ("kind", "i8"),
        ("omega", "f8"),
        ("velocity", "f8"),
        ("curve", "i8"),
        ("index", "i8"),
        ("other_curve", "i8"),
        ("other_index", "i8"),
        ("period", "i8"),
        ("x0", "f8"),
        ("v0", "f8"),
        ("multiplier_1_re", "f8"),
        ("multiplier_1_im", "f8"),
        ("multiplier_2_re", "f8"),
        ("multiplier_2_im", "f8"),
        ("impacts", "i8"),
        ("impacts_beyond", "i8"),
        ("error", "f8"),
    ];
    names
        .into_iter()
        .zip(c)
        .map(|((n, t), c)| (n, t, c))
        .collect()
}

/// Fold and period-doubling curves in (Ω, V) and their codimension-two points (see
/// `bistable_impact.atlas`): `{"curves": table, "points": table}`.
#[pyfunction]
#[pyo3(signature = (omega, velocity, velocity_bounds, period=1, method="natural", ds=0.005,
    max_points=200, settle=2000, threads=0, lanes=4, zeta=0.02, restitution=0.85, tol=1e-16,
    chatter="accumulation"))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn atlas<'py>(
    py: Python<'py>,
    omega: Vec<f64>,
    velocity: f64,
    velocity_bounds: (f64, f64),
    period: u32,
    method: &str,
    ds: f64,
    max_points: usize,
    settle: u32,
    threads: usize,
    lanes: usize,
    zeta: f64,
    restitution: f64,
    tol: f64,
    chatter: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let period = check_period("period", period)?;
    let (method, _) = method_arg(method)?;
    if omega.is_empty() || omega.iter().any(|w| !(w.is_finite() && *w > 0.0)) {
        return Err(invalid_text(
            "omega",
            format!("{omega:?}"),
            "must be at least one finite value > 0",
        ));
    }
    let models = omega
        .iter()
        .map(|&w| model(py, w, velocity, zeta, restitution, tol, chatter))
        .collect::<PyResult<Vec<_>>>()?;
    let (v_lo, v_hi) = velocity_bounds;
    if !(v_lo >= 0.0 && v_lo < velocity && velocity < v_hi) {
        return Err(invalid_text(
            "velocity_bounds",
            format!("({v_lo}, {v_hi})"),
            "must satisfy 0 <= lo < velocity < hi",
        ));
    }
    if !(ds.is_finite() && ds > 0.0) {
        return Err(invalid_text("ds", ds, "must be finite and > 0"));
    }
    if max_points < 1 {
        return Err(invalid_text("max_points", max_points, "must be >= 1"));
    }
    let threads = threads_arg(threads)?;
    let width = lanes_arg(lanes)?;
    let lo = omega.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = omega.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let o = CurveOptions {
        omega_bounds: (lo, hi),
        velocity_bounds,
        ds_max: ds,
        max_points,
    };
    let all = released(
        py,
        || {
            let c = continue_orbits(&models, period, settle, method, threads, width, &mut |_| {
                check_signals()
            })?;
            let on = Branch::from_curves(&models, period, &c);
            let found = locate(&on, threads, &mut |_| check_signals())?;
            Ok(trace_all(&models[0], found, o).map(|all| {
                let points = codim2::points(&models[0], &all, o);
                (all, points)
            }))
        },
        |e: Stop| e.into_py(py),
    )?
    .map_err(|(kind, omega, e)| {
        pyo3::exceptions::PyRuntimeError::new_err(format!(
            "cannot continue the {} at Ω = {omega}: {e}",
            kind.name()
        ))
    })?;
    let (all, points) = all;
    let out = PyDict::new(py);
    out.set_item("curves", table(py, atlas_rows(&all))?)?;
    out.set_item("points", table(py, point_rows(&all, &points))?)?;
    Ok(out)
}

/// The words for the `kind` codes of the bifurcation and codimension-two point tables, in code
/// order: `{"bifurcation": [...], "point": [...]}` (`Kind::ALL`, `PointKind::ALL`), so that
/// Python names the codes from the Rust enums, not from a copy.
#[pyfunction]
pub fn kind_names(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let d = PyDict::new(py);
    d.set_item(
        "bifurcation",
        Kind::ALL.iter().map(|k| k.name()).collect::<Vec<_>>(),
    )?;
    d.set_item(
        "point",
        PointKind::ALL.iter().map(|k| k.name()).collect::<Vec<_>>(),
    )?;
    Ok(d)
}
