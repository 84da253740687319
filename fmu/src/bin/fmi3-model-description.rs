//! Prints the FMI 3.0 model description generated from `modelDescription.xml` (used by
//! `make fmu` to package `bistable_impact_fmi3.fmu`).

fn main() {
    print!("{}", bistable_impact::md::FMI3_MODEL_DESCRIPTION);
}
