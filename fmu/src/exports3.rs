//! The FMI 3.0 functions with C linkage: common, Model Exchange and co-simulation (with event mode
//! and early return). They drive the same [`Instance`] as the FMI 2.0 functions (`exports2.rs`),
//! whose argument checks and panic guard (`call`) they share; an instance made by one version's
//! functions is refused by the other's.
//!
//! Co-simulation with `earlyReturnAllowed`: `fmi3DoStep` stops at the first impact, start or end
//! of sticking, or snap-through after the current time, with the event applied, and returns
//! `earlyReturn = true` and `lastSuccessfulTime` = the event time (exact to the integrator's
//! root location); with `eventModeUsed` it also sets `eventHandlingNeeded`, and in the event mode
//! that follows the host may set inputs and tunable parameters (`fmi3UpdateDiscreteStates`
//! reports no further change). Without early return a step integrates to its end like
//! `fmi2DoStep`, bit for bit.
//!
//! The model has Float64, Int32, Enumeration (Int64) and Boolean variables only: the functions of
//! the other types refuse every value reference. Clocks, configuration mode, directional and
//! adjoint derivatives, variable dependencies and scheduled execution are not provided.
//!
//! # Safety
//! As for `exports2.rs`: pointers as the FMI 3.0 standard specifies, the instance a live handle
//! from `fmi3Instantiate*`.
#![allow(non_snake_case, clippy::missing_safety_doc, clippy::too_many_arguments)]

use std::ffi::{c_char, CString};
use std::panic::catch_unwind;
use std::ptr;

use crate::exports2::{self as states, array, array_mut, call, out, text, write_array};
use crate::fmi2::fmi2EventInfo;
use crate::fmi3::*;
use crate::instance::{allowed, Access, Api, Instance, Interface, Logger, Outcome};
use crate::md::{EVENT_INDICATORS, GUID, STATES};

/// Refuses an array of `n_values` values for `nvr` value references (the model has scalars only).
fn scalars(nvr: usize, n_values: usize) -> Result<(), String> {
    if n_values == nvr {
        Ok(())
    } else {
        Err(format!(
            "nValues = {n_values} but nValueReferences = {nvr}: the model has scalar variables only"
        ))
    }
}

// ---- common functions ----

/// `"3.0"`.
#[no_mangle]
pub extern "C" fn fmi3GetVersion() -> *const c_char {
    c"3.0".as_ptr()
}

/// Switches logging of the listed categories (all of them when `nCategories` is 0) on or off.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetDebugLogging(
    instance: fmi3Instance,
    loggingOn: fmi3Boolean,
    nCategories: usize,
    categories: *const fmi3String,
) -> fmi3Status {
    call(instance, "fmi3SetDebugLogging", allowed::ANY, |inst| {
        let names = array(categories, nCategories, "categories")?
            .iter()
            .map(|&s| text(s, "category"))
            .collect::<Result<Vec<_>, _>>()?;
        inst.set_debug_logging(loggingOn, &names)
    })
}

/// Checks the arguments common to both `fmi3Instantiate*` and makes the instance (or NULL with
/// a logged reason).
unsafe fn instantiate(
    name: fmi3String,
    token: fmi3String,
    interface: Interface,
    api: Api,
    env: fmi3InstanceEnvironment,
    logger: fmi3LogMessageCallback,
    logging_on: bool,
    extra: Result<(), String>,
) -> fmi3Instance {
    let given = text(name, "instanceName").unwrap_or_default();
    let cname = CString::new(given.clone()).unwrap_or_default();
    let inst = Instance::new(cname, interface, api, env, Logger::Fmi3(logger), logging_on);
    let checked = (|| {
        if given.trim().is_empty() {
            return Err("instanceName must be a non-empty string".to_string());
        }
        let t = text(token, "instantiationToken")?;
        if t != GUID {
            return Err(format!(
                "instantiationToken {t} does not match this binary's {GUID}: modelDescription.xml and binary come from different builds"
            ));
        }
        bistable_core::simd::check().map_err(|e| e.to_string())?;
        extra
    })();
    match checked {
        Ok(()) => Box::into_raw(Box::new(inst)).cast(),
        Err(msg) => {
            let func = match interface {
                Interface::ModelExchange => "fmi3InstantiateModelExchange",
                Interface::CoSimulation => "fmi3InstantiateCoSimulation",
            };
            inst.log_error(func, &msg);
            ptr::null_mut()
        }
    }
}

/// A new Model Exchange instance, or NULL (with a logged reason) for a wrong instantiation token
/// or an empty name. `resourcePath` and `visible` are not used.
#[no_mangle]
pub unsafe extern "C" fn fmi3InstantiateModelExchange(
    instanceName: fmi3String,
    instantiationToken: fmi3String,
    _resourcePath: fmi3String,
    _visible: fmi3Boolean,
    loggingOn: fmi3Boolean,
    instanceEnvironment: fmi3InstanceEnvironment,
    logMessage: fmi3LogMessageCallback,
) -> fmi3Instance {
    catch_unwind(|| {
        instantiate(
            instanceName,
            instantiationToken,
            Interface::ModelExchange,
            Api::Fmi3 {
                event_mode: false,
                early_return: false,
            },
            instanceEnvironment,
            logMessage,
            loggingOn,
            Ok(()),
        )
    })
    .unwrap_or(ptr::null_mut())
}

