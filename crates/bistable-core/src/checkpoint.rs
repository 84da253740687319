//! A complete, pointer-free copy of a simulator's state, for rollback and for saving a run to
//! be continued elsewhere (the FMU serialises it). Restoring recomputes the current step from
//! the saved step start, so a restored run continues bit for bit like the original.

use crate::events::{ContactMode, Impact, StickCause, Well};
use crate::params::{ChatterRule, ParamError, Params, SolverOptions};
use crate::shaker::{PlateMotion, PolyPiece, Sinusoid};
use crate::simulator::Stats;
use crate::time::Instant;

/// Plate motion as plain values.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PlateRecord {
    /// See [`Sinusoid`]: `omega`, `velocity`, origin `(hi, lo)`, `phase0`, `offset`.
    Sinusoid {
        /// `Ω`.
        omega: f64,
        /// `V`.
        velocity: f64,
        /// Origin instant as `(hi, lo)`.
        origin: (f64, f64),
        /// Phase at the origin (radians).
        phase0: f64,
        /// Mean position.
        offset: f64,
    },
    /// See [`PolyPiece`].
    Poly {
        /// Start `(hi, lo)`.
        start: (f64, f64),
        /// End `(hi, lo)`.
        end: (f64, f64),
        /// Coefficients.
        coeffs: [f64; crate::shaker::MAX_POLY_DEGREE + 1],
    },
}

/// Every value a [`crate::Simulator`] needs to go on exactly as it would have.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Checkpoint {
    /// `ζ`.
    pub zeta: f64,
    /// `e`.
    pub restitution: f64,
    /// Tolerance.
    pub tol: f64,
    /// Taylor order in use.
    pub order: usize,
    /// Chatter rule.
    pub chatter: ChatterRule,
    /// Zeno guard limit.
    pub max_chatter_impacts: u32,
    /// Plate motion.
    pub plate: PlateRecord,
    /// Start of the current step `(hi, lo)`.
    pub t0: (f64, f64),
    /// Contact mode at `t0`.
    pub mode: ContactMode,
    /// Gap at `t0`.
    pub u0: f64,
    /// Gap rate at `t0`.
    pub w0: f64,
    /// Leading event-function coefficients known to vanish at `t0` (0..=3).
    pub pinned: u8,
    /// Whether `t0` is on the barrier.
    pub on_barrier: bool,
    /// Current well.
    pub well: Well,
    /// Observation time `(hi, lo)`.
    pub now: (f64, f64),
    /// Last impact.
    pub last_impact: Option<Impact>,
    /// Instant of the last impact `(hi, lo)`.
    pub last_impact_t: Option<(f64, f64)>,
    /// Zeno guard count.
    pub short_flights: u32,
    /// Work counters.
    pub stats: Stats,
    /// A pending ride on the plate ending in sticking (the tail of a chatter sequence): its
    /// length from `t0` and cause.
    pub tail: Option<(f64, StickCause)>,
    /// A free step from `t0` that later plate pieces continued (see
    /// [`crate::Simulator::keep_flight`]).
    pub kept: Option<KeptFlight>,
}

/// A free step kept across plate pieces: what rebuilds its series (which does not depend on
/// the plate) and its extent.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KeptFlight {
    /// Mass position at the step's start.
    pub x0: f64,
    /// Mass velocity at the step's start.
    pub v0: f64,
    /// How far from the start the series holds (time units).
    pub reach: f64,
    /// `(s, x(s), x'(s))` where the series was last evaluated for the bound that decides
    /// whether the next piece continues the step (part of the state: that decision depends
    /// on it).
    pub anchor: Option<(f64, f64, f64)>,
}

fn instant(name: &'static str, (hi, lo): (f64, f64)) -> Result<Instant, ParamError> {
    Instant::from_parts(hi, lo).ok_or(ParamError {
        name,
        value: hi,
        rule: "must be a finite two-part instant",
    })
}

impl PlateRecord {
    pub(crate) fn of(p: &PlateMotion) -> Self {
        match p {
            PlateMotion::Sinusoid(s) => {
                let (o, phase0, offset) = s.origin();
                PlateRecord::Sinusoid {
                    omega: s.omega(),
                    velocity: s.velocity(),
                    origin: o.parts(),
                    phase0,
                    offset,
                }
            }
            PlateMotion::Poly(q) => PlateRecord::Poly {
                start: q.start().parts(),
                end: q.end().parts(),
                coeffs: q.coeffs(),
            },
        }
    }

    pub(crate) fn to_motion(self) -> Result<PlateMotion, ParamError> {
        Ok(match self {
            PlateRecord::Sinusoid {
                omega,
                velocity,
                origin,
                phase0,
                offset,
            } => Sinusoid::new(omega, velocity)?
                .with_origin(instant("origin", origin)?, phase0, offset)?
                .into(),
            PlateRecord::Poly { start, end, coeffs } => PolyPiece::new(
                instant("plate_start", start)?,
                instant("plate_end", end)?,
                &coeffs,
            )?
            .into(),
        })
    }
}

impl Checkpoint {
    /// Rebuilds and checks the configuration parts.
    pub(crate) fn config(&self) -> Result<(Params, SolverOptions, PlateMotion), ParamError> {
        let params = Params::new(self.zeta, self.restitution)?;
        let opts = SolverOptions::new(self.tol, self.chatter)?
            .with_order(self.order)?
            .with_max_chatter_impacts(self.max_chatter_impacts)?;
        Ok((params, opts, self.plate.to_motion()?))
    }

    /// Checks the dynamic parts and returns the three instants `(t0, now, last_impact_t)`.
    pub(crate) fn instants(&self) -> Result<(Instant, Instant, Option<Instant>), ParamError> {
        let t0 = instant("t0", self.t0)?;
        let now = instant("now", self.now)?;
        let last = self
            .last_impact_t
            .map(|p| instant("last_impact_t", p))
            .transpose()?;
        let bad = |name, value, rule| Err(ParamError { name, value, rule });
        if now < t0 {
            return bad("now", now.to_f64(), "must not be before the step start");
        }
        if !(self.u0.is_finite() && self.u0 >= 0.0) {
            return bad("u0", self.u0, "must be finite and >= 0");
        }
        if !self.w0.is_finite() {
            return bad("w0", self.w0, "must be finite");
        }
        if self.pinned > 3 {
            return bad("pinned", f64::from(self.pinned), "must be in [0, 3]");
        }
        if self.kept.is_some() && (self.tail.is_some() || self.mode == ContactMode::Sticking) {
            return bad("kept", 0.0, "a kept flight is a free flight without a tail");
        }
        if self.mode == ContactMode::Sticking && self.tail.is_some() {
            return bad("tail", 0.0, "no chatter tail while sticking");
        }
        if let Some((len, _)) = self.tail {
            if !(len.is_finite() && len >= 0.0) || t0 + len < now {
                return bad(
                    "tail",
                    len,
                    "must be finite, >= 0 and reach the current time",
                );
            }
        }
        if let Some(i) = self.last_impact {
            let vals = [i.t, i.x, i.v_before, i.v_after, i.zdot, i.delta_k];
            if vals.iter().any(|v| !v.is_finite()) {
                return bad("last_impact", i.t, "must hold finite values");
            }
        }
        Ok((t0, now, last))
    }
}
