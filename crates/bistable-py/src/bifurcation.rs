//! `bifurcation`: the data of `bistable bifurcation` (Fig. 6/8).

use std::num::NonZeroU32;
use std::time::Instant as WallClock;

use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use bistable_analysis::diagram::{compute, BifurcationOptions};
use bistable_analysis::Model;

use crate::common::{
    check_signals, invalid, invalid_text, lanes as lanes_arg, model, released, table,
    threads as threads_arg,
};
use crate::common::{Col, Stop};
use crate::orbit::{check_period, orbit_rows};
use bistable_core::{MAX_VELOCITY, OMEGA_RANGE};

/// Most recorded cycles over all points of one call.
const MAX_RECORDED: u64 = 100_000_000;

/// Bifurcation data along `values` of `param` (see `bistable_impact.bifurcation`).
#[pyfunction]
#[pyo3(signature = (param, values, omega=None, velocity=None, transient=500, record=100,
    samples=128, branch_periods=vec![1, 2, 4, 8], threads=0, lanes=4, zeta=0.02, restitution=0.85,
    tol=1e-16, chatter="accumulation"))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn bifurcation<'py>(
    py: Python<'py>,
    param: &str,
    values: Vec<f64>,
    omega: Option<f64>,
    velocity: Option<f64>,
    transient: u32,
    record: u32,
    samples: u32,
    branch_periods: Vec<u32>,
    threads: usize,
    lanes: usize,
    zeta: f64,
    restitution: f64,
    tol: f64,
    chatter: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let start = WallClock::now();
    let by_omega = match param {
        "omega" => true,
        "velocity" => false,
        other => {
            return Err(invalid_text(
                "param",
                other,
                "must be 'omega' or 'velocity'",
            ))
        }
    };
    if values.is_empty() {
        return Err(invalid_text("values", "[]", "must have at least one value"));
    }
    for &x in &values {
        let (ok, rule) = if by_omega {
            (OMEGA_RANGE.contains(&x), "Ω must be in [1e-6, 1e6]")
        } else {
            ((0.0..=MAX_VELOCITY).contains(&x), "V must be in [0, 1e6]")
        };
        if !ok {
            return Err(invalid(py, "values", x, rule));
        }
    }
    let (fixed, fixed_name) = if by_omega {
        (velocity, "velocity")
    } else {
        (omega, "omega")
    };
    // The other one is not used, but must be a value the model accepts if it is given.
    if let Some(w) = omega.filter(|_| by_omega) {
        model(py, w, 0.0, zeta, restitution, tol, chatter)?;
    }
    if let Some(v) = velocity.filter(|_| !by_omega) {
        model(py, 1.0, v, zeta, restitution, tol, chatter)?;
    }
    let fixed = fixed.ok_or_else(|| {
        invalid_text(
            fixed_name,
            "None",
            &format!("is required with param='{param}'"),
        )
    })?;
    let models = values
        .iter()
        .map(|&x| {
            let (w, v) = if by_omega { (x, fixed) } else { (fixed, x) };
            model(py, w, v, zeta, restitution, tol, chatter)
        })
        .collect::<PyResult<Vec<Model>>>()?;
    if record < 1 {
        return Err(invalid_text("record", record, "must be >= 1"));
    }
    // The recorded cycles are kept in memory (per point: a maximum and a section per cycle,
    // and every impact).
    if u64::from(record) * values.len() as u64 > MAX_RECORDED {
        return Err(invalid_text(
            "record",
            record,
            &format!("record × len(values) must be at most {MAX_RECORDED}"),
        ));
    }
    let samples = NonZeroU32::new(samples)
        .filter(|s| s.get() >= 8)
        .ok_or_else(|| invalid_text("samples", samples, "must be >= 8"))?;
    for &p in &branch_periods {
        check_period("branch_periods", p)
            .map_err(|_| invalid_text("branch_periods", p, "periods must be in [1, 64]"))?;
    }
    let threads = threads_arg(threads)?;
    let options = BifurcationOptions {
        transient,
        record,
        samples,
        branch_periods,
        width: lanes_arg(lanes)?,
    };
    let data = released(
        py,
        || compute::<Stop>(&models, &options, threads, &mut |_| check_signals()),
        |e| e.into_py(py),
    )?;

    let out = PyDict::new(py);
    out.set_item("param", param)?;
    out.set_item(
        "range",
        format!(
            "{}:{}:{}",
            values[0],
            values[values.len() - 1],
            values.len()
        ),
    )?;
    out.set_item("transient", transient)?;
    out.set_item("record", record)?;
    let points = PyList::empty(py);
    for p in data.point_summaries(&models, record) {
        let d = PyDict::new(py);
        d.set_item("omega", p.omega)?;
        d.set_item("velocity", p.velocity)?;
        d.set_item("period", p.period)?;
        d.set_item("distinct_max_x", p.distinct_max_x)?;
        d.set_item("impacts_per_cycle", p.impacts_per_cycle)?;
        points.append(d)?;
    }
    out.set_item("points", points)?;
    let branches = PyList::empty(py);
    for b in &data.branches {
        let d = PyDict::new(py);
        d.set_item("period", b.period)?;
        d.set_item("orbits", b.len())?;
        d.set_item("stable", b.stable())?;
        d.set_item("links", b.links.len())?;
        branches.append(d)?;
    }
    out.set_item("branches", branches)?;
    out.set_item("wall_time_s", start.elapsed().as_secs_f64())?;

    // The CSV: omega, velocity, kind (0: max_x, 1: impact_phase), cycle, value.
    let mut c: [Col; 5] = Default::default();
    for (m, cy) in models.iter().zip(&data.points) {
        let rows = cy
            .max_x
            .iter()
            .enumerate()
            .map(|(k, &x)| (0, k as i64, x))
            .chain(cy.impacts.iter().map(|&(k, ph)| (1, i64::from(k), ph)));
        for (kind, cycle, value) in rows {
            c[0].f(m.omega());
            c[1].f(m.velocity());
            c[2].i(kind);
            c[3].i(cycle);
            c[4].f(value);
        }
    }
    let names = [
        ("omega", "f8"),
        ("velocity", "f8"),
        ("kind", "i8"),
        ("cycle", "i8"),
        ("value", "f8"),
    ];
    let cols = names.into_iter().zip(c).map(|((n, t), c)| (n, t, c));
    out.set_item("data", table(py, cols.collect())?)?;
    let (rows, cycle_max) = orbit_rows(py, &data.branches)?;
    out.set_item("orbits", rows)?;
    out.set_item("cycle_max", cycle_max)?;
    Ok(out)
}
