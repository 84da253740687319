//! The 44 FMI 2.0 functions with C linkage: 27 common, 7 co-simulation, 10 Model Exchange.
//! A function of one interface is refused (`fmi2Error`) by an instance of the other.
//!
//! # Safety
//! Callers pass pointers as the FMI 2.0 standard specifies: valid for the lengths given, strings
//! NUL-terminated, the component a live handle from `fmi2Instantiate`. Within that contract every
//! function checks its arguments (NULL, unknown value references, ranges, lifecycle state),
//! refuses bad ones with `fmi2Error` and a logged reason, and never lets a panic unwind into the
//! host (a caught panic puts the instance into the error state).
#![allow(non_snake_case, clippy::missing_safety_doc)]

use std::ffi::{c_char, CStr, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::ptr;

use crate::fmi2::*;
use crate::instance::Access;
use crate::instance::{allowed, Api, Instance, Interface, Lifecycle, Logger, Outcome};
use crate::md::{cat, GUID};
use crate::state::Snapshot;

/// Largest array length accepted from a host (guards the slice construction).
const MAX_LEN: usize = 1 << 28;

/// The instance behind a handle, if it looks live.
pub(crate) unsafe fn instance<'a>(c: fmi2Component) -> Option<&'a mut Instance> {
    let inst = c.cast::<Instance>().as_mut()?;
    inst.is_live().then_some(inst)
}

fn panic_text(p: &(dyn std::any::Any + Send)) -> String {
    p.downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| p.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "panic".into())
}

/// Runs `f` on the instance if `func` is allowed in its state, logging a refusal; a panic is
/// caught, logged and leaves the instance in the error state.
pub(crate) fn call(
    c: fmi2Component,
    func: &str,
    mask: allowed::Mask,
    f: impl FnOnce(&mut Instance) -> Outcome,
) -> fmi2Status {
    // SAFETY: FMI contract (module documentation).
    let Some(inst) = (unsafe { instance(c) }) else {
        return fmi2Error;
    };
    let inst: *mut Instance = inst;
    let run = catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: checked above; only this call uses the instance.
        let inst = unsafe { &mut *inst };
        if !func.starts_with(inst.api.prefix()) {
            let msg = format!(
                "the instance was made by {}Instantiate*: use the {} functions",
                inst.api.prefix(),
                inst.api.prefix()
            );
            inst.log_error(func, &msg);
            return fmi2Error;
        }
        if !allowed::provides(mask, inst.interface) {
            let msg = format!("not provided by a {:?} instance", inst.interface);
            inst.log_error(func, &msg);
            return fmi2Error;
        }
        if !allowed::contains(mask, inst.lifecycle) {
            let msg = format!("not allowed in state {:?}", inst.lifecycle);
            inst.log_error(func, &msg);
            return fmi2Error;
        }
        f(inst).unwrap_or_else(|msg| {
            inst.log_error(func, &msg);
            fmi2Error
        })
    }));
    run.unwrap_or_else(|p| {
        // SAFETY: as above; the closure that panicked no longer uses it.
        let inst = unsafe { &mut *inst };
        inst.lifecycle = Lifecycle::Error;
        let msg = format!("{func}: internal error: {}", panic_text(p.as_ref()));
        let _ = catch_unwind(AssertUnwindSafe(|| {
            inst.log(fmi2Fatal, cat::logStatusFatal, &msg)
        }));
        fmi2Error
    })
}

/// A host array of `n` elements (NULL allowed only when `n == 0`).
pub(crate) unsafe fn array<'a, T>(p: *const T, n: usize, what: &str) -> Result<&'a [T], String> {
    match n {
        0 => Ok(&[]),
        n if n > MAX_LEN => Err(format!("{what}: length {n} is too large")),
        _ if p.is_null() => Err(format!("{what} is NULL")),
        _ => Ok(std::slice::from_raw_parts(p, n)),
    }
}

