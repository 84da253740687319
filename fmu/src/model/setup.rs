//! Set-up: the parameters checked and converted for a start, shared by both interfaces.

use bistable_core::{ChatterRule, Instant, Params, Sinusoid, SolverOptions};

use super::plate::ShakerMode;
use super::si::{describe_param, scale_of, Scale};
use crate::md::var;
use crate::num::Num;

/// Chatter rule of the FMU (the core's default, as the CLI uses).
pub(crate) fn chatter_rule() -> ChatterRule {
    SolverOptions::default().chatter()
}

/// What both interfaces build from the parameters at the start time.
pub struct Setup {
    /// Unit conversions.
    pub scale: Scale,
    /// Plate source.
    pub mode: ShakerMode,
    /// `ζ`, `e`.
    pub params: Params,
    /// Solver settings (`tol`, the chatter rule).
    pub opts: SolverOptions,
    /// Phase reference (the plate in internal mode), phase 0 at the start time.
    pub phase_ref: Sinusoid,
    /// Start instant (`τ`).
    pub origin: Instant,
    /// Initial position and velocity (nondimensional).
    pub x0: f64,
    /// See `x0`.
    pub v0: f64,
}

impl Setup {
    /// Checks the parameters and converts them for a start at `t_start` (s).
    pub fn of(values: &[f64], t_start: f64) -> Result<Self, String> {
        let scale = scale_of(values);
        let mode = ShakerMode::of(values[var::shaker_mode])
            .ok_or_else(|| format!("invalid shaker_mode = {}", values[var::shaker_mode]))?;
        let params =
            Params::new(values[var::zeta], values[var::e]).map_err(|e| describe_param(&e))?;
        let opts =
            SolverOptions::new(values[var::tol], chatter_rule()).map_err(|e| describe_param(&e))?;
        let tau0 = scale.tau(t_start);
        if !tau0.is_finite() {
            return Err(format!("start time {t_start} s times omega0 is not finite"));
        }
        let origin = Instant::new(tau0);
        let phase_ref = Sinusoid::new(values[var::Omega], values[var::V])
            .and_then(|s| s.with_origin(origin, 0.0, 0.0))
            .map_err(|e| describe_param(&e))?;
        Ok(Self {
            scale,
            mode,
            params,
            opts,
            phase_ref,
            origin,
            x0: scale.of_length(values[var::x0]),
            v0: scale.of_velocity(values[var::v0]),
        })
    }
}

/// Refusal of an initial position below the plate position `z` (m).
pub fn below_plate(values: &[f64], z: f64) -> String {
    format!(
        "x0 = {} m is below the plate position z = {} m at the start time: the mass must start on or above the plate",
        Num(values[var::x0]),
        Num(z),
    )
}
