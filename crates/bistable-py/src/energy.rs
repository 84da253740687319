//! `energy_map`: the data of `bistable energy-map` (the energy change of an impact over impact
//! phase and pre-impact velocity, Eq. 13–15, with a simulation's impacts).

use std::f64::consts::TAU;

use pyo3::prelude::*;
use pyo3::types::PyDict;

use bistable_analysis::energy::{self, EnergyMap, ImpactPoint};

use crate::common::{
    invalid, invalid_text, model, param_err, positive, released, sim_err, table, Col,
};

/// Most cells of one map (about 240 MB while it is built).
const MAX_CELLS: usize = 10_000_000;
/// Largest `periods·max(Ω, 1)` of the overlaid run (its impacts are kept in memory).
const MAX_OVERLAY_SPAN: f64 = 1e7;

/// The energy map (see `bistable_impact.energy_map`).
#[pyfunction]
#[pyo3(signature = (restitution=0.85, u_range=None, nx=360, ny=300, omega=None, velocity=None,
    periods=200.0, zeta=0.02, tol=1e-16, chatter="accumulation"))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn energy_map<'py>(
    py: Python<'py>,
    restitution: f64,
    u_range: Option<(f64, f64)>,
    nx: usize,
    ny: usize,
    omega: Option<f64>,
    velocity: Option<f64>,
    periods: f64,
    zeta: f64,
    tol: f64,
    chatter: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let e = energy::check_restitution(restitution).map_err(|err| param_err(py, &err))?;
    if let Some((lo, hi)) = u_range {
        if !(lo.is_finite() && hi.is_finite() && lo < hi) {
            return Err(invalid_text(
                "u_range",
                format!("({lo}, {hi})"),
                "expected (lo, hi) with lo < hi",
            ));
        }
    }
    if nx == 0 || ny == 0 || nx.saturating_mul(ny) > MAX_CELLS {
        return Err(invalid_text(
            "nx",
            format!("{nx} (ny = {ny})"),
            "nx and ny must be >= 1 with nx·ny <= 1e7",
        ));
    }
    // The overlaid run's settings are checked also when there is no overlay.
    model(
        py,
        omega.unwrap_or(1.0),
        velocity.unwrap_or(0.0),
        zeta,
        e,
        tol,
        chatter,
    )?;
    let periods = positive(py, "periods", periods)?;
    let span = periods * omega.unwrap_or(1.0).max(1.0);
    if span.is_nan() || span > MAX_OVERLAY_SPAN {
        return Err(invalid(
            py,
            "periods",
            periods,
            "periods·max(omega, 1) must be <= 1e7",
        ));
    }
    let impacts: Vec<ImpactPoint> = match (omega, velocity) {
        (None, None) => Vec::new(),
        (Some(w), Some(v)) => {
            let m = model(py, w, v, zeta, e, tol, chatter)?;
            if m.velocity() <= 0.0 {
                return Err(invalid(py, "velocity", v, "must be > 0 for the overlay"));
            }
            let t_end = periods * TAU;
            released(py, || energy::impacts(&m, t_end), |err| sim_err(py, &err))?
        }
        (Some(_), None) | (None, Some(_)) => {
            return Err(pyo3::exceptions::PyValueError::new_err(
                "'omega' and 'velocity' go together (the overlaid run); give both or neither",
            ))
        }
    };
    let (lo, hi) = u_range.unwrap_or_else(|| energy::default_u_range(e, &impacts));
    let map = py.allow_threads(|| EnergyMap::new(e, (lo, hi), nx, ny));

    let mut ratio = Col::default();
    for i in 0..nx {
        for j in 0..ny {
            ratio.f(map.value(i, j).unwrap_or(f64::NAN));
        }
    }
    let mut phase = Col::default();
    for i in 0..nx {
        phase.f(map.centre(i, 0).0);
    }
    let mut u = Col::default();
    for j in 0..ny {
        u.f(map.centre(0, j).1);
    }
    let out = PyDict::new(py);
    out.set_item("restitution", e)?;
    out.set_item("u_range", (lo, hi))?;
    out.set_item("phase", table(py, vec![("phase", "f8", phase)])?)?;
    out.set_item("u", table(py, vec![("u", "f8", u)])?)?;
    out.set_item("ratio", table(py, vec![("ratio", "f8", ratio)])?)?;
    out.set_item("shape", (nx, ny))?;
    out.set_item("max_abs", map.max_abs())?;
    if omega.is_some() {
        let mut c: [Col; 3] = Default::default();
        for p in &impacts {
            c[0].f(p.phase);
            c[1].f(p.u);
            c[2].f(p.time_fraction);
        }
        let [a, b, t] = c;
        out.set_item(
            "impacts",
            table(
                py,
                vec![
                    ("phase", "f8", a),
                    ("u", "f8", b),
                    ("time_fraction", "f8", t),
                ],
            )?,
        )?;
    } else {
        out.set_item("impacts", py.None())?;
    }
    Ok(out)
}