/// A host output array of `n` elements.
pub(crate) unsafe fn array_mut<'a, T>(
    p: *mut T,
    n: usize,
    what: &str,
) -> Result<&'a mut [T], String> {
    array(p, n, what)?;
    Ok(if n == 0 {
        &mut []
    } else {
        std::slice::from_raw_parts_mut(p, n)
    })
}

/// A host pointer to one value to write.
pub(crate) unsafe fn out<'a, T>(p: *mut T, what: &str) -> Result<&'a mut T, String> {
    p.as_mut().ok_or_else(|| format!("{what} is NULL"))
}

/// A host string (lossy UTF-8).
pub(crate) unsafe fn text(p: fmi2String, what: &str) -> Result<String, String> {
    if p.is_null() {
        return Err(format!("{what} is NULL"));
    }
    Ok(CStr::from_ptr(p).to_string_lossy().into_owned())
}

// ---- common functions ----

/// `"default"`: the standard FMI 2.0 platform types.
#[no_mangle]
pub extern "C" fn fmi2GetTypesPlatform() -> *const c_char {
    c"default".as_ptr()
}

/// `"2.0"`.
#[no_mangle]
pub extern "C" fn fmi2GetVersion() -> *const c_char {
    c"2.0".as_ptr()
}

/// Switches logging of the listed categories (all of them when `nCategories` is 0) on or off.
#[no_mangle]
pub unsafe extern "C" fn fmi2SetDebugLogging(
    c: fmi2Component,
    loggingOn: fmi2Boolean,
    nCategories: usize,
    categories: *const fmi2String,
) -> fmi2Status {
    call(c, "fmi2SetDebugLogging", allowed::ANY, |inst| {
        let names = array(categories, nCategories, "categories")?
            .iter()
            .map(|&s| text(s, "category"))
            .collect::<Result<Vec<_>, _>>()?;
        inst.set_debug_logging(loggingOn != fmi2False, &names)
    })
}

/// Checks the arguments of `fmi2Instantiate`; `log` reports a refusal.
unsafe fn instantiate(
    name: fmi2String,
    kind: fmi2Type,
    guid: fmi2String,
    functions: *const fmi2CallbackFunctions,
    logging_on: fmi2Boolean,
) -> fmi2Component {
    let Some(f) = functions.as_ref() else {
        return ptr::null_mut();
    };
    let given = text(name, "instanceName").unwrap_or_default();
    let cname = CString::new(given.clone()).unwrap_or_default();
    let interface = match kind {
        k if k == fmi2ModelExchange => Some(Interface::ModelExchange),
        k if k == fmi2CoSimulation => Some(Interface::CoSimulation),
        _ => None,
    };
    let inst = Instance::new(
        cname,
        interface.unwrap_or(Interface::CoSimulation),
        Api::Fmi2,
        f.componentEnvironment,
        Logger::Fmi2(f.logger),
        logging_on != fmi2False,
    );
    let checked = (|| {
        if given.is_empty() {
            return Err("instanceName must be a non-empty string".to_string());
        }
        if interface.is_none() {
            return Err(format!(
                "fmuType = {kind}: must be fmi2ModelExchange = {fmi2ModelExchange} or fmi2CoSimulation = {fmi2CoSimulation}"
            ));
        }
        let g = text(guid, "fmuGUID")?;
        if g != GUID {
            return Err(format!(
                "fmuGUID {g} does not match this binary's {GUID}: modelDescription.xml and binary come from different builds"
            ));
        }
        bistable_core::simd::check()
            .map(drop)
            .map_err(|e| e.to_string())
    })();
    match checked {
        Ok(()) => Box::into_raw(Box::new(inst)).cast(),
        Err(msg) => {
            inst.log_error("fmi2Instantiate", &msg);
            ptr::null_mut()
        }
    }
}

