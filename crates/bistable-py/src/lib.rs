//! `bistable_impact._native`: the Python adapter over `bistable-core` and `bistable-analysis`.
//!
//! No numerics here: arguments are validated by the core's own constructors (their errors
//! become `ValueError` naming the argument, simulation failures `RuntimeError`), runs are
//! delegated to the core and the analyses with the GIL released, and results are handed to
//! Python as plain objects (dicts, bytes of little-endian columns that the Python layer views as
//! numpy arrays). The Python package `bistable_impact` (in `python/`) wraps these functions.

use std::f64::consts::TAU;
use std::ops::ControlFlow;
use std::time::{Instant as WallClock, SystemTime, UNIX_EPOCH};

use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyFloat, PyList};

use bistable_analysis::record::{Record, Value};
use bistable_analysis::schedule::Schedule;
use bistable_analysis::sweep::{classify_point, classify_points};
use bistable_analysis::{thresholds, Model, Threads};
use bistable_core::{
    ChatterRule, Checkpoint, ClassifyOptions, ContactMode, Event, Observer, ParamError, Params,
    SimError, Simulator, Sinusoid, SolverOptions, State, StickCause,
};

/// Most trace rows one `simulate` call may return (memory: 40 bytes a row).
const MAX_TRACE_ROWS: f64 = 1e8;
/// Time units simulated between two checks for Python signals (Ctrl-C), with the GIL released
/// in between (about a millisecond of work for the paper's cases).
const CHUNK: f64 = 1000.0;

mod basins;

/// `invalid value '<repr>' for '<name>': <rule>`, the CLI's message with the Python argument.
fn invalid(py: Python<'_>, name: &str, value: f64, rule: &str) -> PyErr {
    let shown = PyFloat::new(py, value)
        .repr()
        .map(|r| r.to_string())
        .unwrap_or_else(|_| value.to_string());
    PyValueError::new_err(format!("invalid value '{shown}' for '{name}': {rule}"))
}

fn param_err(py: Python<'_>, e: &ParamError) -> PyErr {
    invalid(py, e.name, e.value, e.rule)
}

fn sim_err(py: Python<'_>, e: &SimError) -> PyErr {
    match e {
        SimError::Param(p) => param_err(py, p),
        other => PyRuntimeError::new_err(format!("simulation failed: {other}")),
    }
}

fn chatter_rule(py: Python<'_>, name: &str) -> PyResult<ChatterRule> {
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
fn model(
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

fn positive(py: Python<'_>, name: &str, v: f64) -> PyResult<f64> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(invalid(py, name, v, "must be finite and > 0"))
    }
}

fn mode_name(m: ContactMode) -> &'static str {
    match m {
        ContactMode::Free => "free",
        ContactMode::Sticking => "sticking",
    }
}

fn cause_name(c: StickCause) -> &'static str {
    match c {
        StickCause::Accumulation => "accumulation",
        StickCause::FixedGap => "fixed_gap",
        StickCause::Plastic => "plastic",
        StickCause::ZenoGuard => "zeno_guard",
    }
}

/// Seconds since the Unix epoch (to compare instants between threads).
fn epoch_s() -> f64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0.0, |d| d.as_secs_f64())
}

/// Columns of little-endian values, handed to Python as bytes.
#[derive(Default)]
struct Col(Vec<u8>);

impl Col {
    fn f(&mut self, v: f64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn i(&mut self, v: i64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
}

/// A table: `(name, dtype, column)`; dtype `"f8"` or `"i8"`.
fn table<'py>(py: Python<'py>, cols: Vec<(&str, &str, Col)>) -> PyResult<Bound<'py, PyList>> {
    let out = PyList::empty(py);
    for (name, dtype, c) in cols {
        out.append((name, dtype, PyBytes::new(py, &c.0)))?;
    }
    Ok(out)
}

/// Everything `simulate` returns, gathered from the event stream.
#[derive(Default)]
struct Log {
    /// `index, t, phase, x, v_before, v_after, delta_k`.
    impacts: [Col; 7],
    /// `start, end, x_start, x_end` (NaN: still open).
    sticking: [Col; 4],
    /// `t, v, to_well`.
    snaps: [Col; 3],
    open_stick: Option<(f64, f64)>,
    impacts_n: u64,
    sticks_n: u64,
    snaps_n: u64,
    last_impact: Option<bistable_core::Impact>,
}

