//! The paper's analyses of the bistable impact oscillator, on top of `bistable-core`'s model
//! and integrator. Everything starts from a [`Model`] (parameters, plate sinusoid and solver
//! options at one shaker point `(Ω, V)`; [`grid`] spaces parameter values evenly). The entry
//! points, by question:
//!
//! - **What does the response do at `(Ω, V)`, over a map?** [`sweep`] classifies lists of
//!   points (the core's classification, with [`sensitivity`] repeats where rounding decides),
//!   many runs at once in SIMD lanes ([`ensemble`]); [`record`] is a classified point's record.
//! - **Which attractor does each start reach?** [`basins`] (grid of initial states, basin
//!   fractions, uncertainty exponent), with [`recurrence`] stopping starts early on attractors
//!   already found.
//! - **Which responses coexist across `(Ω, V)`, and how likely each is?** [`coexistence`]
//!   (attractors and basin fractions from a box of starts at every point, matched into
//!   branches across the grid).
//! - **Steady states along a parameter**: [`cycles`] (per-cycle maxima, impact phases, section
//!   points), [`period`] (periods and the period label), [`diagram`] (the bifurcation diagram
//!   of Fig. 6/8).
//! - **Periodic orbits**: [`orbit`] (shooting, Floquet multipliers), [`continuation`] of
//!   branches in Ω by natural ([`branches`]) or pseudo-arclength ([`arclength`]) continuation.
//! - **Bifurcation points on the branches**: [`bifurcations`] (fold, period doubling,
//!   Neimark–Sacker, grazing, sticking), [`grazing`] (grazing located by its smooth test
//!   functions and continued through); in `(Ω, V)`: [`twoparam`] (fold and period-doubling
//!   curves) and [`codim2`] (cusps, fold–flip, resonant grazing and crossings on them).
//! - **Other figures of the paper**: [`energy`] (energy change per impact), [`spectrum`],
//!   [`thresholds`] (Eq. 16–18), [`event_log`] (the simulator's events as tables).
//!
//! The root finders, Newton corrector and small linear solves the locators share are in one
//! private module (`numerics.rs`).
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
pub mod coexistence;
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
