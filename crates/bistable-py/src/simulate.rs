//! `simulate` and the stateful `Simulator`.

use std::f64::consts::TAU;
use std::ops::ControlFlow;
use std::time::{Instant as WallClock, SystemTime, UNIX_EPOCH};

use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyList};

use bistable_analysis::event_log::{
    cause_name, mode_name, Cell, EventLog, Row, IMPACT_COLUMNS, INTEGER_COLUMNS, SNAP_COLUMNS,
    STICKING_COLUMNS,
};
use bistable_analysis::schedule::Schedule;
use bistable_core::{Checkpoint, Event, Observer, PlateRecord, SimError, Simulator, State};

use crate::common::{check_scope, invalid, model, positive, released, sim_err, table, Col, Real};

/// Most trace rows one `simulate` call may return (memory: 40 bytes a row).
const MAX_TRACE_ROWS: f64 = 1e8;
/// Most events (impacts, sticking intervals and barrier crossings together) one `simulate` or
/// `Simulator.advance_to` call without a callback may return (memory: up to 56 bytes each).
const MAX_EVENTS: u64 = 10_000_000;
/// Largest span `max(Ω, 1)·|τ − τ_origin|` from the origin of the shaker's sinusoid (as the
/// FMU's clock range): the core keeps the shaker phase accurate below 2^52.
const MAX_CLOCK_SPAN: f64 = 4_503_599_627_370_496.0;

/// The error of a call that returned [`MAX_EVENTS`] events before its end.
fn too_many_events(t: f64) -> PyErr {
    PyRuntimeError::new_err(format!(
        "more than {MAX_EVENTS} events before τ = {t}: split the run, or use \
         Simulator.advance_to with a callback"
    ))
}
/// Seconds since the Unix epoch (to compare instants between threads).
fn epoch_s() -> f64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0.0, |d| d.as_secs_f64())
}

/// Everything `simulate` returns, gathered from the event stream: the event log's tables as
/// columns.
#[derive(Default)]
struct Log {
    log: EventLog,
    /// `index, t, phase, x, v_before, v_after, delta_k`.
    impacts: [Col; 7],
    /// `start, end, x_start, x_end` (NaN: missing).
    sticking: [Col; 4],
    /// `t, v, to_well`.
    snaps: [Col; 3],
    /// Events logged (all kinds); the advance stops at [`MAX_EVENTS`].
    events_n: u64,
}

/// Appends a row of cells to columns (a missing value as NaN).
fn push_row<const N: usize>(cols: &mut [Col; N], cells: [Cell; N]) {
    for (c, cell) in cols.iter_mut().zip(cells) {
        match cell {
            Cell::Int(i) => c.i(i as i64),
            Cell::Real(v) => c.f(v),
            Cell::Missing => c.f(f64::NAN),
        }
    }
}