/// A new Model Exchange or co-simulation instance, or NULL (with a logged reason) for a wrong GUID, FMU type,
/// name or NULL callbacks. `fmuResourceLocation` and `visible` are not used.
#[no_mangle]
pub unsafe extern "C" fn fmi2Instantiate(
    instanceName: fmi2String,
    fmuType: fmi2Type,
    fmuGUID: fmi2String,
    _fmuResourceLocation: fmi2String,
    functions: *const fmi2CallbackFunctions,
    _visible: fmi2Boolean,
    loggingOn: fmi2Boolean,
) -> fmi2Component {
    catch_unwind(|| instantiate(instanceName, fmuType, fmuGUID, functions, loggingOn))
        .unwrap_or(ptr::null_mut())
}

/// Frees the instance and the FMU states it handed out.
#[no_mangle]
pub unsafe extern "C" fn fmi2FreeInstance(c: fmi2Component) {
    let _ = catch_unwind(|| {
        if let Some(inst) = instance(c) {
            inst.retire();
            drop(Box::from_raw(c.cast::<Instance>()));
        }
    });
}

/// Start time and optional stop time (s); the tolerance is ignored (see the parameter `tol`).
#[no_mangle]
pub unsafe extern "C" fn fmi2SetupExperiment(
    c: fmi2Component,
    toleranceDefined: fmi2Boolean,
    tolerance: fmi2Real,
    startTime: fmi2Real,
    stopTimeDefined: fmi2Boolean,
    stopTime: fmi2Real,
) -> fmi2Status {
    let tol = (toleranceDefined != fmi2False).then_some(tolerance);
    let stop = (stopTimeDefined != fmi2False).then_some(stopTime);
    call(c, "fmi2SetupExperiment", allowed::INSTANTIATED, |inst| {
        inst.setup_experiment(startTime, stop, tol)
    })
}

/// Enters initialization mode.
#[no_mangle]
pub unsafe extern "C" fn fmi2EnterInitializationMode(c: fmi2Component) -> fmi2Status {
    call(
        c,
        "fmi2EnterInitializationMode",
        allowed::INSTANTIATED,
        |inst| inst.enter_initialization(),
    )
}

/// Checks the parameters, starts the simulation at the start time (processing the events there)
/// and enters step mode.
#[no_mangle]
pub unsafe extern "C" fn fmi2ExitInitializationMode(c: fmi2Component) -> fmi2Status {
    call(c, "fmi2ExitInitializationMode", allowed::INIT, |inst| {
        inst.exit_initialization()
    })
}

/// Ends the simulation (values stay readable).
#[no_mangle]
pub unsafe extern "C" fn fmi2Terminate(c: fmi2Component) -> fmi2Status {
    call(c, "fmi2Terminate", allowed::TERMINATE, |inst| {
        inst.terminate()
    })
}

/// Back to the instantiated state with the start values.
#[no_mangle]
pub unsafe extern "C" fn fmi2Reset(c: fmi2Component) -> fmi2Status {
    call(c, "fmi2Reset", allowed::ANY, |inst| inst.reset())
}

// ---- getting and setting values ----

/// `fmi2Get<T>`: values read as `ty`, converted by `conv`.
unsafe fn get_values<T>(
    c: fmi2Component,
    func: &str,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut T,
    ty: Access,
    conv: impl Fn(f64) -> T + Copy,
) -> fmi2Status {
    call(c, func, allowed::GET, |inst| {
        let vrs = array(vr, nvr, "vr")?;
        let dst = array_mut(value, nvr, "value")?;
        inst.get_into(vrs, ty, dst, conv)?;
        Ok(fmi2OK)
    })
}

/// `fmi2Set<T>`: values written as `ty`, converted by `conv` (range-checked by the instance).
unsafe fn set_values<T: Copy>(
    c: fmi2Component,
    func: &str,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const T,
    ty: Access,
    conv: impl Fn(T) -> f64 + Copy,
) -> fmi2Status {
    call(c, func, allowed::SET, |inst| {
        let vrs = array(vr, nvr, "vr")?;
        let vals = array(value, nvr, "value")?;
        inst.set_from(vrs, vals, ty, conv)
    })
}

/// Real values (SI units) of the variables `vr[0..nvr]`.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetReal(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2Real,
) -> fmi2Status {
    get_values(c, "fmi2GetReal", vr, nvr, value, Access::Real, |v| v)
}

