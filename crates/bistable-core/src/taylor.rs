//! Taylor-series coefficients of the free flight and of the contact force, and the step size.
//!
//! The right-hand side is a cubic polynomial, so the normalised coefficients `x_k = x^(k)/k!`
//! follow from Cauchy products (Jorba & Zou 2005). The gap `u = x − z` is carried alongside, so the
//! impact condition `u = 0` is a polynomial root on every step.

use crate::lanes::Lane;

/// Largest Taylor order supported.
pub const MAX_ORDER: usize = 40;
/// Length of the coefficient buffers (orders `0..=MAX_ORDER + 2`).
pub(crate) const BUF: usize = MAX_ORDER + 3;

/// Taylor order for a local tolerance: `p = ⌈−ln(tol)/2⌉ + 4` (Jorba & Zou's `−ln(tol)/2`, plus a
/// margin that lengthens the steps by more than it costs), rounded up to even (the products run
/// in chunks of four), clamped to `[8, 40]`. Default tolerance `1e-16` → 24, `1e-15` → 22.
pub fn order_for(tol: f64) -> usize {
    let p = (-tol.ln() / 2.0).ceil() as usize + 4;
    (p + p % 2).clamp(8, MAX_ORDER)
}

/// Coefficients of `x` and of the gap `u = x − z` over one free-flight step, up to `order + 1`,
/// for one trajectory (`T = f64`) or one per lane of a batch ([`Lane`]).
/// `x` is zero-padded past the last coefficient (the products read whole chunks of four).
#[derive(Clone, Copy)]
pub(crate) struct FlightSeries<T = f64> {
    pub x: [T; PAD],
    pub u: [T; BUF],
    /// Coefficients of `x²` (orders `0..order`), for the variational equations.
    pub sq: [T; PAD],
    /// Scratch: `x` in reverse order, `xr[R − j] = x_j`, zero past `R`.
    xr: [T; PAD],
}

impl<T: Lane> Default for FlightSeries<T> {
    fn default() -> Self {
        let zero = T::splat(0.0);
        Self {
            x: [zero; PAD],
            u: [zero; BUF],
            sq: [zero; PAD],
            xr: [zero; PAD],
        }
    }
}

/// Free flight `x'' = −2ζx' − U'(x)` from gap `u0`, gap velocity `w0` and plate coefficients `z`
/// (at least `order + 2` of them). Fills coefficients `0..=order + 1` of `out`. With `var`, also
/// the two columns of the variational equation `δx'' = −2ζδx' − U''(x)δx` along it, from the
/// start given to `var` ([`VariationSeries::start`]), coefficients `0..=order + 1` of each, in
/// the same pass: each order's variational sum runs while the next order of the flight is
/// computed (independent chains).
pub(crate) fn flight(
    zeta: f64,
    u0: f64,
    w0: f64,
    z: &[f64; BUF],
    order: usize,
    out: &mut FlightSeries,
    var: Option<&mut VariationSeries>,
) {
    match var {
        Some(v) => flight_pass::<f64, true>(zeta, u0, w0, z, order, out, Some(v)),
        None => flight_pass::<f64, false>(zeta, u0, w0, z, order, out, None),
    }
}

