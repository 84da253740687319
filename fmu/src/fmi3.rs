//! FMI 3.0 platform types, status codes and callback types, ABI-compatible with the standard's
//! `fmi3PlatformTypes.h` and `fmi3FunctionTypes.h`. Enumerations are plain `int` typedefs so that
//! an out-of-range value from a host is a checked integer, never an invalid Rust enum; the
//! status codes have the values of FMI 2.0's (`fmi3OK` 0 … `fmi3Fatal` 4), so the instance's
//! outcomes serve both versions.
#![allow(non_camel_case_types, non_upper_case_globals, non_snake_case)]

use std::ffi::{c_char, c_int, c_void};

/// Opaque instance handle.
pub type fmi3Instance = *mut c_void;
/// Host data passed back to the callbacks.
pub type fmi3InstanceEnvironment = *mut c_void;
/// Opaque FMU state handle.
pub type fmi3FMUState = *mut c_void;
/// Value reference of a variable.
pub type fmi3ValueReference = u32;
/// 32-bit float (the model has no such variable).
pub type fmi3Float32 = f32;
/// 64-bit float.
pub type fmi3Float64 = f64;
/// 8-bit signed integer (no such variable).
pub type fmi3Int8 = i8;
/// 8-bit unsigned integer (no such variable).
pub type fmi3UInt8 = u8;
/// 16-bit signed integer (no such variable).
pub type fmi3Int16 = i16;
/// 16-bit unsigned integer (no such variable).
pub type fmi3UInt16 = u16;
/// 32-bit signed integer.
pub type fmi3Int32 = i32;
/// 32-bit unsigned integer (no such variable).
pub type fmi3UInt32 = u32;
/// 64-bit signed integer (Enumerations are read and written as Int64).
pub type fmi3Int64 = i64;
/// 64-bit unsigned integer (no such variable).
pub type fmi3UInt64 = u64;
/// C99 `bool`.
pub type fmi3Boolean = bool;
/// Character.
pub type fmi3Char = c_char;
/// NUL-terminated UTF-8 string.
pub type fmi3String = *const fmi3Char;
/// Byte.
pub type fmi3Byte = u8;
/// Binary value (length given separately).
pub type fmi3Binary = *const fmi3Byte;
/// Clock activation (the model has no clocks).
pub type fmi3Clock = bool;

/// Status returned by every function.
pub type fmi3Status = c_int;
/// All well.
pub const fmi3OK: fmi3Status = 0;
/// Not quite right, computation continues.
pub const fmi3Warning: fmi3Status = 1;
/// The step could not be completed.
pub const fmi3Discard: fmi3Status = 2;
/// The call was refused or failed; the instance is unchanged unless the log says otherwise.
pub const fmi3Error: fmi3Status = 3;
/// Irreparable error.
pub const fmi3Fatal: fmi3Status = 4;

/// Kind of a dependency (`fmi3GetVariableDependencies`, not provided).
pub type fmi3DependencyKind = c_int;
/// Whether a clock interval is known (no clocks).
pub type fmi3IntervalQualifier = c_int;

/// Logger: `(env, status, category, message)`.
pub type fmi3LogMessageCallback =
    Option<unsafe extern "C" fn(fmi3InstanceEnvironment, fmi3Status, fmi3String, fmi3String)>;
/// Intermediate update (not used: `providesIntermediateUpdate="false"`).
pub type fmi3IntermediateUpdateCallback = Option<
    unsafe extern "C" fn(
        fmi3InstanceEnvironment,
        fmi3Float64,
        fmi3Boolean,
        fmi3Boolean,
        fmi3Boolean,
        fmi3Boolean,
        *mut fmi3Boolean,
        *mut fmi3Float64,
    ),
>;
/// Clock update of scheduled execution (not provided).
pub type fmi3ClockUpdateCallback = Option<unsafe extern "C" fn(fmi3InstanceEnvironment)>;
/// Preemption lock of scheduled execution (not provided).
pub type fmi3LockPreemptionCallback = Option<unsafe extern "C" fn()>;
/// Preemption unlock of scheduled execution (not provided).
pub type fmi3UnlockPreemptionCallback = Option<unsafe extern "C" fn()>;