/// Integer and Enumeration values of the variables `vr[0..nvr]`.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetInteger(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2Integer,
) -> fmi2Status {
    get_values(c, "fmi2GetInteger", vr, nvr, value, Access::Integer, |v| {
        v as fmi2Integer
    })
}

/// Boolean values (`fmi2True`/`fmi2False`) of the variables `vr[0..nvr]`.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetBoolean(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2Boolean,
) -> fmi2Status {
    get_values(c, "fmi2GetBoolean", vr, nvr, value, Access::Boolean, |v| {
        if v != 0.0 {
            fmi2True
        } else {
            fmi2False
        }
    })
}

/// String values: the model has none, so any value reference is refused.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetString(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2String,
) -> fmi2Status {
    get_values(
        c,
        "fmi2GetString",
        vr,
        nvr,
        value,
        Access::Absent("String"),
        |_| ptr::null(),
    )
}

/// Sets Real parameters or inputs (SI units, checked against their ranges; all or none).
#[no_mangle]
pub unsafe extern "C" fn fmi2SetReal(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2Real,
) -> fmi2Status {
    set_values(c, "fmi2SetReal", vr, nvr, value, Access::Real, |v| v)
}

/// Sets Integer or Enumeration parameters (checked against their ranges; all or none).
#[no_mangle]
pub unsafe extern "C" fn fmi2SetInteger(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2Integer,
) -> fmi2Status {
    set_values(
        c,
        "fmi2SetInteger",
        vr,
        nvr,
        value,
        Access::Integer,
        f64::from,
    )
}

/// Sets Boolean variables: the model has none that can be set.
#[no_mangle]
pub unsafe extern "C" fn fmi2SetBoolean(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2Boolean,
) -> fmi2Status {
    set_values(
        c,
        "fmi2SetBoolean",
        vr,
        nvr,
        value,
        Access::Boolean,
        f64::from,
    )
}

/// Sets String variables: the model has none.
#[no_mangle]
pub unsafe extern "C" fn fmi2SetString(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2String,
) -> fmi2Status {
    set_values(
        c,
        "fmi2SetString",
        vr,
        nvr,
        value,
        Access::Absent("String"),
        |_| f64::NAN,
    )
}

// ---- FMU states ----
// The bodies are shared with the FMI 3.0 functions (`exports3.rs`), which differ only in names.

/// `fmi2GetFMUstate`/`fmi3GetFMUState`.
pub(crate) unsafe fn get_state(
    c: fmi2Component,
    func: &str,
    slot: *mut fmi2FMUstate,
) -> fmi2Status {
    call(c, func, allowed::ANY, |inst| {
        let slot = out(slot, "FMUstate")?;
        let snap = inst.snapshot()?;
        store(inst, slot, snap)
    })
}

/// `fmi2SetFMUstate`/`fmi3SetFMUState`.
pub(crate) fn set_state(c: fmi2Component, func: &str, state: fmi2FMUstate) -> fmi2Status {
    call(c, func, allowed::ANY, |inst| {
        let snap = inst.state_ref(state)?.clone();
        inst.restore(&snap)
    })
}

/// `fmi2FreeFMUstate`/`fmi3FreeFMUState`.
pub(crate) unsafe fn free_state(
    c: fmi2Component,
    func: &str,
    slot: *mut fmi2FMUstate,
) -> fmi2Status {
    call(c, func, allowed::ANY, |inst| {
        let slot = out(slot, "FMUstate")?;
        if !slot.is_null() {
            inst.free_state(*slot)?;
            *slot = ptr::null_mut();
        }
        Ok(fmi2OK)
    })
}

/// `fmi2SerializedFMUstateSize`/`fmi3SerializedFMUStateSize`.
pub(crate) unsafe fn state_size(
    c: fmi2Component,
    func: &str,
    state: fmi2FMUstate,
    size: *mut usize,
) -> fmi2Status {
    call(c, func, allowed::ANY, |inst| {
        let size = out(size, "size")?;
        *size = inst.state_ref(state)?.serialize().len();
        Ok(fmi2OK)
    })
}

