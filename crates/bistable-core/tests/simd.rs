//! The SIMD path in use is the one `BISTABLE_SIMD` asks for (the CPU's widest when unset or
//! `auto`). `make test-simd` runs this test with `--nocapture` beside the lanes' bit-identity
//! tests, so that its line names the path they ran on in the log.

use bistable_core::{simd, SimdPath};

#[test]
fn simd_path_is_the_one_asked_for() {
    let asked = std::env::var(simd::ENV).unwrap_or_default();
    let path = simd::check().unwrap_or_else(|e| panic!("{e}"));
    eprintln!(
        "SIMD path in use: {path} ({}={asked:?}, the CPU's widest: {})",
        simd::ENV,
        SimdPath::detected()
    );
    assert_eq!(simd::path(), path);
    match asked.as_str() {
        "" | "auto" => assert_eq!(path, SimdPath::detected()),
        name => assert_eq!(path.name(), name),
    }
}
