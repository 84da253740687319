//! `spectrum`: the data of `bistable spectrum` (amplitude spectrum of the steady-state
//! displacement).

use std::num::NonZeroU32;

use pyo3::prelude::*;
use pyo3::types::PyDict;

use bistable_analysis::spectrum::{flatness, Spectrum, SpectrumOptions};

use crate::common::{invalid, invalid_text, model, released, sim_err, table, Col};

/// The spectrum at one point (see `bistable_impact.spectrum`).
#[pyfunction]
#[pyo3(signature = (omega, velocity, transient=500, record=1024, samples=64, max_freq=5.0,
    zeta=0.02, restitution=0.85, tol=1e-16, chatter="accumulation"))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn spectrum<'py>(
    py: Python<'py>,
    omega: f64,
    velocity: f64,
    transient: u32,
    record: u32,
    samples: u32,
    max_freq: f64,
    zeta: f64,
    restitution: f64,
    tol: f64,
    chatter: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let m = model(py, omega, velocity, zeta, restitution, tol, chatter)?;
    let count = |name: &str, v: u32, min: u32| {
        NonZeroU32::new(v)
            .filter(|n| n.get() >= min)
            .ok_or_else(|| invalid_text(name, v, &format!("must be >= {min}")))
    };
    let rec = count("record", record, 8)?;
    let spp = count("samples", samples, 4)?;
    if u64::from(record) * u64::from(samples) > 1 << 26 {
        return Err(invalid_text(
            "record",
            record,
            "record × samples must be at most 2^26",
        ));
    }
    if !(max_freq.is_finite() && max_freq > 0.0) {
        return Err(invalid(py, "max_freq", max_freq, "must be > 0"));
    }
    let max_f = max_freq.min(0.5 * f64::from(samples));
    let o = SpectrumOptions {
        transient,
        record: rec,
        samples: spp,
    };
    let s = released(py, || Spectrum::compute(&m, o), |e| sim_err(py, &e))?;
    let flat = flatness(&s.bins, max_f);
    let out = PyDict::new(py);
    out.set_item("omega", m.omega())?;
    out.set_item("velocity", m.velocity())?;
    out.set_item("transient", transient)?;
    out.set_item("record", record)?;
    out.set_item("samples_per_period", samples)?;
    out.set_item("period", s.period)?;
    out.set_item("spectral_flatness", flat)?;
    out.set_item("peak_freq_over_omega", s.peak.0)?;
    out.set_item("peak_amplitude", s.peak.1)?;
    let mut c: [Col; 2] = Default::default();
    for &(f, a) in &s.bins {
        c[0].f(f);
        c[1].f(a);
    }
    let [f, a] = c;
    out.set_item(
        "spectrum",
        table(
            py,
            vec![("freq_over_omega", "f8", f), ("amplitude", "f8", a)],
        )?,
    )?;
    Ok(out)
}
