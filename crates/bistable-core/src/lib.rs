//! Core of bistable-impact: a mass on a bistable spring driven only by impacts with a
//! sinusoidally vibrating plate (Nonlinear Dynamics 2022, doi 10.1007/s11071-022-07793-w).
//!
//! Everything here is nondimensional (`model.md` Sec. 2): time `τ = ω0 t`, lengths in units of
//! the well distance `Δx`, energies in `k0 Δx²`. The crate does no I/O.
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
