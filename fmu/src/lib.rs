//! FMI 2.0 Model Exchange and co-simulation FMU `bistable_impact`: a thin C-ABI adapter over
//! `bistable-core`.
//!
//! The shared library exports the 44 common, co-simulation and Model Exchange `fmi2*` functions (see
//! `exports2.rs` and the generated header `include/bistable_impact.h`). Variables, value
//! references, start values and ranges come from the top-level `modelDescription.xml` (through
//! `build.rs`). Every export catches panics and checks its arguments; see `fmu/README.md`.

pub mod ahead;
pub mod exports2;
pub mod exports3;
pub mod fmi2;
pub mod fmi3;
pub mod instance;
pub mod md;
pub mod me;
pub mod model;
pub mod num;
pub mod state;