/// A new co-simulation instance, or NULL (with a logged reason). `eventModeUsed`: after an
/// early return at an event, `eventHandlingNeeded` asks for event mode; `earlyReturnAllowed`:
/// `fmi3DoStep` stops at every event. No intermediate update is provided, so
/// `requiredIntermediateVariables` must be empty; `intermediateUpdate` is not called.
#[no_mangle]
pub unsafe extern "C" fn fmi3InstantiateCoSimulation(
    instanceName: fmi3String,
    instantiationToken: fmi3String,
    _resourcePath: fmi3String,
    _visible: fmi3Boolean,
    loggingOn: fmi3Boolean,
    eventModeUsed: fmi3Boolean,
    earlyReturnAllowed: fmi3Boolean,
    _requiredIntermediateVariables: *const fmi3ValueReference,
    nRequiredIntermediateVariables: usize,
    instanceEnvironment: fmi3InstanceEnvironment,
    logMessage: fmi3LogMessageCallback,
    _intermediateUpdate: fmi3IntermediateUpdateCallback,
) -> fmi3Instance {
    let extra = if nRequiredIntermediateVariables == 0 {
        Ok(())
    } else {
        Err(format!(
            "nRequiredIntermediateVariables = {nRequiredIntermediateVariables}: this FMU provides no intermediate update (providesIntermediateUpdate=false)"
        ))
    };
    catch_unwind(|| {
        instantiate(
            instanceName,
            instantiationToken,
            Interface::CoSimulation,
            Api::Fmi3 {
                event_mode: eventModeUsed,
                early_return: earlyReturnAllowed,
            },
            instanceEnvironment,
            logMessage,
            loggingOn,
            extra,
        )
    })
    .unwrap_or(ptr::null_mut())
}

/// Scheduled execution is not provided: logs why and returns NULL.
#[no_mangle]
pub unsafe extern "C" fn fmi3InstantiateScheduledExecution(
    _instanceName: fmi3String,
    _instantiationToken: fmi3String,
    _resourcePath: fmi3String,
    _visible: fmi3Boolean,
    _loggingOn: fmi3Boolean,
    instanceEnvironment: fmi3InstanceEnvironment,
    logMessage: fmi3LogMessageCallback,
    _clockUpdate: fmi3ClockUpdateCallback,
    _lockPreemption: fmi3LockPreemptionCallback,
    _unlockPreemption: fmi3UnlockPreemptionCallback,
) -> fmi3Instance {
    let _ = catch_unwind(|| {
        if let Some(log) = logMessage {
            log(
                instanceEnvironment,
                fmi3Error,
                c"logStatusError".as_ptr(),
                c"fmi3InstantiateScheduledExecution: this FMU provides Model Exchange and Co-Simulation only".as_ptr(),
            );
        }
    });
    ptr::null_mut()
}

/// Frees the instance and the FMU states it handed out.
#[no_mangle]
pub unsafe extern "C" fn fmi3FreeInstance(instance: fmi3Instance) {
    let _ = catch_unwind(|| {
        if let Some(inst) = crate::exports2::instance(instance) {
            inst.retire();
            drop(Box::from_raw(instance.cast::<Instance>()));
        }
    });
}

/// Start time, optional stop time (s) and tolerance (ignored: see the parameter `tol`); enters
/// initialization mode.
#[no_mangle]
pub unsafe extern "C" fn fmi3EnterInitializationMode(
    instance: fmi3Instance,
    toleranceDefined: fmi3Boolean,
    tolerance: fmi3Float64,
    startTime: fmi3Float64,
    stopTimeDefined: fmi3Boolean,
    stopTime: fmi3Float64,
) -> fmi3Status {
    let tol = toleranceDefined.then_some(tolerance);
    let stop = stopTimeDefined.then_some(stopTime);
    call(
        instance,
        "fmi3EnterInitializationMode",
        allowed::INSTANTIATED,
        |inst| {
            inst.setup_experiment(startTime, stop, tol)?;
            inst.enter_initialization()
        },
    )
}

/// Checks the parameters and starts the simulation at the start time. Co-simulation: step mode
/// (event mode with `eventModeUsed`); Model Exchange: event mode.
#[no_mangle]
pub unsafe extern "C" fn fmi3ExitInitializationMode(instance: fmi3Instance) -> fmi3Status {
    call(
        instance,
        "fmi3ExitInitializationMode",
        allowed::INIT,
        |inst| inst.exit_initialization(),
    )
}

/// Enters event mode: Model Exchange from continuous-time mode; co-simulation (with
/// `eventModeUsed`) after a step.
#[no_mangle]
pub unsafe extern "C" fn fmi3EnterEventMode(instance: fmi3Instance) -> fmi3Status {
    call(
        instance,
        "fmi3EnterEventMode",
        allowed::ENTER_EVENT3,
        Instance::enter_event_mode,
    )
}

/// Ends the simulation (values stay readable).
#[no_mangle]
pub unsafe extern "C" fn fmi3Terminate(instance: fmi3Instance) -> fmi3Status {
    call(
        instance,
        "fmi3Terminate",
        allowed::TERMINATE,
        Instance::terminate,
    )
}

/// Back to the instantiated state with the start values.
#[no_mangle]
pub unsafe extern "C" fn fmi3Reset(instance: fmi3Instance) -> fmi3Status {
    call(instance, "fmi3Reset", allowed::ANY, Instance::reset)
}

// ---- getting and setting values ----

