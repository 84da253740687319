//! First root of a polynomial on an interval, with no root missed.
//!
//! The polynomial is converted to the Bernstein basis on the step; by the convex-hull property a
//! Bernstein polynomial whose coefficients are all positive has no root. Intervals that cannot be
//! cleared are halved (de Casteljau) left to right, so the first root is isolated first; an
//! interval whose coefficients change sign exactly once holds exactly one crossing, which is then
//! polished to the last bit by safeguarded Newton iteration. A minimum that touches zero (grazing)
//! survives halving down to a width of `2^-44` of the step and is reported as a root there.

use crate::lanes::Lane;
use crate::taylor::{eval, BUF};

/// Width (as a fraction of the step) below which an uncleared interval is reported as a touch.
const MIN_WIDTH: f64 = 1.0 / (1u64 << 44) as f64;

/// First `s ∈ (0, h]` with `p(s) ≤ 0`, for `p(s) = Σ c_k s^k` with `c[0] > 0`.
///
/// Returns the last double before the crossing at which `p` is still positive (so the located
/// instant never lies past the root), or `None` if `p > 0` on all of `[0, h]`.
pub(crate) fn first_root(c: &[f64], h: f64) -> Option<f64> {
    debug_assert!(c[0] > 0.0);
    let n = c.len() - 1;
    // Scale to σ ∈ [0, 1]: d_k = c_k h^k.
    let mut d = [0.0; BUF];
    let mut hk = 1.0;
    for (dk, &ck) in d.iter_mut().zip(c) {
        *dk = ck * hk;
        hk *= h;
    }
    // Cheap certificate: on [0, 1], p(σ) ≥ min of the quadratic part + Σ_{k≥3} min(d_k, 0).
    let tail: f64 = d[3.min(n + 1)..=n].iter().map(|&v| v.min(0.0)).sum();
    if quadratic_min(d[0], d[1], if n >= 2 { d[2] } else { 0.0 }) + tail > 0.0 {
        return None;
    }
    if n > LOW_DEGREE && clearly_positive(&d[..=n]) {
        return None;
    }
    bernstein(&mut d[..=n]);
    search(c, h, &d[..=n], 0.0, 1.0)
}

/// [`first_root`] past its certificates, from the Bernstein coefficients `b` of `p(hσ)` on
/// `σ ∈ [0, 1]` (as [`first_root`] converts them).
pub(crate) fn first_root_from(c: &[f64], h: f64, b: &[f64]) -> Option<f64> {
    search(c, h, b, 0.0, 1.0)
}

/// The cheap certificates of [`first_root`] in each lane of a batch: `true` in a lane whose
/// polynomial `Σ c_k s^k` (`c[0] > 0`, degree `c.len() − 1 > LOW_DEGREE`) [`first_root`]
/// certifies root-free on `[0, h]` without a search, with the same operations, so that it
/// would return `None` there; `false` leaves the lane to [`first_root`].
/// Also returns, in `bern`, the Bernstein coefficients that [`first_root`] converts next.
#[inline(always)]
pub(crate) fn certified_clear<T: Lane>(c: &[T], h: T, bern: &mut [T; BUF]) -> T::Mask {
    let n = c.len() - 1;
    debug_assert!(n > LOW_DEGREE);
    let zero = T::splat(0.0);
    let mut d = [zero; BUF];
    let mut hk = T::splat(1.0);
    for (dk, &ck) in d.iter_mut().zip(c) {
        *dk = ck * hk;
        hk *= h;
    }
    let tail = d[3..=n]
        .iter()
        .fold(T::splat(-0.0), |t, &v| t + v.min(zero));
    let (a, b, q) = (d[0], d[1], d[2]);
    let ends = a.min(a + b + q);
    let inner = T::and(T::and(q.gt(zero), b.lt(zero)), (-b).lt(T::splat(2.0) * q));
    let least = T::select(inner, ends.min(a - b * b / (T::splat(4.0) * q)), ends);
    let quadratic = (least + tail).gt(zero);
    // The second certificate, as `clearly_positive`.
    let size = d[..=n].iter().fold(T::splat(-0.0), |t, &v| t + v.abs());
    let tail = d[LOW_DEGREE + 1..=n]
        .iter()
        .fold(T::splat(-0.0), |t, &v| t + v.min(zero));
    let mut low = [zero; LOW_DEGREE + 1];
    low.copy_from_slice(&d[..=LOW_DEGREE]);
    bernstein(&mut low);
    let least = low.iter().fold(T::splat(f64::INFINITY), |m, &v| m.min(v));
    let sized = size.gt(T::splat(1e-200));
    let clear = T::and(sized, (least + tail).gt(T::splat(1e-11) * size));
    bern[..=n].copy_from_slice(&d[..=n]);
    bernstein(&mut bern[..=n]);
    T::or(quadratic, clear)
}