impl Log {
    fn stick_row(&mut self, start: f64, end: f64, x0: f64, x1: f64) {
        let [a, b, c, d] = &mut self.sticking;
        a.f(start);
        b.f(end);
        c.f(x0);
        d.f(x1);
    }
}

impl Observer for Log {
    fn event(&mut self, event: &Event) -> ControlFlow<()> {
        match *event {
            Event::Impact(i) => {
                self.impacts_n += 1;
                self.last_impact = Some(i);
                let c = &mut self.impacts;
                c[0].i(i.index as i64);
                c[1].f(i.t);
                c[2].f(i.phase.unwrap_or(f64::NAN));
                c[3].f(i.x);
                c[4].f(i.v_before);
                c[5].f(i.v_after);
                c[6].f(i.delta_k);
            }
            Event::StickStart { t, x, .. } => {
                self.sticks_n += 1;
                if let Some((t0, x0)) = self.open_stick.replace((t, x)) {
                    // A second start without an end closes the first where the next begins.
                    self.stick_row(t0, t, x0, x);
                }
            }
            Event::StickEnd { t, x, .. } => {
                let (t0, x0) = self.open_stick.take().unwrap_or((f64::NAN, f64::NAN));
                self.stick_row(t0, t, x0, x);
            }
            Event::SnapThrough { t, v, to } => {
                self.snaps_n += 1;
                self.snaps[0].f(t);
                self.snaps[1].f(v);
                self.snaps[2].i(i64::from(to.number()));
            }
        }
        ControlFlow::Continue(())
    }
}

fn state_dict<'py>(py: Python<'py>, s: &State) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("t", s.t)?;
    d.set_item("x", s.x)?;
    d.set_item("v", s.v)?;
    d.set_item("z", s.z)?;
    d.set_item("zdot", s.zdot)?;
    d.set_item("mode", mode_name(s.mode))?;
    d.set_item("well", s.well.number())?;
    d.set_item("kinetic_energy", s.kinetic_energy())?;
    d.set_item("potential_energy", s.potential_energy())?;
    Ok(d)
}

fn event_dict<'py>(py: Python<'py>, e: &Event) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    match *e {
        Event::Impact(i) => {
            d.set_item("kind", "impact")?;
            d.set_item("index", i.index)?;
            d.set_item("t", i.t)?;
            d.set_item("phase", i.phase)?;
            d.set_item("x", i.x)?;
            d.set_item("v_before", i.v_before)?;
            d.set_item("v_after", i.v_after)?;
            d.set_item("zdot", i.zdot)?;
            d.set_item("delta_k", i.delta_k)?;
        }
        Event::StickStart {
            t,
            x,
            cause,
            impacts,
        } => {
            d.set_item("kind", "stick_start")?;
            d.set_item("t", t)?;
            d.set_item("x", x)?;
            d.set_item("cause", cause_name(cause))?;
            d.set_item("impacts", impacts)?;
        }
        Event::StickEnd { t, x, v } => {
            d.set_item("kind", "stick_end")?;
            d.set_item("t", t)?;
            d.set_item("x", x)?;
            d.set_item("v", v)?;
        }
        Event::SnapThrough { t, v, to } => {
            d.set_item("kind", "snap_through")?;
            d.set_item("t", t)?;
            d.set_item("v", v)?;
            d.set_item("to_well", to.number())?;
        }
    }
    Ok(d)
}

/// One run from the paper's initial condition (see `bistable_impact.simulate`).
#[pyfunction]
#[pyo3(signature = (omega, velocity, t_end=None, periods=None, zeta=0.02, restitution=0.85,
    tol=1e-16, chatter="accumulation", trace_dt=None))]
