//! Validated model parameters and solver options.
//!
//! Every constructor checks its inputs and returns a [`ParamError`] naming the offending value;
//! a `Params` or `SolverOptions` that exists is always usable.

use std::fmt;

use crate::events::StickCause;

/// A parameter that failed validation: which one, the value given and the rule it broke.
#[derive(Debug, Clone, PartialEq)]
pub struct ParamError {
    /// Name of the parameter as users know it (`zeta`, `restitution`, `omega`, ...).
    pub name: &'static str,
    /// The rejected value.
    pub value: f64,
    /// The rule, e.g. "must be finite and >= 0".
    pub rule: &'static str,
}

impl fmt::Display for ParamError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "invalid {} = {}: {}", self.name, self.value, self.rule)
    }
}

impl std::error::Error for ParamError {}

pub(crate) fn check(
    name: &'static str,
    value: f64,
    ok: bool,
    rule: &'static str,
) -> Result<f64, ParamError> {
    if value.is_finite() && ok {
        Ok(value)
    } else {
        Err(ParamError { name, value, rule })
    }
}

/// Physical parameters of the nondimensional model (see `model.md`, Sec. 2).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Params {
    zeta: f64,
    restitution: f64,
}

impl Params {
    /// Damping ratio `ζ ≥ 0` and coefficient of restitution `0 ≤ e ≤ 1`.
    pub fn new(zeta: f64, restitution: f64) -> Result<Self, ParamError> {
        Ok(Self {
            zeta: check("zeta", zeta, zeta >= 0.0, "must be finite and >= 0")?,
            restitution: check(
                "restitution",
                restitution,
                (0.0..=1.0).contains(&restitution),
                "must be finite and in [0, 1]",
            )?,
        })
    }

    /// The paper's values: `ζ = 0.02`, `e = 0.85`.
    pub fn paper() -> Self {
        Self {
            zeta: 0.02,
            restitution: 0.85,
        }
    }

    /// Damping ratio `ζ` (dimensionless).
    pub fn zeta(&self) -> f64 {
        self.zeta
    }

    /// Coefficient of restitution `e` (dimensionless).
    pub fn restitution(&self) -> f64 {
        self.restitution
    }

    /// Free-flight acceleration `x'' = −2ζx' − U'(x)` (Eq. 4) at position `x`, velocity `v`.
    pub fn flight_acceleration(&self, x: f64, v: f64) -> f64 {
        -2.0 * self.zeta * v - crate::potential::force(x)
    }

    /// Contact force per unit mass `N = z̈ + 2ζż + U'(z)` (Eq. 9) of a mass riding a plate at
    /// `z` moving with `ż`, `z̈`: the mass stays on the plate while `N ≥ 0`.
    pub fn contact_force(&self, z: f64, zdot: f64, zddot: f64) -> f64 {
        zddot + 2.0 * self.zeta * zdot + crate::potential::force(z)
    }

    /// Impact law (Eq. 5) on the relative velocity `w = x' − ż`: `w₊ = −e·w₋`.
    pub fn rebound(&self, w_minus: f64) -> f64 {
        -self.restitution * w_minus
    }
}

/// How a chatter sequence (impacts accumulating in finite time) is ended and turned into sticking.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ChatterRule {
    /// Budd & Dux (1994) accumulation point: after an impact with relative velocity `w₊` while the
    /// contact force is `N > 0`, the remaining impacts accumulate after `Δ = 2w₊/(N(1−e))`. When
    /// `Δ ≤ horizon` the mass is put on the plate at `τₙ + Δ`. The error of this prediction is
    /// second order in `Δ`, so a small horizon makes it negligible while the impacts before it are
    /// all resolved individually.
    Accumulation {
        /// Largest predicted remaining chatter time that is skipped (time units, `> 0`).
        horizon: f64,
    },
    /// The paper's rule: sticking starts at an impact that follows the previous one by less than
    /// `gap` (the paper uses `1e-9`), provided the contact force is non-negative there.
    FixedGap {
        /// Threshold on the time between two impacts (time units, `> 0`).
        gap: f64,
    },
}

impl ChatterRule {
    /// The paper's `1e-9` fixed-gap rule, for comparison with its figures.
    pub fn paper() -> Self {
        ChatterRule::FixedGap { gap: 1e-9 }
    }