/// Degree of the part of the polynomial whose Bernstein coefficients [`clearly_positive`] takes.
const LOW_DEGREE: usize = 6;

/// Second certificate, for steps the quadratic one leaves open (most of them when the plate
/// moves fast): on `[0, 1]`, `p(σ) ≥ min_i B_i(p_{≤6}) + Σ_{k>6} min(d_k, 0)`, with `B_i` the
/// Bernstein coefficients of the part of degree at most 6. The bound must clear `1e-11 Σ|d_k|`,
/// far above the rounding of the full search (every value it computes is within about
/// `3e-13 Σ|d_k|` of the polynomial's values), so that the search would have found no root
/// either: the answer is the same, without the degree-`n` conversion.
fn clearly_positive(d: &[f64]) -> bool {
    let n = d.len() - 1;
    let size: f64 = d.iter().map(|v| v.abs()).sum();
    // Rounding relative to the size only holds away from the subnormal range (and a NaN
    // fails here).
    if size.is_nan() || size <= 1e-200 {
        return false;
    }
    let tail: f64 = d[LOW_DEGREE + 1..=n].iter().map(|&v| v.min(0.0)).sum();
    let mut low = [0.0; LOW_DEGREE + 1];
    low.copy_from_slice(&d[..=LOW_DEGREE]);
    bernstein(&mut low);
    let least = low.iter().copied().fold(f64::INFINITY, f64::min);
    least + tail > 1e-11 * size
}

/// Depth-first search of `[a, a + w]` (in units of the step) whose Bernstein coefficients are `b`,
/// left half first, for the first crossing.
fn search(c: &[f64], h: f64, b: &[f64], a: f64, w: f64) -> Option<f64> {
    let n = b.len() - 1;
    if b.iter().all(|&v| v > 0.0) {
        return None;
    }
    if b[0] <= 0.0 {
        // p(a) ≤ 0 at the left end: the previous interval ended positive, so the crossing
        // is at a (to within the previous interval's resolution).
        return Some(polish(c, h, (a - w).max(0.0) * h, a * h, None));
    }
    let changes = b
        .windows(2)
        .filter(|p| (p[0] > 0.0) != (p[1] > 0.0))
        .count();
    if changes == 1 && b[n] <= 0.0 {
        return Some(polish(c, h, a * h, (a + w) * h, Some((b[0], b[n]))));
    }
    if w <= MIN_WIDTH {
        // A minimum within rounding of zero: a grazing contact.
        let m = b.iter().copied().fold(f64::INFINITY, f64::min);
        return (m <= 0.0).then(|| ((a + 0.5 * w) * h).min(h));
    }
    let (left, right) = split(b);
    let half = 0.5 * w;
    search(c, h, &left[..=n], a, half).or_else(|| search(c, h, &right[..=n], a + half, half))
}

/// Minimum of `a + bσ + cσ²` over `σ ∈ [0, 1]`.
fn quadratic_min(a: f64, b: f64, c: f64) -> f64 {
    let ends = a.min(a + b + c);
    if c > 0.0 && b < 0.0 && -b < 2.0 * c {
        ends.min(a - b * b / (4.0 * c))
    } else {
        ends
    }
}