#[allow(clippy::too_many_arguments)]
fn simulate<'py>(
    py: Python<'py>,
    omega: f64,
    velocity: f64,
    t_end: Option<f64>,
    periods: Option<f64>,
    zeta: f64,
    restitution: f64,
    tol: f64,
    chatter: &str,
    trace_dt: Option<f64>,
) -> PyResult<Bound<'py, PyDict>> {
    let m = model(py, omega, velocity, zeta, restitution, tol, chatter)?;
    let t_end = match (t_end, periods) {
        (Some(t), None) => positive(py, "t_end", t)?,
        (None, Some(n)) => {
            let t = positive(py, "periods", n)? * TAU;
            if !t.is_finite() {
                return Err(invalid(py, "periods", n, "too large (2π·N overflows)"));
            }
            t
        }
        _ => {
            return Err(PyValueError::new_err(
                "exactly one of 't_end' and 'periods' must be given",
            ))
        }
    };
    let mut trace = match trace_dt {
        Some(h) => {
            let h = positive(py, "trace_dt", h)?;
            let rows = t_end / h;
            if rows > MAX_TRACE_ROWS {
                let rule = format!(
                    "too small for a run up to τ = {t_end}: {rows:.3e} rows (at most {MAX_TRACE_ROWS:e})"
                );
                return Err(invalid(py, "trace_dt", h, &rule));
            }
            Schedule::new(h, 0.0, t_end)
        }
        None => Schedule::none(),
    };
    let mut sim = m.simulator().map_err(|e| sim_err(py, &e))?;
    let mut log = Log::default();
    let mut tr: [Col; 5] = Default::default();
    let started_at = epoch_s();
    let clock = WallClock::now();
    let mut reached = 0.0;
    while reached < t_end {
        let until = (reached + CHUNK).min(t_end);
        py.allow_threads(|| -> Result<(), SimError> {
            while let Some(next) = trace.peek().filter(|&t| t <= until) {
                sim.advance(next, &mut log)?;
                trace.take(next);
                let s = sim.state();
                for (c, v) in tr.iter_mut().zip([s.t, s.x, s.v, s.z, s.zdot]) {
                    c.f(v);
                }
            }
            sim.advance(until, &mut log).map(|_| ())
        })
        .map_err(|e| sim_err(py, &e))?;
        reached = until;
        py.check_signals()?;
    }
    let wall_time_s = clock.elapsed().as_secs_f64();
    let finished_at = epoch_s();
    let fin = sim.state();
    if let Some((t0, x0)) = log.open_stick.take() {
        log.stick_row(t0, f64::NAN, x0, f64::NAN);
    }

    let out = PyDict::new(py);
    let [index, t, phase, x, vb, va, dk] = std::mem::take(&mut log.impacts);
    out.set_item(
        "impacts",
        table(
            py,
            vec![
                ("index", "i8", index),
                ("t", "f8", t),
                ("phase", "f8", phase),
                ("x", "f8", x),
                ("v_before", "f8", vb),
                ("v_after", "f8", va),
                ("delta_k", "f8", dk),
            ],
        )?,
    )?;
    let [s0, s1, x0, x1] = std::mem::take(&mut log.sticking);
    out.set_item(
        "sticking",
        table(
            py,
            vec![
                ("start", "f8", s0),
                ("end", "f8", s1),
                ("x_start", "f8", x0),
                ("x_end", "f8", x1),
            ],
        )?,
    )?;
    let [st, sv, sw] = std::mem::take(&mut log.snaps);
    out.set_item(
        "snaps",
        table(
            py,
            vec![("t", "f8", st), ("v", "f8", sv), ("to_well", "i8", sw)],
        )?,
    )?;
    if trace_dt.is_some() {
        let names = ["t", "x", "v", "z", "zdot"];
        let cols = names.into_iter().zip(tr).map(|(n, c)| (n, "f8", c));
        out.set_item("trace", table(py, cols.collect())?)?;
    } else {
        out.set_item("trace", py.None())?;
    }
    let fs = state_dict(py, &fin)?;
    out.set_item("final_state", &fs)?;

    let s = PyDict::new(py);
    s.set_item("omega", m.omega())?;
    s.set_item("velocity", m.velocity())?;
    s.set_item("zeta", m.params.zeta())?;
    s.set_item("restitution", m.restitution())?;
    s.set_item("tol", m.opts.tol())?;
    s.set_item("chatter", chatter)?;
    s.set_item("t_end", t_end)?;
    s.set_item("natural_periods", t_end / TAU)?;
    s.set_item("shaker_periods", t_end / m.shaker_period())?;
    s.set_item("impacts", log.impacts_n)?;
    s.set_item("sticking_intervals", log.sticks_n)?;
    s.set_item("snap_throughs", log.snaps_n)?;
    s.set_item("final_well", fin.well.number())?;
    s.set_item("final_state", fs)?;
    match log.last_impact {
        Some(i) => {
            let e = event_dict(py, &Event::Impact(i))?;
            e.del_item("kind")?;
            e.del_item("zdot")?;
            s.set_item("last_impact", e)?;
        }
        None => s.set_item("last_impact", py.None())?,
    }
    s.set_item("wall_time_s", wall_time_s)?;
    s.set_item("steps", sim.stats().steps)?;
    s.set_item("started_at", started_at)?;
    s.set_item("finished_at", finished_at)?;
    out.set_item("summary", s)?;
    Ok(out)
}

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

