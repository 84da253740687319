//! One FMU instance: lifecycle, logging, variable values, steps and FMU states. Everything the
//! C functions do after their arguments became Rust values; no shared state between instances.
//!
//! A refused call (illegal in the current state, bad argument or value) returns an error message,
//! which the export logs and turns into `fmi2Error`; the instance is left as it was.

use std::collections::HashSet;
use std::ffi::CString;

use bistable_core::Event;

use crate::fmi2::*;
use crate::md::{cat, var, Causality, Kind, CATEGORIES, VARS};
use crate::model::{
    Model, PlateInputs, StepFailure, MAX_CLOCK_SPAN, MAX_PLATE_ORDER, MAX_STEP_SPAN,
};
use crate::state::Snapshot;

/// FMI 2.0 co-simulation states (steps are synchronous: no `stepInProgress`/`stepCanceled`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Lifecycle {
    /// After `fmi2Instantiate` or `fmi2Reset`.
    Instantiated,
    /// Between `fmi2EnterInitializationMode` and `fmi2ExitInitializationMode`.
    InitializationMode,
    /// Ready for `fmi2DoStep`.
    StepComplete,
    /// `fmi2DoStep` returned `fmi2Discard`.
    StepFailed,
    /// After `fmi2Terminate`.
    Terminated,
    /// After an internal fault.
    Error,
}

/// Sets of lifecycle states in which a function may be called.
pub mod allowed {
    use super::Lifecycle::{self, *};

    /// A set of states.
    pub type Mask = u8;

    const fn bit(l: Lifecycle) -> Mask {
        1 << l as u8
    }

    /// Every state.
    pub const ANY: Mask = !0;
    /// `fmi2SetupExperiment`, `fmi2EnterInitializationMode`.
    pub const INSTANTIATED: Mask = bit(Instantiated);
    /// `fmi2ExitInitializationMode`.
    pub const INIT: Mask = bit(InitializationMode);
    /// `fmi2Set*`, `fmi2SetRealInputDerivatives`.
    pub const SET: Mask = bit(Instantiated) | bit(InitializationMode) | bit(StepComplete);
    /// `fmi2Get*`.
    pub const GET: Mask = bit(InitializationMode)
        | bit(StepComplete)
        | bit(StepFailed)
        | bit(Terminated)
        | bit(Error);
    /// `fmi2GetRealOutputDerivatives`.
    pub const GET_DERIVATIVES: Mask =
        bit(StepComplete) | bit(StepFailed) | bit(Terminated) | bit(Error);
    /// `fmi2DoStep`.
    pub const STEP: Mask = bit(StepComplete);
    /// `fmi2Terminate`.
    pub const TERMINATE: Mask = bit(StepComplete) | bit(StepFailed);
    /// `fmi2Get*Status`.
    pub const STATUS: Mask = bit(StepComplete) | bit(StepFailed) | bit(Terminated);
    /// `fmi2CancelStep` (only while an asynchronous step runs, which never happens).
    pub const NONE: Mask = 0;

    /// Whether `l` is in `mask`.
    pub fn contains(mask: Mask, l: Lifecycle) -> bool {
        mask & bit(l) != 0
    }
}

/// Marks a live instance (a cheap check against stray handles).
const MAGIC: u64 = 0x6269_7374_6162_6c65;

/// Outcome of a call: a status to return, or a refusal to log and return as `fmi2Error`.
pub type Outcome = Result<fmi2Status, String>;

/// One instance of the FMU.
pub struct Instance {
    magic: u64,
    name: CString,
    env: fmi2ComponentEnvironment,
    logger: fmi2CallbackLogger,
    logging_on: bool,
    enabled: Vec<bool>,
    /// Lifecycle state.
    pub lifecycle: Lifecycle,
    values: Vec<f64>,
    /// Plate derivatives of order ≥ 1 set for the next step (`fmi2SetRealInputDerivatives`).
    derivatives: PlateInputs,
    /// Some entry of `derivatives` is set.
    derivatives_given: bool,
    start_time: f64,
    stop_time: Option<f64>,
    model: Option<Model>,
    /// Outputs must be recomputed before they are read (they are computed on demand, so a
    /// step costs only the integration).
    outputs_stale: bool,
    last_successful_time: f64,
    terminated: bool,
    /// FMU states handed out by this instance (addresses of `Box<Snapshot>`).
    states: HashSet<usize>,
    events: Vec<Event>,
}

fn start_values() -> Vec<f64> {
    VARS.iter().map(|v| v.start).collect()
}

