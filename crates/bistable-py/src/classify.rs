//! `classify`, the point lists of `sweep.map` (`classify_many`) and `thresholds`.

use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use bistable_analysis::record::{outcomes_text as text_of, parse_outcomes, OutcomeShare, Record};
use bistable_analysis::sensitivity::SensitivityOptions;
use bistable_analysis::sweep::{classify_point_with, classify_points_with};
use bistable_analysis::thresholds::{self, check_restitution};
use bistable_core::{ClassifyOptions, Sinusoid};

use crate::common::{
    check_signals, invalid_text, lanes as lanes_arg, model, outcome_list, param_err, positive,
    record_dict, released, sim_err, threads as threads_arg, Stop,
};

#[allow(clippy::too_many_arguments)]
fn classify_options(
    py: Python<'_>,
    max_periods: f64,
    full: bool,
    max_period: u32,
    period_tol: f64,
    lyapunov_periods: u32,
) -> PyResult<ClassifyOptions> {
    ClassifyOptions {
        max_natural_periods: max_periods,
        full_length: full,
        max_period,
        period_tol,
        lyapunov_periods,
    }
    .check()
    .map_err(|e| param_err(py, &e))
}

/// The settings of the sensitivity test, each `None` taking its default
/// ([`SensitivityOptions::default`], also `SENSITIVITY_DEFAULTS`), checked in the CLI's order.
#[allow(clippy::too_many_arguments)]
fn sensitivity_options(
    py: Python<'_>,
    repeats: Option<u32>,
    efoldings: Option<f64>,
    perturbation: Option<f64>,
    horizon: Option<f64>,
    repeat_periods: Option<f64>,
    lyapunov_windows: Option<u32>,
) -> PyResult<SensitivityOptions> {
    let d = SensitivityOptions::default();
    SensitivityOptions {
        repeats: repeats.unwrap_or(d.repeats),
        efoldings: efoldings.unwrap_or(d.efoldings),
        perturbation: perturbation.unwrap_or(d.perturbation),
        horizon: horizon.unwrap_or(d.horizon),
        repeat_periods: repeat_periods.unwrap_or(d.repeat_periods),
        windows: lyapunov_windows.unwrap_or(d.windows),
    }
    .check()
    .map_err(|e| param_err(py, &e))
}

/// The defaults of the sensitivity test's settings, by their Python names.
pub(crate) fn sensitivity_defaults(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let d = SensitivityOptions::default();
    let out = PyDict::new(py);
    out.set_item("repeats", d.repeats)?;
    out.set_item("efoldings", d.efoldings)?;
    out.set_item("perturbation", d.perturbation)?;
    out.set_item("horizon", d.horizon)?;
    out.set_item("repeat_periods", d.repeat_periods)?;
    out.set_item("lyapunov_windows", d.windows)?;
    Ok(out)
}

/// The response class at one point (see `bistable_impact.classify`).
#[pyfunction]
#[pyo3(signature = (omega, velocity, zeta=0.02, restitution=0.85, tol=1e-16,
    chatter="accumulation", max_periods=20000.0, full=false, max_period=16, period_tol=1e-8,
    lyapunov_periods=2000, repeats=None, efoldings=None, perturbation=None, horizon=None,
    repeat_periods=None, lyapunov_windows=None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn classify<'py>(
    py: Python<'py>,
    omega: f64,
    velocity: f64,
    zeta: f64,
    restitution: f64,
    tol: f64,
    chatter: &str,
    max_periods: f64,
    full: bool,
    max_period: u32,
    period_tol: f64,
    lyapunov_periods: u32,
    repeats: Option<u32>,
    efoldings: Option<f64>,
    perturbation: Option<f64>,
    horizon: Option<f64>,
    repeat_periods: Option<f64>,
    lyapunov_windows: Option<u32>,
) -> PyResult<Bound<'py, PyDict>> {
    let m = model(py, omega, velocity, zeta, restitution, tol, chatter)?;
    let co = classify_options(
        py,
        max_periods,
        full,
        max_period,
        period_tol,
        lyapunov_periods,
    )?;
    let so = sensitivity_options(
        py,
        repeats,
        efoldings,
        perturbation,
        horizon,
        repeat_periods,
        lyapunov_windows,
    )?;
    let point = released(py, || classify_point_with(&m, co, so), |e| sim_err(py, &e))?;
    record_dict(py, &Record::new(&point))
}