/// `fmi3Get<T>`: values read as `ty`, converted by `conv`.
unsafe fn get<T>(
    c: fmi3Instance,
    func: &str,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *mut T,
    n_values: usize,
    ty: Access,
    conv: impl Fn(f64) -> T + Copy,
) -> fmi3Status {
    call(c, func, allowed::GET, |inst| {
        scalars(nvr, n_values)?;
        let vrs = array(vr, nvr, "valueReferences")?;
        let dst = array_mut(values, nvr, "values")?;
        inst.get_into(vrs, ty, dst, conv)?;
        Ok(fmi3OK)
    })
}

/// `fmi3Set<T>`: values written as `ty`, converted by `conv` (range-checked by the instance; all
/// or none).
unsafe fn set<T: Copy>(
    c: fmi3Instance,
    func: &str,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *const T,
    n_values: usize,
    ty: Access,
    conv: impl Fn(T) -> f64 + Copy,
) -> fmi3Status {
    call(c, func, allowed::SET, |inst| {
        scalars(nvr, n_values)?;
        let vrs = array(vr, nvr, "valueReferences")?;
        let vals = array(values, nvr, "values")?;
        inst.set_from(vrs, vals, ty, conv)
    })
}

/// Float64 values (SI units).
#[no_mangle]
pub unsafe extern "C" fn fmi3GetFloat64(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *mut fmi3Float64,
    nValues: usize,
) -> fmi3Status {
    get(
        instance,
        "fmi3GetFloat64",
        valueReferences,
        nValueReferences,
        values,
        nValues,
        Access::Real,
        |v| v,
    )
}

/// Int32 values (the counters and `well`).
#[no_mangle]
pub unsafe extern "C" fn fmi3GetInt32(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *mut fmi3Int32,
    nValues: usize,
) -> fmi3Status {
    get(
        instance,
        "fmi3GetInt32",
        valueReferences,
        nValueReferences,
        values,
        nValues,
        Access::Int32,
        |v| v as fmi3Int32,
    )
}

/// Int64 values: the Enumerations `shaker_mode`, `plate_reconstruction`.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetInt64(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *mut fmi3Int64,
    nValues: usize,
) -> fmi3Status {
    get(
        instance,
        "fmi3GetInt64",
        valueReferences,
        nValueReferences,
        values,
        nValues,
        Access::Int64,
        |v| v as fmi3Int64,
    )
}

/// Boolean values (`in_contact`).
#[no_mangle]
pub unsafe extern "C" fn fmi3GetBoolean(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *mut fmi3Boolean,
    nValues: usize,
) -> fmi3Status {
    get(
        instance,
        "fmi3GetBoolean",
        valueReferences,
        nValueReferences,
        values,
        nValues,
        Access::Boolean,
        |v| v != 0.0,
    )
}

/// Sets Float64 parameters or inputs (SI units, checked against their ranges; all or none).
#[no_mangle]
pub unsafe extern "C" fn fmi3SetFloat64(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *const fmi3Float64,
    nValues: usize,
) -> fmi3Status {
    set(
        instance,
        "fmi3SetFloat64",
        valueReferences,
        nValueReferences,
        values,
        nValues,
        Access::Real,
        |v| v,
    )
}

/// Sets Int32 variables: the model has none that can be set.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetInt32(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *const fmi3Int32,
    nValues: usize,
) -> fmi3Status {
    set(
        instance,
        "fmi3SetInt32",
        valueReferences,
        nValueReferences,
        values,
        nValues,
        Access::Int32,
        f64::from,
    )
}

/// Sets the Enumeration parameters (Int64; checked against their items; all or none).
#[no_mangle]
pub unsafe extern "C" fn fmi3SetInt64(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *const fmi3Int64,
    nValues: usize,
) -> fmi3Status {
    set(
        instance,
        "fmi3SetInt64",
        valueReferences,
        nValueReferences,
        values,
        nValues,
        Access::Int64,
        |v| v as f64,
    )
}

/// Sets Boolean variables: the model has none that can be set. The values are read as bytes
/// (any non-zero byte is true).
#[no_mangle]
pub unsafe extern "C" fn fmi3SetBoolean(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *const fmi3Boolean,
    nValues: usize,
) -> fmi3Status {
    set(
        instance,
        "fmi3SetBoolean",
        valueReferences,
        nValueReferences,
        values.cast::<u8>(),
        nValues,
        Access::Boolean,
        |b| f64::from(b != 0),
    )
}

/// `fmi3Get<T>` of a type the model has no variable of: every value reference is refused.
unsafe fn get_absent<T>(
    c: fmi3Instance,
    func: &str,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *mut T,
    n_values: usize,
    name: &'static str,
) -> fmi3Status {
    call(c, func, allowed::GET, |inst| {
        get_absent_in(inst, vr, nvr, values, n_values, name)
    })
}

/// `fmi3Set<T>` of a type the model has no variable of: every value reference is refused.
unsafe fn set_absent<T>(
    c: fmi3Instance,
    func: &str,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *const T,
    n_values: usize,
    name: &'static str,
) -> fmi3Status {
    call(c, func, allowed::SET, |inst| {
        set_absent_in(inst, vr, nvr, values, n_values, name)
    })
}

/// The model has no Float32 variable: every value reference is refused.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetFloat32(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *mut fmi3Float32,
    nValues: usize,
) -> fmi3Status {
    let (vr, n) = (valueReferences, nValueReferences);
    get_absent(
        instance,
        "fmi3GetFloat32",
        vr,
        n,
        values,
        nValues,
        "Float32",
    )
}

/// The model has no Int8 variable: every value reference is refused.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetInt8(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *mut fmi3Int8,
    nValues: usize,
) -> fmi3Status {
    let (vr, n) = (valueReferences, nValueReferences);
    get_absent(instance, "fmi3GetInt8", vr, n, values, nValues, "Int8")
}

