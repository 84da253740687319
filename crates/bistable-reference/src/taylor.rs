//! Taylor series of the plate motion, the contact force and the gap.
//!
//! Notation: a step starts at time `τ0`; `s = τ - τ0`. Every series is a vector of Taylor
//! coefficients `c_k` with `f(τ0 + s) = Σ c_k s^k`.
//!
//! Plate: `z(τ) = (V/Ω) sin(Ωτ)`, so `z_k = (V/Ω) Ω^k/k! · sin(Ωτ0 + kπ/2)`.
//!
//! Gap `u = x - z` with `x = z + u` substituted into `x'' + 2ζx' + U'(x) = 0`,
//! `U'(x) = x - 3x² + 2x³`, expanded exactly in powers of `u`:
//!
//! `u'' = -N(τ) - 2ζ u' - (1 - 6z + 6z²) u + (3 - 6z) u² - 2u³`
//!
//! where `N(τ) = z̈ + 2ζż + z - 3z² + 2z³` is the contact force per unit mass that the plate
//! would have to apply to carry the mass along (`u ≡ 0`). A small gap therefore keeps its full
//! relative precision. The coefficients follow from the Cauchy-product recurrence
//!
//! `(k+1)(k+2) u_{k+2} = -N_k - 2ζ(k+1) u_{k+1} - (L*u)_k + (M*u²)_k - 2(u³)_k`
//!
//! with `L = 1 - 6z + 6z²`, `M = 3 - 6z` and `(a*b)_k = Σ_{j<=k} a_j b_{k-j}`.

use crate::real::{sgn, to_f64, Prec, Real};

/// The model's constants at working precision.
pub(crate) struct Model {
    pub prec: Prec,
    /// Taylor order `n` (series carry coefficients `0..=n`).
    pub order: usize,
    /// `2ζ`.
    pub two_zeta: Real,
    /// Restitution `e`.
    pub e: Real,
    /// Shaker angular frequency `Ω`.
    pub omega: Real,
    /// `V`.
    pub v: Real,
    /// Plate amplitude `V/Ω`.
    pub amp: Real,
    /// `1 - Ω²` (the plate's `z̈ + z = (1 - Ω²) z`).
    pub one_minus_omega2: Real,
    /// `2π`.
    pub two_pi: Real,
    /// `1/2` (the barrier).
    pub half: Real,
    /// Natural log of the truncation tolerance per step, `(bits + 16)·ln 2` below 1.
    ln_tol: f64,
    /// Largest step.
    h_max: f64,
}

/// The three series that depend on the plate only.
pub(crate) struct PlateSeries {
    /// `z_0..=z_{n+1}`.
    pub z: Vec<Real>,
    /// Contact force `N_0..=N_n`.
    pub force: Vec<Real>,
    /// `L = 1 - 6z + 6z²`, coefficients `0..=n`.
    pub lin: Vec<Real>,
    /// `M = 3 - 6z`, coefficients `0..=n`.
    pub quad: Vec<Real>,
}

/// `(a*a)_k = Σ_{j=0..k} a_j a_{k-j}`, using the symmetry of the terms.
fn cauchy_square(a: &[Real], k: usize) -> Real {
    let mut acc = &a[0] * &a[k];
    for j in 1..k.div_ceil(2) {
        acc += &a[j] * &a[k - j];
    }
    if k > 0 {
        acc *= 2u8;
    }
    if k & 1 == 0 && k > 0 {
        acc += &a[k / 2] * &a[k / 2];
    }
    acc
}

/// `(a*b)_k = Σ_{j=0..k} a_j b_{k-j}`.
fn cauchy(a: &[Real], b: &[Real], k: usize) -> Real {
    let mut acc = &a[0] * &b[k];
    for j in 1..=k {
        acc += &a[j] * &b[k - j];
    }
    acc
}

impl Model {
    pub fn new(prec: Prec, zeta: f64, e: f64, omega: f64, v: f64) -> Model {
        let omega_r = prec.exact(omega);
        let v_r = prec.exact(v);
        // Order from the precision. The cost per unit time is ~ order² / step, and the step grows
        // with the order until about 1.2 orders per decimal digit (measured: at 128 bits, order
        // 48 is twice as fast as order 27 and as fast as order 60).
        let order = (1.2 * prec.digits() as f64).ceil() as usize + 2;
        Model {
            prec,
            order,
            two_zeta: prec.exact(zeta) * 2u8,
            e: prec.exact(e),
            amp: &v_r / &omega_r,
            one_minus_omega2: prec.int(1) - &omega_r * &omega_r,
            omega: omega_r,
            v: v_r,
            two_pi: Real::pi(prec.bits) * 2u8,
            half: prec.exact(0.5),
            ln_tol: -((prec.bits + 16) as f64) * std::f64::consts::LN_2,
            h_max: 1.0,
        }
    }