/// `"name" (vr N)` for messages.
fn label(index: usize) -> String {
    format!("{} (vr {})", VARS[index].name, VARS[index].vr)
}

impl Instance {
    /// A new instance in state `Instantiated`.
    pub fn new(
        name: CString,
        env: fmi2ComponentEnvironment,
        logger: fmi2CallbackLogger,
        logging_on: bool,
    ) -> Self {
        Self {
            magic: MAGIC,
            name,
            env,
            logger,
            logging_on,
            enabled: vec![logging_on; CATEGORIES.len()],
            lifecycle: Lifecycle::Instantiated,
            values: start_values(),
            derivatives: [None; MAX_PLATE_ORDER + 1],
            derivatives_given: false,
            start_time: 0.0,
            stop_time: None,
            model: None,
            outputs_stale: true,
            last_successful_time: 0.0,
            terminated: false,
            states: HashSet::new(),
            events: Vec::new(),
        }
    }

    /// Whether this looks like a live instance.
    pub fn is_live(&self) -> bool {
        self.magic == MAGIC
    }

    /// Marks the instance as freed (a later use of the stale handle is then refused).
    pub fn retire(&mut self) {
        self.magic = 0;
        for addr in self.states.drain() {
            // SAFETY: every registered address came from `Box::into_raw` and is unique.
            drop(unsafe { Box::from_raw(addr as *mut Snapshot) });
        }
    }

    /// Sends `msg` to the host's logger: errors always, the rest when logging is on and the
    /// category enabled. The message goes as the argument of a `"%s"` format.
    pub fn log(&self, status: fmi2Status, category: usize, msg: &str) {
        let wanted = self.logging_on && (self.enabled[category] || self.enabled[cat::logAll]);
        if status < fmi2Error && !wanted {
            return;
        }
        let Some(logger) = self.logger else { return };
        let text = CString::new(msg.replace('\0', "\\0")).unwrap_or_default();
        let category = CString::new(CATEGORIES[category]).unwrap_or_default();
        // SAFETY: the host's logger with valid NUL-terminated strings, as FMI specifies.
        unsafe {
            logger(
                self.env,
                self.name.as_ptr(),
                status,
                category.as_ptr(),
                c"%s".as_ptr(),
                text.as_ptr(),
            )
        };
    }

    /// Logs a refusal of `func`.
    pub fn log_error(&self, func: &str, msg: &str) {
        self.log(fmi2Error, cat::logStatusError, &format!("{func}: {msg}"));
    }

    /// `fmi2SetDebugLogging`.
    pub fn set_debug_logging(&mut self, on: bool, categories: &[String]) -> Outcome {
        let mut which = Vec::with_capacity(categories.len());
        for c in categories {
            let i = CATEGORIES.iter().position(|k| k == c).ok_or_else(|| {
                format!(
                    "unknown log category \"{c}\" (known: {})",
                    CATEGORIES.join(", ")
                )
            })?;
            which.push(i);
        }
        if which.is_empty() {
            self.enabled.iter_mut().for_each(|e| *e = on);
        } else {
            which.iter().for_each(|&i| self.enabled[i] = on);
        }
        self.logging_on = self.enabled.iter().any(|&e| e);
        Ok(fmi2OK)
    }

    /// `fmi2SetupExperiment`.
    pub fn setup_experiment(
        &mut self,
        start: f64,
        stop: Option<f64>,
        tolerance: Option<f64>,
    ) -> Outcome {
        if !start.is_finite() {
            return Err(format!("startTime = {start} s must be finite"));
        }
        if let Some(stop) = stop {
            if !(stop.is_finite() && stop >= start) {
                return Err(format!(
                    "stopTime = {stop} s must be finite and >= startTime = {start} s"
                ));
            }
        }
        if let Some(tol) = tolerance {
            if !(tol.is_finite() && tol > 0.0) {
                return Err(format!("tolerance = {tol} must be finite and > 0"));
            }
            self.log(
                fmi2OK,
                cat::logAll,
                &format!("tolerance {tol} ignored: the integrator's accuracy is the parameter tol"),
            );
        }
        self.start_time = start;
        self.stop_time = stop;
        self.outputs_stale = true;
        Ok(fmi2OK)
    }

    /// `fmi2EnterInitializationMode`.
    pub fn enter_initialization(&mut self) -> Outcome {
        self.lifecycle = Lifecycle::InitializationMode;
        Ok(fmi2OK)
    }

