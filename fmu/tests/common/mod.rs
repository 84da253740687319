//! What the Rust tests of the FMU share: an FMI 2.0 instance with a logger that records every
//! message.

use std::ffi::{c_char, c_void, CStr, CString};
use std::sync::Mutex;

use bistable_impact::exports2::fmi2Instantiate;
use bistable_impact::fmi2::*;

/// Messages logged by one instance: `(status, category, message)`.
pub type Log = Mutex<Vec<(fmi2Status, String, String)>>;

/// A logger with the fixed arguments of the variadic FMI logger plus the one `%s` argument.
/// x86-64 and AArch64 Linux pass these in the same registers whether or not the callee is
/// variadic; the C host tests a real variadic logger.
unsafe extern "C" fn record(
    env: fmi2ComponentEnvironment,
    _name: fmi2String,
    status: fmi2Status,
    category: fmi2String,
    format: fmi2String,
    msg: *const c_char,
) {
    let log = &*(env as *const Log);
    assert_eq!(CStr::from_ptr(format).to_str().unwrap(), "%s");
    let text = |p| CStr::from_ptr(p).to_string_lossy().into_owned();
    log.lock()
        .unwrap()
        .push((status, text(category), text(msg)));
}

/// `fmi2Instantiate` (name "test", visible, logging on) with a recording logger: the component
/// (NULL when refused), its log and the callbacks, which must outlive it.
pub fn instantiate(
    guid: &str,
    kind: fmi2Type,
) -> (fmi2Component, Box<Log>, Box<fmi2CallbackFunctions>) {
    let log: Box<Log> = Box::default();
    // SAFETY: the logger's leading arguments match; see `record`.
    let logger: fmi2CallbackLogger = unsafe {
        std::mem::transmute::<*const c_void, fmi2CallbackLogger>(record as *const c_void)
    };
    let callbacks = Box::new(fmi2CallbackFunctions {
        logger,
        allocateMemory: None,
        freeMemory: None,
        stepFinished: None,
        componentEnvironment: &*log as *const Log as *mut c_void,
    });
    let name = CString::new("test").unwrap();
    let guid = CString::new(guid).unwrap();
    let c = unsafe {
        fmi2Instantiate(
            name.as_ptr(),
            kind,
            guid.as_ptr(),
            std::ptr::null(),
            &*callbacks,
            fmi2False,
            fmi2True,
        )
    };
    (c, log, callbacks)
}
