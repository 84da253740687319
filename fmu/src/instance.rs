//! One FMU instance: lifecycle, logging, variable values, steps and FMU states. Everything the
//! C functions do after their arguments became Rust values; no shared state between instances.
//!
//! A refused call (illegal in the current state, bad argument or value) returns an error message,
//! which the export logs and turns into `fmi2Error`/`fmi3Error`; the instance is left as it was.
//! One instance type serves FMI 2.0 (`exports2.rs`) and FMI 3.0 (`exports3.rs`): the versions
//! differ in the logger, the names of their functions and, for FMI 3.0 co-simulation, event mode
//! and early return ([`Api`]).

use std::collections::HashSet;
use std::ffi::CString;

use bistable_core::Event;

use crate::fmi2::*;
use crate::fmi3::fmi3LogMessageCallback;
use crate::md::{cat, var, Causality, Kind, CATEGORIES, EVENT_INDICATORS, STATES, VARS};
use crate::me::Me;
use crate::model::outputs::{bit, VarSet, ALL};
use crate::model::plate::{PlateInputs, MAX_CLOCK_SPAN, MAX_PLATE_ORDER};
use crate::model::{Model, StepFailure, MAX_STEP_SPAN};
use crate::num::Num;
use crate::state::Snapshot;

/// Which FMI 2.0 interface an instance provides (the `fmuType` of `fmi2Instantiate`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Interface {
    /// `fmi2ModelExchange`.
    ModelExchange,
    /// `fmi2CoSimulation`.
    CoSimulation,
}

/// Which FMI version drives an instance, and how (fixed at instantiation).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Api {
    /// FMI 2.0.
    Fmi2,
    /// FMI 3.0. Co-simulation: `event_mode` (`eventModeUsed`: events are reported for event
    /// mode) and `early_return` (`earlyReturnAllowed`: `fmi3DoStep` stops at each event); both
    /// false for Model Exchange.
    Fmi3 {
        /// `eventModeUsed`.
        event_mode: bool,
        /// `earlyReturnAllowed`.
        early_return: bool,
    },
}

impl Api {
    /// `"fmi2"` or `"fmi3"`, the prefix of the version's function names.
    pub fn prefix(self) -> &'static str {
        match self {
            Api::Fmi2 => "fmi2",
            Api::Fmi3 { .. } => "fmi3",
        }
    }

    /// FMI 3.0 co-simulation with event mode.
    pub fn event_mode(self) -> bool {
        matches!(
            self,
            Api::Fmi3 {
                event_mode: true,
                ..
            }
        )
    }
}

/// The host's logging callback.
#[derive(Debug, Clone, Copy)]
pub enum Logger {
    /// FMI 2.0: variadic `(env, instanceName, status, category, format, ...)`.
    Fmi2(fmi2CallbackLogger),
    /// FMI 3.0: `(env, status, category, message)`.
    Fmi3(fmi3LogMessageCallback),
}

/// Lifecycle states of both interfaces and versions (co-simulation steps are synchronous: no
/// `stepInProgress`/`stepCanceled`). FMI 3.0's Step Mode is `StepComplete`; its co-simulation
/// Event Mode (with `eventModeUsed`) is `EventMode`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Lifecycle {
    /// After `fmi2Instantiate` or `fmi2Reset`.
    Instantiated,
    /// Between `fmi2EnterInitializationMode` and `fmi2ExitInitializationMode`.
    InitializationMode,
    /// Co-simulation: ready for `fmi2DoStep`.
    StepComplete,
    /// Co-simulation: `fmi2DoStep` returned `fmi2Discard`.
    StepFailed,
    /// After `fmi2Terminate`.
    Terminated,
    /// After an internal fault.
    Error,
    /// Model Exchange: after `fmi2ExitInitializationMode` or `fmi2EnterEventMode`; FMI 3.0
    /// co-simulation with event mode: after `fmi3ExitInitializationMode`, or
    /// `fmi3EnterEventMode` after a step.
    EventMode,
    /// Model Exchange: after `fmi2EnterContinuousTimeMode`.
    ContinuousTimeMode,
}

/// Sets of lifecycle states, and the interfaces, in which a function may be called (the
/// FMI 2.0 tables of allowed calls for co-simulation and Model Exchange).
pub mod allowed {
    use super::Interface;
    use super::Lifecycle::{self, *};

    /// A set of states (bits 0..8) and interfaces (bits 8, 9).
    pub type Mask = u16;

    const fn bit(l: Lifecycle) -> Mask {
        1 << l as u8
    }