/// [`flight`] over any lane type: compiled once with the variational equations (`VAR`, `var`
/// given) and once without, for `f64` and for each batch width. Lane `i` of a batch computes
/// exactly what `f64` computes from lane `i`'s inputs (the same operations in the same order).
#[inline(always)]
pub(crate) fn flight_pass<T: Lane, const VAR: bool>(
    zeta: f64,
    u0: T,
    w0: T,
    z: &[T; BUF],
    order: usize,
    out: &mut FlightSeries<T>,
    mut var: Option<&mut VariationSeries<T>>,
) {
    let zero = T::splat(0.0);
    let FlightSeries { x: xp, u, sq, xr } = out;
    // U''(x) = 1 − 6x + 6x² as a series, built order by order for the variational equation.
    let mut a = [zero; BUF];
    // With x reversed in xr (zero past x_0), each Cauchy product is a dot product over a length
    // rounded up to a multiple of 4; the entries read past the last computed coefficient of xp
    // and sq must be zero. Only entries written here are read from xr below R.
    sq[..order + 4].iter_mut().for_each(|c| *c = zero);
    xp[0] = u0 + z[0];
    xp[1] = w0 + z[1];
    u[0] = u0;
    u[1] = w0;
    xr[R] = xp[0];
    xr[R - 1] = xp[1];
    xp[order + 2..order + 5].iter_mut().for_each(|c| *c = zero);
    let three_minus_2x0 = T::splat(3.0) - T::splat(2.0) * xp[0];
    // The newest values, x_k, x_{k+1} and sq[k − 1], are taken from registers: a load of a value
    // stored just before (above all a vector load across it) would wait for the store.
    let (mut x_k, mut x_k1) = (xp[0], xp[1]);
    let mut sq_prev = zero;
    for k in 0..order {
        let len = (k + 4) & !3;
        let rev = &xr[R - k..R - k + len];
        // Off the critical path: the linear terms and the cube's products with older squares
        // (sq[k] is still zero here, so its term s·x_0 is folded in below and the vector loads
        // never wait for a value stored just before).
        let lin = T::splat(-2.0 * zeta * (k + 1) as f64) * x_k1 - x_k;
        let c_old = if k == 0 {
            dot4(&sq[..len], rev)
        } else {
            dot4_newest(&sq[..len], rev, k - 1, sq_prev)
        };
        // Square by symmetry: twice the pairs j < k − j, plus the middle term.
        let half = k.div_ceil(2);
        let mut s = T::splat(2.0) * dot_exact(&xp[..half], &rev[..half]);
        if k % 2 == 0 {
            s += xp[k / 2] * xp[k / 2];
        }
        sq[k] = s;
        sq_prev = s;
        if let (true, Some(var)) = (VAR, var.as_deref_mut()) {
            // Order k of both columns: Σ_{i≤k} a_i d_{k−i} summed from i = 0, lanes apart.
            a[k] = if k == 0 {
                T::splat(6.0) * (s - x_k) + T::splat(1.0)
            } else {
                T::splat(6.0) * (s - x_k)
            };
            let d = &mut var.d;
            let mut c = [T::splat(-0.0); 2];
            for (&ai, dj) in a[..=k].iter().zip(d[..=k].iter().rev()) {
                c[0] += ai * dj[0];
                c[1] += ai * dj[1];
            }
            let damp = T::splat(-2.0 * zeta * (k + 1) as f64);
            let inv = T::splat(INV_PAIR[k]);
            let prev = d[k + 1];
            d[k + 2] = [(damp * prev[0] - c[0]) * inv, (damp * prev[1] - c[1]) * inv];
        }
        // rhs = lin + 3s − 2(c_old + s·x_0)
        let rhs = (lin - T::splat(2.0) * c_old) + s * three_minus_2x0;
        let xk2 = rhs * T::splat(INV_PAIR[k]);
        xp[k + 2] = xk2;
        xr[R - k - 2] = xk2;
        u[k + 2] = xk2 - z[k + 2];
        (x_k, x_k1) = (x_k1, xk2);
    }
}

/// `1/((k+1)(k+2))`: the recurrence multiplies instead of dividing (a division per order would
/// sit on the critical path).
const INV_PAIR: [f64; BUF] = {
    let mut t = [0.0; BUF];
    let mut k = 0;
    while k < BUF {
        t[k] = 1.0 / ((k + 1) * (k + 2)) as f64;
        k += 1;
    }
    t
};

/// Padded buffer length for the products (room for a dot product of length `BUF` rounded up).
pub(crate) const PAD: usize = BUF + 8;
/// Index of `x_0` in the reversed buffer.
const R: usize = BUF + 2;

/// `Σ a_j b_j` over equal-length slices: chunks of four with four accumulators, then the rest
/// (summed from `−0`, as `Iterator::sum` does).
#[inline(always)]
fn dot_exact<T: Lane>(a: &[T], b: &[T]) -> T {
    let (ac, ar) = a.as_chunks::<4>();
    let (bc, br) = b.as_chunks::<4>();
    let mut acc = [T::splat(0.0); 4];
    add_chunks(&mut acc, ac, bc);
    let tail = ar
        .iter()
        .zip(br)
        .fold(T::splat(-0.0), |t, (&x, &y)| t + x * y);
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail
}