/// `fmi2SerializeFMUstate`/`fmi3SerializeFMUState`.
pub(crate) unsafe fn serialize_state(
    c: fmi2Component,
    func: &str,
    state: fmi2FMUstate,
    dst: *mut u8,
    size: usize,
) -> fmi2Status {
    call(c, func, allowed::ANY, |inst| {
        let bytes = inst.state_ref(state)?.serialize();
        if size < bytes.len() {
            return Err(format!(
                "buffer of {size} bytes is too small: {} needed",
                bytes.len()
            ));
        }
        array_mut(dst, bytes.len(), "serializedState")?.copy_from_slice(&bytes);
        Ok(fmi2OK)
    })
}

/// `fmi2DeSerializeFMUstate`/`fmi3DeserializeFMUState`.
pub(crate) unsafe fn deserialize_state(
    c: fmi2Component,
    func: &str,
    src: *const u8,
    size: usize,
    slot: *mut fmi2FMUstate,
) -> fmi2Status {
    call(c, func, allowed::ANY, |inst| {
        let slot = out(slot, "FMUstate")?;
        let snap = Snapshot::deserialize(array(src, size, "serializedState")?)?;
        inst.accept(&snap)?;
        store(inst, slot, snap)
    })
}

/// Copies the instance state into `*FMUstate` (a new state if it is NULL, else overwritten).
#[no_mangle]
pub unsafe extern "C" fn fmi2GetFMUstate(
    c: fmi2Component,
    FMUstate: *mut fmi2FMUstate,
) -> fmi2Status {
    get_state(c, "fmi2GetFMUstate", FMUstate)
}

/// Puts `snap` into the state `*slot` (reused when non-NULL, else a new one).
fn store(inst: &mut Instance, slot: &mut fmi2FMUstate, snap: Snapshot) -> Outcome {
    if slot.is_null() {
        *slot = inst.register(snap);
    } else {
        *inst.state_ref(*slot)? = snap;
    }
    Ok(fmi2OK)
}

/// Restores a state made by this instance.
#[no_mangle]
pub unsafe extern "C" fn fmi2SetFMUstate(c: fmi2Component, FMUstate: fmi2FMUstate) -> fmi2Status {
    set_state(c, "fmi2SetFMUstate", FMUstate)
}

/// Frees `*FMUstate` and sets it to NULL.
#[no_mangle]
pub unsafe extern "C" fn fmi2FreeFMUstate(
    c: fmi2Component,
    FMUstate: *mut fmi2FMUstate,
) -> fmi2Status {
    free_state(c, "fmi2FreeFMUstate", FMUstate)
}

/// Size (bytes) of the serialized form of a state.
#[no_mangle]
pub unsafe extern "C" fn fmi2SerializedFMUstateSize(
    c: fmi2Component,
    FMUstate: fmi2FMUstate,
    size: *mut usize,
) -> fmi2Status {
    state_size(c, "fmi2SerializedFMUstateSize", FMUstate, size)
}

/// Writes the serialized state into `serializedState[0..size]`.
#[no_mangle]
pub unsafe extern "C" fn fmi2SerializeFMUstate(
    c: fmi2Component,
    FMUstate: fmi2FMUstate,
    serializedState: *mut fmi2Byte,
    size: usize,
) -> fmi2Status {
    serialize_state(
        c,
        "fmi2SerializeFMUstate",
        FMUstate,
        serializedState.cast::<u8>(),
        size,
    )
}

/// A state from bytes made by `fmi2SerializeFMUstate` (in any process); corrupt, truncated or
/// foreign bytes are refused.
#[no_mangle]
pub unsafe extern "C" fn fmi2DeSerializeFMUstate(
    c: fmi2Component,
    serializedState: *const fmi2Byte,
    size: usize,
    FMUstate: *mut fmi2FMUstate,
) -> fmi2Status {
    deserialize_state(
        c,
        "fmi2DeSerializeFMUstate",
        serializedState.cast::<u8>(),
        size,
        FMUstate,
    )
}

