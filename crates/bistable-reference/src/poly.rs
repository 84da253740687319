//! Polynomials in monomial form and a robust search for their sign changes on an interval.
//!
//! Root isolation uses the Bernstein form on `[0, 1]` (after scaling `s = h·t`):
//! the number of sign changes `V` of the Bernstein coefficients bounds the number of roots in the
//! interval and has the same parity (Descartes' rule of signs in Bernstein form). `V = 0` proves
//! there is no root, `V = 1` proves there is exactly one simple root, and otherwise the interval is
//! halved with de Casteljau's algorithm. Each isolated root is then refined to full working
//! precision by Newton's method safeguarded with bisection.
//!
//! Sign convention: zero counts as positive. "A root" always means a point where the polynomial
//! goes from `>= 0` to `< 0` or back. A touch of zero without a sign change (exact tangency) is
//! not a root, and neither is a dip below zero narrower than `h·2^-max_depth` (such a dip is
//! about `2^-(2·max_depth)` deep, far below the working precision).

use crate::real::{abs, sgn, sgn_nonneg, Prec, Real};

/// `p(s)` by Horner's rule.
pub(crate) fn eval(a: &[Real], s: &Real) -> Real {
    let mut acc = a[a.len() - 1].clone();
    for c in a[..a.len() - 1].iter().rev() {
        acc = acc * s + c;
    }
    acc
}

/// `(p(s), p'(s))` by Horner's rule.
pub(crate) fn eval_with_derivative(a: &[Real], s: &Real) -> (Real, Real) {
    let n = a.len() - 1;
    let mut p = a[n].clone();
    let mut dp = Real::ZERO;
    for c in a[..n].iter().rev() {
        dp = dp * s + &p;
        p = p * s + c;
    }
    (p, dp)
}

/// The polynomial divided by the largest power of `s` that divides it exactly (its leading
/// coefficients that are exactly zero are dropped). Returns the quotient and that power.
pub(crate) fn strip_zero_root(a: &[Real]) -> (&[Real], usize) {
    let m = a.iter().take_while(|c| sgn(c) == 0).count();
    (&a[m.min(a.len() - 1)..], m)
}

/// Root finder with cached binomial coefficients.
pub(crate) struct RootFinder {
    prec: Prec,
    /// Maximum bisection depth of the isolation.
    max_depth: usize,
    /// `binom[n][k] = C(n, k)` as exact reals, filled on demand.
    binom: Vec<Vec<Real>>,
}

impl RootFinder {
    pub fn new(prec: Prec) -> Self {
        RootFinder {
            prec,
            // Two roots closer than about 2^-(bits/2) are indistinguishable from a double root at
            // working precision; resolving the interval beyond that gains nothing.
            max_depth: prec.bits / 2 + 8,
            binom: Vec::new(),
        }
    }

    fn binomials(&mut self, n: usize) -> &[Real] {
        while self.binom.len() <= n {
            let m = self.binom.len();
            // Pascal's triangle with exact (unrounded, precision 0) integers, then carried at the
            // working precision (exact as long as C(m, k) < 2^bits, true for m < bits).
            let mut row = Vec::with_capacity(m + 1);
            if m == 0 {
                row.push(Real::ONE);
            } else {
                let prev = &self.binom[m - 1];
                row.push(Real::ONE);
                for k in 1..m {
                    row.push(&prev[k - 1] + &prev[k]);
                }
                row.push(Real::ONE);
            }
            self.binom.push(row);
        }
        &self.binom[n]
    }