    /// `(sin Ωτ, cos Ωτ)`.
    pub fn trig(&self, tau: &Real) -> (Real, Real) {
        (&self.omega * tau).sin_cos()
    }

    /// Plate position and velocity `(z, ż)` at `τ`.
    pub fn plate(&self, tau: &Real) -> (Real, Real) {
        let (s, c) = self.trig(tau);
        (&self.amp * s, &self.v * c)
    }

    /// Contact force `N = z̈ + 2ζż + z - 3z² + 2z³` from `(z, ż)`.
    pub fn contact_force(&self, z: &Real, zd: &Real) -> Real {
        let z2 = z * z;
        let z3 = &z2 * z;
        &self.one_minus_omega2 * z + &self.two_zeta * zd - z2 * 3u8 + z3 * 2u8
    }

    /// Phase of `τ` in shaker cycles, `frac(Ωτ/2π)`.
    pub fn phase(&self, tau: &Real) -> Real {
        let cycles = &self.omega * tau / &self.two_pi;
        let whole = cycles.floor();
        cycles - whole
    }

    /// Taylor coefficients `c_0..=c_m` of `amp · sin(φ + f·s)` given `sin φ`, `cos φ`:
    /// `c_j = amp · f^j/j! · sin(φ + jπ/2)`.
    fn sine_series(
        &self,
        amp: &Real,
        f: &Real,
        sin_phi: &Real,
        cos_phi: &Real,
        m: usize,
    ) -> Vec<Real> {
        let neg_s = -sin_phi.clone();
        let neg_c = -cos_phi.clone();
        let cycle = [sin_phi, cos_phi, &neg_s, &neg_c];
        let mut p = amp.clone();
        let mut out = Vec::with_capacity(m + 1);
        for j in 0..=m {
            if j > 0 {
                p = p * f / j;
            }
            out.push(&p * cycle[j % 4]);
        }
        out
    }

    /// Taylor coefficients of the plate, the contact force, `L` and `M` at `τ0`.
    ///
    /// `z²` and `z³` are expanded with trigonometric identities (with `θ = Ωτ`,
    /// `A = V/Ω`): `z² = A²/2 - (A²/2) cos 2θ`, `z³ = (3A³/4) sin θ - (A³/4) sin 3θ`, so every
    /// plate series is exact up to rounding and costs O(n).
    pub fn plate_series(&self, tau0: &Real) -> PlateSeries {
        let n = self.order;
        let (s, c) = self.trig(tau0);
        let a = &self.amp;
        // Double and triple angles.
        let s2 = &s * &c * 2u8;
        let c2 = &c * &c - &s * &s;
        let s3 = &s * 3u8 - &s * &s * &s * 4u8;
        let c3 = &c * &c * &c * 4u8 - &c * 3u8;
        let a2 = a * a;
        let a3 = &a2 * a;
        let z = self.sine_series(a, &self.omega, &s, &c, n + 1);
        // cos ψ = sin(ψ + π/2): pass (cos ψ, -sin ψ) as (sin, cos) of the shifted angle.
        let cos2 = self.sine_series(
            &(-(a2.clone() >> 1isize)),
            &(&self.omega * 2u8),
            &c2,
            &(-s2.clone()),
            n,
        );
        let sin1 = self.sine_series(&((&a3 * 3u8) >> 2isize), &self.omega, &s, &c, n);
        let sin3 = self.sine_series(
            &(-(a3.clone() >> 2isize)),
            &(&self.omega * 3u8),
            &s3,
            &c3,
            n,
        );
        let one = self.prec.int(1);
        let three = self.prec.int(3);
        let mut force = Vec::with_capacity(n + 1);
        let mut lin = Vec::with_capacity(n + 1);
        let mut quad = Vec::with_capacity(n + 1);
        for k in 0..=n {
            let mut z2 = cos2[k].clone();
            if k == 0 {
                z2 += a2.clone() >> 1isize;
            }
            let z3 = &sin1[k] + &sin3[k];
            // N_k = (1 - Ω²) z_k + 2ζ (k+1) z_{k+1} - 3 (z²)_k + 2 (z³)_k
            force.push(
                &self.one_minus_omega2 * &z[k] + &self.two_zeta * &z[k + 1] * (k + 1) - &z2 * 3u8
                    + z3 * 2u8,
            );
            let mut l = z2 * 6u8 - &z[k] * 6u8;
            let mut m = -(&z[k] * 6u8);
            if k == 0 {
                l += &one;
                m += &three;
            }
            lin.push(l);
            quad.push(m);
        }
        PlateSeries {
            z,
            force,
            lin,
            quad,
        }
    }

