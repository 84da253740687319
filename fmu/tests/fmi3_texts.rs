//! The FMI 3.0 model description's texts are FMI 3.0's: generated from `modelDescription.xml`
//! with the per-version texts of `fmu/build_fmi3.rs` (`FMI3_TEXTS`), it names no FMI 2.0
//! function and promises no input derivatives, while the FMI 2.0 file keeps its own texts.

use bistable_impact::md::FMI3_MODEL_DESCRIPTION as FMI3;

/// The `description` of the element named `name` in `xml`.
fn description<'a>(xml: &'a str, name: &str) -> &'a str {
    let at = xml
        .find(&format!("name=\"{name}\""))
        .unwrap_or_else(|| panic!("{name} not found"));
    let rest = &xml[at..];
    let start = rest.find("description=\"").expect("a description") + "description=\"".len();
    &rest[start..start + rest[start..].find('"').expect("closing quote")]
}

#[test]
fn fmi3_texts_speak_of_fmi3() {
    let fmi2 = include_str!("../../modelDescription.xml");
    assert!(
        !FMI3.contains("fmi2"),
        "an FMI 2.0 function in the FMI 3.0 description"
    );
    for name in [
        "z_in",
        "zdot_in",
        "plate_reconstruction",
        "PlateReconstruction",
    ] {
        let (two, three) = (description(fmi2, name), description(FMI3, name));
        assert_ne!(two, three, "{name}: the same text in both versions");
        assert!(
            three.contains("FMI 3.0 has no input derivatives"),
            "{name}: {three}"
        );
    }
    assert!(description(fmi2, "z_in").contains("fmi2SetRealInputDerivatives"));
    assert_eq!(
        description(FMI3, "external"),
        "plate motion from the inputs z_in, zdot_in"
    );
    // Texts without FMI 2.0 matters are the same in both.
    for name in ["zeta", "x", "impact_count", "der_x"] {
        assert_eq!(description(fmi2, name), description(FMI3, name), "{name}");
    }
}