fn record_dict<'py>(py: Python<'py>, r: &Record) -> PyResult<Bound<'py, PyDict>> {
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

/// The response class at one point (see `bistable_impact.classify`).
#[pyfunction]
#[pyo3(signature = (omega, velocity, zeta=0.02, restitution=0.85, tol=1e-16,
    chatter="accumulation", max_periods=20000.0, full=false, max_period=16, period_tol=1e-8,
    lyapunov_periods=2000))]
#[allow(clippy::too_many_arguments)]
fn classify<'py>(
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
    let point = py
        .allow_threads(|| classify_point(&m, co))
        .map_err(|e| sim_err(py, &e))?;
    record_dict(py, &Record::new(&point))
}

/// Classifies every `(omega, velocity)` of `points` on `threads` threads (0: all cores); the
/// records in the order of `points`; a point that fails raises.
#[pyfunction]
#[pyo3(signature = (points, zeta=0.02, restitution=0.85, tol=1e-16, chatter="accumulation",
    max_periods=20000.0, full=false, max_period=16, period_tol=1e-8, lyapunov_periods=300,
    threads=0))]
#[allow(clippy::too_many_arguments)]
fn classify_many<'py>(
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
    threads: usize,
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
    let threads = if threads == 0 {
        Threads::all()
    } else {
        Threads::new(threads).ok_or_else(|| invalid(py, "threads", 0.0, "must be >= 1"))?
    };
    let mut records: Vec<Option<Record>> = vec![None; points.len()];
    py.allow_threads(|| {
        classify_points(&m, &points, co, threads, |i, r| {
            records[i] = Some(Record::new(&r?));
            Ok::<(), SimError>(())
        })
    })
    .map_err(|e| sim_err(py, &e))?;
    let out = PyList::empty(py);
    for r in records.iter().flatten() {
        out.append(record_dict(py, r)?)?;
    }
    Ok(out)
}

/// The velocity thresholds of Eq. 16–18 (see `bistable_impact.thresholds`).
#[pyfunction]
#[pyo3(signature = (restitution=0.85, omega=None))]
fn thresholds_of<'py>(
    py: Python<'py>,
    restitution: f64,
    omega: Option<f64>,
) -> PyResult<Bound<'py, PyDict>> {
    let e = restitution;
    if !(e.is_finite() && (0.0..1.0).contains(&e)) {
        return Err(invalid(py, "restitution", e, "must be in [0, 1)"));
    }
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

/// Passes events to a Python callable; a `False` answer or an exception stops the advance.
struct Callback<'a> {
    f: &'a Py<PyAny>,
    error: Option<PyErr>,
}

impl Observer for Callback<'_> {
    fn event(&mut self, event: &Event) -> ControlFlow<()> {
        Python::with_gil(|py| {
            let r = event_dict(py, event).and_then(|d| self.f.call1(py, (d,)));
            match r {
                Ok(v) if v.bind(py).is(pyo3::types::PyBool::new(py, false)) => {
                    ControlFlow::Break(())
                }
                Ok(_) => ControlFlow::Continue(()),
                Err(e) => {
                    self.error = Some(e);
                    ControlFlow::Break(())
                }
            }
        })
    }
}

/// A stateful simulator (see `bistable_impact.Simulator`).
#[pyclass(module = "bistable_impact", name = "Simulator")]
struct PySimulator {
    sim: Simulator,
}