/// Not provided (`providesDirectionalDerivative="false"`): always refused.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetDirectionalDerivative(
    c: fmi2Component,
    _vUnknown_ref: *const fmi2ValueReference,
    _nUnknown: usize,
    _vKnown_ref: *const fmi2ValueReference,
    _nKnown: usize,
    _dvKnown: *const fmi2Real,
    _dvUnknown: *mut fmi2Real,
) -> fmi2Status {
    call(c, "fmi2GetDirectionalDerivative", allowed::ANY, |_| {
        Err("directional derivatives are not provided (providesDirectionalDerivative=false)".into())
    })
}

// ---- co-simulation ----

/// Derivatives (SI) of the inputs for the next step: `z_in` orders 1..5, `zdot_in` orders 1..4.
#[no_mangle]
pub unsafe extern "C" fn fmi2SetRealInputDerivatives(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    order: *const fmi2Integer,
    value: *const fmi2Real,
) -> fmi2Status {
    call(
        c,
        "fmi2SetRealInputDerivatives",
        allowed::SET_DERIVATIVES,
        |inst| {
            let vrs = array(vr, nvr, "vr")?;
            let orders = array(order, nvr, "order")?;
            let vals = array(value, nvr, "value")?;
            inst.set_input_derivatives(vrs, orders, vals)
        },
    )
}

/// First time derivatives (SI) of `x`, `v`, `z`, `zdot`.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetRealOutputDerivatives(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    order: *const fmi2Integer,
    value: *mut fmi2Real,
) -> fmi2Status {
    call(
        c,
        "fmi2GetRealOutputDerivatives",
        allowed::GET_DERIVATIVES,
        |inst| {
            let vrs = array(vr, nvr, "vr")?;
            let orders = array(order, nvr, "order")?;
            let dst = array_mut(value, nvr, "value")?;
            dst.copy_from_slice(&inst.output_derivatives(vrs, orders)?);
            Ok(fmi2OK)
        },
    )
}

/// Integrates from `currentCommunicationPoint` to exactly `currentCommunicationPoint +
/// communicationStepSize` (s), locating every event inside.
#[no_mangle]
pub unsafe extern "C" fn fmi2DoStep(
    c: fmi2Component,
    currentCommunicationPoint: fmi2Real,
    communicationStepSize: fmi2Real,
    _noSetFMUStatePriorToCurrentPoint: fmi2Boolean,
) -> fmi2Status {
    call(c, "fmi2DoStep", allowed::STEP, |inst| {
        inst.do_step(currentCommunicationPoint, communicationStepSize)
    })
}

/// Steps are synchronous: there is never a step to cancel, so this is refused.
#[no_mangle]
pub unsafe extern "C" fn fmi2CancelStep(c: fmi2Component) -> fmi2Status {
    call(c, "fmi2CancelStep", allowed::CANCEL, |_| {
        Err("no asynchronous step is in progress: fmi2DoStep is synchronous".into())
    })
}

/// `fmi2Get*Status` for a kind the instance answers with `get` (`None`: not available, which
/// returns `fmi2Discard`).
fn status<T>(
    c: fmi2Component,
    func: &str,
    value: *mut T,
    get: impl FnOnce(&Instance) -> Result<Option<T>, String>,
) -> fmi2Status {
    call(c, func, allowed::STATUS, |inst| {
        // SAFETY: FMI contract (module documentation).
        let dst = unsafe { out(value, "value")? };
        Ok(match get(inst)? {
            Some(v) => {
                *dst = v;
                fmi2OK
            }
            None => fmi2Discard,
        })
    })
}

/// `fmi2DoStepStatus`/`fmi2PendingStatus`: not available (`fmi2Discard`).
#[no_mangle]
pub unsafe extern "C" fn fmi2GetStatus(
    c: fmi2Component,
    s: fmi2StatusKind,
    value: *mut fmi2Status,
) -> fmi2Status {
    status(c, "fmi2GetStatus", value, |inst| {
        inst.other_status(s).map(|_| None)
    })
}