/// The model has no UInt8 variable: every value reference is refused.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetUInt8(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *mut fmi3UInt8,
    nValues: usize,
) -> fmi3Status {
    let (vr, n) = (valueReferences, nValueReferences);
    get_absent(instance, "fmi3GetUInt8", vr, n, values, nValues, "UInt8")
}

/// The model has no Int16 variable: every value reference is refused.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetInt16(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *mut fmi3Int16,
    nValues: usize,
) -> fmi3Status {
    let (vr, n) = (valueReferences, nValueReferences);
    get_absent(instance, "fmi3GetInt16", vr, n, values, nValues, "Int16")
}

/// The model has no UInt16 variable: every value reference is refused.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetUInt16(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *mut fmi3UInt16,
    nValues: usize,
) -> fmi3Status {
    let (vr, n) = (valueReferences, nValueReferences);
    get_absent(instance, "fmi3GetUInt16", vr, n, values, nValues, "UInt16")
}

/// The model has no UInt32 variable: every value reference is refused.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetUInt32(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *mut fmi3UInt32,
    nValues: usize,
) -> fmi3Status {
    let (vr, n) = (valueReferences, nValueReferences);
    get_absent(instance, "fmi3GetUInt32", vr, n, values, nValues, "UInt32")
}

/// The model has no UInt64 variable: every value reference is refused.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetUInt64(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *mut fmi3UInt64,
    nValues: usize,
) -> fmi3Status {
    let (vr, n) = (valueReferences, nValueReferences);
    get_absent(instance, "fmi3GetUInt64", vr, n, values, nValues, "UInt64")
}

/// The model has no String variable: every value reference is refused.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetString(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *mut fmi3String,
    nValues: usize,
) -> fmi3Status {
    let (vr, n) = (valueReferences, nValueReferences);
    get_absent(instance, "fmi3GetString", vr, n, values, nValues, "String")
}

/// The model has no Binary variable: every value reference is refused.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetBinary(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    valueSizes: *mut usize,
    values: *mut fmi3Binary,
    nValues: usize,
) -> fmi3Status {
    let (vr, n) = (valueReferences, nValueReferences);
    call(instance, "fmi3GetBinary", allowed::GET, |inst| {
        array_mut(valueSizes, nValues, "valueSizes")?;
        get_absent_in(inst, vr, n, values, nValues, "Binary")
    })
}

/// The model has no Float32 variable: every value reference is refused.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetFloat32(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *const fmi3Float32,
    nValues: usize,
) -> fmi3Status {
    let (vr, n) = (valueReferences, nValueReferences);
    set_absent(
        instance,
        "fmi3SetFloat32",
        vr,
        n,
        values,
        nValues,
        "Float32",
    )
}

/// The model has no Int8 variable: every value reference is refused.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetInt8(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *const fmi3Int8,
    nValues: usize,
) -> fmi3Status {
    let (vr, n) = (valueReferences, nValueReferences);
    set_absent(instance, "fmi3SetInt8", vr, n, values, nValues, "Int8")
}

/// The model has no UInt8 variable: every value reference is refused.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetUInt8(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *const fmi3UInt8,
    nValues: usize,
) -> fmi3Status {
    let (vr, n) = (valueReferences, nValueReferences);
    set_absent(instance, "fmi3SetUInt8", vr, n, values, nValues, "UInt8")
}

/// The model has no Int16 variable: every value reference is refused.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetInt16(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *const fmi3Int16,
    nValues: usize,
) -> fmi3Status {
    let (vr, n) = (valueReferences, nValueReferences);
    set_absent(instance, "fmi3SetInt16", vr, n, values, nValues, "Int16")
}

/// The model has no UInt16 variable: every value reference is refused.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetUInt16(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *const fmi3UInt16,
    nValues: usize,
) -> fmi3Status {
    let (vr, n) = (valueReferences, nValueReferences);
    set_absent(instance, "fmi3SetUInt16", vr, n, values, nValues, "UInt16")
}

/// The model has no UInt32 variable: every value reference is refused.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetUInt32(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *const fmi3UInt32,
    nValues: usize,
) -> fmi3Status {
    let (vr, n) = (valueReferences, nValueReferences);
    set_absent(instance, "fmi3SetUInt32", vr, n, values, nValues, "UInt32")
}

/// The model has no UInt64 variable: every value reference is refused.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetUInt64(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *const fmi3UInt64,
    nValues: usize,
) -> fmi3Status {
    let (vr, n) = (valueReferences, nValueReferences);
    set_absent(instance, "fmi3SetUInt64", vr, n, values, nValues, "UInt64")
}

/// The model has no String variable: every value reference is refused.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetString(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *const fmi3String,
    nValues: usize,
) -> fmi3Status {
    let (vr, n) = (valueReferences, nValueReferences);
    set_absent(instance, "fmi3SetString", vr, n, values, nValues, "String")
}

/// The model has no Binary variable: every value reference is refused.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetBinary(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    valueSizes: *const usize,
    values: *const fmi3Binary,
    nValues: usize,
) -> fmi3Status {
    let (vr, n) = (valueReferences, nValueReferences);
    call(instance, "fmi3SetBinary", allowed::SET, |inst| {
        scalars(n, nValues)?;
        array(valueSizes, nValues, "valueSizes")?;
        set_absent_in(inst, vr, n, values, nValues, "Binary")
    })
}