    const CS: Mask = 1 << 8;
    const ME: Mask = 1 << 9;
    const BOTH: Mask = CS | ME;
    const AFTER_INIT: Mask = bit(Terminated) | bit(Error);
    const ME_RUN: Mask = bit(EventMode) | bit(ContinuousTimeMode);

    /// Every state, both interfaces.
    pub const ANY: Mask = !0;
    /// `fmi2SetupExperiment`, `fmi2EnterInitializationMode`.
    pub const INSTANTIATED: Mask = bit(Instantiated) | BOTH;
    /// `fmi2ExitInitializationMode`.
    pub const INIT: Mask = bit(InitializationMode) | BOTH;
    /// `fmi2Set*` (which variables, see `Instance::set`).
    pub const SET: Mask =
        bit(Instantiated) | bit(InitializationMode) | bit(StepComplete) | ME_RUN | BOTH;
    /// `fmi2Get*`.
    pub const GET: Mask =
        bit(InitializationMode) | bit(StepComplete) | bit(StepFailed) | ME_RUN | AFTER_INIT | BOTH;
    /// `fmi2Terminate`.
    pub const TERMINATE: Mask = bit(StepComplete) | bit(StepFailed) | ME_RUN | BOTH;
    /// `fmi2SetRealInputDerivatives` (co-simulation).
    pub const SET_DERIVATIVES: Mask =
        bit(Instantiated) | bit(InitializationMode) | bit(StepComplete) | CS;
    /// `fmi2GetRealOutputDerivatives` (co-simulation).
    pub const GET_DERIVATIVES: Mask = bit(StepComplete) | bit(StepFailed) | AFTER_INIT | CS;
    /// `fmi2DoStep` (co-simulation).
    pub const STEP: Mask = bit(StepComplete) | CS;
    /// `fmi2Get*Status` (co-simulation).
    pub const STATUS: Mask = bit(StepComplete) | bit(StepFailed) | bit(Terminated) | CS;
    /// `fmi2CancelStep` (co-simulation; refused in every state, no step is ever pending).
    pub const CANCEL: Mask = !ME;
    /// `fmi2EnterEventMode` (Model Exchange).
    pub const ENTER_EVENT: Mask = ME_RUN | ME;
    /// `fmi2NewDiscreteStates`, `fmi2EnterContinuousTimeMode` (Model Exchange).
    pub const EVENT: Mask = bit(EventMode) | ME;
    /// `fmi2CompletedIntegratorStep`, `fmi2SetContinuousStates` (Model Exchange).
    pub const CONTINUOUS: Mask = bit(ContinuousTimeMode) | ME;
    /// `fmi2SetTime` (Model Exchange).
    pub const SET_TIME: Mask = ME_RUN | ME;
    /// `fmi2GetEventIndicators`, `fmi2GetContinuousStates`, `fmi2GetDerivatives` (Model
    /// Exchange).
    pub const ME_GET: Mask = bit(InitializationMode) | ME_RUN | AFTER_INIT | ME;
    /// `fmi2GetNominalsOfContinuousStates` (Model Exchange).
    pub const NOMINALS: Mask = bit(Instantiated) | ME_GET;
    /// `fmi3EnterEventMode`: Model Exchange as in FMI 2.0; co-simulation (with event mode)
    /// after a step.
    pub const ENTER_EVENT3: Mask = ME_RUN | bit(StepComplete) | BOTH;
    /// `fmi3UpdateDiscreteStates` (both interfaces).
    pub const EVENT3: Mask = bit(EventMode) | BOTH;
    /// `fmi3EnterStepMode` (co-simulation).
    pub const ENTER_STEP: Mask = bit(EventMode) | CS;
    /// `fmi3GetNumberOf*` (Model Exchange).
    pub const COUNTS: Mask = !CS;

    /// Whether `l` is in `mask`.
    pub fn contains(mask: Mask, l: Lifecycle) -> bool {
        mask & bit(l) != 0
    }

    /// Whether `mask` includes the interface `i`.
    pub fn provides(mask: Mask, i: Interface) -> bool {
        mask & match i {
            Interface::CoSimulation => CS,
            Interface::ModelExchange => ME,
        } != 0
    }
}

/// The value type of a get or set function, and which variables it reaches.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Access {
    /// `fmi2Real`, `fmi3Float64`: Real variables.
    Real,
    /// `fmi2Integer`: Integer and Enumeration variables.
    Integer,
    /// `fmi3Int32`: Integer variables.
    Int32,
    /// `fmi3Int64`: Enumeration variables.
    Int64,
    /// `fmi2Boolean`, `fmi3Boolean`: Boolean variables.
    Boolean,
    /// A type the model has no variable of (its name, e.g. `"String"`).
    Absent(&'static str),
}