    /// Builds the model at the start time and writes its outputs.
    fn start_model(&mut self) -> Result<Model, String> {
        self.events.clear();
        let mut model = Model::start(
            &self.values,
            &self.derivatives,
            self.start_time,
            &mut self.events,
        )?;
        model.write_outputs(&mut self.values)?;
        self.outputs_stale = false;
        Ok(model)
    }

    /// `fmi2ExitInitializationMode`: checks the parameters and starts the simulation.
    pub fn exit_initialization(&mut self) -> Outcome {
        let model = self.start_model()?;
        self.model = Some(model);
        self.log_events();
        self.last_successful_time = self.start_time;
        self.lifecycle = Lifecycle::StepComplete;
        Ok(fmi2OK)
    }

    /// Logs the collected events under `logEvents` (when enabled) and clears them.
    fn log_events(&mut self) {
        let on = self.logging_on && (self.enabled[cat::logEvents] || self.enabled[cat::logAll]);
        if let (true, Some(model)) = (on, &self.model) {
            for e in &self.events {
                self.log(fmi2OK, cat::logEvents, &model.describe_event(e));
            }
        }
        self.events.clear();
    }

    /// `fmi2Terminate`.
    pub fn terminate(&mut self) -> Outcome {
        self.lifecycle = Lifecycle::Terminated;
        Ok(fmi2OK)
    }

    /// `fmi2Reset`: back to `Instantiated` with the start values (FMU states stay valid).
    pub fn reset(&mut self) -> Outcome {
        self.lifecycle = Lifecycle::Instantiated;
        self.values = start_values();
        self.clear_derivatives();
        self.start_time = 0.0;
        self.stop_time = None;
        self.model = None;
        self.outputs_stale = true;
        self.last_successful_time = 0.0;
        self.terminated = false;
        Ok(fmi2OK)
    }

    /// Forgets the input derivatives (they hold for one step).
    fn clear_derivatives(&mut self) {
        self.derivatives = [None; MAX_PLATE_ORDER + 1];
        self.derivatives_given = false;
    }

    /// Index of the variable with value reference `vr` and type `kind`.
    fn lookup(vr: fmi2ValueReference, kind: Kind) -> Result<usize, String> {
        let i = VARS
            .iter()
            .position(|v| v.vr == vr)
            .ok_or_else(|| format!("unknown value reference {vr}"))?;
        if VARS[i].kind != kind {
            return Err(format!("{} is {:?}, not {kind:?}", label(i), VARS[i].kind));
        }
        Ok(i)
    }

    /// Values of the variables `vrs` of type `kind`.
    pub fn get(&mut self, vrs: &[fmi2ValueReference], kind: Kind) -> Result<Vec<f64>, String> {
        let idx = vrs
            .iter()
            .map(|&vr| Self::lookup(vr, kind))
            .collect::<Result<Vec<_>, _>>()?;
        let wants_output = idx.iter().any(|&i| VARS[i].causality == Causality::Output);
        if wants_output && self.outputs_stale {
            match &mut self.model {
                Some(model) => model.write_outputs(&mut self.values)?,
                // Initialization mode: the outputs at the start time from the current values.
                None => {
                    self.start_model()
                        .map_err(|e| format!("outputs cannot be computed: {e}"))?;
                }
            }
            self.outputs_stale = false;
        }
        Ok(idx.iter().map(|&i| self.values[i]).collect())
    }

    /// Sets the variables `vrs` of type `kind` (all or none).
    pub fn set(&mut self, vrs: &[fmi2ValueReference], vals: &[f64], kind: Kind) -> Outcome {
        let mut checked = Vec::with_capacity(vrs.len());
        for (&vr, &value) in vrs.iter().zip(vals) {
            let i = Self::lookup(vr, kind)?;
            self.check_settable(i)?;
            checked.push((i, check_range(i, value)?));
        }
        for (i, value) in checked {
            self.values[i] = value;
        }
        self.outputs_stale = true;
        Ok(fmi2OK)
    }

    fn check_settable(&self, i: usize) -> Result<(), String> {
        let v = &VARS[i];
        match v.causality {
            Causality::Output => Err(format!("{} is an output and cannot be set", label(i))),
            Causality::Parameter
                if !v.tunable && self.lifecycle == Lifecycle::StepComplete =>
            {
                Err(format!(
                    "{} is a fixed parameter: set it before fmi2ExitInitializationMode (or after fmi2Reset)",
                    label(i)
                ))
            }
            _ => Ok(()),
        }
    }