/// Bernstein coefficients of `Σ d_k σ^k` on `[0, 1]`, in place: `b_i = Σ_{k≤i} C(i,k) d_k/C(n,k)`,
/// by the additive triangle (pass `j` adds each coefficient's left neighbour for `i ≥ j`).
#[inline(always)]
fn bernstein<T: Lane>(d: &mut [T]) {
    let n = d.len() - 1;
    for (dk, &inv) in d.iter_mut().zip(&INV_BINOM[n]) {
        *dk *= T::splat(inv);
    }
    // Passes j and j + 1 together: for i > j, (b_i + b_{i−1}) + (b_{i−1} + b_{i−2}) from the
    // old values, descending (in blocks of four) so that these are still the old ones.
    let mut j = 1;
    while j < n {
        let mut end = n + 1;
        while end >= j + 5 {
            let w = &mut d[end - 6..end];
            let t = [
                w[1] + w[0],
                w[2] + w[1],
                w[3] + w[2],
                w[4] + w[3],
                w[5] + w[4],
            ];
            let new = [t[1] + t[0], t[2] + t[1], t[3] + t[2], t[4] + t[3]];
            w[2..].copy_from_slice(&new);
            end -= 4;
        }
        for i in (j + 1..end).rev() {
            d[i] = (d[i] + d[i - 1]) + (d[i - 1] + d[i - 2]);
        }
        d[j] += d[j - 1];
        j += 2;
    }
    if j == n {
        d[n] += d[n - 1];
    }
}

/// `INV_BINOM[n][k] = 1/C(n,k)` for `k ≤ n`, as the running product `Π_{i≤k} i/(n+1−i)`.
static INV_BINOM: [[f64; BUF]; BUF] = {
    let mut t = [[0.0; BUF]; BUF];
    let mut n = 0;
    while n < BUF {
        let mut inv = 1.0;
        t[n][0] = inv;
        let mut k = 1;
        while k <= n {
            inv *= k as f64 / (n + 1 - k) as f64;
            t[n][k] = inv;
            k += 1;
        }
        n += 1;
    }
    t
};

/// De Casteljau split of a Bernstein polynomial at the midpoint.
fn split(b: &[f64]) -> ([f64; BUF], [f64; BUF]) {
    let n = b.len() - 1;
    // Pass r averages neighbours in 0..=n − r, which leaves the right half's r-th coefficient
    // (index n − r) final: the work array ends as the right half.
    let mut right = [0.0; BUF];
    right[..=n].copy_from_slice(b);
    let mut left = [0.0; BUF];
    left[0] = right[0];
    for (r, l) in (1..=n).zip(&mut left[1..]) {
        for i in 0..=n - r {
            right[i] = 0.5 * (right[i] + right[i + 1]);
        }
        *l = right[0];
    }
    (left, right)
}

