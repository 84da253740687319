//! Conversions between SI and the core's nondimensional units (`model.md` Sec. 6): time
//! `t = τ/ω0` (s), lengths `x̂ = Δx·x` (m), velocities `ω0Δx·v` (m/s), accelerations
//! `ω0²Δx·a` (m/s²), energies `m·ω0²Δx²·E` (J) and specific energies `(ω0Δx)²·E` (J/kg).
//!
//! One type for every adapter (the FMU, the ROS node), so that each conversion is computed with
//! the same operations in the same order everywhere. With `ω0 = 1`, `Δx = 1` and `m = 1` every
//! conversion is a multiplication or division by 1: SI values are the nondimensional ones bit
//! for bit.

/// The SI scales of one model: `ω0`, `Δx` and the mass.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Scale {
    /// `ω0` (rad/s).
    pub omega0: f64,
    /// `Δx` (m).
    pub dx: f64,
    /// Mass (kg), for [`Scale::energy`] only.
    pub mass: f64,
}

impl Scale {
    /// `τ` of the SI time `t` (s).
    pub fn tau(&self, t: f64) -> f64 {
        t * self.omega0
    }

    /// SI time (s) of `τ`.
    pub fn time(&self, tau: f64) -> f64 {
        tau / self.omega0
    }

    /// Length (m).
    pub fn length(&self, x: f64) -> f64 {
        x * self.dx
    }

    /// Nondimensional length of `x` (m).
    pub fn of_length(&self, x: f64) -> f64 {
        x / self.dx
    }

    /// Velocity (m/s).
    pub fn velocity(&self, v: f64) -> f64 {
        v * (self.omega0 * self.dx)
    }

    /// Nondimensional velocity of `v` (m/s).
    pub fn of_velocity(&self, v: f64) -> f64 {
        v / (self.omega0 * self.dx)
    }

    /// Angular frequency (rad/s) of the nondimensional `Ω`.
    pub fn frequency(&self, omega: f64) -> f64 {
        omega * self.omega0
    }

    /// Nondimensional `Ω` of the angular frequency `omega` (rad/s).
    pub fn of_frequency(&self, omega: f64) -> f64 {
        omega / self.omega0
    }

    /// Acceleration (m/s²).
    pub fn acceleration(&self, a: f64) -> f64 {
        a * (self.omega0 * self.omega0 * self.dx)
    }

    /// Energy (J).
    pub fn energy(&self, e: f64) -> f64 {
        e * (self.mass * self.omega0 * self.omega0 * self.dx * self.dx)
    }

    /// Energy per unit mass (J/kg); does not use the mass.
    pub fn specific_energy(&self, e: f64) -> f64 {
        (self.omega0 * self.dx).powi(2) * e
    }

    /// Nondimensional Taylor coefficient `z_k` of the SI plate derivative `d^k ẑ/dt^k`.
    #[inline]
    pub fn plate_coefficient(&self, k: usize, d: f64) -> f64 {
        let mut c = d / self.dx;
        for j in 1..=k {
            c /= self.omega0 * j as f64;
        }
        c
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unit_scales_are_the_identity_and_conversions_invert() {
        let one = Scale {
            omega0: 1.0,
            dx: 1.0,
            mass: 1.0,
        };
        for x in [0.3, -1.7, 1e-300, 5e300] {
            assert_eq!(one.time(x), x);
            assert_eq!(one.length(x), x);
            assert_eq!(one.velocity(x), x);
            assert_eq!(one.energy(x), x);
            assert_eq!(one.specific_energy(x), x);
        }
        let s = Scale {
            omega0: 2.0,
            dx: 0.5,
            mass: 3.0,
        };
        assert_eq!(s.time(s.tau(1.25)), 1.25);
        assert_eq!(s.of_length(s.length(0.75)), 0.75);
        assert_eq!(s.of_velocity(s.velocity(0.75)), 0.75);
        assert_eq!(s.energy(1.0), 3.0);
        assert_eq!(s.specific_energy(1.0), 1.0);
        assert_eq!(s.acceleration(1.0), 2.0);
        // d³ẑ/dt³ = 12 m/s³: z_3 = 12 / (Δx · ω0³ · 3!) = 0.5.
        assert_eq!(s.plate_coefficient(3, 12.0), 0.5);
    }
}
