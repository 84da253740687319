//! The checked-in C header `fmu/include/bistable_impact.h` is what cbindgen makes from the
//! sources now (set `BISTABLE_UPDATE_HEADER=1` to rewrite it).

use std::path::Path;

#[test]
fn header_is_in_sync_with_the_sources() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let config = cbindgen::Config::from_file(dir.join("cbindgen.toml")).expect("cbindgen.toml");
    let mut fresh = Vec::new();
    cbindgen::Builder::new()
        .with_crate(dir)
        .with_config(config)
        .generate()
        .expect("cbindgen")
        .write(&mut fresh);
    let path = dir.join("include/bistable_impact.h");
    if std::env::var_os("BISTABLE_UPDATE_HEADER").is_some() {
        std::fs::write(&path, &fresh).expect("write header");
    }
    let text = String::from_utf8(fresh).unwrap();
    for f in [
        "fmi2Instantiate",
        "fmi2DoStep",
        "fmi2DeSerializeFMUstate",
        "fmi2CallbackFunctions",
        "fmi2NewDiscreteStates",
        "fmi2GetEventIndicators",
        "fmi2EventInfo",
    ] {
        assert!(text.contains(f), "{f} missing from the generated header");
    }
    assert_eq!(
        text.matches("\nfmi2Status fmi2").count() + 4,
        44,
        "44 functions expected"
    );
    let current = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        current == text,
        "{} is out of date: run BISTABLE_UPDATE_HEADER=1 cargo test -p bistable-fmu --test header",
        path.display()
    );
}
