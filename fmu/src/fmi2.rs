//! FMI 2.0 platform types, status codes and callback types, ABI-compatible with the standard's
//! `fmi2TypesPlatform.h` and `fmi2FunctionTypes.h`. Enumerations are plain `int` typedefs so that
//! an out-of-range value from a host is a checked integer, never an invalid Rust enum.
#![allow(non_camel_case_types, non_upper_case_globals, non_snake_case)]

use std::ffi::{c_char, c_int, c_uint, c_void};

/// Opaque instance handle.
pub type fmi2Component = *mut c_void;
/// Host data passed back to the callbacks.
pub type fmi2ComponentEnvironment = *mut c_void;
/// Opaque FMU state handle.
pub type fmi2FMUstate = *mut c_void;
/// Value reference of a variable.
pub type fmi2ValueReference = c_uint;
/// Real value.
pub type fmi2Real = f64;
/// Integer value (32 bits).
pub type fmi2Integer = c_int;
/// Boolean: a 4-byte int, `fmi2True` or `fmi2False`.
pub type fmi2Boolean = c_int;
/// Character.
pub type fmi2Char = c_char;
/// NUL-terminated string.
pub type fmi2String = *const fmi2Char;
/// Byte of a serialized FMU state.
pub type fmi2Byte = c_char;

/// `fmi2True`.
pub const fmi2True: fmi2Boolean = 1;
/// `fmi2False`.
pub const fmi2False: fmi2Boolean = 0;

/// Status returned by every function (`fmi2OK` ... `fmi2Pending`).
pub type fmi2Status = c_int;
/// All well.
pub const fmi2OK: fmi2Status = 0;
/// Not quite right, computation continues.
pub const fmi2Warning: fmi2Status = 1;
/// The step could not be completed (see `fmi2GetRealStatus`).
pub const fmi2Discard: fmi2Status = 2;
/// The call was refused or failed; the instance is unchanged unless the log says otherwise.
pub const fmi2Error: fmi2Status = 3;
/// Irreparable error.
pub const fmi2Fatal: fmi2Status = 4;
/// Asynchronous step in progress (never returned: steps are synchronous).
pub const fmi2Pending: fmi2Status = 5;

/// Kind of FMU requested at instantiation.
pub type fmi2Type = c_int;
/// Model exchange.
pub const fmi2ModelExchange: fmi2Type = 0;
/// Co-simulation.
pub const fmi2CoSimulation: fmi2Type = 1;

/// Status queried with `fmi2Get*Status`.
pub type fmi2StatusKind = c_int;
/// Status of an asynchronous `fmi2DoStep`.
pub const fmi2DoStepStatus: fmi2StatusKind = 0;
/// Message of a pending step.
pub const fmi2PendingStatus: fmi2StatusKind = 1;
/// End of the last successful step (s).
pub const fmi2LastSuccessfulTime: fmi2StatusKind = 2;
/// Whether the slave asks to end the simulation.
pub const fmi2Terminated: fmi2StatusKind = 3;

/// Variadic logger: `(env, instanceName, status, category, format, ...)`.
pub type fmi2CallbackLogger = Option<
    unsafe extern "C" fn(
        fmi2ComponentEnvironment,
        fmi2String,
        fmi2Status,
        fmi2String,
        fmi2String,
        ...
    ),
>;
/// `calloc`-like allocator (not used: `canNotUseMemoryManagementFunctions`).
pub type fmi2CallbackAllocateMemory = Option<unsafe extern "C" fn(usize, usize) -> *mut c_void>;
/// `free`-like deallocator (not used).
pub type fmi2CallbackFreeMemory = Option<unsafe extern "C" fn(*mut c_void)>;
/// Completion callback of asynchronous steps (not used).
pub type fmi2StepFinished = Option<unsafe extern "C" fn(fmi2ComponentEnvironment, fmi2Status)>;

/// Callbacks given by the host to `fmi2Instantiate` (by pointer).
#[repr(C)]
pub struct fmi2CallbackFunctions {
    /// Logger.
    pub logger: fmi2CallbackLogger,
    /// Allocator.
    pub allocateMemory: fmi2CallbackAllocateMemory,
    /// Deallocator.
    pub freeMemory: fmi2CallbackFreeMemory,
    /// Step completion.
    pub stepFinished: fmi2StepFinished,
    /// Host data for the callbacks.
    pub componentEnvironment: fmi2ComponentEnvironment,
}

/// What `fmi2NewDiscreteStates` reports about the event iteration.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct fmi2EventInfo {
    /// Another `fmi2NewDiscreteStates` call is needed.
    pub newDiscreteStatesNeeded: fmi2Boolean,
    /// The model asks to end the simulation.
    pub terminateSimulation: fmi2Boolean,
    /// `fmi2GetNominalsOfContinuousStates` changed.
    pub nominalsOfContinuousStatesChanged: fmi2Boolean,
    /// The continuous states changed (re-read them, restart the integrator).
    pub valuesOfContinuousStatesChanged: fmi2Boolean,
    /// `nextEventTime` holds the time of the next time event.
    pub nextEventTimeDefined: fmi2Boolean,
    /// Time of the next time event (s), when defined.
    pub nextEventTime: fmi2Real,
}