    /// The roots (sign changes) of `p(s) = Σ a_k s^k` in `(0, h]`, ascending, refined to working
    /// precision; at most `max_roots` of them (the leftmost ones).
    ///
    /// `p(0)` must be nonzero (divide out a root at `s = 0` first, see [`strip_zero_root`]).
    pub fn roots(&mut self, a: &[Real], h: &Real, max_roots: usize) -> Vec<Real> {
        let n = a.len() - 1;
        debug_assert!(sgn(&a[0]) != 0, "p(0) must be nonzero");
        // Scaled coefficients: p(h t) = Σ c_k t^k, t in [0, 1].
        let mut c = Vec::with_capacity(n + 1);
        let mut hk = self.prec.int(1);
        for ak in a {
            c.push(ak * &hk);
            hk *= h;
        }
        // Cheap exclusion: |c_0| > Σ_{k>=1} |c_k| means p has the sign of c_0 on all of [0, 1].
        let mut tail = self.prec.zero();
        for ck in &c[1..] {
            tail += abs(ck);
        }
        if abs(&c[0]) > tail {
            return Vec::new();
        }
        if n == 0 {
            return Vec::new();
        }
        // Bernstein coefficients: b_i = Σ_k C(i,k)/C(n,k) c_k, computed as the binomial
        // transform of d_k = c_k / C(n,k) (only additions after the divisions).
        let binom = self.binomials(n).to_vec();
        let mut b: Vec<Real> = c.iter().zip(&binom).map(|(ck, bk)| ck / bk).collect();
        for j in 1..=n {
            for i in (j..=n).rev() {
                let prev = b[i - 1].clone();
                b[i] += prev;
            }
        }
        let mut brackets = Vec::new();
        let zero = self.prec.zero();
        let one = self.prec.int(1);
        self.isolate(&b, zero, one, 0, max_roots, &mut brackets);
        brackets
            .into_iter()
            .map(|(lo, hi)| self.refine(&c, lo, hi) * h)
            .collect()
    }

    /// Depth-first (left half first) isolation of sign changes of the Bernstein polynomial `b`
    /// on `[lo, hi]` (in `t`). Pushes brackets `(lo, hi)` whose end values differ in sign.
    fn isolate(
        &self,
        b: &[Real],
        lo: Real,
        hi: Real,
        depth: usize,
        max_roots: usize,
        out: &mut Vec<(Real, Real)>,
    ) {
        if out.len() >= max_roots {
            return;
        }
        let n = b.len() - 1;
        let changes = b
            .windows(2)
            .filter(|w| sgn_nonneg(&w[0]) != sgn_nonneg(&w[1]))
            .count();
        if changes == 0 {
            return;
        }
        let ends_differ = sgn_nonneg(&b[0]) != sgn_nonneg(&b[n]);
        if changes == 1 {
            // Exactly one simple root; b_0 = p(lo) and b_n = p(hi) differ in sign.
            out.push((lo, hi));
            return;
        }
        if depth >= self.max_depth {
            // A cluster of roots narrower than the resolution: an odd number of crossings is
            // one crossing, an even number is a touch without effect.
            if ends_differ {
                out.push((lo, hi));
            }
            return;
        }
        // de Casteljau subdivision at the midpoint (halving is exact in binary).
        let mut work = b.to_vec();
        let mut left = Vec::with_capacity(n + 1);
        let mut right = vec![self.prec.zero(); n + 1];
        left.push(work[0].clone());
        right[n] = work[n].clone();
        for r in 1..=n {
            for i in 0..=(n - r) {
                work[i] = (&work[i] + &work[i + 1]) >> 1isize;
            }
            left.push(work[0].clone());
            right[n - r] = work[n - r].clone();
        }
        let mid = (&lo + &hi) >> 1isize;
        self.isolate(&left, lo, mid.clone(), depth + 1, max_roots, out);
        self.isolate(&right, mid, hi, depth + 1, max_roots, out);
    }

