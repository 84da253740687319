//! A refused `BISTABLE_SIMD` (read once per process, so this file is a process of its own with
//! one test) makes `fmi2Instantiate` return NULL with the reason logged, not a panic later.

mod common;

use bistable_impact::fmi2::*;
use bistable_impact::md::GUID;

#[test]
fn an_unknown_simd_path_refuses_instantiation_with_the_reason() {
    std::env::set_var("BISTABLE_SIMD", "avx9000");
    let (c, log, _callbacks) = common::instantiate(GUID, fmi2CoSimulation);
    assert!(c.is_null());
    let log = log.lock().unwrap();
    assert!(
        log.iter().any(|(s, _, m)| *s == fmi2Error
            && m.contains("BISTABLE_SIMD=\"avx9000\" is not a SIMD path")),
        "{log:?}"
    );
}