impl Access {
    /// Whether a variable `v` is read and written with this type.
    fn reaches(self, v: &crate::md::Var) -> bool {
        match self {
            Access::Real => v.kind == Kind::Real,
            Access::Integer => v.kind == Kind::Integer,
            Access::Int32 => v.kind == Kind::Integer && !v.enumeration,
            Access::Int64 => v.enumeration,
            Access::Boolean => v.kind == Kind::Boolean,
            Access::Absent(_) => false,
        }
    }

    /// How a variable `v` is accessed, for messages.
    fn of(v: &crate::md::Var, api: Api) -> &'static str {
        match (v.kind, v.enumeration, api) {
            (Kind::Real, _, Api::Fmi2) => "Real",
            (Kind::Real, _, Api::Fmi3 { .. }) => "Float64",
            (Kind::Integer, false, Api::Fmi2) => "Integer",
            (Kind::Integer, false, Api::Fmi3 { .. }) => "Int32",
            (_, true, Api::Fmi2) => "an Enumeration (Integer)",
            (_, true, Api::Fmi3 { .. }) => "an Enumeration (Int64)",
            (Kind::Boolean, ..) => "Boolean",
            (Kind::String, ..) => "String",
        }
    }

    /// The type's name, for messages.
    fn name(self) -> &'static str {
        match self {
            Access::Real => "Real/Float64",
            Access::Integer => "Integer",
            Access::Int32 => "Int32",
            Access::Int64 => "Int64",
            Access::Boolean => "Boolean",
            Access::Absent(name) => name,
        }
    }
}

/// Marks a live instance (a cheap check against stray handles).
const MAGIC: u64 = 0x6269_7374_6162_6c65;

/// Outcome of a call: a status to return, or a refusal to log and return as `fmi2Error`.
pub type Outcome = Result<fmi2Status, String>;

/// One instance of the FMU. Aligned to a cache line, so that where the host's heap puts it does
/// not move its fields across cache lines: unaligned, the same library took 43.8 to 45.3 ns per
/// `fmi2DoStep` + `fmi2GetReal(x, v)` depending only on the path it was loaded from; aligned,
/// 44.1 to 44.7 ns by either path (C host bench, 21 rounds; `docs/benchmarks.md`).
#[repr(align(64))]
pub struct Instance {
    magic: u64,
    name: CString,
    env: fmi2ComponentEnvironment,
    logger: Logger,
    logging_on: bool,
    enabled: Vec<bool>,
    /// Interface provided (fixed at instantiation).
    pub interface: Interface,
    /// FMI version and its options (fixed at instantiation).
    pub api: Api,
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
    /// The running Model Exchange model, after initialization (ME instances).
    me: Option<Me>,
    /// The computed variables (outputs, state derivatives, event indicators, time) whose
    /// value in `values` is current: a read computes only the variables it asks for that are
    /// not (so a step costs only the integration, and a read only what it reads), each at most
    /// once between two changes of the model.
    fresh: VarSet,
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
    /// A new instance of `interface` in state `Instantiated`.
    pub fn new(
        name: CString,
        interface: Interface,
        api: Api,
        env: fmi2ComponentEnvironment,
        logger: Logger,
        logging_on: bool,
    ) -> Self {
        Self {
            magic: MAGIC,
            interface,
            api,
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
            me: None,
            fresh: 0,
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
        let text = CString::new(msg.replace('\0', "\\0")).unwrap_or_default();
        let category = CString::new(CATEGORIES[category]).unwrap_or_default();
        match self.logger {
            // SAFETY: the host's logger with valid NUL-terminated strings, as FMI specifies.
            Logger::Fmi2(Some(logger)) => unsafe {
                logger(
                    self.env,
                    self.name.as_ptr(),
                    status,
                    category.as_ptr(),
                    c"%s".as_ptr(),
                    text.as_ptr(),
                )
            },
            // SAFETY: as above.
            Logger::Fmi3(Some(logger)) => unsafe {
                logger(self.env, status, category.as_ptr(), text.as_ptr())
            },
            Logger::Fmi2(None) | Logger::Fmi3(None) => {}
        }
    }

    /// The name of the function `name` (without prefix) in this instance's FMI version.
    fn func(&self, name: &str) -> String {
        format!("{}{name}", self.api.prefix())
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
            return Err(format!("startTime = {} s must be finite", Num(start)));
        }
        if let Some(stop) = stop {
            if !(stop.is_finite() && stop >= start) {
                return Err(format!(
                    "stopTime = {} s must be finite and >= startTime = {} s",
                    Num(stop),
                    Num(start)
                ));
            }
        }
        if let Some(tol) = tolerance {
            if !(tol.is_finite() && tol > 0.0) {
                return Err(format!("tolerance = {} must be finite and > 0", Num(tol)));
            }
            self.log(
                fmi2OK,
                cat::logAll,
                &format!("tolerance {tol} ignored: the integrator's accuracy is the parameter tol"),
            );
        }
        self.start_time = start;
        self.stop_time = stop;
        self.fresh = 0;
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
        self.fresh = ALL;
        Ok(model)
    }