    /// Whether this rule ends a chatter sequence after an impact with rebound relative velocity
    /// `w_plus ≥ 0`, contact force `force` (Eq. 9) and time `since` the previous impact (`e`: the
    /// coefficient of restitution): the time to ride on the plate before sticking (0: at once)
    /// and the cause, or `None` (free flight).
    pub fn stick_delay(
        self,
        e: f64,
        w_plus: f64,
        force: f64,
        since: Option<f64>,
    ) -> Option<(f64, StickCause)> {
        if w_plus == 0.0 {
            return (force > 0.0).then_some((0.0, StickCause::Plastic));
        }
        match self {
            ChatterRule::Accumulation { horizon } => {
                if force > 0.0 && e < 1.0 {
                    let delta = 2.0 * w_plus / (force * (1.0 - e));
                    if delta <= horizon {
                        return Some((delta, StickCause::Accumulation));
                    }
                }
            }
            ChatterRule::FixedGap { gap } => {
                if force >= 0.0 && since.is_some_and(|d| d < gap) {
                    return Some((0.0, StickCause::FixedGap));
                }
            }
        }
        None
    }

    fn validate(self) -> Result<Self, ParamError> {
        match self {
            ChatterRule::Accumulation { horizon } => {
                check(
                    "chatter_horizon",
                    horizon,
                    horizon > 0.0,
                    "must be finite and > 0",
                )?;
            }
            ChatterRule::FixedGap { gap } => {
                check("chatter_gap", gap, gap > 0.0, "must be finite and > 0")?;
            }
        }
        Ok(self)
    }
}

/// Integrator settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolverOptions {
    tol: f64,
    order: Option<usize>,
    chatter: ChatterRule,
    max_chatter_impacts: u32,
}

impl SolverOptions {
    /// Local error tolerance `tol ∈ [1e-18, 1e-3]` per Taylor step (absolute for state values of
    /// size ≤ 1, relative above), and a chatter rule.
    pub fn new(tol: f64, chatter: ChatterRule) -> Result<Self, ParamError> {
        Ok(Self {
            tol: check(
                "tol",
                tol,
                (1e-18..=1e-3).contains(&tol),
                "must be finite and in [1e-18, 1e-3]",
            )?,
            order: None,
            chatter: chatter.validate()?,
            max_chatter_impacts: 100_000,
        })
    }

    /// Fixes the Taylor order (`8 ≤ order ≤ 40`) instead of deriving it from the tolerance.
    pub fn with_order(mut self, order: usize) -> Result<Self, ParamError> {
        check(
            "order",
            order as f64,
            (8..=crate::taylor::MAX_ORDER).contains(&order),
            "must be in [8, 40]",
        )?;
        self.order = Some(order);
        Ok(self)
    }

    /// Taylor order: the fixed one, or `taylor::order_for(tol)`.
    pub fn order(&self) -> usize {
        self.order
            .unwrap_or_else(|| crate::taylor::order_for(self.tol))
    }

    /// Zeno guard: after this many consecutive impacts that each follow the previous one by less
    /// than `1e-6` time units, the mass is put on the plate (if the contact force is `≥ 0`) or the
    /// run stops with an error. Must be `≥ 10`.
    pub fn with_max_chatter_impacts(mut self, n: u32) -> Result<Self, ParamError> {
        check(
            "max_chatter_impacts",
            f64::from(n),
            n >= 10,
            "must be >= 10",
        )?;
        self.max_chatter_impacts = n;
        Ok(self)
    }

    /// Local error tolerance.
    pub fn tol(&self) -> f64 {
        self.tol
    }

    /// Chatter rule.
    pub fn chatter(&self) -> ChatterRule {
        self.chatter
    }

    /// Zeno guard limit (see [`SolverOptions::with_max_chatter_impacts`]).
    pub fn max_chatter_impacts(&self) -> u32 {
        self.max_chatter_impacts
    }
}

impl Default for SolverOptions {
    /// `tol = 1e-16` (order 24: truncation error at the level of rounding, so energy drifts by
    /// < 1e-12 over 10⁴ undamped natural periods) and the accumulation rule with a `1e-7` horizon.
    fn default() -> Self {
        Self {
            tol: 1e-16,
            order: None,
            chatter: ChatterRule::Accumulation { horizon: 1e-7 },
            max_chatter_impacts: 100_000,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_bad_values_with_their_names() {
        let e = Params::new(-0.1, 0.5).unwrap_err();
        assert_eq!(e.name, "zeta");
        assert_eq!(Params::new(0.0, 1.5).unwrap_err().name, "restitution");
        assert_eq!(Params::new(f64::NAN, 0.5).unwrap_err().name, "zeta");
        assert_eq!(
            SolverOptions::new(0.0, ChatterRule::paper())
                .unwrap_err()
                .name,
            "tol"
        );
        assert_eq!(
            SolverOptions::new(1e-12, ChatterRule::FixedGap { gap: -1.0 })
                .unwrap_err()
                .name,
            "chatter_gap"
        );
        assert!(e.to_string().contains("zeta = -0.1"));
    }
}