/// `fmi2LastSuccessfulTime`: end (s) of the last successful step or of a discarded one.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetRealStatus(
    c: fmi2Component,
    s: fmi2StatusKind,
    value: *mut fmi2Real,
) -> fmi2Status {
    status(c, "fmi2GetRealStatus", value, |inst| inst.real_status(s))
}

/// No integer status is defined: `fmi2Discard`.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetIntegerStatus(
    c: fmi2Component,
    s: fmi2StatusKind,
    value: *mut fmi2Integer,
) -> fmi2Status {
    status(c, "fmi2GetIntegerStatus", value, |inst| {
        inst.other_status(s).map(|_| None)
    })
}

/// `fmi2Terminated`: whether the FMU asks to end the simulation (after `fmi2Discard`).
#[no_mangle]
pub unsafe extern "C" fn fmi2GetBooleanStatus(
    c: fmi2Component,
    s: fmi2StatusKind,
    value: *mut fmi2Boolean,
) -> fmi2Status {
    status(c, "fmi2GetBooleanStatus", value, |inst| {
        inst.boolean_status(s).map(|b| b.map(fmi2Boolean::from))
    })
}

/// `fmi2PendingStatus`: not available (`fmi2Discard`).
#[no_mangle]
pub unsafe extern "C" fn fmi2GetStringStatus(
    c: fmi2Component,
    s: fmi2StatusKind,
    value: *mut fmi2String,
) -> fmi2Status {
    status(c, "fmi2GetStringStatus", value, |inst| {
        inst.other_status(s).map(|_| None)
    })
}

// ---- Model Exchange ----

/// Enters event mode (from continuous-time or event mode).
#[no_mangle]
pub unsafe extern "C" fn fmi2EnterEventMode(c: fmi2Component) -> fmi2Status {
    call(c, "fmi2EnterEventMode", allowed::ENTER_EVENT, |inst| {
        inst.enter_event_mode()
    })
}

/// Settles the events at the current time (impacts, sticking, release, snap-throughs, a due
/// chatter tail) and reports in `*eventInfo` whether the states changed and the next time event.
#[no_mangle]
pub unsafe extern "C" fn fmi2NewDiscreteStates(
    c: fmi2Component,
    eventInfo: *mut fmi2EventInfo,
) -> fmi2Status {
    call(c, "fmi2NewDiscreteStates", allowed::EVENT, |inst| {
        let info = out(eventInfo, "eventInfo")?;
        inst.new_discrete_states(info)
    })
}

/// Enters continuous-time mode.
#[no_mangle]
pub unsafe extern "C" fn fmi2EnterContinuousTimeMode(c: fmi2Component) -> fmi2Status {
    call(c, "fmi2EnterContinuousTimeMode", allowed::EVENT, |inst| {
        inst.enter_continuous_time_mode()
    })
}

/// After an accepted integrator step: `*enterEventMode` is true when the states have moved
/// where event mode must act (see `fmu/README.md`); `*terminateSimulation` is always false.
#[no_mangle]
pub unsafe extern "C" fn fmi2CompletedIntegratorStep(
    c: fmi2Component,
    _noSetFMUStatePriorToCurrentPoint: fmi2Boolean,
    enterEventMode: *mut fmi2Boolean,
    terminateSimulation: *mut fmi2Boolean,
) -> fmi2Status {
    call(
        c,
        "fmi2CompletedIntegratorStep",
        allowed::CONTINUOUS,
        |inst| {
            let enter = out(enterEventMode, "enterEventMode")?;
            let terminate = out(terminateSimulation, "terminateSimulation")?;
            *enter = inst.completed_integrator_step()?.into();
            *terminate = fmi2False;
            Ok(fmi2OK)
        },
    )
}