    /// `fmi2ExitInitializationMode`: checks the parameters and starts the simulation
    /// (co-simulation: with the events at the start time; Model Exchange: in event mode, where
    /// `fmi2NewDiscreteStates` processes them).
    pub fn exit_initialization(&mut self) -> Outcome {
        if self.interface == Interface::ModelExchange {
            self.me = Some(Me::start(&self.values, self.start_time)?);
            self.fresh = 0;
            self.lifecycle = Lifecycle::EventMode;
            return Ok(fmi2OK);
        }
        let model = self.start_model()?;
        self.model = Some(model);
        self.log_events();
        self.last_successful_time = self.start_time;
        self.lifecycle = if self.api.event_mode() {
            Lifecycle::EventMode
        } else {
            Lifecycle::StepComplete
        };
        Ok(fmi2OK)
    }

    /// Logs the collected events under `logEvents` (when enabled) and clears them.
    fn log_events(&mut self) {
        let on = self.logging_on && (self.enabled[cat::logEvents] || self.enabled[cat::logAll]);
        if on {
            for e in &self.events {
                let line = match (&self.model, &self.me) {
                    (Some(model), _) => model.describe_event(e),
                    (_, Some(me)) => me.describe_event(e),
                    _ => continue,
                };
                self.log(fmi2OK, cat::logEvents, &line);
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
        self.me = None;
        self.fresh = 0;
        self.last_successful_time = 0.0;
        self.terminated = false;
        Ok(fmi2OK)
    }

    /// Forgets the input derivatives (they hold for one step).
    fn clear_derivatives(&mut self) {
        self.derivatives = [None; MAX_PLATE_ORDER + 1];
        self.derivatives_given = false;
    }

    /// Index of the variable with value reference `vr`, read or written as `ty`.
    #[inline]
    fn lookup(&self, vr: fmi2ValueReference, ty: Access) -> Result<usize, String> {
        // Value references are the variables' positions in the model description; the search
        // covers any other numbering.
        let i = match VARS.get(vr as usize) {
            Some(v) if v.vr == vr => vr as usize,
            _ => VARS
                .iter()
                .position(|v| v.vr == vr)
                .ok_or_else(|| format!("unknown value reference {vr}"))?,
        };
        if !ty.reaches(&VARS[i]) {
            return Err(self.wrong_type(i, ty));
        }
        Ok(i)
    }

    /// Refusal of variable `i` read or written as `ty`.
    #[cold]
    fn wrong_type(&self, i: usize, ty: Access) -> String {
        format!(
            "{} is {}, not {}",
            label(i),
            Access::of(&VARS[i], self.api),
            ty.name()
        )
    }

    /// Values of the variables `vrs`, read as `ty`.
    pub fn get(&mut self, vrs: &[fmi2ValueReference], ty: Access) -> Result<Vec<f64>, String> {
        let mut out = vec![0.0; vrs.len()];
        self.get_into(vrs, ty, &mut out, |v| v)?;
        Ok(out)
    }

    /// Values of the variables `vrs`, read as `ty`, converted by `conv` into `dst` (as long as
    /// `vrs`); nothing is written when a value reference is refused.
    pub fn get_into<T>(
        &mut self,
        vrs: &[fmi2ValueReference],
        ty: Access,
        dst: &mut [T],
        conv: impl Fn(f64) -> T + Copy,
    ) -> Result<(), String> {
        let mut want: VarSet = 0;
        for &vr in vrs {
            let i = self.lookup(vr, ty)?;
            if computed(i) {
                want |= bit(i);
            }
        }
        let missing = want & !self.fresh;
        if missing != 0 {
            self.refresh_outputs(missing)?;
        }
        for (d, &vr) in dst.iter_mut().zip(vrs) {
            *d = conv(self.values[vr_index(vr)]);
        }
        Ok(())
    }

    /// Computes the variables of `missing` (outputs, state derivatives) into `values`; in
    /// initialization mode, every one from a model built at the start time from the current
    /// values. Inline for a co-simulation model, which a host may read after every step: out of
    /// line, the call cost about 2 ns of a 22 ns read.
    #[inline]
    fn refresh_outputs(&mut self, missing: VarSet) -> Result<(), String> {
        match self.model.as_mut() {
            Some(model) => {
                model.write_some(&mut self.values, missing)?;
                self.fresh |= missing;
                Ok(())
            }
            None => self.refresh_without_model(missing),
        }
    }

    /// [`Instance::refresh_outputs`] without a co-simulation model.
    #[inline(never)]
    fn refresh_without_model(&mut self, missing: VarSet) -> Result<(), String> {
        let cannot = |e: String| format!("outputs cannot be computed: {e}");
        match (&self.me, self.interface) {
            (Some(me), _) => {
                me.write_some(&mut self.values, missing);
                self.fresh |= missing;
            }
            (None, Interface::CoSimulation) => {
                self.start_model().map_err(cannot)?;
                self.fresh = ALL;
            }
            (None, Interface::ModelExchange) => {
                Me::start(&self.values, self.start_time)
                    .map_err(cannot)?
                    .write_outputs(&mut self.values);
                self.fresh = ALL;
            }
        }
        Ok(())
    }

    /// Sets the variables `vrs`, written as `ty` (all or none).
    pub fn set(&mut self, vrs: &[fmi2ValueReference], vals: &[f64], ty: Access) -> Outcome {
        self.set_from(vrs, vals, ty, |v| v)
    }

    /// Sets the variables `vrs` to `vals` converted by `conv`, written as `ty` (all or none). A
    /// value equal to the one held changes nothing; a changed one makes stale only the computed
    /// values that depend on it now (see `Instance::affects_outputs`).
    pub fn set_from<T: Copy>(
        &mut self,
        vrs: &[fmi2ValueReference],
        vals: &[T],
        ty: Access,
        conv: impl Fn(T) -> f64 + Copy,
    ) -> Outcome {
        for (&vr, &value) in vrs.iter().zip(vals) {
            let i = self.lookup(vr, ty)?;
            self.check_settable(i)?;
            check_range(i, conv(value))?;
        }
        let mut stale = false;
        for (&vr, &value) in vrs.iter().zip(vals) {
            let (i, value) = (vr_index(vr), conv(value));
            if self.values[i].to_bits() != value.to_bits() {
                self.values[i] = value;
                stale |= self.affects_outputs(i);
            }
        }
        if stale {
            self.fresh = 0;
        }
        Ok(fmi2OK)
    }

    /// Whether a new value of variable `i` changes computed values before the next step or
    /// event: not for a co-simulation model that runs (its outputs come from its own state;
    /// inputs and tunable parameters act from the next step on), nor for a Model Exchange one
    /// but through the inputs of its external plate; always before a model runs (the values
    /// of initialization mode come from a model built from the current values).
    fn affects_outputs(&self, i: usize) -> bool {
        match (&self.model, &self.me) {
            (Some(_), _) => false,
            (_, Some(me)) => me.reads_input(i),
            (None, None) => true,
        }
    }

    /// Whether variable `i` may be set now (an input always; a parameter as its variability
    /// and the lifecycle state allow).
    #[inline]
    fn check_settable(&self, i: usize) -> Result<(), String> {
        let v = &VARS[i];
        let running = matches!(
            self.lifecycle,
            Lifecycle::StepComplete | Lifecycle::EventMode | Lifecycle::ContinuousTimeMode
        );
        let settable = match v.causality {
            Causality::Input => true,
            Causality::Parameter => {
                self.lifecycle != Lifecycle::ContinuousTimeMode && (v.tunable || !running)
            }
            _ => false,
        };
        if settable {
            Ok(())
        } else {
            Err(self.not_settable(i, running))
        }
    }

    /// Why variable `i` cannot be set now (see [`Instance::check_settable`]).
    #[cold]
    fn not_settable(&self, i: usize, running: bool) -> String {
        let v = &VARS[i];
        let refusal: Result<(), String> = match v.causality {
            Causality::Output => Err(format!("{} is an output and cannot be set", label(i))),
            Causality::Local => Err(format!(
                "{} is computed by the FMU and cannot be set",
                label(i)
            )),
            Causality::Independent => Err(format!(
                "{} is the independent variable: the host sets the time through the step or time functions",
                label(i)
            )),
            Causality::Parameter if self.lifecycle == Lifecycle::ContinuousTimeMode => {
                Err(format!(
                    "{} is a parameter: in continuous-time mode only inputs can be set (tunable parameters in event mode)",
                    label(i)
                ))
            }
            Causality::Parameter if !v.tunable && running => Err(format!(
                "{} is a fixed parameter: set it before {} (or after {})",
                label(i),
                self.func("ExitInitializationMode"),
                self.func("Reset")
            )),
            _ => Ok(()),
        };
        refusal.err().unwrap_or_default()
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
            let i = self.lookup(vr, Access::Real)?;
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
                    "derivative of order {order} of {} = {} must be finite",
                    label(i),
                    Num(value)
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
        let idx = vrs
            .iter()
            .map(|&vr| self.lookup(vr, Access::Real))
            .collect::<Result<Vec<_>, _>>()?;
        let model = self.model.as_mut().ok_or("no model yet")?;
        model.sync()?;
        idx.iter()
            .zip(orders)
            .map(|(&i, &order)| {
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

    /// `fmi2DoStep`/`fmi3DoStep`: integrates from the current time to exactly `tc + h`, or (FMI
    /// 3.0 with early return) to the first event after the current time (see
    /// [`Instance::stopped_at_event`]).
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
        let early = matches!(
            self.api,
            Api::Fmi3 {
                early_return: true,
                ..
            }
        );
        model.ahead.host_step(self.start_time, tc, h);
        let result = model.step(
            t_end,
            &self.values,
            &self.derivatives,
            &mut self.events,
            early,
        );
        self.fresh = 0;
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
                // An early return ends the step at the event (`reached`, before `t_end`).
                self.last_successful_time = reached;
                Ok(fmi2OK)
            }
            Err(StepFailure::Stopped(msg)) => {
                self.last_successful_time = reached;
                self.terminated = true;
                self.lifecycle = Lifecycle::StepFailed;
                let msg = format!("{}: {msg}; stopped at t = {reached} s", self.func("DoStep"));
                self.log(fmi2Discard, cat::logStatusDiscard, &msg);
                Ok(fmi2Discard)
            }
            Err(StepFailure::Refused(msg)) => Err(msg),
        }
    }

    /// The running Model Exchange model.
    fn me_mut(&mut self) -> Result<&mut Me, String> {
        self.me
            .as_mut()
            .ok_or_else(|| "no model (internal state lost)".to_string())
    }

    /// The Model Exchange model now: the running one, or in initialization mode one built at
    /// the start time from the current values.
    fn me_now(&self) -> Result<std::borrow::Cow<'_, Me>, String> {
        match &self.me {
            Some(me) => Ok(std::borrow::Cow::Borrowed(me)),
            None if self.lifecycle == Lifecycle::InitializationMode => {
                Me::start(&self.values, self.start_time).map(std::borrow::Cow::Owned)
            }
            None => Err("no model (internal state lost)".into()),
        }
    }

    /// `fmi2SetTime` (s).
    pub fn set_time(&mut self, t: f64) -> Outcome {
        self.me_mut()?.set_time(t)?;
        self.fresh = 0;
        Ok(fmi2OK)
    }

    /// `fmi2SetContinuousStates` (SI, `x` then `v`).
    pub fn set_continuous_states(&mut self, x: &[f64]) -> Outcome {
        self.me_mut()?.set_states(x)?;
        self.fresh = 0;
        Ok(fmi2OK)
    }

    /// `fmi2GetContinuousStates` (SI) for `n` states.
    pub fn continuous_states(&self, n: usize) -> Result<[f64; 2], String> {
        check_count("nx", n, STATES.len())?;
        Ok(self.me_now()?.states())
    }

    /// `fmi2GetNominalsOfContinuousStates` (SI) for `n` states.
    pub fn nominals(&self, n: usize) -> Result<[f64; 2], String> {
        check_count("nx", n, STATES.len())?;
        Ok(Me::nominals(&self.values))
    }

    /// `fmi2GetDerivatives` (SI) for `n` states.
    pub fn derivatives(&mut self, n: usize) -> Result<Vec<f64>, String> {
        check_count("nx", n, STATES.len())?;
        let want = crate::md::DERIVATIVES.iter().fold(0, |w, &i| w | bit(i));
        let missing = want & !self.fresh;
        if missing != 0 {
            self.refresh_outputs(missing)?;
        }
        Ok(crate::md::DERIVATIVES
            .iter()
            .map(|&i| self.values[i])
            .collect())
    }

    /// `fmi2GetEventIndicators` (SI) for `n` indicators.
    pub fn event_indicators(&self, n: usize) -> Result<[f64; 2], String> {
        check_count("ni", n, EVENT_INDICATORS.len())?;
        Ok(self.me_now()?.indicators(&self.values))
    }

    /// `fmi2EnterEventMode`/`fmi3EnterEventMode`. FMI 3.0 co-simulation (with event mode):
    /// after a step, to act on an event at its end (the event is already applied, so event mode
    /// lets the host set inputs and tunable parameters there).
    pub fn enter_event_mode(&mut self) -> Outcome {
        if self.interface == Interface::CoSimulation {
            if !self.api.event_mode() {
                return Err(
                    "event mode was not requested at instantiation (eventModeUsed = false)".into(),
                );
            }
            self.lifecycle = Lifecycle::EventMode;
            return Ok(fmi2OK);
        }
        self.me_mut()?.enter_event_mode();
        self.fresh = 0;
        self.lifecycle = Lifecycle::EventMode;
        Ok(fmi2OK)
    }

    /// `fmi2NewDiscreteStates`: settles the events at the current time (one call suffices).
    /// FMI 3.0 co-simulation in event mode: the events at the current time were applied by the
    /// step that reached it, so nothing changes (no time events either).
    pub fn new_discrete_states(&mut self, info: &mut fmi2EventInfo) -> Outcome {
        if self.interface == Interface::CoSimulation {
            *info = fmi2EventInfo::default();
            return Ok(fmi2OK);
        }
        let me = self.me.as_mut().ok_or("no model (internal state lost)")?;
        let up = me.update(&self.values, &mut self.events)?;
        let next = me.next_event_time();
        self.fresh = 0;
        self.log_events();
        *info = fmi2EventInfo {
            valuesOfContinuousStatesChanged: up.states_changed.into(),
            nextEventTimeDefined: next.is_some().into(),
            nextEventTime: next.unwrap_or(0.0),
            ..fmi2EventInfo::default()
        };
        Ok(fmi2OK)
    }

    /// The last step stopped at an event it reached (FMI 3.0 co-simulation with early return):
    /// the event, at `last_successful_time`, has been applied.
    pub fn stopped_at_event(&self) -> bool {
        self.model.as_ref().is_some_and(|m| m.at_event)
    }

    /// Where the last step ended (s).
    pub fn last_successful_time(&self) -> f64 {
        self.last_successful_time
    }

    /// The FMU asks to end the simulation (after a step it could not complete).
    pub fn terminated(&self) -> bool {
        self.terminated
    }

    /// `fmi3EnterStepMode` (co-simulation, from event mode).
    pub fn enter_step_mode(&mut self) -> Outcome {
        self.lifecycle = Lifecycle::StepComplete;
        Ok(fmi2OK)
    }

    /// `fmi2EnterContinuousTimeMode`.
    pub fn enter_continuous_time_mode(&mut self) -> Outcome {
        self.lifecycle = Lifecycle::ContinuousTimeMode;
        Ok(fmi2OK)
    }

    /// `fmi2CompletedIntegratorStep`: whether event mode is needed now (see
    /// [`Me::needs_event`]); the model never asks to terminate.
    pub fn completed_integrator_step(&mut self) -> Result<bool, String> {
        let values = &self.values;
        let me = self.me.as_ref().ok_or("no model (internal state lost)")?;
        Ok(me.needs_event(values))
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
            interface: self.interface,
            api: self.api,
            me: self.me.as_ref().map(Me::save),
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

    /// Checks that a snapshot fits this instance (same interface) and returns its models.
    pub fn accept(&self, s: &Snapshot) -> Result<(Option<Model>, Option<Me>), String> {
        if (s.interface, s.api) != (self.interface, self.api) {
            return Err(format!(
                "FMU state: made by a {:?} instance of {:?}, this one is {:?} of {:?}",
                s.interface, s.api, self.interface, self.api
            ));
        }
        Self::validate(s)
    }

    /// Checks a snapshot fully and returns the models it holds (co-simulation, Model Exchange).
    pub fn validate(s: &Snapshot) -> Result<(Option<Model>, Option<Me>), String> {
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
        if s.interface == Interface::ModelExchange {
            return Self::validate_me(s, needs_model).map(|me| (None, me));
        }
        let event_mode_ok = s.lifecycle != Lifecycle::EventMode || s.api.event_mode();
        let early_ok = matches!(
            s.api,
            Api::Fmi3 {
                early_return: true,
                ..
            }
        );
        if s.model.as_ref().is_some_and(|m| m.at_event) && !early_ok {
            return Err("FMU state: stopped at an event without early return".into());
        }
        if s.me.is_some() || s.lifecycle == Lifecycle::ContinuousTimeMode || !event_mode_ok {
            return Err(format!(
                "FMU state: a Model Exchange model or state {:?} in a co-simulation state",
                s.lifecycle
            ));
        }
        let model = match &s.model {
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
        }?;
        Ok((model, None))
    }

    /// The Model Exchange part of [`Instance::validate`] (`needs_model`: the lifecycle state
    /// is after initialization).
    fn validate_me(s: &Snapshot, needs_model: bool) -> Result<Option<Me>, String> {
        let cs_only = matches!(s.lifecycle, Lifecycle::StepComplete | Lifecycle::StepFailed)
            || s.model.is_some()
            || s.terminated
            || !matches!(
                s.api,
                Api::Fmi2
                    | Api::Fmi3 {
                        event_mode: false,
                        early_return: false
                    }
            )
            || s.inputs.iter().any(Option::is_some);
        if cs_only {
            return Err(format!(
                "FMU state: co-simulation state {:?}, model or flags in a Model Exchange state",
                s.lifecycle
            ));
        }
        let me = match &s.me {
            Some(_) if !needs_model && s.lifecycle != Lifecycle::Error => {
                return Err(format!(
                    "FMU state: a running model in state {:?}",
                    s.lifecycle
                ))
            }
            Some(m) => Me::restore(&s.values, m).map_err(|e| format!("FMU state: {e}"))?,
            None if needs_model && s.lifecycle != Lifecycle::Error => {
                return Err(format!("FMU state: no model in state {:?}", s.lifecycle))
            }
            None => return Ok(None),
        };
        if me.time() < s.start_time - slack(s.start_time) {
            return Err(format!(
                "FMU state: time {} s before the start time {} s",
                me.time(),
                s.start_time
            ));
        }
        Ok(Some(me))
    }

    /// `fmi2SetFMUstate`.
    pub fn restore(&mut self, s: &Snapshot) -> Outcome {
        let (model, me) = self.accept(s)?;
        self.lifecycle = s.lifecycle;
        self.values.clone_from(&s.values);
        self.derivatives = s.inputs;
        self.derivatives_given = s.inputs.iter().any(Option::is_some);
        self.start_time = s.start_time;
        self.stop_time = s.stop_time;
        self.last_successful_time = s.last_successful_time;
        self.terminated = s.terminated;
        self.fresh = 0;
        self.model = model;
        self.me = me;
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

/// Position in `VARS` of the value reference `vr`, which [`Instance::lookup`] accepted.
fn vr_index(vr: fmi2ValueReference) -> usize {
    match VARS.get(vr as usize) {
        Some(v) if v.vr == vr => vr as usize,
        _ => VARS.iter().position(|v| v.vr == vr).unwrap_or(0),
    }
}

/// Whether variable `i` is computed by the model (an output, a state derivative or event
/// indicator, or the time), rather than set.
fn computed(i: usize) -> bool {
    matches!(
        VARS[i].causality,
        Causality::Output | Causality::Local | Causality::Independent
    )
}

/// Refuses an array length `n` (named `what`) other than `expected`.
fn check_count(what: &str, n: usize, expected: usize) -> Result<(), String> {
    if n == expected {
        Ok(())
    } else {
        Err(format!("{what} = {n}: the model has {expected}"))
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
        format!(
            "communicationStepSize = {} s must be finite and > 0",
            Num(h)
        )
    } else if !tc.is_finite() || (tc - now).abs() > slack(now) {
        format!(
            "currentCommunicationPoint = {} s does not match the FMU's time {} s",
            Num(tc),
            Num(now)
        )
    } else if t_end <= now {
        format!(
            "the step ends at {} s, not after the FMU's time {} s",
            Num(t_end),
            Num(now)
        )
    } else if span >= MAX_CLOCK_SPAN {
        format!(
            "the step ends at {} s, {span:e} shaker radians (time units when Omega < 1) after the start time: beyond the FMU's clock range of 2^52",
            Num(t_end)
        )
    } else if step_span > MAX_STEP_SPAN {
        format!(
            "the step from {} s to {} s spans {step_span:e} shaker radians (time units when Omega < 1), more than {MAX_STEP_SPAN:e} in one step: its cost grows with its length, split it into shorter steps",
            Num(now),
            Num(t_end)
        )
    } else {
        format!(
            "the step ends at {} s, beyond stopTime = {} s",
            Num(t_end),
            Num(stop.unwrap_or(f64::NAN))
        )
    }
}

/// Checks `value` against the type and range of variable `i` from the model description.
#[inline]
fn check_range(i: usize, value: f64) -> Result<f64, String> {
    let v = &VARS[i];
    let whole = v.kind == Kind::Real || value.fract() == 0.0;
    if value.is_finite() && whole && (v.min..=v.max).contains(&value) {
        Ok(value)
    } else {
        Err(out_of_range(i, value))
    }
}

/// Refusal of `value` for variable `i` (see [`check_range`]).
#[cold]
fn out_of_range(i: usize, value: f64) -> String {
    let v = &VARS[i];
    let unit = if v.unit.is_empty() {
        String::new()
    } else {
        format!(" {}", v.unit)
    };
    format!(
        "{} = {}{unit} is out of range: must be {}in [{}, {}]{unit}",
        v.name,
        Num(value),
        if v.kind == Kind::Real {
            "finite and "
        } else {
            ""
        },
        Num(v.min),
        Num(v.max)
    )
}