/// Locates the crossing in a bracket `[lo, hi]` (in `s`) with `p(lo) > 0 ≥ p(hi)` (`ends`: these
/// two values, when the caller knows them). Safeguarded Newton (bisection when Newton leaves the
/// bracket) runs until its update is below two ulps, or `p` is at its rounding level and the
/// updates stop shrinking; then an exponential search from the last iterate and a bisection pin
/// the last double where `p > 0` (never past the crossing), which is returned.
fn polish(c: &[f64], h: f64, mut lo: f64, mut hi: f64, ends: Option<(f64, f64)>) -> f64 {
    hi = hi.min(h);
    // Values at the ends: the Bernstein end coefficients when known, else evaluated.
    let (plo, phi) = ends.unwrap_or_else(|| (eval(c, lo), eval(c, hi)));
    if plo <= 0.0 {
        return lo.max(f64::MIN_POSITIVE);
    }
    // Start from the secant through the bracket ends.
    let mut x = if phi < 0.0 {
        lo + (hi - lo) * (plo / (plo - phi))
    } else {
        0.5 * (lo + hi)
    };
    let mut last_step = f64::INFINITY;
    for _ in 0..100 {
        let (p, dp, size) = eval_d_size(c, x);
        if p > 0.0 {
            lo = x;
        } else {
            hi = x;
        }
        let mut next = x - p / dp;
        if !(next > lo && next < hi) {
            next = 0.5 * (lo + hi);
        }
        let step = (next - x).abs();
        let noisy = p.abs() <= 8.0 * f64::EPSILON * size && step >= 0.5 * last_step;
        if step <= 2.0 * f64::EPSILON * x.abs() || noisy {
            break;
        }
        last_step = step;
        x = next;
    }
    // The last iterate is lo or hi. Exponential search away from it for the other sign, within
    // the bracket, then bisection down to adjacent doubles.
    let (mut a, mut b) = (lo, hi);
    let mut d = f64::EPSILON * x.abs().max(f64::MIN_POSITIVE);
    // The first probe, the one after it and the first midpoint after it are evaluated together
    // (independent chains, in the time of one); later points one by one.
    let first = if x == lo { x + d } else { x - d };
    let second = if x == lo { x + 2.0 * d } else { x - 2.0 * d };
    let ahead = [first, second, 0.5 * (x + first)];
    let known = eval_n(c, ahead);
    let positive = |v: f64| {
        let hit = ahead.iter().position(|s| s.to_bits() == v.to_bits());
        hit.map_or_else(|| eval(c, v), |i| known[i]) > 0.0
    };
    if x == lo {
        while x + d < b {
            if positive(x + d) {
                a = x + d;
                d *= 2.0;
            } else {
                b = x + d;
                break;
            }
        }
    } else {
        while x - d > a {
            if positive(x - d) {
                a = x - d;
                break;
            }
            b = x - d;
            d *= 2.0;
        }
    }
    loop {
        let mid = 0.5 * (a + b);
        if mid <= a || mid >= b {
            return a;
        }
        if positive(mid) {
            a = mid;
        } else {
            b = mid;
        }
    }
}

/// `Σ c_k s^k` at each point of `s` (Horner, as [`eval`], the chains interleaved).
#[inline]
fn eval_n<const N: usize>(c: &[f64], s: [f64; N]) -> [f64; N] {
    let mut acc = [0.0; N];
    for &ck in c.iter().rev() {
        for j in 0..N {
            acc[j] = acc[j] * s[j] + ck;
        }
    }
    acc
}