/// Sets the time (s): finite, not before the last event mode.
#[no_mangle]
pub unsafe extern "C" fn fmi2SetTime(c: fmi2Component, time: fmi2Real) -> fmi2Status {
    call(c, "fmi2SetTime", allowed::SET_TIME, |inst| {
        inst.set_time(time)
    })
}

/// Sets the continuous states `x` (m), `v` (m/s); `nx` must be 2.
#[no_mangle]
pub unsafe extern "C" fn fmi2SetContinuousStates(
    c: fmi2Component,
    x: *const fmi2Real,
    nx: usize,
) -> fmi2Status {
    call(c, "fmi2SetContinuousStates", allowed::CONTINUOUS, |inst| {
        inst.set_continuous_states(array(x, nx, "x")?)
    })
}

/// Copies `values` (`n` of them) into the host array `dst` (NULL refused unless `n` is 0).
pub(crate) unsafe fn write_array(
    dst: *mut fmi2Real,
    n: usize,
    what: &str,
    values: Result<impl AsRef<[f64]>, String>,
) -> Outcome {
    let values = values?;
    let dst = array_mut(dst, n, what)?;
    dst.copy_from_slice(values.as_ref());
    Ok(fmi2OK)
}

/// Derivatives `der_x` (m/s), `der_v` (m/s²) of the continuous states; `nx` must be 2.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetDerivatives(
    c: fmi2Component,
    derivatives: *mut fmi2Real,
    nx: usize,
) -> fmi2Status {
    call(c, "fmi2GetDerivatives", allowed::ME_GET, |inst| {
        let d = inst.derivatives(nx);
        write_array(derivatives, nx, "derivatives", d)
    })
}

/// Event indicators: gap `x − z` (m) in free flight or contact force (m/s²) while sticking, and
/// `x − delta_x/2` (m); `ni` must be 2.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetEventIndicators(
    c: fmi2Component,
    eventIndicators: *mut fmi2Real,
    ni: usize,
) -> fmi2Status {
    call(c, "fmi2GetEventIndicators", allowed::ME_GET, |inst| {
        let z = inst.event_indicators(ni);
        write_array(eventIndicators, ni, "eventIndicators", z)
    })
}

/// The continuous states `x` (m), `v` (m/s); `nx` must be 2.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetContinuousStates(
    c: fmi2Component,
    x: *mut fmi2Real,
    nx: usize,
) -> fmi2Status {
    call(c, "fmi2GetContinuousStates", allowed::ME_GET, |inst| {
        let s = inst.continuous_states(nx);
        write_array(x, nx, "x", s)
    })
}

/// Nominal magnitudes of the continuous states: `delta_x` (m), `omega0*delta_x` (m/s).
#[no_mangle]
pub unsafe extern "C" fn fmi2GetNominalsOfContinuousStates(
    c: fmi2Component,
    x_nominal: *mut fmi2Real,
    nx: usize,
) -> fmi2Status {
    call(
        c,
        "fmi2GetNominalsOfContinuousStates",
        allowed::NOMINALS,
        |inst| {
            let n = inst.nominals(nx);
            write_array(x_nominal, nx, "x_nominal", n)
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_panic_is_caught_and_puts_the_instance_into_the_error_state() {
        let inst = Instance::new(
            c"t".into(),
            Interface::CoSimulation,
            Api::Fmi2,
            ptr::null_mut(),
            Logger::Fmi2(None),
            false,
        );
        let c: fmi2Component = Box::into_raw(Box::new(inst)).cast();
        let status = call(c, "fmi2Test", allowed::ANY, |_| panic!("boom"));
        assert_eq!(status, fmi2Error);
        // SAFETY: `c` is the live instance made above.
        let inst = unsafe { instance(c) }.unwrap();
        assert_eq!(inst.lifecycle, Lifecycle::Error);
        // Only what the standard allows in the error state still works.
        assert_eq!(unsafe { fmi2DoStep(c, 0.0, 1.0, 0) }, fmi2Error);
        assert_eq!(unsafe { fmi2Reset(c) }, fmi2OK);
        unsafe { fmi2FreeInstance(c) };
    }
}