/// The refusal of [`get_absent`] (also inside a call that checked more arguments).
unsafe fn get_absent_in<T>(
    inst: &mut Instance,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *mut T,
    n_values: usize,
    name: &'static str,
) -> Outcome {
    scalars(nvr, n_values)?;
    array_mut(values, nvr, "values")?;
    inst.get(array(vr, nvr, "valueReferences")?, Access::Absent(name))?;
    Ok(fmi3OK)
}

/// The refusal of [`set_absent`] (also inside a call that checked more arguments).
unsafe fn set_absent_in<T>(
    inst: &mut Instance,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *const T,
    n_values: usize,
    name: &'static str,
) -> Outcome {
    scalars(nvr, n_values)?;
    array(values, nvr, "values")?;
    inst.set(
        array(vr, nvr, "valueReferences")?,
        &vec![0.0; nvr],
        Access::Absent(name),
    )
}

/// The model has no clocks: every value reference is refused.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetClock(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *mut fmi3Clock,
) -> fmi3Status {
    let (vr, n) = (valueReferences, nValueReferences);
    get_absent(instance, "fmi3GetClock", vr, n, values, n, "Clock")
}

/// The model has no clocks: every value reference is refused.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetClock(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *const fmi3Clock,
) -> fmi3Status {
    let (vr, n) = (valueReferences, nValueReferences);
    set_absent(
        instance,
        "fmi3SetClock",
        vr,
        n,
        values.cast::<u8>(),
        n,
        "Clock",
    )
}

/// A function for something the model does not provide: refused with `why`.
fn not_provided(c: fmi3Instance, func: &str, why: &str) -> fmi3Status {
    call(c, func, allowed::ANY, |_| Err(why.to_string()))
}

/// Not provided (`providesPerElementDependencies="false"`; the dependencies are in the model
/// description).
#[no_mangle]
pub unsafe extern "C" fn fmi3GetNumberOfVariableDependencies(
    instance: fmi3Instance,
    _valueReference: fmi3ValueReference,
    _nDependencies: *mut usize,
) -> fmi3Status {
    not_provided(
        instance,
        "fmi3GetNumberOfVariableDependencies",
        "not provided (providesPerElementDependencies=false): see ModelStructure in modelDescription.xml",
    )
}

/// Not provided (`providesPerElementDependencies="false"`).
#[no_mangle]
pub unsafe extern "C" fn fmi3GetVariableDependencies(
    instance: fmi3Instance,
    _dependent: fmi3ValueReference,
    _elementIndicesOfDependent: *mut usize,
    _independents: *mut fmi3ValueReference,
    _elementIndicesOfIndependents: *mut usize,
    _dependencyKinds: *mut fmi3DependencyKind,
    _nDependencies: usize,
) -> fmi3Status {
    not_provided(
        instance,
        "fmi3GetVariableDependencies",
        "not provided (providesPerElementDependencies=false): see ModelStructure in modelDescription.xml",
    )
}

// ---- FMU states (the FMI 2.0 functions' bodies) ----

/// Copies the instance state into `*FMUState` (a new state if it is NULL, else overwritten).
#[no_mangle]
pub unsafe extern "C" fn fmi3GetFMUState(
    instance: fmi3Instance,
    FMUState: *mut fmi3FMUState,
) -> fmi3Status {
    states::get_state(instance, "fmi3GetFMUState", FMUState)
}

/// Restores a state made by this instance.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetFMUState(
    instance: fmi3Instance,
    FMUState: fmi3FMUState,
) -> fmi3Status {
    states::set_state(instance, "fmi3SetFMUState", FMUState)
}

/// Frees `*FMUState` and sets it to NULL.
#[no_mangle]
pub unsafe extern "C" fn fmi3FreeFMUState(
    instance: fmi3Instance,
    FMUState: *mut fmi3FMUState,
) -> fmi3Status {
    states::free_state(instance, "fmi3FreeFMUState", FMUState)
}

/// Size (bytes) of the serialized form of a state.
#[no_mangle]
pub unsafe extern "C" fn fmi3SerializedFMUStateSize(
    instance: fmi3Instance,
    FMUState: fmi3FMUState,
    size: *mut usize,
) -> fmi3Status {
    states::state_size(instance, "fmi3SerializedFMUStateSize", FMUState, size)
}

/// Writes the serialized state into `serializedState[0..size]`.
#[no_mangle]
pub unsafe extern "C" fn fmi3SerializeFMUState(
    instance: fmi3Instance,
    FMUState: fmi3FMUState,
    serializedState: *mut fmi3Byte,
    size: usize,
) -> fmi3Status {
    let func = "fmi3SerializeFMUState";
    states::serialize_state(instance, func, FMUState, serializedState, size)
}

/// A state from bytes made by `fmi3SerializeFMUState` (in any process) for an instance of the
/// same interface and options; corrupt, truncated or foreign bytes are refused.
#[no_mangle]
pub unsafe extern "C" fn fmi3DeserializeFMUState(
    instance: fmi3Instance,
    serializedState: *const fmi3Byte,
    size: usize,
    FMUState: *mut fmi3FMUState,
) -> fmi3Status {
    let func = "fmi3DeserializeFMUState";
    states::deserialize_state(instance, func, serializedState, size, FMUState)
}

/// Not provided (`providesDirectionalDerivatives="false"`).
#[no_mangle]
pub unsafe extern "C" fn fmi3GetDirectionalDerivative(
    instance: fmi3Instance,
    _unknowns: *const fmi3ValueReference,
    _nUnknowns: usize,
    _knowns: *const fmi3ValueReference,
    _nKnowns: usize,
    _seed: *const fmi3Float64,
    _nSeed: usize,
    _sensitivity: *mut fmi3Float64,
    _nSensitivity: usize,
) -> fmi3Status {
    not_provided(
        instance,
        "fmi3GetDirectionalDerivative",
        "directional derivatives are not provided (providesDirectionalDerivatives=false)",
    )
}