#[pymethods]
impl PySimulator {
    #[new]
    #[pyo3(signature = (omega, velocity, zeta=0.02, restitution=0.85, tol=1e-16,
        chatter="accumulation", t0=0.0, x0=0.0, v0=0.0))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        omega: f64,
        velocity: f64,
        zeta: f64,
        restitution: f64,
        tol: f64,
        chatter: &str,
        t0: f64,
        x0: f64,
        v0: f64,
    ) -> PyResult<Self> {
        let m = model(py, omega, velocity, zeta, restitution, tol, chatter)?;
        let sim = Simulator::with_state(m.params, m.shaker.into(), m.opts, t0, x0, v0)
            .map_err(|e| sim_err(py, &e))?;
        Ok(Self { sim })
    }

    /// Advances to `t`; see the stub for the callback protocol.
    #[pyo3(signature = (t, callback=None))]
    fn advance_to(
        &mut self,
        py: Python<'_>,
        t: f64,
        callback: Option<Py<PyAny>>,
    ) -> PyResult<PyObject> {
        let sim = &mut self.sim;
        match callback {
            Some(f) => {
                let mut cb = Callback { f: &f, error: None };
                let r = py.allow_threads(|| sim.advance(t, &mut cb));
                if let Some(e) = cb.error {
                    return Err(e);
                }
                let reached = r.map_err(|e| sim_err(py, &e))?;
                Ok(reached.into_pyobject(py)?.to_owned().into_any().unbind())
            }
            None => {
                let events = py
                    .allow_threads(|| sim.events_until(t))
                    .map_err(|e| sim_err(py, &e))?;
                let out = PyList::empty(py);
                for e in &events {
                    out.append(event_dict(py, e)?)?;
                }
                Ok(out.into_any().unbind())
            }
        }
    }

    /// The state now: `t, x, v, z, zdot, mode, well, kinetic_energy, potential_energy`.
    fn state<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        state_dict(py, &self.sim.state())
    }

    /// Current time τ.
    #[getter]
    fn time(&self) -> f64 {
        self.sim.time()
    }

    /// Work counters: steps, impacts, sticks, snap_throughs.
    fn stats<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let s = self.sim.stats();
        let d = PyDict::new(py);
        d.set_item("steps", s.steps)?;
        d.set_item("impacts", s.impacts)?;
        d.set_item("sticks", s.sticks)?;
        d.set_item("snap_throughs", s.snap_throughs)?;
        Ok(d)
    }

    /// Switches to a sinusoidal shaker `(omega, velocity)` now, continuing the plate.
    fn set_sinusoid(&mut self, py: Python<'_>, omega: f64, velocity: f64) -> PyResult<()> {
        self.sim
            .set_sinusoid(omega, velocity)
            .map_err(|e| sim_err(py, &e))
    }

    /// The complete state as bytes (versioned, checksummed format of `bistable_core::codec`).
    fn checkpoint<'py>(&self, py: Python<'py>) -> Bound<'py, PyBytes> {
        PyBytes::new(py, &self.sim.checkpoint().to_bytes())
    }

    /// A simulator that continues exactly as the one `data` was taken from.
    #[staticmethod]
    fn from_checkpoint(py: Python<'_>, data: &[u8]) -> PyResult<Self> {
        let c = Checkpoint::from_bytes(data).map_err(PyValueError::new_err)?;
        let sim = Simulator::from_checkpoint(&c).map_err(|e| match e {
            SimError::Param(p) => PyValueError::new_err(format!("invalid checkpoint: {p}")),
            other => sim_err(py, &other),
        })?;
        Ok(Self { sim })
    }

    fn __reduce__<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<(Bound<'py, PyAny>, (Bound<'py, PyBytes>,))> {
        let f = py.get_type::<PySimulator>().getattr("from_checkpoint")?;
        Ok((f, (self.checkpoint(py),)))
    }

    fn __repr__(&self) -> String {
        let s = self.sim.state();
        format!(
            "Simulator(t={}, x={}, v={}, mode={}, well={})",
            s.t,
            s.x,
            s.v,
            mode_name(s.mode),
            s.well.number()
        )
    }
}

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(simulate, m)?)?;
    m.add_function(wrap_pyfunction!(classify, m)?)?;
    m.add_function(wrap_pyfunction!(classify_many, m)?)?;
    m.add_function(wrap_pyfunction!(thresholds_of, m)?)?;
    m.add_function(wrap_pyfunction!(basins::basin_cells, m)?)?;
    m.add_function(wrap_pyfunction!(basins::basin_attractors, m)?)?;
    m.add_class::<PySimulator>()?;
    // The classify record's keys in order: the map CSV's columns (one definition, in Rust).
    m.add("COLUMNS", bistable_analysis::record::COLUMNS.to_vec())?;
    Ok(())
}