/// Value, derivative and `Σ |c_k| s^k` (the scale of the rounding error of the value) at `s ≥ 0`.
#[inline]
fn eval_d_size(c: &[f64], s: f64) -> (f64, f64, f64) {
    let (mut p, mut d, mut m) = (0.0_f64, 0.0_f64, 0.0_f64);
    for &ck in c.iter().rev() {
        d = d * s + p;
        p = p * s + ck;
        m = m * s + ck.abs();
    }
    (p, d, m)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn poly_from_roots(roots: &[f64], lead: f64) -> Vec<f64> {
        let mut c = vec![lead];
        for &r in roots {
            let mut next = vec![0.0; c.len() + 1];
            for (k, &ck) in c.iter().enumerate() {
                next[k + 1] += ck;
                next[k] -= r * ck;
            }
            c = next;
        }
        c
    }

    #[test]
    fn finds_the_first_of_several_roots() {
        // (s−0.3)(s−0.31)(s−0.7) · (−1): positive at 0.
        let c = poly_from_roots(&[0.3, 0.31, 0.7], -1.0);
        let r = first_root(&c, 1.0).unwrap();
        // Conditioning: rounding of p (~1e-17) over |p'(0.3)| = 0.004.
        assert!((r - 0.3).abs() < 1e-14, "{r}");
        assert!(eval(&c, r) > 0.0);
        assert!(first_root(&c, 0.29).is_none());
    }

    #[test]
    fn finds_a_narrow_dip_between_samples() {
        // Negative only on (0.5, 0.5 + 1e-9), by at most 2.5e-19 (below the rounding of p):
        // missed by any sampling, found here to within the √ε accuracy of a near-double root.
        let c = poly_from_roots(&[0.5, 0.5 + 1e-9], 1.0);
        let r = first_root(&c, 1.0).unwrap();
        assert!((r - 0.5).abs() < 1e-8, "{r}");
        // A dip of depth 1e-12 and width 2e-6: root error = rounding (~5e-17) / slope (2e-6).
        let c = poly_from_roots(&[0.5, 0.5 + 2e-6], 1.0);
        let r = first_root(&c, 1.0).unwrap();
        assert!((r - 0.5).abs() < 1e-10, "{r}");
    }

    #[test]
    fn double_root_is_a_touch() {
        // Grazing: a minimum 1e-14 below zero.
        let mut c = poly_from_roots(&[0.4, 0.4], 1.0);
        c[0] -= 1e-14;
        let r = first_root(&c, 1.0).unwrap();
        assert!((r - (0.4 - 1e-7)).abs() < 1e-9, "{r}");
        // Lifted by 1e-10 it does not touch.
        let mut lifted = c.clone();
        lifted[0] += 1e-10;
        assert!(first_root(&lifted, 1.0).is_none());
    }

    #[test]
    fn interleaved_evaluation_equals_horner_bit_for_bit() {
        let c = poly_from_roots(&[0.3, 0.31, 0.7, -0.2, 1.3], -1.7);
        for i in 0..1000 {
            let s = [
                f64::from(i) * 1.37e-3,
                0.5 - f64::from(i) * 1e-4,
                1.0 / f64::from(i + 1),
            ];
            let got = eval_n(&c, s);
            for (g, &sj) in got.iter().zip(&s) {
                assert_eq!(g.to_bits(), eval(&c, sj).to_bits(), "{sj}");
            }
        }
    }

    #[test]
    fn second_certificate_clears_only_what_the_search_clears() {
        // Polynomials of degree 24 on [0, 1] whose low part dominates, with a root or not:
        // wherever the certificate clears a polynomial, the full search finds no root.
        let mut cleared = 0;
        let mut v = 0.271_f64;
        for i in 0..20_000 {
            v = (v * 9_301.0 + 0.497_3).fract();
            let mut d = [0.0; 25];
            d[0] = 10f64.powf(-6.0 * v);
            let mut w = v;
            for (k, dk) in d.iter_mut().enumerate().skip(1) {
                w = (w * 9_301.0 + 0.497_3).fract();
                *dk = (w - 0.5) * 2.0 * 0.8f64.powi(k as i32) * if i % 2 == 0 { 0.01 } else { 1.0 };
            }
            let mut b = d;
            bernstein(&mut b);
            let found = search(&d, 1.0, &b, 0.0, 1.0);
            if clearly_positive(&d) {
                cleared += 1;
                assert!(found.is_none(), "case {i}: {d:?}");
            }
        }
        // The certificate does clear many of them (not a vacuous pass).
        assert!(cleared > 2_000, "{cleared}");
    }

    #[test]
    fn bernstein_matches_definition() {
        let d = [0.3, -1.2, 0.7, 2.5, -0.4];
        let mut b = d;
        bernstein(&mut b);
        let binom =
            |n: u64, k: u64| -> f64 { (1..=k).map(|j| (n + 1 - j) as f64 / j as f64).product() };
        for i in 0..5u64 {
            let want: f64 = (0..=i)
                .map(|k| binom(i, k) / binom(4, k) * d[k as usize])
                .sum();
            assert!((b[i as usize] - want).abs() < 1e-15, "{i}");
        }
    }

    #[test]
    fn high_degree_polynomial() {
        // A degree-20 polynomial with its first root at 0.123456789.
        let mut roots: Vec<f64> = (0..19).map(|i| 0.5 + 0.03 * f64::from(i)).collect();
        roots.push(0.123456789);
        let c = poly_from_roots(&roots, 1.0);
        let r = first_root(&c, 0.9).unwrap();
        // Ill-conditioned (Wilkinson-like): small |p'(r)| against the rounding of p.
        assert!((r - 0.123456789).abs() < 1e-13, "{r}");
    }
}
