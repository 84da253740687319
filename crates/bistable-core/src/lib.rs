//! Core of bistable-impact: a mass on a bistable spring driven only by impacts with a
//! sinusoidally vibrating plate (Nonlinear Dynamics 2022, doi 10.1007/s11071-022-07793-w).
//!
//! Everything here is nondimensional (`model.md` Sec. 2): time `τ = ω0 t`, lengths in units of
//! the well distance `Δx`, energies in `k0 Δx²`. The crate does no I/O.
//!
//! Where to start:
//!
//! - [`Params`] (`ζ`, `e`) and [`SolverOptions`] (tolerance, chatter rule), validated;
//!   [`Sinusoid`] and [`PlateMotion`] (the plate; also polynomial pieces from outside,
//!   [`sampled`] plates rebuilt from samples, [`ramp`]ed set-point changes).
//! - [`Simulator`]: the event-driven integrator (Taylor steps, every impact located as a
//!   polynomial root); it reports [`Event`]s (impacts, sticking, snap-throughs) to an
//!   [`Observer`], gives the [`State`] between events, and saves and restores itself as a
//!   [`Checkpoint`] ([`codec`] is its byte format).
//! - [`Batch`] and [`LaneRun`]: many trajectories at once in SIMD lanes, bit-identical to one at
//!   a time ([`simd`] selects or forces the instruction set).
//! - [`classify()`]: the response classes of the paper's map (Sec. 3.4, Fig. 9);
//!   [`shoot`]: periodic orbits by shooting, with Floquet multipliers.
//! - [`units`]: SI conversions (used by the FMU); [`potential`]: the bistable potential;
//!   [`audit`]: a check that no impact was missed.
//!
//! The analyses of the paper (maps, basins, bifurcations, continuation) are in
//! `bistable-analysis`; the CLI, Python package and FMU are thin front ends over both.
//!
//! ```
//! use bistable_core::{Params, Simulator, Sinusoid, SolverOptions, Event};
//! let plate = Sinusoid::new(1.75, 0.07).unwrap();
//! let mut sim = Simulator::new(Params::paper(), plate.into(), SolverOptions::default()).unwrap();
//! let events = sim.events_until(20.0).unwrap();
//! let Event::Impact(second) = events.iter().filter(|e| matches!(e, Event::Impact(_))).nth(1).unwrap()
//! else { unreachable!() };
//! assert!((second.phase.unwrap() - 0.0507).abs() < 5e-4);
//! ```
#![warn(missing_docs)]

pub mod audit;
pub mod batch;
mod chatter;
pub mod checkpoint;
pub mod classify;
pub mod codec;
pub mod events;
pub mod interrupt;
pub mod lane_run;
pub mod lanes;
pub mod law;
pub mod params;
pub mod potential;
pub mod ramp;
mod roots;
pub mod sampled;
pub mod shaker;
pub mod shooting;
pub mod simd;
pub mod simulator;
pub mod taylor;
pub mod time;
pub mod units;

pub use audit::GapAudit;
pub use batch::{Batch, JoinError, LaneObserver};
pub use checkpoint::{Checkpoint, KeptFlight, PlateRecord};
pub use classify::{
    classify, classify_from, largest_lyapunov, Classification, ClassifyOptions, ClassifyRun,
    ResponseClass, Tracking,
};
pub use events::{ContactMode, Event, Impact, StickCause, Well};
pub use lane_run::{drive, LaneRun};
pub use lanes::Width;
pub use params::{ChatterRule, ParamError, Params, SolverOptions};
pub use ramp::SetpointRamp;
pub use sampled::{PieceMemo, Sample, SampleHistory};
pub use shaker::{PlateMotion, PolyPiece, Sinusoid};
pub use shaker::{MAX_VELOCITY, OMEGA_RANGE};
pub use shooting::{shoot, PeriodicOrbit, ShootError, ShootOptions};
pub use simd::SimdPath;
pub use simulator::{
    Flights, Observer, SimError, Simulator, State, Stats, StepKey, StepView, FLIGHT_LANES,
};
pub use time::Instant;