    /// Refine the single sign change of `p(t) = Σ c_k t^k` in `[lo, hi]` (end values of opposite
    /// sign) to working precision: Newton steps, falling back to bisection whenever a step leaves
    /// the current bracket.
    fn refine(&self, c: &[Real], mut lo: Real, mut hi: Real) -> Real {
        let sign_lo = sgn_nonneg(&eval(c, &lo));
        let tol = self.prec.pow2_neg(self.prec.bits - 3);
        // Start from the secant (regula falsi) point: exact for nearly linear pieces, and it
        // lands next to a root that sits very close to an end of a wide bracket.
        let p_lo = eval(c, &lo);
        let p_hi = eval(c, &hi);
        let mut t = &lo - &p_lo * (&hi - &lo) / (&p_hi - &p_lo);
        if !(t > lo && t < hi) {
            t = (&lo + &hi) >> 1isize;
        }
        for _ in 0..(4 * self.prec.bits) {
            let (p, dp) = eval_with_derivative(c, &t);
            if sgn(&p) == 0 {
                return t;
            }
            if sgn_nonneg(&p) == sign_lo {
                lo = t.clone();
            } else {
                hi = t.clone();
            }
            let mut next = if sgn(&dp) != 0 {
                &t - &p / &dp
            } else {
                (&lo + &hi) >> 1isize
            };
            if !(next > lo && next < hi) {
                next = (&lo + &hi) >> 1isize;
            }
            let step = abs(&(&next - &t));
            let scale = abs(&next);
            t = next;
            if step <= &tol * &scale || abs(&(&hi - &lo)) <= &tol * &abs(&hi) {
                break;
            }
        }
        t
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(prec: Prec, xs: &[f64]) -> Vec<Real> {
        xs.iter().map(|&x| prec.exact(x)).collect()
    }

    #[test]
    fn finds_both_roots_of_a_shallow_dip() {
        let prec = Prec { bits: 128 };
        let mut rf = RootFinder::new(prec);
        // (s - 0.5)^2 - 1e-12 = s^2 - s + 0.25 - 1e-12: roots 0.5 ± 1e-6.
        let mut a = p(prec, &[0.25, -1.0, 1.0]);
        a[0] -= prec.exact(1e-12);
        let r = rf.roots(&a, &prec.int(1), 10);
        assert_eq!(r.len(), 2);
        let r0 = crate::real::to_f64(&r[0]);
        let r1 = crate::real::to_f64(&r[1]);
        assert!((r0 - (0.5 - 1e-6)).abs() < 1e-15, "{r0}");
        assert!((r1 - (0.5 + 1e-6)).abs() < 1e-15, "{r1}");
    }

    #[test]
    fn exact_double_root_is_not_a_sign_change() {
        let prec = Prec { bits: 128 };
        let mut rf = RootFinder::new(prec);
        let a = p(prec, &[0.25, -1.0, 1.0]);
        assert!(rf.roots(&a, &prec.int(1), 10).is_empty());
    }

    #[test]
    fn root_is_refined_to_working_precision() {
        let prec = Prec { bits: 160 };
        let mut rf = RootFinder::new(prec);
        // s^3 - 2 on (0, 2]: cube root of 2.
        let a = p(prec, &[-2.0, 0.0, 0.0, 1.0]);
        let r = rf.roots(&a, &prec.int(2), 1);
        assert_eq!(r.len(), 1);
        let cube = &r[0] * &r[0] * &r[0] - prec.int(2);
        assert!(abs(&cube) < prec.pow2_neg(150));
    }

    #[test]
    fn tiny_root_next_to_the_start() {
        let prec = Prec { bits: 128 };
        let mut rf = RootFinder::new(prec);
        // 1e-20 - 0.05 s + s^2: root near 2e-19.
        let a = p(prec, &[1e-20, -0.05, 1.0]);
        let r = rf.roots(&a, &prec.exact(0.01), 1);
        assert_eq!(r.len(), 1);
        let val = eval(&a, &r[0]);
        assert!(
            abs(&val) < prec.pow2_neg(190),
            "{}",
            crate::real::to_f64(&val)
        );
        assert!((crate::real::to_f64(&r[0]) / 2e-19 - 1.0).abs() < 1e-10);
    }
}