    /// Taylor coefficients `u_0..=u_n` of the gap from `u(τ0) = u0`, `u'(τ0) = w0`.
    ///
    /// The nonlinear terms are grouped as `-L u + u² (M - 2u)`, three Cauchy products per order.
    pub fn gap_series(&self, ps: &PlateSeries, u0: &Real, w0: &Real) -> Vec<Real> {
        let n = self.order;
        let mut u = Vec::with_capacity(n + 1);
        u.push(u0.clone());
        u.push(w0.clone());
        let mut u2: Vec<Real> = Vec::with_capacity(n + 1);
        // g = M - 2u
        let mut g: Vec<Real> = Vec::with_capacity(n + 1);
        for k in 0..=(n - 2) {
            u2.push(cauchy_square(&u, k));
            g.push(&ps.quad[k] - &u[k] * 2u8);
            let lu = cauchy(&ps.lin, &u, k);
            let nonlin = cauchy(&u2, &g, k);
            let rhs = -ps.force[k].clone() - &self.two_zeta * &u[k + 1] * (k + 1) - lu + nonlin;
            u.push(rhs / ((k + 1) * (k + 2)));
        }
        u
    }

    /// Step size for which the last two retained terms of every given series are below the
    /// truncation tolerance `2^-(bits+16)` (Jorba & Zou 2005): `h = min_k (tol/|c_k|)^(1/k)`
    /// over `k = n-1, n`, times a safety factor, capped at `h_max`.
    pub fn step_size(&self, series: &[&[Real]]) -> f64 {
        let mut h = self.h_max;
        for c in series {
            let n = c.len() - 1;
            for k in [n - 1, n] {
                if sgn(&c[k]) == 0 {
                    continue;
                }
                let mag = to_f64(&c[k]).abs();
                if mag == 0.0 || !mag.is_finite() {
                    continue;
                }
                let hk = ((self.ln_tol - mag.ln()) / k as f64).exp();
                h = h.min(0.9 * hk);
            }
        }
        h
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::real::abs;

    /// The gap series, added to the plate series, satisfies the original equation of motion
    /// `x'' + 2ζx' + x - 3x² + 2x³ = 0` coefficient by coefficient (checked with plain Cauchy
    /// products of `x`, independently of the closed-form plate identities).
    #[test]
    fn gap_plus_plate_satisfies_the_equation_of_motion() {
        let prec = Prec { bits: 160 };
        let m = Model::new(prec, 0.02, 0.85, 1.75, 0.07);
        let tau0 = prec.exact(3.7);
        let ps = m.plate_series(&tau0);
        let u = m.gap_series(&ps, &prec.exact(0.013), &prec.exact(-0.11));
        let n = m.order;
        let x: Vec<Real> = (0..=n).map(|k| &u[k] + &ps.z[k]).collect();
        let tol = prec.pow2_neg(150);
        for k in 0..=(n - 2) {
            let x2 = cauchy(&x, &x, k);
            let x3: Real = (0..=k).map(|j| cauchy(&x, &x, j) * &x[k - j]).sum();
            let acc = &x[k + 2] * ((k + 1) * (k + 2)) + &m.two_zeta * &x[k + 1] * (k + 1) + &x[k]
                - x2 * 3u8
                + x3 * 2u8;
            assert!(abs(&acc) < tol, "order {k}: residual {}", to_f64(&acc));
        }
    }

    #[test]
    fn plate_series_matches_sin_cos_at_a_later_time() {
        let prec = Prec { bits: 128 };
        let m = Model::new(prec, 0.02, 0.85, 2.5, 0.07);
        let tau0 = prec.exact(123.25);
        let ps = m.plate_series(&tau0);
        let s = prec.exact(0.1);
        let z_series = crate::poly::eval(&ps.z, &s);
        let (z_exact, _) = m.plate(&(&tau0 + &s));
        assert!(abs(&(z_series - z_exact)) < prec.pow2_neg(125));
    }
}