/// `Σ a_j b_j` over slices whose length is a multiple of 4, with four accumulators.
#[inline(always)]
fn dot4<T: Lane>(a: &[T], b: &[T]) -> T {
    let (a, _) = a.as_chunks::<4>();
    let (b, _) = b.as_chunks::<4>();
    let mut acc = [T::splat(0.0); 4];
    add_chunks(&mut acc, a, b);
    (acc[0] + acc[1]) + (acc[2] + acc[3])
}

/// Adds the products of the chunks of `a` and `b`, lane by lane, to `acc`.
#[inline(always)]
fn add_chunks<T: Lane>(acc: &mut [T; 4], a: &[[T; 4]], b: &[[T; 4]]) {
    for (x, y) in a.iter().zip(b) {
        for i in 0..4 {
            acc[i] += x[i] * y[i];
        }
    }
}

/// [`dot4`] for `a` whose entry `at` is `newest` (passed in a register) and zero past it: the
/// chunk holding it is assembled lane by lane, the same products in the same order.
#[inline(always)]
fn dot4_newest<T: Lane>(a: &[T], b: &[T], at: usize, newest: T) -> T {
    let zero = T::splat(0.0);
    let q = at / 4;
    let (a, _) = a.as_chunks::<4>();
    let (b, _) = b.as_chunks::<4>();
    let mut acc = [zero; 4];
    add_chunks(&mut acc, &a[..q], &b[..q]);
    let m = &a[q];
    let y = &b[q];
    // Lane by lane: entries before `at` (stored iterations ago), `newest`, zeros.
    let lane = at % 4;
    for i in 0..4 {
        let x = if i < lane {
            m[i]
        } else if i == lane {
            newest
        } else {
            zero
        };
        acc[i] += x * y[i];
    }
    for y in &b[q + 1..] {
        for i in 0..4 {
            acc[i] += zero * y[i];
        }
    }
    (acc[0] + acc[1]) + (acc[2] + acc[3])
}

/// Coefficients of the two columns of the variational solution over a free-flight step
/// ([`flight`]), order by order, both columns of an order side by side.
#[derive(Clone)]
pub(crate) struct VariationSeries<T = f64> {
    pub(crate) d: [[T; 2]; BUF],
}

impl<T: Lane> Default for VariationSeries<T> {
    fn default() -> Self {
        Self {
            d: [[T::splat(0.0); 2]; BUF],
        }
    }
}

impl VariationSeries {
    /// Sets the start of the next step's series: `Φ = ∂(x, x')/∂(x, x')(t_e)` there
    /// (row-major).
    pub(crate) fn start(&mut self, phi: [[f64; 2]; 2]) {
        self.d[0] = phi[0];
        self.d[1] = phi[1];
    }

    /// `Φ` at `s` into the step from coefficients `0..=n`: `[[δx₀, δx₁], [δx₀', δx₁']]` (Horner
    /// on each column, as [`eval_d`]).
    pub(crate) fn phi_at(&self, n: usize, s: f64) -> [[f64; 2]; 2] {
        let (mut p, mut d) = ([0.0_f64; 2], [0.0_f64; 2]);
        for ck in self.d[..=n].iter().rev() {
            for j in 0..2 {
                d[j] = d[j] * s + p[j];
                p[j] = p[j] * s + ck[j];
            }
        }
        [p, d]
    }

    /// Multiplies every coefficient by `r`.
    pub(crate) fn scale(&mut self, r: f64) {
        self.d.iter_mut().flatten().for_each(|c| *c *= r);
    }
}

