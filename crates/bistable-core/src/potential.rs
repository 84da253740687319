//! The equal-well bistable potential `U(x) = ½x²(1−x)²` (unit `k0 Δx²`), wells at 0 and 1.

/// Potential energy `U(x) = ½x²(1−x)²`.
pub fn energy(x: f64) -> f64 {
    let y = x * (1.0 - x);
    0.5 * y * y
}

/// Restoring force term `U'(x) = x − 3x² + 2x³ = x(1−x)(1−2x)`.
pub fn force(x: f64) -> f64 {
    x * (1.0 - x) * (1.0 - 2.0 * x)
}

/// Stiffness `U''(x) = 1 − 6x + 6x²` (1 at both wells, −½ on the barrier).
pub fn stiffness(x: f64) -> f64 {
    1.0 - 6.0 * x + 6.0 * x * x
}

/// Height of the barrier at `x = ½`: `U(½) = 1/32`.
pub const BARRIER_ENERGY: f64 = 1.0 / 32.0;

/// Position of the barrier separating well 1 (`x < ½`) from well 2 (`x > ½`).
pub const BARRIER: f64 = 0.5;

/// Kinetic energy `v²/2` (unit `k0 Δx²`).
pub fn kinetic(v: f64) -> f64 {
    0.5 * v * v
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn force_and_stiffness_are_derivatives() {
        for i in -20..=40 {
            let x = f64::from(i) * 0.05;
            let h = 1e-6;
            let fd = (energy(x + h) - energy(x - h)) / (2.0 * h);
            assert!((fd - force(x)).abs() < 1e-9, "x={x}");
            let fd2 = (force(x + h) - force(x - h)) / (2.0 * h);
            assert!((fd2 - stiffness(x)).abs() < 1e-8, "x={x}");
        }
        assert_eq!(energy(BARRIER), BARRIER_ENERGY);
        assert_eq!(force(0.0), 0.0);
        assert_eq!(force(1.0), 0.0);
    }
}
