//! The shaker velocity thresholds of the paper's Eq. 16–18 (nondimensional `V = V̂/(ω0·Δx)`).

use bistable_core::ParamError;

/// The rule the thresholds put on the restitution (Eq. 17 has `1 − e` over `1 + e`; the model
/// itself also allows `e = 1`).
pub const RESTITUTION_RULE: &str = "must be in [0, 1)";

/// Whether `e` is a restitution the thresholds (and the energy map) accept: finite, in `[0, 1)`.
pub fn restitution_ok(e: f64) -> bool {
    e.is_finite() && (0.0..1.0).contains(&e)
}

/// `e` when [`restitution_ok`], else the error naming `restitution` with [`RESTITUTION_RULE`].
pub fn check_restitution(e: f64) -> Result<f64, ParamError> {
    if restitution_ok(e) {
        Ok(e)
    } else {
        Err(ParamError {
            name: "restitution",
            value: e,
            rule: RESTITUTION_RULE,
        })
    }
}

/// `V = 1/(4(1+e))` (Eq. 16): the first impact alone, `x' = (1+e)V`, gives the barrier energy
/// `U(1/2) = 1/32` (damping neglected).
pub fn single_impact(e: f64) -> f64 {
    1.0 / (4.0 * (1.0 + e))
}

/// `V = (1−e)/(2(1+e))` (Eq. 17): below it only intrawell motion is possible.
pub fn interwell(e: f64) -> f64 {
    (1.0 - e) / (2.0 * (1.0 + e))
}

/// `V = Ω/2` (Eq. 18): the plate displacement amplitude `V/Ω` reaches the barrier `x = 1/2`.
pub fn quasi_static(omega: f64) -> f64 {
    0.5 * omega
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paper_values() {
        assert!((single_impact(0.85) - 1.0 / 7.4).abs() < 1e-15);
        assert!((interwell(0.85) - 0.15 / 3.7).abs() < 1e-15);
        assert_eq!(quasi_static(0.3), 0.15);
        // The single-impact threshold is where ½((1+e)V)² equals the barrier energy 1/32.
        let w = (1.0 + 0.7) * single_impact(0.7);
        assert!((0.5 * w * w - bistable_core::potential::BARRIER_ENERGY).abs() < 1e-15);
    }

    #[test]
    fn restitution_rule() {
        assert_eq!(check_restitution(0.0), Ok(0.0));
        for bad in [1.0, -0.1, f64::NAN, f64::INFINITY] {
            let e = check_restitution(bad).unwrap_err();
            assert_eq!((e.name, e.rule), ("restitution", RESTITUTION_RULE));
        }
    }
}