/// Contact force `N = z̈ + 2ζż + U'(z)` (Eq. 9) as a series, coefficients `0..=order`, from plate
/// coefficients `0..=order + 2`.
pub(crate) fn contact_force(zeta: f64, z: &[f64; BUF], order: usize) -> [f64; BUF] {
    let mut zp = [0.0; PAD];
    let mut zr = [0.0; PAD];
    for (j, &zj) in z.iter().enumerate().take(order + 1) {
        zp[j] = zj;
        zr[R - j] = zj;
    }
    let mut n = [0.0; BUF];
    let mut sq = [0.0; PAD];
    for k in 0..=order {
        let len = (k + 4) & !3;
        let rev = &zr[R - k..R - k + len];
        sq[k] = dot4(&zp[..len], rev);
        let c = dot4(&sq[..len], rev);
        n[k] =
            ((k + 1) * (k + 2)) as f64 * z[k + 2] + 2.0 * zeta * (k + 1) as f64 * z[k + 1] + z[k]
                - 3.0 * sq[k]
                + 2.0 * c;
    }
    n
}

/// Jorba–Zou step size from the last two coefficients of the given series (each a slice of
/// coefficients `0..=order`), for an absolute tolerance scaled by the size of the state
/// (`ln_tol`: `tol.ln()`, the log of the tolerance when that size is at most 1). For one
/// trajectory (`f64`) or one per lane of a batch ([`Lane`]; `ln` and `exp` lane by lane).
#[inline(always)]
pub(crate) fn step_size<T: Lane>(series: &[&[T]], order: usize, tol: f64, ln_tol: f64) -> T {
    let scale = series
        .iter()
        .map(|c| c[0].abs().max(c[1].abs()))
        .fold(T::splat(1.0), T::max);
    let eps = T::splat(tol) * scale;
    let last = series
        .iter()
        .map(|c| c[order].abs())
        .fold(T::splat(0.0), T::max);
    let prev = series
        .iter()
        .map(|c| c[order - 1].abs())
        .fold(T::splat(0.0), T::max);
    // min((ε/prev)^(1/(p−1)), (ε/last)^(1/p)) times the safety factor e^(−0.7/(p−1)), in logs.
    let mut ln_eps = eps;
    for i in 0..T::LANES {
        let v = if scale.lane(i) == 1.0 {
            ln_tol
        } else {
            eps.lane(i).ln()
        };
        ln_eps.set_lane(i, v);
    }
    let l1 = (ln_eps - prev.map(f64::ln) - T::splat(0.7)) / T::splat((order - 1) as f64);
    let l2 =
        (ln_eps - last.map(f64::ln)) / T::splat(order as f64) - T::splat(0.7 / (order - 1) as f64);
    l1.min(l2).map(f64::exp).min(T::splat(MAX_STEP))
}

/// Upper bound on any step (time units): a series that vanishes identically gives no bound.
pub(crate) const MAX_STEP: f64 = 8.0;

/// `Σ c_k s^k` (Horner).
#[inline]
pub(crate) fn eval(c: &[f64], s: f64) -> f64 {
    c.iter().rev().fold(0.0, |acc, &ck| acc * s + ck)
}

/// Value and derivative of `Σ c_k s^k`, at one `s` (`f64`) or at one per lane, with the same
/// coefficients for every lane (`C = f64`) or each lane's own (`C = L`) (inlined, so that a
/// caller compiled for wider registers evaluates the lanes in them).
#[inline(always)]
pub(crate) fn eval_d<L: Lane + From<C>, C: Copy>(c: &[C], s: L) -> (L, L) {
    let mut p = L::splat(0.0);
    let mut d = L::splat(0.0);
    for &ck in c.iter().rev() {
        d = d * s + p;
        p = p * s + L::from(ck);
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
        let mut s = FlightSeries::default();
        flight(zeta, a, 0.0, &z, order, &mut s, None);
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
        let mut s = FlightSeries::default();
        flight(0.0, 0.3, 0.2, &z, order, &mut s, None);
        let h = step_size(&[&s.x[..=order]], order, 1e-16, 1e-16_f64.ln());
        let e0 = 0.5 * 0.2 * 0.2 + crate::potential::energy(0.3);
        let (x, v) = eval_d(&s.x[..=order], h);
        let e1 = 0.5 * v * v + crate::potential::energy(x);
        assert!(h > 0.2, "step {h}");
        assert!((e1 - e0).abs() < 1e-16, "{e1} vs {e0}");
    }
}