    /// `fmi2SetRealInputDerivatives`: derivatives of `z_in` (orders 1..=5) and `zdot_in`
    /// (orders 1..=4), in SI units, valid for the next step. Both name plate derivatives of
    /// order ≥ 2 (the later call wins); order 1 of `z_in` is accepted and superseded by `zdot_in`.
    pub fn set_input_derivatives(
        &mut self,
        vrs: &[fmi2ValueReference],
        orders: &[fmi2Integer],
        vals: &[f64],
    ) -> Outcome {
        let mut checked = Vec::with_capacity(vrs.len());
        for ((&vr, &order), &value) in vrs.iter().zip(orders).zip(vals) {
            let i = Self::lookup(vr, Kind::Real)?;
            let shift = match i {
                i if i == var::z_in => 0,
                i if i == var::zdot_in => 1,
                _ => {
                    return Err(format!(
                        "{} is not an input; only z_in and zdot_in have derivatives",
                        label(i)
                    ))
                }
            };
            let max = (MAX_PLATE_ORDER - shift) as i32;
            if !(1..=max).contains(&order) {
                return Err(format!(
                    "derivative order {order} of {} must be in [1, {max}]",
                    label(i)
                ));
            }
            if !value.is_finite() {
                return Err(format!(
                    "derivative of order {order} of {} = {value} must be finite",
                    label(i)
                ));
            }
            checked.push((order as usize + shift, value));
        }
        // Order 1 of z_in is the plate velocity, which the input zdot_in gives: not stored.
        for (k, value) in checked.into_iter().filter(|&(k, _)| k >= 2) {
            self.derivatives[k] = Some(value);
            self.derivatives_given = true;
        }
        Ok(fmi2OK)
    }

    /// `fmi2GetRealOutputDerivatives` (order 1 of `x`, `v`, `z`, `zdot`).
    pub fn output_derivatives(
        &mut self,
        vrs: &[fmi2ValueReference],
        orders: &[fmi2Integer],
    ) -> Result<Vec<f64>, String> {
        let model = self.model.as_mut().ok_or("no model yet")?;
        model.sync()?;
        vrs.iter()
            .zip(orders)
            .map(|(&vr, &order)| {
                let i = Self::lookup(vr, Kind::Real)?;
                if order != 1 {
                    return Err(format!(
                        "derivative order {order} of {}: only order 1 is provided",
                        label(i)
                    ));
                }
                model.output_derivative(i).ok_or_else(|| {
                    format!("{} has no derivative output (only x, v, z, zdot)", label(i))
                })
            })
            .collect()
    }

    /// `fmi2DoStep`: integrates from the current time to exactly `tc + h`.
    pub fn do_step(&mut self, tc: f64, h: f64) -> Outcome {
        let Some(model) = self.model.as_mut() else {
            return Err("no model (internal state lost)".into());
        };
        let now = model.time;
        let t_end = tc + h;
        let span = clock_span(&self.values, self.start_time, t_end);
        let step_span = clock_span(&self.values, now, t_end);
        let valid = h.is_finite()
            && h > 0.0
            && (tc - now).abs() <= slack(now)
            && t_end > now
            && self
                .stop_time
                .is_none_or(|stop| t_end <= stop + slack(stop))
            && span < MAX_CLOCK_SPAN
            && step_span <= MAX_STEP_SPAN;
        if !valid {
            return Err(step_refusal(tc, h, now, self.stop_time, span, step_span));
        }
        let result = model.step(t_end, &self.values, &self.derivatives, &mut self.events);
        self.outputs_stale = true;
        if result.is_ok() && self.events.is_empty() {
            // The common case, kept short.
            if self.derivatives_given {
                self.clear_derivatives();
            }
            self.last_successful_time = t_end;
            return Ok(fmi2OK);
        }
        self.finish_step(result, t_end)
    }

    /// The rest of `do_step` after events or a failure.
    #[inline(never)]
    fn finish_step(&mut self, result: Result<(), StepFailure>, t_end: f64) -> Outcome {
        let reached = self.model.as_ref().map_or(t_end, |m| m.time);
        self.log_events();
        match result {
            Ok(()) => {
                self.clear_derivatives();
                self.last_successful_time = t_end;
                Ok(fmi2OK)
            }
            Err(StepFailure::Stopped(msg)) => {
                self.last_successful_time = reached;
                self.terminated = true;
                self.lifecycle = Lifecycle::StepFailed;
                let msg = format!("fmi2DoStep: {msg}; stopped at t = {reached} s");
                self.log(fmi2Discard, cat::logStatusDiscard, &msg);
                Ok(fmi2Discard)
            }
            Err(StepFailure::Refused(msg)) => Err(msg),
        }
    }

