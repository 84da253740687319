//! The kinetic energy change of an impact (Eq. 10, 11, 13–15) over the impact phase and the
//! pre-impact velocity, and the impacts of a simulation in those coordinates.
//!
//! `u = x'₋/V` is the mass velocity just before the impact in units of the shaker velocity
//! amplitude; `φ` is the shaker phase angle (radians) of the impact.

use bistable_core::{Event, ParamError, SimError};

use crate::Model;

const TAU: f64 = std::f64::consts::TAU;

/// `ΔK/ΔK0 = (((1+e)·cos φ − e·u)² − u²)/(1+e)²` of an impact at phase angle `phi` with
/// pre-impact velocity `u·V` (Eq. 13), `ΔK0 = ½((1+e)V)²`.
pub fn energy_ratio(e: f64, phi: f64, u: f64) -> f64 {
    let after = (1.0 + e) * phi.cos() - e * u;
    (after * after - u * u) / ((1.0 + e) * (1.0 + e))
}

/// `u = −(1+e)/(1−e)·cos φ`: the neutral line `ΔK = 0` other than the grazing line (Eq. 14).
pub fn neutral(e: f64, phi: f64) -> f64 {
    -(1.0 + e) / (1.0 - e) * phi.cos()
}

/// `u = cos φ`: the grazing line (zero relative velocity, also `ΔK = 0`).
pub fn grazing(phi: f64) -> f64 {
    phi.cos()
}

/// Whether the plate can hit a mass with `u` at phase angle `phi`: `u <= cos φ` (Eq. 15).
pub fn contact_possible(phi: f64, u: f64) -> bool {
    u <= grazing(phi)
}

/// `ΔK/ΔK0` at the centres of an `nx × ny` grid of cells over the phase `φ/2π ∈ [0, 1)`
/// and `u ∈ [lo, hi]`.
#[derive(Debug, Clone, PartialEq)]
pub struct EnergyMap {
    nx: usize,
    ny: usize,
    u_range: (f64, f64),
    /// Row `i` (phase) major; `None` where no contact is possible.
    values: Vec<Option<f64>>,
    max_abs: f64,
}

impl EnergyMap {
    /// The map for restitution `e` over `u_range = (lo, hi)` on `nx × ny` cells.
    pub fn new(e: f64, u_range: (f64, f64), nx: usize, ny: usize) -> Self {
        let mut map = Self {
            nx,
            ny,
            u_range,
            values: Vec::with_capacity(nx * ny),
            max_abs: 1.0,
        };
        for i in 0..nx {
            for j in 0..ny {
                let (ph, u) = map.centre(i, j);
                let value = contact_possible(TAU * ph, u).then(|| energy_ratio(e, TAU * ph, u));
                if let Some(r) = value {
                    map.max_abs = map.max_abs.max(r.abs());
                }
                map.values.push(value);
            }
        }
        map
    }

    /// Cells along the phase and along `u`.
    pub fn size(&self) -> (usize, usize) {
        (self.nx, self.ny)
    }

    /// The centre `(φ/2π, u)` of cell `(i, j)`.
    pub fn centre(&self, i: usize, j: usize) -> (f64, f64) {
        let cell = |i: usize, n: usize, a: f64, b: f64| a + (b - a) * (i as f64 + 0.5) / n as f64;
        let (lo, hi) = self.u_range;
        (cell(i, self.nx, 0.0, 1.0), cell(j, self.ny, lo, hi))
    }

    /// `ΔK/ΔK0` at the centre of cell `(i, j)`; `None` where no contact is possible.
    pub fn value(&self, i: usize, j: usize) -> Option<f64> {
        self.values[i * self.ny + j]
    }

    /// The largest `|ΔK/ΔK0|` on the map, at least 1.
    pub fn max_abs(&self) -> f64 {
        self.max_abs
    }
}

/// `e` when it is in `[0, 1)` (the neutral line has `1 − e` in a denominator), else the error
/// naming `restitution`.
pub fn check_restitution(e: f64) -> Result<f64, ParamError> {
    if crate::thresholds::restitution_ok(e) {
        Ok(e)
    } else {
        Err(ParamError {
            name: "restitution",
            value: e,
            rule: "must be in [0, 1) for the energy map",
        })
    }
}

/// Largest `u` shown by default.
pub const DEFAULT_U_MAX: f64 = 1.5;

/// The default range of `u` of a map for restitution `e`: up to [`DEFAULT_U_MAX`], down to below
/// the neutral line at `φ = 0` (`1.15·neutral(e, 0)`), or with `impacts` to below the lowest of
/// them (and at most −1); the lower end lowered by 8 % of the span.
pub fn default_u_range(e: f64, impacts: &[ImpactPoint]) -> (f64, f64) {
    let lo = if impacts.is_empty() {
        1.15 * neutral(e, 0.0)
    } else {
        impacts.iter().map(|i| i.u).fold(-1.0, f64::min)
    };
    (lo - 0.08 * (DEFAULT_U_MAX - lo), DEFAULT_U_MAX)
}

/// An impact of a simulation in the coordinates of the energy map.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImpactPoint {
    /// Shaker phase in cycles, `[0, 1)`.
    pub phase: f64,
    /// Pre-impact velocity `u = x'₋/V`.
    pub u: f64,
    /// Impact time as a fraction of the run, `t/t_end ∈ [0, 1]`.
    pub time_fraction: f64,
}

/// The impacts of a run from the paper's initial condition up to `τ = t_end` (> 0) at `model`
/// (`V > 0`).
pub fn impacts(model: &Model, t_end: f64) -> Result<Vec<ImpactPoint>, SimError> {
    let mut out = Vec::new();
    let mut sim = model.simulator()?;
    sim.advance_to(t_end, &mut |ev: &Event| {
        if let Event::Impact(i) = ev {
            if let Some(phase) = i.phase {
                out.push(ImpactPoint {
                    phase,
                    u: i.v_before / model.velocity(),
                    time_fraction: i.t / t_end,
                });
            }
        }
    })?;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn energy_ratio_of_the_first_impact_and_the_neutral_lines() {
        let e = 0.85;
        // The first impact (mass at rest, plate at full speed) is the unit.
        assert!((energy_ratio(e, 0.0, 0.0) - 1.0).abs() < 1e-15);
        for phi in [0.0, 0.3, 1.0, 2.0, 3.0] {
            // Both lines of Eq. 14 have ΔK = 0 …
            assert!(energy_ratio(e, phi, grazing(phi)).abs() < 1e-14);
            assert!(energy_ratio(e, phi, neutral(e, phi)).abs() < 1e-12);
            // … and between them the impact adds energy when cos φ > 0.
            if phi.cos() > 0.0 {
                let mid = 0.5 * (phi.cos() + neutral(e, phi));
                assert!(energy_ratio(e, phi, mid) > 0.0);
                assert!(energy_ratio(e, phi, neutral(e, phi) - 1.0) < 0.0);
            }
        }
    }

    #[test]
    fn map_cells() {
        let m = EnergyMap::new(0.85, (-2.0, 1.6), 4, 3);
        assert_eq!(m.size(), (4, 3));
        let (ph, u) = m.centre(0, 2);
        assert!(ph == 0.125 && (u - 1.0).abs() < 1e-15);
        // At φ/2π = 0.125 a mass at u = −0.2 < cos(π/4) can be hit, one at u = 1 not.
        assert!(m.value(0, 1).is_some());
        assert_eq!(m.value(0, 2), None);
        assert!(m.max_abs() >= 1.0);
    }
}
