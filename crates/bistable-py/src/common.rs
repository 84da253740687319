//! What every function of the adapter shares: argument checks with the CLI's messages, the
//! model and the Python package's documented limits on it, columns handed to Python as bytes,
//! classify records as dicts, and the checks for Python signals (Ctrl-C): from the progress
//! callbacks of long analyses ([`check_signals`]) and inside single runs ([`released`]).

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::{self, ThreadId};
use std::time::{Duration, Instant as WallClock};

use pyo3::exceptions::{PyRuntimeError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyBytes, PyDict, PyFloat, PyList};

use bistable_analysis::record::{OutcomeShare, Record, Value};
use bistable_analysis::{Model, Threads};
use bistable_core::{ChatterRule, ParamError, Params, SimError, Sinusoid, SolverOptions, Width};

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

/// Largest damping ratio `zeta` (the FMU's range): beyond it the integrator's steps shrink as
/// `1/zeta` and one call would run for hours.
pub(crate) const MAX_ZETA: f64 = 10.0;
/// The Python package's limit on the model's parameters beyond the core's own checks (which
/// come first and give the CLI's messages; they keep `omega` and `velocity` in the FMU's
/// ranges): `zeta` in the FMU's range, inside which the work of one run grows with its length
/// only.
pub(crate) fn check_scope(py: Python<'_>, zeta: f64) -> PyResult<()> {
    if zeta > MAX_ZETA {
        return Err(invalid(py, "zeta", zeta, "must be in [0, 10]"));
    }
    Ok(())
}

/// The validated model, checked in the CLI's order: omega, velocity, zeta, restitution, tol,
/// then the package's limits ([`check_scope`]).
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
    check_scope(py, zeta)?;
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
    values_dict(py, &mut r.pairs())
}

/// A dict of `(key, value)` pairs: reals, counts, flags and names as Python's, `None` for
/// null, outcomes as a list of dicts ([`outcome_list`]).
pub(crate) fn values_dict<'py>(
    py: Python<'py>,
    pairs: &mut dyn Iterator<Item = (&str, Value<'_>)>,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    for (k, v) in pairs {
        match v {
            Value::F(x) => d.set_item(k, x)?,
            Value::I(n) => d.set_item(k, n)?,
            Value::Bool(b) => d.set_item(k, b)?,
            Value::S(s) => d.set_item(k, s)?,
            Value::Null => d.set_item(k, py.None())?,
            Value::Outcomes(list, _) => d.set_item(k, outcome_list(py, list)?)?,
        }
    }
    Ok(d)
}

/// Outcomes as a list of dicts with the keys of [`OutcomeShare::FIELDS`] (those of the
/// `outcomes` objects of `bistable classify`).
pub(crate) fn outcome_list<'py>(
    py: Python<'py>,
    list: &[OutcomeShare],
) -> PyResult<Bound<'py, PyList>> {
    let out = PyList::empty(py);
    let [class, period, chaotic, final_well, count, fraction] = OutcomeShare::FIELDS;
    for o in list {
        let d = PyDict::new(py);
        d.set_item(class, &o.class)?;
        d.set_item(period, o.period)?;
        d.set_item(chaotic, o.chaotic)?;
        d.set_item(final_well, o.final_well)?;
        d.set_item(count, o.count)?;
        d.set_item(fraction, o.fraction)?;
        out.append(d)?;
    }
    Ok(out)
}

/// Most worker threads of a `threads` argument (also `bistable_impact._native.MAX_THREADS`).
pub(crate) const MAX_THREADS: usize = 1024;

/// The thread count of a `threads` argument: 0 means all cores; at most 1024.
/// The lane width of a sweep: 1 (one trajectory at a time), 4 or 8 trajectories per thread in
/// SIMD lanes (the results are the same).
pub(crate) fn lanes(n: usize) -> PyResult<Width> {
    Width::from_lanes(n).ok_or_else(|| invalid_text("lanes", n, "must be 1, 4 or 8"))
}

pub(crate) fn threads(n: usize) -> PyResult<Threads> {
    match Threads::new(n) {
        _ if n > MAX_THREADS => Err(invalid_text("threads", n, "must be in [0, 1024]")),
        Some(t) => Ok(t),
        None => Ok(Threads::all()),
    }
}

