//! Periodic orbits by shooting (the core's Newton on the `p`-period stroboscopic map), with
//! what the analyses derive from them: per-cycle maxima, section points, Floquet exponent and
//! the `det M` consistency check.

use std::num::NonZeroU32;

use bistable_core::{PeriodicOrbit, ShootError, ShootOptions, SimError};

use crate::cycles::record_cycles;
use crate::Model;

/// Samples per shaker period for the orbits' per-cycle maxima.
const SAMPLES: NonZeroU32 = NonZeroU32::new(128).expect("128 > 0");
/// Two orbits are the same when a section point of one is this close to the other's fixed
/// point (max norm in `(x, x')`).
const SAME: f64 = 1e-6;
/// Relative distance of section points `d < p` periods apart below which a `p`-periodic orbit
/// has the smaller period `d`.
const MINIMAL_TOL: f64 = 1e-7;

/// A periodic orbit of minimal period `orbit.periods` with its per-cycle maxima and section
/// points.
#[derive(Debug, Clone)]
pub struct Orbit {
    /// The shooting result.
    pub orbit: PeriodicOrbit,
    /// Largest `x` in each of its shaker cycles, ascending (units of `Δx`).
    pub cycle_max: Vec<f64>,
    /// Its section points `(x, x')` at plate phase 0, one per shaker cycle, the fixed point
    /// first.
    pub sections: Vec<(f64, f64)>,
}

impl Orbit {
    /// The fixed point `(x, x')` at plate phase 0.
    pub fn point(&self) -> (f64, f64) {
        (self.orbit.x0, self.orbit.v0)
    }

    /// Largest modulus of the Floquet multipliers.
    pub fn abs_multiplier(&self) -> f64 {
        abs_multiplier(&self.orbit)
    }

    /// Whether `other` is the same orbit (same period, a section point of this one at the
    /// other's fixed point).
    pub fn same_as(&self, other: &Orbit) -> bool {
        self.orbit.periods == other.orbit.periods
            && self
                .sections
                .iter()
                .any(|&(x, v)| (x - other.orbit.x0).abs().max((v - other.orbit.v0).abs()) < SAME)
    }
}

/// Largest modulus of an orbit's Floquet multipliers (they are sorted largest first).
pub fn abs_multiplier(orbit: &PeriodicOrbit) -> f64 {
    let (re, im) = orbit.multipliers[0];
    re.hypot(im)
}

/// `ln|λ|max / (p·T)`: the growth rate of perturbations per unit of `τ`, with `T = 2π/Ω` the
/// `shaker_period` of the orbit's model.
pub fn floquet_exponent(orbit: &PeriodicOrbit, shaker_period: f64) -> f64 {
    abs_multiplier(orbit).ln() / (f64::from(orbit.periods) * shaker_period)
}

/// `det M` of the monodromy matrix.
pub fn det_monodromy(orbit: &PeriodicOrbit) -> f64 {
    let m = orbit.monodromy;
    m[0][0] * m[1][1] - m[0][1] * m[1][0]
}

/// `|det M − det_identity| / det_identity`, the consistency check of the variational equations
/// (`det_identity = e^(2·impacts)·exp(−2ζpT)`); `None` when the orbit sticks (then `M = 0`).
pub fn det_relative_error(orbit: &PeriodicOrbit) -> Option<f64> {
    let det = det_monodromy(orbit);
    (!orbit.sticks).then(|| ((det - orbit.det_identity) / orbit.det_identity).abs())
}

/// Everything reported about one orbit found by shooting (`bistable orbit`, `orbit()` of the
/// Python package).
#[derive(Debug, Clone)]
pub struct Summary {
    /// The shooting result (fixed point, multipliers sorted largest first, monodromy, counts).
    pub orbit: PeriodicOrbit,
    /// Largest modulus of the Floquet multipliers.
    pub max_abs_multiplier: f64,
    /// `ln|λ|max/(p·T)`, per unit of `τ`.
    pub floquet_exponent: f64,
    /// Largest `x` in each cycle, ascending (empty when the minimal period is smaller).
    pub cycle_max: Vec<f64>,
    /// `det M`.
    pub det_monodromy: f64,
    /// `|det M − det_identity| / det_identity`; `None` when the orbit sticks.
    pub det_relative_error: Option<f64>,
    /// The initial guess `(x, x')`.
    pub guess: (f64, f64),
    /// Distance from the guess to the fixed point (Euclidean in `(x, x')`).
    pub distance_to_guess: f64,
}

/// What [`Summary`] reports about `orbit`, found at `model` by [`shoot`] from `guess`.
pub fn summarise(
    model: &Model,
    orbit: PeriodicOrbit,
    guess: (f64, f64),
) -> Result<Summary, SimError> {
    let cycle_max = analyse(model, orbit)?
        .map(|o| o.cycle_max)
        .unwrap_or_default();
    Ok(Summary {
        orbit,
        max_abs_multiplier: abs_multiplier(&orbit),
        floquet_exponent: floquet_exponent(&orbit, model.shaker_period()),
        cycle_max,
        det_monodromy: det_monodromy(&orbit),
        det_relative_error: det_relative_error(&orbit),
        guess,
        distance_to_guess: (orbit.x0 - guess.0).hypot(orbit.v0 - guess.1),
    })
}

/// Shoots the `period`-periodic orbit (`1..=64` shaker periods) at `model` from `guess`
/// `(x, x')` at plate phase 0, with the core's default Newton settings.
pub fn shoot(model: &Model, period: u32, guess: (f64, f64)) -> Result<PeriodicOrbit, ShootError> {
    let so = ShootOptions::default();
    bistable_core::shoot(model.params, model.shaker, model.opts, period, guess, so)
}

/// Shoots the `period`-periodic orbit at `model` from `guess` `(x, x')` at plate phase 0;
/// `None` when Newton fails, the orbit has a smaller period (it is then found as that period's
/// orbit) or no impacts (the equilibria at the barrier and in well 2, which are not impact
/// orbits).
pub fn solve(model: &Model, period: u32, guess: (f64, f64)) -> Option<Orbit> {
    let orbit = shoot(model, period, guess).ok()?;
    if orbit.impacts == 0 {
        return None;
    }
    analyse(model, orbit).ok().flatten()
}

/// Per-cycle maxima and section points of `orbit` (found at `model`); `None` if its minimal
/// period is smaller than `orbit.periods`.
pub fn analyse(model: &Model, orbit: PeriodicOrbit) -> Result<Option<Orbit>, SimError> {
    let mut sim = model.simulator_from(orbit.x0, orbit.v0)?;
    let c = record_cycles(&mut sim, model.shaker, 0, orbit.periods, SAMPLES)?;
    let q = orbit.periods as usize;
    let y0 = c.sections[0];
    let scale = y0.0.abs().max(y0.1.abs()).max(1.0);
    let minimal = (1..q).filter(|&d| q.is_multiple_of(d)).any(|d| {
        let y = c.sections[d];
        (y.0 - y0.0).abs().max((y.1 - y0.1).abs()) < MINIMAL_TOL * scale
    });
    if minimal {
        return Ok(None);
    }
    let mut cycle_max = c.max_x;
    cycle_max.sort_by(f64::total_cmp);
    let mut sections = c.sections;
    sections.truncate(q);
    Ok(Some(Orbit {
        orbit,
        cycle_max,
        sections,
    }))
}