    /// `fmi2GetRealStatus`.
    pub fn real_status(&self, kind: fmi2StatusKind) -> Result<Option<f64>, String> {
        match kind {
            k if k == fmi2LastSuccessfulTime => Ok(Some(self.last_successful_time)),
            _ => self.other_status(kind).map(|_| None),
        }
    }

    /// `fmi2GetBooleanStatus`.
    pub fn boolean_status(&self, kind: fmi2StatusKind) -> Result<Option<bool>, String> {
        match kind {
            k if k == fmi2Terminated => Ok(Some(self.terminated)),
            _ => self.other_status(kind).map(|_| None),
        }
    }

    /// A status kind this function does not provide: `Ok` (to return `fmi2Discard`) for a known
    /// kind, `Err` for an unknown one.
    pub fn other_status(&self, kind: fmi2StatusKind) -> Result<(), String> {
        if (fmi2DoStepStatus..=fmi2Terminated).contains(&kind) {
            self.log(
                fmi2Discard,
                cat::logStatusDiscard,
                &format!("status kind {kind} is not available from this function (steps are synchronous)"),
            );
            Ok(())
        } else {
            Err(format!("unknown status kind {kind}"))
        }
    }

    /// A pointer-free copy of the whole instance state.
    pub fn snapshot(&mut self) -> Result<Snapshot, String> {
        let model = self.model.as_mut().map(Model::save).transpose()?;
        Ok(Snapshot {
            lifecycle: self.lifecycle,
            values: self.values.clone(),
            inputs: self.derivatives,
            start_time: self.start_time,
            stop_time: self.stop_time,
            last_successful_time: self.last_successful_time,
            terminated: self.terminated,
            model,
        })
    }

    /// Checks a snapshot fully and returns the model it holds.
    pub fn validate(s: &Snapshot) -> Result<Option<Model>, String> {
        for (i, &v) in s.values.iter().enumerate() {
            check_range(i, v).map_err(|e| format!("FMU state: {e}"))?;
        }
        let times = [
            Some(s.start_time),
            s.stop_time,
            Some(s.last_successful_time),
        ];
        if times.iter().flatten().any(|t| !t.is_finite())
            || s.inputs.iter().flatten().any(|d| !d.is_finite())
        {
            return Err("FMU state: non-finite time or input derivative".into());
        }
        if s.stop_time.is_some_and(|stop| stop < s.start_time) {
            return Err("FMU state: stop time before the start time".into());
        }
        // Discard sets `terminated` and leaves StepFailed; only Terminated keeps it (and Error,
        // which may follow anything).
        let terminated_ok = match s.lifecycle {
            Lifecycle::StepFailed => s.terminated,
            Lifecycle::Terminated | Lifecycle::Error => true,
            _ => !s.terminated,
        };
        if !terminated_ok {
            return Err(format!(
                "FMU state: terminated = {} in state {:?}",
                s.terminated, s.lifecycle
            ));
        }
        if let Some(m) = &s.model {
            // A running simulation is at its last successful time, between start and stop.
            let stop_ok = s.stop_time.is_none_or(|stop| m.time <= stop + slack(stop));
            if m.time != s.last_successful_time
                || m.time < s.start_time - slack(s.start_time)
                || !stop_ok
            {
                return Err(format!(
                    "FMU state: time {} s, last successful time {} s, start {} s and stop {:?} s are inconsistent",
                    m.time, s.last_successful_time, s.start_time, s.stop_time
                ));
            }
        }
        let needs_model = !matches!(
            s.lifecycle,
            Lifecycle::Instantiated | Lifecycle::InitializationMode
        );
        match &s.model {
            Some(_) if !needs_model && s.lifecycle != Lifecycle::Error => Err(format!(
                "FMU state: a running model in state {:?}",
                s.lifecycle
            )),
            Some(m) => Model::restore(&s.values, m)
                .map(Some)
                .map_err(|e| format!("FMU state: {e}")),
            None if needs_model && s.lifecycle != Lifecycle::Error => {
                Err(format!("FMU state: no model in state {:?}", s.lifecycle))
            }
            None => Ok(None),
        }
    }