/// A number argument as it arrived, converted to a float by [`Real::get`], which names the
/// argument in the error: `TypeError` for what is not a real number (also `bool` and `str`),
/// `ValueError` for an integer beyond the range of floats. (A plain `f64` argument raises an
/// `OverflowError` that does not name it.)
pub(crate) struct Real(Result<f64, (bool, String)>);

impl Real {
    pub(crate) const fn new(v: f64) -> Self {
        Real(Ok(v))
    }

    pub(crate) fn get(&self, name: &str) -> PyResult<f64> {
        match &self.0 {
            Ok(v) => Ok(*v),
            Err((true, type_name)) => Err(PyTypeError::new_err(format!(
                "'{name}' must be a real number, not {type_name}"
            ))),
            Err((false, shown)) => Err(invalid_text(name, shown, "too large for a float")),
        }
    }
}

impl<'py> FromPyObject<'py> for Real {
    fn extract_bound(value: &Bound<'py, PyAny>) -> PyResult<Self> {
        let numbers = value.py().import("numbers")?.getattr("Real")?;
        if value.is_instance_of::<PyBool>() || !value.is_instance(&numbers)? {
            return Ok(Real(Err((true, value.get_type().name()?.to_string()))));
        }
        Ok(Real(value.extract::<f64>().map_err(|_| {
            (
                false,
                value.repr().map(|r| r.to_string()).unwrap_or_default(),
            )
        })))
    }
}

/// Wall time between two checks for Python signals inside a run.
const SIGNAL_INTERVAL: Duration = Duration::from_millis(20);

/// The state of the interrupt check of one call (see [`released`]).
struct Signals {
    /// The calling thread: the one where Python runs signal handlers.
    owner: ThreadId,
    last: Mutex<WallClock>,
    tripped: AtomicBool,
    raised: Mutex<Option<PyErr>>,
}

impl Signals {
    /// `true` once a signal handler raised: on the calling thread it runs the handlers (at most
    /// every 20 ms), on other threads (the workers of a parallel analysis) it only reads what
    /// the calling thread found.
    fn check(&self) -> bool {
        if self.tripped.load(Ordering::Relaxed) {
            return true;
        }
        if thread::current().id() != self.owner {
            return false;
        }
        {
            let mut last = self.last.lock().unwrap_or_else(|p| p.into_inner());
            if last.elapsed() < SIGNAL_INTERVAL {
                return false;
            }
            *last = WallClock::now();
        }
        match Python::with_gil(|py| py.check_signals()) {
            Ok(()) => false,
            Err(e) => {
                *self.raised.lock().unwrap_or_else(|p| p.into_inner()) = Some(e);
                self.tripped.store(true, Ordering::Relaxed);
                true
            }
        }
    }
}

/// Runs `body` with the GIL released, checking for Python signals about every 20 ms from
/// inside the simulations it runs, on this thread and on the workers of the parallel analyses
/// it calls (`bistable_core::interrupt`): Ctrl-C stops them (with `SimError::Interrupted`) and
/// the call raises `KeyboardInterrupt` (or what the signal handler raised) instead of `body`'s
/// own error, mapped by `error`.
pub(crate) fn released<T: Send, E: Send>(
    py: Python<'_>,
    body: impl FnOnce() -> Result<T, E> + Send,
    error: impl FnOnce(E) -> PyErr,
) -> PyResult<T> {
    let (result, raised) = py.allow_threads(|| {
        let signals = Arc::new(Signals {
            owner: thread::current().id(),
            last: Mutex::new(WallClock::now()),
            tripped: AtomicBool::new(false),
            raised: Mutex::new(None),
        });
        let state = signals.clone();
        let result = bistable_core::interrupt::with_check(Arc::new(move || state.check()), body);
        let raised = signals
            .raised
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .take();
        (result, raised)
    });
    match raised {
        Some(e) => Err(e),
        None => result.map_err(error),
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
/// computation that called it; also `Err` once the check of [`released`] found one (its
/// exception is the one the call raises).
pub(crate) fn check_signals() -> Result<(), Stop> {
    if bistable_core::interrupt::poll() {
        return Err(Stop::Py(PyRuntimeError::new_err("interrupted")));
    }
    Python::with_gil(|py| py.check_signals()).map_err(Stop::Py)
}
