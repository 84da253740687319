//! A refused `BISTABLE_SIMD` (read once per process, so this file is a process of its own with
//! one test) makes `fmi2Instantiate` return NULL with the reason logged, not a panic later.

use std::ffi::{c_char, c_void, CStr, CString};
use std::sync::Mutex;

use bistable_impact::exports::*;
use bistable_impact::fmi2::*;
use bistable_impact::md::GUID;

type Log = Mutex<Vec<(fmi2Status, String)>>;

/// The fixed arguments of the variadic FMI logger plus its one `%s` argument (as in api.rs).
unsafe extern "C" fn record(
    env: fmi2ComponentEnvironment,
    _name: fmi2String,
    status: fmi2Status,
    _category: fmi2String,
    _format: fmi2String,
    msg: *const c_char,
) {
    let log = &*(env as *const Log);
    let text = CStr::from_ptr(msg).to_string_lossy().into_owned();
    log.lock().unwrap().push((status, text));
}

#[test]
fn an_unknown_simd_path_refuses_instantiation_with_the_reason() {
    std::env::set_var("BISTABLE_SIMD", "avx9000");
    let log: Box<Log> = Box::default();
    // SAFETY: the logger's leading arguments match; see `record`.
    let logger: fmi2CallbackLogger = unsafe {
        std::mem::transmute::<*const c_void, fmi2CallbackLogger>(record as *const c_void)
    };
    let callbacks = fmi2CallbackFunctions {
        logger,
        allocateMemory: None,
        freeMemory: None,
        stepFinished: None,
        componentEnvironment: &*log as *const Log as *mut c_void,
    };
    let name = CString::new("simd").unwrap();
    let guid = CString::new(GUID).unwrap();
    let c = unsafe {
        fmi2Instantiate(
            name.as_ptr(),
            fmi2CoSimulation,
            guid.as_ptr(),
            std::ptr::null(),
            &callbacks,
            fmi2False,
            fmi2True,
        )
    };
    assert!(c.is_null());
    let log = log.lock().unwrap();
    assert!(
        log.iter()
            .any(|(s, m)| *s == fmi2Error
                && m.contains("BISTABLE_SIMD=\"avx9000\" is not a SIMD path")),
        "{log:?}"
    );
}