    /// `fmi2SetFMUstate`.
    pub fn restore(&mut self, s: &Snapshot) -> Outcome {
        let model = Self::validate(s)?;
        self.lifecycle = s.lifecycle;
        self.values.clone_from(&s.values);
        self.derivatives = s.inputs;
        self.derivatives_given = s.inputs.iter().any(Option::is_some);
        self.start_time = s.start_time;
        self.stop_time = s.stop_time;
        self.last_successful_time = s.last_successful_time;
        self.terminated = s.terminated;
        self.outputs_stale = true;
        self.model = model;
        Ok(fmi2OK)
    }

    /// Registers a new FMU state and returns its handle.
    pub fn register(&mut self, s: Snapshot) -> fmi2FMUstate {
        let p = Box::into_raw(Box::new(s));
        self.states.insert(p as usize);
        p.cast()
    }

    /// The snapshot behind a handle this instance handed out.
    pub fn state_ref(&mut self, h: fmi2FMUstate) -> Result<&mut Snapshot, String> {
        if h.is_null() {
            return Err("FMUstate is NULL".into());
        }
        if !self.states.contains(&(h as usize)) {
            return Err(format!(
                "FMUstate {h:?} was not created by this instance or was freed"
            ));
        }
        // SAFETY: registered addresses are live boxes owned by this instance.
        Ok(unsafe { &mut *h.cast::<Snapshot>() })
    }

    /// Frees a registered FMU state.
    pub fn free_state(&mut self, h: fmi2FMUstate) -> Outcome {
        self.state_ref(h)?;
        self.states.remove(&(h as usize));
        // SAFETY: registered, so it came from `Box::into_raw` and is freed once.
        drop(unsafe { Box::from_raw(h.cast::<Snapshot>()) });
        Ok(fmi2OK)
    }
}

/// Rounding allowance (s) when comparing a host's time with the FMU's time `t` (s).
fn slack(t: f64) -> f64 {
    1e-9 * t.abs().max(1.0)
}

/// `|τ_end − τ_from|·max(Ω, 1)` for the times `from` and `t_end` (s): the shaker radians, or
/// natural time units when `Ω < 1`, between them (NaN-safe: a non-finite span is infinite).
fn clock_span(values: &[f64], start: f64, t_end: f64) -> f64 {
    let span = ((t_end - start) * values[var::omega0]).abs() * values[var::Omega].max(1.0);
    if span.is_nan() {
        f64::INFINITY
    } else {
        span
    }
}

/// Why `fmi2DoStep(tc, h)` is refused at the FMU time `now` (s).
#[cold]
fn step_refusal(tc: f64, h: f64, now: f64, stop: Option<f64>, span: f64, step_span: f64) -> String {
    let t_end = tc + h;
    if !(h.is_finite() && h > 0.0) {
        format!("communicationStepSize = {h} s must be finite and > 0")
    } else if !tc.is_finite() || (tc - now).abs() > slack(now) {
        format!("currentCommunicationPoint = {tc} s does not match the FMU's time {now} s")
    } else if t_end <= now {
        format!("the step ends at {t_end} s, not after the FMU's time {now} s")
    } else if span >= MAX_CLOCK_SPAN {
        format!(
            "the step ends at {t_end} s, {span:e} shaker radians (time units when Omega < 1) after the start time: beyond the FMU's clock range of 2^52"
        )
    } else if step_span > MAX_STEP_SPAN {
        format!(
            "the step from {now} s to {t_end} s spans {step_span:e} shaker radians (time units when Omega < 1), more than {MAX_STEP_SPAN:e} in one fmi2DoStep: its cost grows with its length, split it into shorter steps"
        )
    } else {
        format!(
            "the step ends at {t_end} s, beyond stopTime = {} s",
            stop.unwrap_or(f64::NAN)
        )
    }
}

/// Checks `value` against the type and range of variable `i` from the model description.
fn check_range(i: usize, value: f64) -> Result<f64, String> {
    let v = &VARS[i];
    let unit = if v.unit.is_empty() {
        String::new()
    } else {
        format!(" {}", v.unit)
    };
    let whole = v.kind == Kind::Real || value.fract() == 0.0;
    if value.is_finite() && whole && (v.min..=v.max).contains(&value) {
        Ok(value)
    } else {
        Err(format!(
            "{} = {value}{unit} is out of range: must be {}in [{}, {}]{unit}",
            v.name,
            if v.kind == Kind::Real {
                "finite and "
            } else {
                ""
            },
            v.min,
            v.max
        ))
    }
}
