//! Taylor-series coefficients of the free flight and of the contact force, and the step size.
//!
//! The right-hand side is a cubic polynomial, so the normalised coefficients `x_k = x^(k)/k!`
//! follow from Cauchy products (Jorba & Zou 2005). The gap `u = x − z` is carried alongside, so the
//! impact condition `u = 0` is a polynomial root on every step.

/// Largest Taylor order supported.
pub const MAX_ORDER: usize = 40;
/// Length of the coefficient buffers (orders `0..=MAX_ORDER + 2`).
pub(crate) const BUF: usize = MAX_ORDER + 3;

/// Taylor order for a local tolerance (Jorba & Zou: `p ≈ −ln(tol)/2 + 1`), clamped to `[8, 40]`.
pub fn order_for(tol: f64) -> usize {
    let p = (-tol.ln() / 2.0).ceil() as usize + 2;
    p.clamp(8, MAX_ORDER)
}

/// Coefficients of `x` and of the gap `u = x − z` over one free-flight step, up to `order + 1`.
#[derive(Clone, Copy)]
pub(crate) struct FlightSeries {
    pub x: [f64; BUF],
    pub u: [f64; BUF],
}

/// Free flight `x'' = −2ζx' − U'(x)` from gap `u0`, gap velocity `w0` and plate coefficients `z`
/// (at least `order + 2` of them). Fills coefficients `0..=order + 1`.
pub(crate) fn flight(zeta: f64, u0: f64, w0: f64, z: &[f64; BUF], order: usize) -> FlightSeries {
    let mut x = [0.0; BUF];
    let mut u = [0.0; BUF];
    let mut sq = [0.0; BUF];
    x[0] = u0 + z[0];
    x[1] = w0 + z[1];
    u[0] = u0;
    u[1] = w0;
    for k in 0..order {
        let s = cauchy(&x, &x, k);
        sq[k] = s;
        let c = cauchy(&sq, &x, k);
        let rhs = -2.0 * zeta * (k + 1) as f64 * x[k + 1] - x[k] + 3.0 * s - 2.0 * c;
        let xk2 = rhs / ((k + 1) * (k + 2)) as f64;
        x[k + 2] = xk2;
        u[k + 2] = xk2 - z[k + 2];
    }
    FlightSeries { x, u }
}

/// Contact force `N = z̈ + 2ζż + U'(z)` (Eq. 9) as a series, coefficients `0..=order`, from plate
/// coefficients `0..=order + 2`.
pub(crate) fn contact_force(zeta: f64, z: &[f64; BUF], order: usize) -> [f64; BUF] {
    let mut n = [0.0; BUF];
    let mut sq = [0.0; BUF];
    for k in 0..=order {
        sq[k] = cauchy(z, z, k);
        let c = cauchy(&sq, z, k);
        n[k] = ((k + 1) * (k + 2)) as f64 * z[k + 2] + 2.0 * zeta * (k + 1) as f64 * z[k + 1] + z[k]
            - 3.0 * sq[k]
            + 2.0 * c;
    }
    n
}

/// `Σ_{j=0}^{k} a_j b_{k−j}`, with two accumulators to shorten the dependency chain.
#[inline]
fn cauchy(a: &[f64; BUF], b: &[f64; BUF], k: usize) -> f64 {
    let (mut s0, mut s1) = (0.0, 0.0);
    let mut j = 0;
    while j + 1 <= k {
        s0 = a[j].mul_add(b[k - j], s0);
        s1 = a[j + 1].mul_add(b[k - j - 1], s1);
        j += 2;
    }
    if j == k {
        s0 = a[j].mul_add(b[0], s0);
    }
    s0 + s1
}

/// Jorba–Zou step size from the last two coefficients of the given series (each a slice of
/// coefficients `0..=order`), for an absolute tolerance scaled by the size of the state.
pub(crate) fn step_size(series: &[&[f64]], order: usize, tol: f64) -> f64 {
    let scale = series
        .iter()
        .map(|c| c[0].abs().max(c[1].abs()))
        .fold(1.0_f64, f64::max);
    let eps = tol * scale;
    let last = series.iter().map(|c| c[order].abs()).fold(0.0, f64::max);
    let prev = series.iter().map(|c| c[order - 1].abs()).fold(0.0, f64::max);
    let r1 = (eps / prev).powf(1.0 / (order - 1) as f64);
    let r2 = (eps / last).powf(1.0 / order as f64);
    let safety = (-0.7 / (order - 1) as f64).exp();
    (safety * r1.min(r2)).min(MAX_STEP)
}

/// Upper bound on any step (time units): a series that vanishes identically gives no bound.
pub(crate) const MAX_STEP: f64 = 8.0;

/// `Σ c_k s^k` (Horner).
#[inline]
pub(crate) fn eval(c: &[f64], s: f64) -> f64 {
    c.iter().rev().fold(0.0, |acc, &ck| acc.mul_add(s, ck))
}

/// Value and derivative of `Σ c_k s^k`.
#[inline]
pub(crate) fn eval_d(c: &[f64], s: f64) -> (f64, f64) {
    let mut p = 0.0_f64;
    let mut d = 0.0_f64;
    for &ck in c.iter().rev() {
        d = d.mul_add(s, p);
        p = p.mul_add(s, ck);
    }
    (p, d)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linearised_flight_matches_damped_oscillator() {
        // Near the well bottom with tiny amplitude, x'' + 2ζx' + x ≈ 0: compare coefficients of
        // the exact solution x = a e^{−ζt}(cos ωd t + ζ/ωd sin ωd t) at the level of the
        // neglected quadratic terms (a² ~ 1e-16).
        let (zeta, a) = (0.1, 1e-8);
        let z = [0.0; BUF];
        let order = 20;
        let s = flight(zeta, a, 0.0, &z, order);
        let wd = (1.0 - zeta * zeta).sqrt();
        let h = 0.3;
        let exact = a * (-zeta * h).exp() * ((wd * h).cos() + zeta / wd * (wd * h).sin());
        let approx = eval(&s.x[..=order], h);
        assert!(((approx - exact) / a).abs() < 1e-7, "{approx} vs {exact}");
    }

    #[test]
    fn energy_is_conserved_along_a_series_without_damping() {
        let z = [0.0; BUF];
        let order = 24;
        let s = flight(0.0, 0.3, 0.2, &z, order);
        let h = step_size(&[&s.x[..=order]], order, 1e-16);
        let e0 = 0.5 * 0.2 * 0.2 + crate::potential::energy(0.3);
        let (x, v) = eval_d(&s.x[..=order], h);
        let e1 = 0.5 * v * v + crate::potential::energy(x);
        assert!(h > 0.2, "step {h}");
        assert!((e1 - e0).abs() < 1e-16, "{e1} vs {e0}");
    }
}