/// Not provided (`providesAdjointDerivatives="false"`).
#[no_mangle]
pub unsafe extern "C" fn fmi3GetAdjointDerivative(
    instance: fmi3Instance,
    _unknowns: *const fmi3ValueReference,
    _nUnknowns: usize,
    _knowns: *const fmi3ValueReference,
    _nKnowns: usize,
    _seed: *const fmi3Float64,
    _nSeed: usize,
    _sensitivity: *mut fmi3Float64,
    _nSensitivity: usize,
) -> fmi3Status {
    not_provided(
        instance,
        "fmi3GetAdjointDerivative",
        "adjoint derivatives are not provided (providesAdjointDerivatives=false)",
    )
}

/// The model has no structural parameters: refused.
#[no_mangle]
pub unsafe extern "C" fn fmi3EnterConfigurationMode(instance: fmi3Instance) -> fmi3Status {
    not_provided(
        instance,
        "fmi3EnterConfigurationMode",
        "the model has no structural parameters",
    )
}

/// The model has no structural parameters: refused.
#[no_mangle]
pub unsafe extern "C" fn fmi3ExitConfigurationMode(instance: fmi3Instance) -> fmi3Status {
    not_provided(
        instance,
        "fmi3ExitConfigurationMode",
        "the model has no structural parameters",
    )
}

const NO_CLOCKS: &str = "the model has no clocks";

/// The model has no clocks: refused.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetIntervalDecimal(
    instance: fmi3Instance,
    _valueReferences: *const fmi3ValueReference,
    _nValueReferences: usize,
    _intervals: *mut fmi3Float64,
    _qualifiers: *mut fmi3IntervalQualifier,
) -> fmi3Status {
    not_provided(instance, "fmi3GetIntervalDecimal", NO_CLOCKS)
}

/// The model has no clocks: refused.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetIntervalFraction(
    instance: fmi3Instance,
    _valueReferences: *const fmi3ValueReference,
    _nValueReferences: usize,
    _counters: *mut fmi3UInt64,
    _resolutions: *mut fmi3UInt64,
    _qualifiers: *mut fmi3IntervalQualifier,
) -> fmi3Status {
    not_provided(instance, "fmi3GetIntervalFraction", NO_CLOCKS)
}

/// The model has no clocks: refused.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetShiftDecimal(
    instance: fmi3Instance,
    _valueReferences: *const fmi3ValueReference,
    _nValueReferences: usize,
    _shifts: *mut fmi3Float64,
) -> fmi3Status {
    not_provided(instance, "fmi3GetShiftDecimal", NO_CLOCKS)
}

/// The model has no clocks: refused.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetShiftFraction(
    instance: fmi3Instance,
    _valueReferences: *const fmi3ValueReference,
    _nValueReferences: usize,
    _counters: *mut fmi3UInt64,
    _resolutions: *mut fmi3UInt64,
) -> fmi3Status {
    not_provided(instance, "fmi3GetShiftFraction", NO_CLOCKS)
}

/// The model has no clocks: refused.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetIntervalDecimal(
    instance: fmi3Instance,
    _valueReferences: *const fmi3ValueReference,
    _nValueReferences: usize,
    _intervals: *const fmi3Float64,
) -> fmi3Status {
    not_provided(instance, "fmi3SetIntervalDecimal", NO_CLOCKS)
}

/// The model has no clocks: refused.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetIntervalFraction(
    instance: fmi3Instance,
    _valueReferences: *const fmi3ValueReference,
    _nValueReferences: usize,
    _counters: *const fmi3UInt64,
    _resolutions: *const fmi3UInt64,
) -> fmi3Status {
    not_provided(instance, "fmi3SetIntervalFraction", NO_CLOCKS)
}

/// The model has no clocks: refused.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetShiftDecimal(
    instance: fmi3Instance,
    _valueReferences: *const fmi3ValueReference,
    _nValueReferences: usize,
    _shifts: *const fmi3Float64,
) -> fmi3Status {
    not_provided(instance, "fmi3SetShiftDecimal", NO_CLOCKS)
}

/// The model has no clocks: refused.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetShiftFraction(
    instance: fmi3Instance,
    _valueReferences: *const fmi3ValueReference,
    _nValueReferences: usize,
    _counters: *const fmi3UInt64,
    _resolutions: *const fmi3UInt64,
) -> fmi3Status {
    not_provided(instance, "fmi3SetShiftFraction", NO_CLOCKS)
}

/// Not provided (`providesEvaluateDiscreteStates="false"`).
#[no_mangle]
pub unsafe extern "C" fn fmi3EvaluateDiscreteStates(instance: fmi3Instance) -> fmi3Status {
    not_provided(
        instance,
        "fmi3EvaluateDiscreteStates",
        "not provided (providesEvaluateDiscreteStates=false)",
    )
}