/// A table's columns with their names and dtypes.
fn columns<const N: usize>(
    names: &[&'static str; N],
    cols: [Col; N],
) -> Vec<(&'static str, &'static str, Col)> {
    let dtype = |n: &str| {
        if INTEGER_COLUMNS.contains(&n) {
            "i8"
        } else {
            "f8"
        }
    };
    names
        .iter()
        .zip(cols)
        .map(|(&n, c)| (n, dtype(n), c))
        .collect()
}

impl Log {
    /// Moves the rows the log has completed into the columns.
    fn take_rows(&mut self) {
        for row in self.log.rows() {
            match row {
                Row::Impact(r) => push_row(&mut self.impacts, r.cells()),
                Row::Stick(r) => push_row(&mut self.sticking, r.cells()),
                Row::Snap(r) => push_row(&mut self.snaps, r.cells()),
            }
        }
    }
}

impl Observer for Log {
    fn event(&mut self, event: &Event) -> ControlFlow<()> {
        self.events_n += 1;
        self.log.record(event);
        self.take_rows();
        if self.events_n >= MAX_EVENTS {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
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
pub(crate) fn simulate<'py>(
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
    let finished = released(
        py,
        || -> Result<bool, SimError> {
            while let Some(next) = trace.peek() {
                if !sim.advance(next, &mut log)? {
                    return Ok(false);
                }
                trace.take(next);
                let s = sim.state();
                for (c, v) in tr.iter_mut().zip([s.t, s.x, s.v, s.z, s.zdot]) {
                    c.f(v);
                }
            }
            sim.advance(t_end, &mut log)
        },
        |e| sim_err(py, &e),
    )?;
    if !finished {
        return Err(too_many_events(sim.time()));
    }
    let wall_time_s = clock.elapsed().as_secs_f64();
    let finished_at = epoch_s();
    let fin = sim.state();
    log.log.finish();
    log.take_rows();

    let out = PyDict::new(py);
    let impacts = columns(&IMPACT_COLUMNS, std::mem::take(&mut log.impacts));
    out.set_item("impacts", table(py, impacts)?)?;
    let sticking = columns(&STICKING_COLUMNS, std::mem::take(&mut log.sticking));
    out.set_item("sticking", table(py, sticking)?)?;
    let snaps = columns(&SNAP_COLUMNS, std::mem::take(&mut log.snaps));
    out.set_item("snaps", table(py, snaps)?)?;
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
    s.set_item("impacts", log.log.impacts())?;
    s.set_item("sticking_intervals", log.log.sticks())?;
    s.set_item("snap_throughs", log.log.snaps())?;
    s.set_item("final_well", fin.well.number())?;
    s.set_item("final_state", fs)?;
    match log.log.last_impact() {
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

/// Collects the events of an advance, stopping at [`MAX_EVENTS`].
#[derive(Default)]
struct Events(Vec<Event>);

impl Observer for Events {
    fn event(&mut self, event: &Event) -> ControlFlow<()> {
        self.0.push(*event);
        if self.0.len() as u64 >= MAX_EVENTS {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    }
}

/// The shaker of a Python simulator's plate: `(Ω, V, origin τ)`; `None` for an external
/// piece (which only a crafted checkpoint can hold).
fn sinusoid_of(sim: &Simulator) -> Option<(f64, f64, f64)> {
    match sim.checkpoint().plate {
        PlateRecord::Sinusoid {
            omega,
            velocity,
            origin,
            ..
        } => Some((omega, velocity, origin.0 + origin.1)),
        PlateRecord::Poly { .. } => None,
    }
}

/// Whether `t` is within the clock range of `sim`'s sinusoid ([`MAX_CLOCK_SPAN`]).
fn in_clock_range(sim: &Simulator, t: f64) -> bool {
    sinusoid_of(sim)
        .is_some_and(|(omega, _, origin)| omega.max(1.0) * (t - origin).abs() < MAX_CLOCK_SPAN)
}

/// Why a restored simulator is not one a run of this package can reach, if it is not: a plate
/// that is not a sinusoid, a `zeta` beyond the package's limit (the core's decoding checks the
/// shaker's own ranges), or a time or state that is not finite or beyond the clock range
/// (checked as the FMU checks its restored states).
fn unreachable_state(py: Python<'_>, sim: &Simulator) -> Option<String> {
    if sinusoid_of(sim).is_none() {
        return Some("the plate is not the shaker's sinusoid".into());
    }
    if let Err(e) = check_scope(py, sim.params().zeta()) {
        return Some(e.value(py).to_string());
    }
    let s = sim.state();
    let values = [
        ("t", s.t),
        ("x", s.x),
        ("v", s.v),
        ("z", s.z),
        ("zdot", s.zdot),
        ("kinetic_energy", s.kinetic_energy()),
        ("potential_energy", s.potential_energy()),
    ];
    if let Some((name, v)) = values.iter().find(|(_, v)| !v.is_finite()) {
        return Some(format!("{name} = {v} is not finite"));
    }
    if !in_clock_range(sim, s.t) {
        return Some(format!(
            "t = {} is beyond the clock range (max(Ω, 1)·|t − origin| < 2^52)",
            s.t
        ));
    }
    None
}

/// A stateful simulator (see `bistable_impact.Simulator`).
#[pyclass(module = "bistable_impact", name = "Simulator")]
pub(crate) struct PySimulator {
    sim: Simulator,
}

#[pymethods]
impl PySimulator {
    #[new]
    #[pyo3(signature = (omega, velocity, zeta=Real::new(0.02), restitution=Real::new(0.85),
        tol=Real::new(1e-16), chatter="accumulation", t0=Real::new(0.0), x0=Real::new(0.0),
        v0=Real::new(0.0)))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        omega: Real,
        velocity: Real,
        zeta: Real,
        restitution: Real,
        tol: Real,
        chatter: &str,
        t0: Real,
        x0: Real,
        v0: Real,
    ) -> PyResult<Self> {
        let m = model(
            py,
            omega.get("omega")?,
            velocity.get("velocity")?,
            zeta.get("zeta")?,
            restitution.get("restitution")?,
            tol.get("tol")?,
            chatter,
        )?;
        let (t0, x0, v0) = (t0.get("t0")?, x0.get("x0")?, v0.get("v0")?);
        let sim = Simulator::with_state(m.params, m.shaker.into(), m.opts, t0, x0, v0)
            .map_err(|e| sim_err(py, &e))?;
        if !in_clock_range(&sim, t0) {
            return Err(invalid(
                py,
                "t0",
                t0,
                "beyond the clock range: max(Ω, 1)·|t0| must be < 2^52",
            ));
        }
        Ok(Self { sim })
    }

    /// Advances to `t`; see the stub for the callback protocol.
    #[pyo3(signature = (t, callback=None))]
    fn advance_to(
        &mut self,
        py: Python<'_>,
        t: Real,
        callback: Option<Py<PyAny>>,
    ) -> PyResult<PyObject> {
        let t = t.get("t")?;
        if !t.is_finite() {
            return Err(invalid(py, "t", t, "must be finite"));
        }
        if !in_clock_range(&self.sim, t) {
            let rule = "beyond the clock range: max(Ω, 1)·|t − origin| must be < 2^52";
            return Err(invalid(py, "t", t, rule));
        }
        if let Some(f) = &callback {
            if !f.bind(py).is_callable() {
                return Err(pyo3::exceptions::PyTypeError::new_err(format!(
                    "'callback' must be callable, not {}",
                    f.bind(py).get_type().name()?
                )));
            }
        }
        let sim = &mut self.sim;
        match callback {
            Some(f) => {
                let mut cb = Callback { f: &f, error: None };
                let r = released(py, || sim.advance(t, &mut cb), |e| sim_err(py, &e));
                if let Some(e) = cb.error {
                    return Err(e);
                }
                Ok(r?.into_pyobject(py)?.to_owned().into_any().unbind())
            }
            None => {
                let mut events = Events::default();
                let reached = released(py, || sim.advance(t, &mut events), |e| sim_err(py, &e))?;
                if !reached {
                    return Err(too_many_events(sim.time()));
                }
                let out = PyList::empty(py);
                for e in &events.0 {
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
    fn set_sinusoid(&mut self, py: Python<'_>, omega: Real, velocity: Real) -> PyResult<()> {
        let (omega, velocity) = (omega.get("omega")?, velocity.get("velocity")?);
        bistable_core::Sinusoid::new(omega, velocity)
            .map_err(|e| crate::common::param_err(py, &e))?;
        // The new sinusoid's origin is now: the clock range starts again from here.
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
        let refused =
            |why: String| PyValueError::new_err(format!("invalid checkpoint 'data': {why}"));
        let c = Checkpoint::from_bytes(data).map_err(refused)?;
        let sim = Simulator::from_checkpoint(&c).map_err(|e| match e {
            SimError::Param(p) => refused(p.to_string()),
            other => sim_err(py, &other),
        })?;
        if let Some(why) = unreachable_state(py, &sim) {
            return Err(refused(format!("not a state a run can reach: {why}")));
        }
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