/// Classifies every `(omega, velocity)` of `points` on `threads` threads (0: all cores) of
/// `lanes` trajectories each in SIMD lanes (1, 4 or 8; the records are the same); the
/// records in the order of `points`; a point that fails raises. After each point, Python's
/// signal handlers run (Ctrl-C raises `KeyboardInterrupt` and stops the sweep), `on_record`, if
/// given, is called with the point's record (a dict) and `progress`, if given, with
/// `(points done, points)`; an exception from either stops the sweep.
#[pyfunction]
#[pyo3(signature = (points, zeta=0.02, restitution=0.85, tol=1e-16, chatter="accumulation",
    max_periods=20000.0, full=false, max_period=16, period_tol=1e-8, lyapunov_periods=300,
    repeats=None, efoldings=None, perturbation=None, horizon=None, repeat_periods=None,
    lyapunov_windows=None, threads=0, lanes=4, progress=None, on_record=None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn classify_many<'py>(
    py: Python<'py>,
    points: Vec<(f64, f64)>,
    zeta: f64,
    restitution: f64,
    tol: f64,
    chatter: &str,
    max_periods: f64,
    full: bool,
    max_period: u32,
    period_tol: f64,
    lyapunov_periods: u32,
    repeats: Option<u32>,
    efoldings: Option<f64>,
    perturbation: Option<f64>,
    horizon: Option<f64>,
    repeat_periods: Option<f64>,
    lyapunov_windows: Option<u32>,
    threads: usize,
    lanes: usize,
    progress: Option<Py<PyAny>>,
    on_record: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyList>> {
    let first = points.first().copied().unwrap_or((1.0, 0.0));
    let m = model(py, first.0, first.1, zeta, restitution, tol, chatter)?;
    for &(w, v) in &points {
        Sinusoid::new(w, v).map_err(|e| param_err(py, &e))?;
    }
    let co = classify_options(
        py,
        max_periods,
        full,
        max_period,
        period_tol,
        lyapunov_periods,
    )?;
    let so = sensitivity_options(
        py,
        repeats,
        efoldings,
        perturbation,
        horizon,
        repeat_periods,
        lyapunov_windows,
    )?;
    let threads = threads_arg(threads)?;
    let width = lanes_arg(lanes)?;
    let mut records: Vec<Option<Record>> = vec![None; points.len()];
    let (mut done, total) = (0usize, points.len());
    let sweep = || {
        classify_points_with(&m, &points, co, so, threads, width, |i, r| {
            let record = Record::new(&r?);
            done += 1;
            check_signals()?;
            if on_record.is_some() || progress.is_some() {
                Python::with_gil(|py| -> PyResult<()> {
                    if let Some(f) = &on_record {
                        f.call1(py, (record_dict(py, &record)?,))?;
                    }
                    if let Some(f) = &progress {
                        f.call1(py, (done, total))?;
                    }
                    Ok(())
                })
                .map_err(Stop::Py)?;
            }
            records[i] = Some(record);
            Ok::<(), Stop>(())
        })
    };
    released(py, sweep, |e| e.into_py(py))?;
    let out = PyList::empty(py);
    for r in records.iter().flatten() {
        out.append(record_dict(py, r)?)?;
    }
    Ok(out)
}

/// The velocity thresholds of Eq. 16–18 (see `bistable_impact.thresholds`).
#[pyfunction]
#[pyo3(signature = (restitution=0.85, omega=None))]
pub(crate) fn thresholds_of<'py>(
    py: Python<'py>,
    restitution: f64,
    omega: Option<f64>,
) -> PyResult<Bound<'py, PyDict>> {
    let e = check_restitution(restitution).map_err(|e| param_err(py, &e))?;
    if let Some(w) = omega {
        positive(py, "omega", w)?;
    }
    let d = PyDict::new(py);
    d.set_item("restitution", e)?;
    d.set_item("single_impact", thresholds::single_impact(e))?;
    d.set_item("interwell", thresholds::interwell(e))?;
    d.set_item("omega", omega)?;
    d.set_item("quasi_static", omega.map(thresholds::quasi_static))?;
    Ok(d)
}

/// The map CSV's text of a record's `outcomes` (a list of dicts with the keys `class, period,
/// chaotic, final_well, count, fraction`): `class:period:well=fraction;...`.
#[pyfunction]
pub(crate) fn outcomes_text(outcomes: &Bound<'_, PyList>) -> PyResult<String> {
    let mut shares = Vec::with_capacity(outcomes.len());
    for item in outcomes.iter() {
        let d = item.downcast::<PyDict>()?;
        let get = |k: &str| -> PyResult<Bound<'_, PyAny>> {
            d.get_item(k)?
                .ok_or_else(|| invalid_text("outcomes", k, "is missing from an outcome"))
        };
        shares.push(OutcomeShare {
            class: get("class")?.extract()?,
            period: get("period")?.extract()?,
            chaotic: get("chaotic")?.extract()?,
            final_well: get("final_well")?.extract()?,
            count: get("count")?.extract()?,
            fraction: get("fraction")?.extract()?,
        });
    }
    Ok(text_of(&shares))
}

/// The outcomes (a list of dicts) of a map CSV's `outcomes` text, of a point with `runs` runs.
#[pyfunction]
pub(crate) fn outcomes_from_text<'py>(
    py: Python<'py>,
    text: &str,
    runs: u32,
) -> PyResult<Bound<'py, PyList>> {
    let shares = parse_outcomes(text, runs).map_err(|e| invalid_text("outcomes", text, &e))?;
    outcome_list(py, &shares)
}