/// Settles the events at the current time. Model Exchange: impacts, sticking, release,
/// snap-throughs, a due chatter tail (one call suffices), and the next time event;
/// co-simulation: nothing is left (the step applied its events).
#[no_mangle]
pub unsafe extern "C" fn fmi3UpdateDiscreteStates(
    instance: fmi3Instance,
    discreteStatesNeedUpdate: *mut fmi3Boolean,
    terminateSimulation: *mut fmi3Boolean,
    nominalsOfContinuousStatesChanged: *mut fmi3Boolean,
    valuesOfContinuousStatesChanged: *mut fmi3Boolean,
    nextEventTimeDefined: *mut fmi3Boolean,
    nextEventTime: *mut fmi3Float64,
) -> fmi3Status {
    call(
        instance,
        "fmi3UpdateDiscreteStates",
        allowed::EVENT3,
        |inst| {
            let flags = [
                out(discreteStatesNeedUpdate, "discreteStatesNeedUpdate")?,
                out(terminateSimulation, "terminateSimulation")?,
                out(
                    nominalsOfContinuousStatesChanged,
                    "nominalsOfContinuousStatesChanged",
                )?,
                out(
                    valuesOfContinuousStatesChanged,
                    "valuesOfContinuousStatesChanged",
                )?,
                out(nextEventTimeDefined, "nextEventTimeDefined")?,
            ];
            let next = out(nextEventTime, "nextEventTime")?;
            let mut info = fmi2EventInfo::default();
            let status = inst.new_discrete_states(&mut info)?;
            let values = [
                info.newDiscreteStatesNeeded,
                info.terminateSimulation,
                info.nominalsOfContinuousStatesChanged,
                info.valuesOfContinuousStatesChanged,
                info.nextEventTimeDefined,
            ];
            for (f, v) in flags.into_iter().zip(values) {
                *f = v != 0;
            }
            *next = info.nextEventTime;
            Ok(status)
        },
    )
}

// ---- Model Exchange ----

/// Enters continuous-time mode.
#[no_mangle]
pub unsafe extern "C" fn fmi3EnterContinuousTimeMode(instance: fmi3Instance) -> fmi3Status {
    call(
        instance,
        "fmi3EnterContinuousTimeMode",
        allowed::EVENT,
        Instance::enter_continuous_time_mode,
    )
}

/// After an accepted integrator step: `*enterEventMode` is true when the states have moved
/// where event mode must act (see `fmu/README.md`); `*terminateSimulation` is always false.
#[no_mangle]
pub unsafe extern "C" fn fmi3CompletedIntegratorStep(
    instance: fmi3Instance,
    _noSetFMUStatePriorToCurrentPoint: fmi3Boolean,
    enterEventMode: *mut fmi3Boolean,
    terminateSimulation: *mut fmi3Boolean,
) -> fmi3Status {
    call(
        instance,
        "fmi3CompletedIntegratorStep",
        allowed::CONTINUOUS,
        |inst| {
            let enter = out(enterEventMode, "enterEventMode")?;
            let terminate = out(terminateSimulation, "terminateSimulation")?;
            *enter = inst.completed_integrator_step()?;
            *terminate = false;
            Ok(fmi3OK)
        },
    )
}

/// Sets the time (s): finite, not before the last event mode.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetTime(instance: fmi3Instance, time: fmi3Float64) -> fmi3Status {
    call(instance, "fmi3SetTime", allowed::SET_TIME, |inst| {
        inst.set_time(time)
    })
}

/// Sets the continuous states `x` (m), `v` (m/s); `nContinuousStates` must be 2.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetContinuousStates(
    instance: fmi3Instance,
    continuousStates: *const fmi3Float64,
    nContinuousStates: usize,
) -> fmi3Status {
    call(
        instance,
        "fmi3SetContinuousStates",
        allowed::CONTINUOUS,
        |inst| {
            inst.set_continuous_states(array(
                continuousStates,
                nContinuousStates,
                "continuousStates",
            )?)
        },
    )
}

/// Derivatives `der_x` (m/s), `der_v` (m/s²) of the continuous states; `nContinuousStates`
/// must be 2.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetContinuousStateDerivatives(
    instance: fmi3Instance,
    derivatives: *mut fmi3Float64,
    nContinuousStates: usize,
) -> fmi3Status {
    call(
        instance,
        "fmi3GetContinuousStateDerivatives",
        allowed::ME_GET,
        |inst| {
            let d = inst.derivatives(nContinuousStates);
            write_array(derivatives, nContinuousStates, "derivatives", d)
        },
    )
}

/// Event indicators `contact_indicator` and `barrier_indicator` (see the model description);
/// `nEventIndicators` must be 2.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetEventIndicators(
    instance: fmi3Instance,
    eventIndicators: *mut fmi3Float64,
    nEventIndicators: usize,
) -> fmi3Status {
    call(
        instance,
        "fmi3GetEventIndicators",
        allowed::ME_GET,
        |inst| {
            let z = inst.event_indicators(nEventIndicators);
            write_array(eventIndicators, nEventIndicators, "eventIndicators", z)
        },
    )
}

/// The continuous states `x` (m), `v` (m/s); `nContinuousStates` must be 2.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetContinuousStates(
    instance: fmi3Instance,
    continuousStates: *mut fmi3Float64,
    nContinuousStates: usize,
) -> fmi3Status {
    call(
        instance,
        "fmi3GetContinuousStates",
        allowed::ME_GET,
        |inst| {
            let s = inst.continuous_states(nContinuousStates);
            write_array(continuousStates, nContinuousStates, "continuousStates", s)
        },
    )
}

/// Nominal magnitudes of the continuous states: `delta_x` (m), `omega0*delta_x` (m/s).
#[no_mangle]
pub unsafe extern "C" fn fmi3GetNominalsOfContinuousStates(
    instance: fmi3Instance,
    nominals: *mut fmi3Float64,
    nContinuousStates: usize,
) -> fmi3Status {
    call(
        instance,
        "fmi3GetNominalsOfContinuousStates",
        allowed::NOMINALS,
        |inst| {
            let n = inst.nominals(nContinuousStates);
            write_array(nominals, nContinuousStates, "nominals", n)
        },
    )
}

