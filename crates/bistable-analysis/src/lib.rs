//! The paper's analyses of the bistable impact oscillator, on top of `bistable-core`'s model
//! and integrator: cycle recording and period detection, classification sweeps over point
//! lists, bifurcation data, periodic orbits by shooting with natural and pseudo-arclength
//! continuation, energy maps, spectra and the velocity thresholds of Eq. 16–18.
//!
//! Everything is nondimensional as in the core (time `τ = ω0 t`, lengths in units of the well
//! distance `Δx`, velocities in `ω0 Δx`, energies in `k0 Δx²`); phases are in shaker cycles.
//!
//! The crate does no I/O: no files, no printing, no progress bars. Work spread over threads
//! ([`parallel`]) hands each result to a callback on the calling thread as it completes; the
//! callback is where a caller shows progress or writes results, and it cancels the run by
//! returning an error. Multi-stage analyses report [`Progress`] the same way.
//!
//! ```
//! use bistable_analysis::{cycles, period, Model};
//! use std::num::NonZeroU32;
//! use bistable_core::{Params, Sinusoid, SolverOptions};
//! let model = Model::new(Params::paper(), Sinusoid::new(1.75, 0.07).unwrap(), SolverOptions::default());
//! // 600 shaker periods of transient, then 8 recorded with 64 samples each.
//! let c = cycles::steady_cycles(&model, 600, 8, NonZeroU32::new(64).unwrap()).unwrap();
//! assert_eq!(period::detect_period(&c.sections, 16, 1e-7), Some(1));
//! assert_eq!(period::distinct(&c.max_x, 1e-9), 1); // the same maximum every cycle
//! ```
#![warn(missing_docs)]

pub mod arclength;
pub mod basins;
pub mod bifurcations;
pub mod branches;
pub mod codim2;
pub mod continuation;
pub mod cycles;
pub mod diagram;
pub mod energy;
pub mod ensemble;
pub mod event_log;
pub mod grazing;
pub mod grid;
pub mod model;
mod numerics;
pub mod orbit;
pub mod parallel;
pub mod period;
pub mod progress;
pub mod record;
pub mod recurrence;
pub mod schedule;
pub mod seeds;
pub mod sensitivity;
pub mod spectrum;
pub mod sweep;
pub mod thresholds;
pub mod twoparam;

pub use model::Model;
pub use parallel::Threads;
pub use progress::{Progress, Stage};
