//! What every function of the adapter shares: argument checks with the CLI's messages, the
//! model, columns handed to Python as bytes, classify records as dicts, and the check for
//! Python signals (Ctrl-C) from the progress callbacks of long analyses.

use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyFloat, PyList};

use bistable_analysis::record::{Record, Value};
use bistable_analysis::{Model, Threads};
use bistable_core::{ChatterRule, ParamError, Params, SimError, Sinusoid, SolverOptions};

/// `invalid value '<repr>' for '<name>': <rule>`, the CLI's message with the Python argument.
pub(crate) fn invalid(py: Python<'_>, name: &str, value: f64, rule: &str) -> PyErr {
    let shown = PyFloat::new(py, value)
        .repr()
        .map(|r| r.to_string())
        .unwrap_or_else(|_| value.to_string());
    PyValueError::new_err(format!("invalid value '{shown}' for '{name}': {rule}"))
}

/// The CLI's message for a value shown as text (integers, tuples).
pub(crate) fn invalid_text(name: &str, value: impl std::fmt::Display, rule: &str) -> PyErr {
    PyValueError::new_err(format!("invalid value '{value}' for '{name}': {rule}"))
}

pub(crate) fn param_err(py: Python<'_>, e: &ParamError) -> PyErr {
    invalid(py, e.name, e.value, e.rule)
}

pub(crate) fn sim_err(py: Python<'_>, e: &SimError) -> PyErr {
    match e {
        SimError::Param(p) => param_err(py, p),
        other => PyRuntimeError::new_err(format!("simulation failed: {other}")),
    }
}

pub(crate) fn chatter_rule(py: Python<'_>, name: &str) -> PyResult<ChatterRule> {
    match name {
        "accumulation" => Ok(SolverOptions::default().chatter()),
        "paper" => Ok(ChatterRule::paper()),
        other => Err(PyValueError::new_err(format!(
            "invalid value {} for 'chatter': must be 'accumulation' or 'paper'",
            pyo3::types::PyString::new(py, other).repr()?
        ))),
    }
}

/// The validated model, checked in the CLI's order: omega, velocity, zeta, restitution, tol.
pub(crate) fn model(
    py: Python<'_>,
    omega: f64,
    velocity: f64,
    zeta: f64,
    restitution: f64,
    tol: f64,
    chatter: &str,
) -> PyResult<Model> {
    let shaker = Sinusoid::new(omega, velocity).map_err(|e| param_err(py, &e))?;
    let params = Params::new(zeta, restitution).map_err(|e| param_err(py, &e))?;
    let rule = chatter_rule(py, chatter)?;
    let opts = SolverOptions::new(tol, rule).map_err(|e| param_err(py, &e))?;
    Ok(Model::new(params, shaker, opts))
}

pub(crate) fn positive(py: Python<'_>, name: &str, v: f64) -> PyResult<f64> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(invalid(py, name, v, "must be finite and > 0"))
    }
}

/// Columns of little-endian values, handed to Python as bytes.
#[derive(Default)]
pub(crate) struct Col(Vec<u8>);

impl Col {
    pub(crate) fn f(&mut self, v: f64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    pub(crate) fn b(&mut self, v: bool) {
        self.0.push(u8::from(v));
    }
    pub(crate) fn i(&mut self, v: i64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
}

/// A table: `(name, dtype, column)`; dtype `"f8"`, `"i8"` or `"b1"` (bool, one byte).
pub(crate) fn table<'py>(
    py: Python<'py>,
    cols: Vec<(&str, &str, Col)>,
) -> PyResult<Bound<'py, PyList>> {
    let out = PyList::empty(py);
    for (name, dtype, c) in cols {
        out.append((name, dtype, PyBytes::new(py, &c.0)))?;
    }
    Ok(out)
}

pub(crate) fn record_dict<'py>(py: Python<'py>, r: &Record) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    for (k, v) in r.pairs() {
        match v {
            Value::F(x) => d.set_item(k, x)?,
            Value::I(n) => d.set_item(k, n)?,
            Value::Bool(b) => d.set_item(k, b)?,
            Value::S(s) => d.set_item(k, s)?,
            Value::Null => d.set_item(k, py.None())?,
        }
    }
    Ok(d)
}

/// The thread count of a `threads` argument: 0 means all cores.
pub(crate) fn threads(py: Python<'_>, n: usize) -> PyResult<Threads> {
    if n == 0 {
        Ok(Threads::all())
    } else {
        Threads::new(n).ok_or_else(|| invalid(py, "threads", 0.0, "must be >= 1"))
    }
}

/// Why a long computation stopped: a failed simulation, or an exception raised in Python (a
/// `KeyboardInterrupt` from Ctrl-C, found by [`check_signals`]).
pub(crate) enum Stop {
    Sim(SimError),
    Py(PyErr),
}

impl From<SimError> for Stop {
    fn from(e: SimError) -> Self {
        Stop::Sim(e)
    }
}

impl Stop {
    pub(crate) fn into_py(self, py: Python<'_>) -> PyErr {
        match self {
            Stop::Sim(e) => sim_err(py, &e),
            Stop::Py(e) => e,
        }
    }
}

/// Runs Python's signal handlers (with the GIL, from a thread that released it): `Err` with
/// the handler's exception, e.g. `KeyboardInterrupt` after Ctrl-C, which cancels the
/// computation that called it.
pub(crate) fn check_signals() -> Result<(), Stop> {
    Python::with_gil(|py| py.check_signals()).map_err(Stop::Py)
}