/// `*nEventIndicators` = 2.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetNumberOfEventIndicators(
    instance: fmi3Instance,
    nEventIndicators: *mut usize,
) -> fmi3Status {
    call(
        instance,
        "fmi3GetNumberOfEventIndicators",
        allowed::COUNTS,
        |_| {
            *out(nEventIndicators, "nEventIndicators")? = EVENT_INDICATORS.len();
            Ok(fmi3OK)
        },
    )
}

/// `*nContinuousStates` = 2.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetNumberOfContinuousStates(
    instance: fmi3Instance,
    nContinuousStates: *mut usize,
) -> fmi3Status {
    call(
        instance,
        "fmi3GetNumberOfContinuousStates",
        allowed::COUNTS,
        |_| {
            *out(nContinuousStates, "nContinuousStates")? = STATES.len();
            Ok(fmi3OK)
        },
    )
}

// ---- co-simulation ----

/// Leaves event mode for step mode.
#[no_mangle]
pub unsafe extern "C" fn fmi3EnterStepMode(instance: fmi3Instance) -> fmi3Status {
    call(
        instance,
        "fmi3EnterStepMode",
        allowed::ENTER_STEP,
        Instance::enter_step_mode,
    )
}

/// First time derivatives (SI) of `x`, `v`, `z`, `zdot`.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetOutputDerivatives(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    orders: *const fmi3Int32,
    values: *mut fmi3Float64,
    nValues: usize,
) -> fmi3Status {
    call(
        instance,
        "fmi3GetOutputDerivatives",
        allowed::GET_DERIVATIVES,
        |inst| {
            scalars(nValueReferences, nValues)?;
            let vrs = array(valueReferences, nValueReferences, "valueReferences")?;
            let orders = array(orders, nValueReferences, "orders")?;
            let dst = array_mut(values, nValueReferences, "values")?;
            dst.copy_from_slice(&inst.output_derivatives(vrs, orders)?);
            Ok(fmi3OK)
        },
    )
}

/// Integrates from `currentCommunicationPoint` to `currentCommunicationPoint +
/// communicationStepSize` (s), locating every event inside; with `earlyReturnAllowed` it stops
/// at the first event (see the module documentation). `*lastSuccessfulTime` is where the FMU
/// is after the call (the step's end, the event, or where a `fmi3Discard` stopped it).
#[no_mangle]
pub unsafe extern "C" fn fmi3DoStep(
    instance: fmi3Instance,
    currentCommunicationPoint: fmi3Float64,
    communicationStepSize: fmi3Float64,
    _noSetFMUStatePriorToCurrentPoint: fmi3Boolean,
    eventHandlingNeeded: *mut fmi3Boolean,
    terminateSimulation: *mut fmi3Boolean,
    earlyReturn: *mut fmi3Boolean,
    lastSuccessfulTime: *mut fmi3Float64,
) -> fmi3Status {
    call(instance, "fmi3DoStep", allowed::STEP, |inst| {
        let handling = out(eventHandlingNeeded, "eventHandlingNeeded")?;
        let terminate = out(terminateSimulation, "terminateSimulation")?;
        let early = out(earlyReturn, "earlyReturn")?;
        let last = out(lastSuccessfulTime, "lastSuccessfulTime")?;
        let t_end = currentCommunicationPoint + communicationStepSize;
        let status = inst.do_step(currentCommunicationPoint, communicationStepSize)?;
        let (reached, stopped) = (inst.last_successful_time(), inst.stopped_at_event());
        *last = reached;
        *early = stopped && reached < t_end;
        *handling = stopped && inst.api.event_mode();
        *terminate = inst.terminated();
        Ok(status)
    })
}

/// Not provided: this FMU has no scheduled execution interface.
#[no_mangle]
pub unsafe extern "C" fn fmi3ActivateModelPartition(
    instance: fmi3Instance,
    _clockReference: fmi3ValueReference,
    _activationTime: fmi3Float64,
) -> fmi3Status {
    not_provided(
        instance,
        "fmi3ActivateModelPartition",
        "this FMU provides Model Exchange and Co-Simulation only",
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::exports2::instance;

    #[test]
    fn instances_of_one_version_are_refused_by_the_other() {
        use crate::exports2::{fmi2DoStep, fmi2GetFMUstate};
        let name = c"t";
        let token = CString::new(GUID).unwrap();
        let c = unsafe {
            fmi3InstantiateCoSimulation(
                name.as_ptr(),
                token.as_ptr(),
                ptr::null(),
                false,
                false,
                true,
                true,
                ptr::null(),
                0,
                ptr::null_mut(),
                None,
                None,
            )
        };
        assert!(!c.is_null());
        // SAFETY: `c` is the live instance made above.
        assert!(unsafe { instance(c) }.is_some());
        let mut snap: fmi3FMUState = ptr::null_mut();
        assert_eq!(unsafe { fmi2GetFMUstate(c, &mut snap) }, fmi3Error);
        assert!(snap.is_null());
        assert_eq!(unsafe { fmi3GetFMUState(c, &mut snap) }, fmi3OK);
        assert!(!snap.is_null());
        assert_eq!(unsafe { fmi2DoStep(c, 0.0, 1.0, 0) }, fmi3Error);
        unsafe { fmi3FreeInstance(c) };
    }
}
