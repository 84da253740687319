//! Simulation time kept as an unevaluated sum of two doubles.
//!
//! A run of 20,000 natural periods reaches `τ ≈ 1.3e5`, where one ulp of a double is `1.5e-11`.
//! Adding step lengths to a plain `f64` would lose the low bits at every step; keeping the rounding
//! error in `lo` makes the accumulated time exact to about `1e-27` relative, and the shaker phase
//! `Ωτ mod 2π` is then computed from both parts (see [`crate::shaker`]).

use crate::lanes::Lane;

/// An instant `hi + lo` (time units), with `|lo| ≤ ulp(hi)/2`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Instant {
    hi: f64,
    lo: f64,
}

/// Error-free sum: `a + b = s + err` exactly (Knuth's TwoSum), in each lane.
#[inline]
pub(crate) fn two_sum<L: Lane>(a: L, b: L) -> (L, L) {
    let s = a + b;
    let bb = s - a;
    let err = (a - (s - bb)) + (b - bb);
    (s, err)
}

/// `(hi + lo) − (e_hi + e_lo)` as a double (accurate to one rounding) in each lane: instants
/// given by their parts ([`Instant::since`] for one).
#[inline(always)]
pub(crate) fn since<L: Lane>(hi: L, lo: L, e_hi: L, e_lo: L) -> L {
    let (s, e) = two_sum(hi, -e_hi);
    s + (e + (lo - e_lo))
}

/// `x.round()` (halves away from zero) in plain arithmetic, the same value for every `x`: on
/// x86-64 without SSE4.1 `f64::round` is a library call, and this one sits on every plate
/// evaluation.
#[inline]
pub(crate) fn round_half_away(x: f64) -> f64 {
    const TWO_52: f64 = 4_503_599_627_370_496.0;
    let a = x.abs();
    if a >= TWO_52 || a.is_nan() {
        // Already an integer (or NaN).
        return x;
    }
    // a + 2^52 rounds to the nearest integer, halves to even (exact otherwise); a half that
    // went down is taken up.
    let mut r = (a + TWO_52) - TWO_52;
    if r - a == -0.5 {
        r += 1.0;
    }
    r.copysign(x)
}

/// Error-free product: `a * b = p + err` exactly (Dekker; no FMA needed, valid while the
/// operands are below `2^996` in magnitude).
#[inline]
pub(crate) fn two_prod(a: f64, b: f64) -> (f64, f64) {
    let p = a * b;
    let (ah, al) = split(a);
    let (bh, bl) = split(b);
    (p, ((ah * bh - p) + ah * bl + al * bh) + al * bl)
}

/// [`two_prod`], the error by a fused multiply-add (`FMA`, for code compiled with FMA) where
/// Dekker's product is exact, so that both give the same value: operands below `2^995` and a
/// product in `[2^-968, 2^1023)` in magnitude (no split overflows, no partial product
/// underflows). Elsewhere (zero among them), Dekker's product.
#[inline(always)]
fn two_prod_by<const FMA: bool>(a: f64, b: f64) -> (f64, f64) {
    const BIG: f64 = 1e298; // < 2^995
    const TINY: f64 = 1e-291; // > 2^-968
    let p = a * b;
    if FMA && a.abs() < BIG && b.abs() < BIG && p.abs() >= TINY && p.abs() < f64::MAX {
        (p, a.mul_add(b, -p))
    } else {
        two_prod(a, b)
    }
}

/// Veltkamp split of `a` into two halves of 26 significant bits each.
#[inline]
fn split(a: f64) -> (f64, f64) {
    let c = 134_217_729.0 * a;
    let hi = c - (c - a);
    (hi, a - hi)
}

impl Instant {
    /// The instant `t` (exactly).
    pub fn new(t: f64) -> Self {
        Self { hi: t, lo: 0.0 }
    }

    /// The instant `hi + lo` from its two parts, which must be finite with `lo` below half an
    /// ulp of `hi` (as [`Instant::parts`] returns them); `None` otherwise.
    pub fn from_parts(hi: f64, lo: f64) -> Option<Self> {
        let (s, e) = two_sum(hi, lo);
        (hi.is_finite() && lo.is_finite() && s == hi && e == lo).then_some(Self { hi, lo })
    }

    /// Nearest double.
    pub fn to_f64(self) -> f64 {
        self.hi + self.lo
    }

    /// Both parts, `(hi, lo)`.
    pub fn parts(self) -> (f64, f64) {
        (self.hi, self.lo)
    }

    /// `self − earlier` as a double (accurate to one rounding).
    pub fn since(self, earlier: Instant) -> f64 {
        since(self.hi, self.lo, earlier.hi, earlier.lo)
    }

    /// `ω·(self − origin) + offset` reduced to `[−π, π)`, accurate to a few ulps of `2π` for any
    /// instant whose product with `ω` stays below `2^52`.
    pub fn angle(self, origin: Instant, omega: f64, offset: f64) -> f64 {
        #[cfg(target_arch = "x86_64")]
        if crate::simd::fma() {
            // SAFETY: the CPU has FMA (the SIMD path allows only features it has).
            return unsafe { self.angle_fma(origin, omega, offset) };
        }
        self.angle_by::<false>(origin, omega, offset)
    }

    /// [`Instant::angle`] on a CPU with FMA: the same value, sooner (the products' errors
    /// take one instruction each, see [`two_prod_by`]).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "fma")]
    fn angle_fma(self, origin: Instant, omega: f64, offset: f64) -> f64 {
        self.angle_by::<true>(origin, omega, offset)
    }

    /// [`Instant::angle`], with the products' errors by FMA (`FMA`) or by Dekker's product.
    #[inline(always)]
    fn angle_by<const FMA: bool>(self, origin: Instant, omega: f64, offset: f64) -> f64 {
        // d = self - origin as a double-double.
        let (dh, de) = two_sum(self.hi, -origin.hi);
        let dl = de + (self.lo - origin.lo);
        let (dh, dl) = two_sum(dh, dl);
        // p = omega * d + offset as a double-double.
        let (p, pe) = two_prod_by::<FMA>(omega, dh);
        let pe = pe + omega * dl;
        let (p, e2) = two_sum(p, offset);
        let pe = pe + e2;
        // Subtract the nearest multiple of 2π, with 2π in three parts.
        let k = turns(p + pe);
        let (q, qe) = two_prod_by::<FMA>(k, TWO_PI.0);
        let r = (p - q) + (pe - qe - k * TWO_PI.1 - k * TWO_PI.2);
        if r >= std::f64::consts::PI {
            r - TWO_PI.0
        } else if r < -std::f64::consts::PI {
            r + TWO_PI.0
        } else {
            r
        }
    }
}

/// `round(x / 2π)` (halves away from zero), from the product with `1/2π` (a division would
/// sit on every plate evaluation's path), or from the quotient itself where the two could
/// round apart: they differ by under 2 ulps of the result, so only within that of a
/// half-integer.
#[inline(always)]
fn turns(x: f64) -> f64 {
    let y = x * INV_TWO_PI;
    let k = round_half_away(y);
    // `y − k` is exact (`|y − k| ≤ ½`); NaN and `|y| ≥ 2^52` take the quotient.
    if 0.5 - (y - k).abs() > 4.0 * f64::EPSILON * y.abs() {
        k
    } else {
        round_half_away(x / TWO_PI.0)
    }
}

/// `1/2π`, rounded.
const INV_TWO_PI: f64 = 1.0 / std::f64::consts::TAU;

/// `2π` as an unevaluated sum of three doubles.
pub(crate) const TWO_PI: (f64, f64, f64) = (
    std::f64::consts::TAU,
    2.4492935982947064e-16,
    -5.989539619436679e-33,
);

impl std::ops::Add<f64> for Instant {
    type Output = Instant;

    /// `self + dt`, with the rounding error carried into the low part.
    fn add(self, dt: f64) -> Self {
        let (s, e) = two_sum(self.hi, dt);
        let (hi, lo) = two_sum(s, e + self.lo);
        Self { hi, lo }
    }
}

impl PartialOrd for Instant {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        self.since(*other).partial_cmp(&0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn accumulates_without_drift() {
        // 1e6 steps of the double nearest 0.1, whose exact value is 0.1 + 5.551115123125783e-18.
        let mut t = Instant::new(0.0);
        let mut naive = 0.0_f64;
        for _ in 0..1_000_000 {
            t = t + 0.1;
            naive += 0.1;
        }
        let (hi, lo) = t.parts();
        assert_eq!(hi, 100_000.0);
        assert!((lo - 5.551115123125783e-12).abs() < 1e-24, "{lo}");
        // The plain sum is off by many ulps; the two-part sum is not.
        assert!((naive - 100_000.0).abs() > 1e-7);
    }

    #[test]
    fn round_half_away_is_round() {
        let mut xs = vec![
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.5,
            2.5,
            -2.5,
            0.49999999999999994,
            1e15 + 0.5,
        ];
        xs.extend([
            4503599627370495.5,
            4503599627370496.0,
            1e300,
            f64::INFINITY,
            -1e-300,
        ]);
        let mut v = 0.123_f64;
        for _ in 0..10_000 {
            // A spread of magnitudes and signs, and the halves next to them.
            v = (v * 7919.0).fract();
            let x = (v - 0.5) * 10f64.powi((v * 40.0) as i32 - 10);
            xs.extend([x, x.trunc() + 0.5, x.trunc() - 0.5]);
        }
        for x in xs {
            assert_eq!(round_half_away(x).to_bits(), x.round().to_bits(), "{x}");
        }
        assert!(round_half_away(f64::NAN).is_nan());
    }

    /// Instants, frequencies and offsets over the ranges the simulator meets, and edge cases.
    fn angle_cases() -> Vec<(Instant, Instant, f64, f64)> {
        let mut out = Vec::new();
        let mut v = 0.123_456_789_f64;
        for i in 0..20_000 {
            v = (v * 9_301.0 + 0.497_3).fract();
            let t = Instant::new(10f64.powf(8.0 * v - 2.0)) + v * 1e-9;
            let origin = Instant::new(if i % 3 == 0 { 0.0 } else { v * 17.0 });
            let omega = 10f64.powf(3.0 * v - 1.5);
            let offset = (v - 0.5) * 7.0;
            out.push((t, origin, omega, offset));
        }
        // Exact multiples of a half turn, zero, tiny and huge spans.
        let omega = 1.75;
        for k in [0.0, 0.5, 1.0, 2.5, 1e3 + 0.5, 1e6 + 0.5] {
            out.push((
                Instant::new(k * TWO_PI.0 / omega),
                Instant::new(0.0),
                omega,
                0.0,
            ));
        }
        out.push((Instant::new(0.0), Instant::new(0.0), omega, 0.0));
        out.push((Instant::new(1e-300), Instant::new(0.0), 1e-3, 0.0));
        out.push((Instant::new(1e15), Instant::new(0.0), 3.0, 1.0));
        out
    }

    #[test]
    fn angle_with_fma_equals_angle_without_bit_for_bit() {
        for (t, origin, omega, offset) in angle_cases() {
            let plain = t.angle_by::<false>(origin, omega, offset);
            let fma = t.angle_by::<true>(origin, omega, offset);
            assert_eq!(fma.to_bits(), plain.to_bits(), "{t:?} {omega} {offset}");
            assert_eq!(t.angle(origin, omega, offset).to_bits(), plain.to_bits());
        }
    }

    #[test]
    fn turns_equals_the_rounded_quotient() {
        let mut xs = vec![0.0, -0.0, f64::NAN, 1e300, -1e300, 3.0, -3.0];
        for k in 0..2_000 {
            let h = (f64::from(k) - 1_000.0 + 0.5) * TWO_PI.0;
            // At, and a few ulps either side of, half turns.
            let mut x = h;
            for _ in 0..4 {
                xs.extend([x, -x]);
                x = f64::from_bits(x.to_bits() + 1);
            }
            let mut x = h;
            for _ in 0..4 {
                xs.push(x);
                x = f64::from_bits(x.to_bits() - 1);
            }
            xs.push(f64::from(k) * 12_345.678_9);
        }
        for x in xs {
            let want = round_half_away(x / TWO_PI.0);
            assert_eq!(turns(x).to_bits(), want.to_bits(), "{x}");
        }
    }

    #[test]
    fn two_prod_is_exact() {
        let (a, b) = (0.1_f64, 1.75 * 123_456.789);
        let (p, e) = two_prod(a, b);
        assert_eq!(e, a.mul_add(b, -p));
        assert!(e != 0.0);
    }

    #[test]
    fn angle_is_reduced_accurately_at_long_times() {
        // ω·τ with τ = 2π·20000/ω exactly should be a multiple of 2π up to the rounding of τ.
        let omega = 1.75;
        let tau = Instant::new(20_000.0 * TWO_PI.0 / omega);
        let a = tau.angle(Instant::new(0.0), omega, 0.0);
        // Representation error of tau itself: |tau|·2^-53·ω.
        assert!(a.abs() < 1.3e5 * 1.2e-16 * omega * 2.0, "{a}");
        // Offset and sign handling.
        let b = Instant::new(1.0).angle(Instant::new(0.0), 1.0, 3.0);
        assert!((b - (4.0 - 2.0 * std::f64::consts::PI)).abs() < 1e-15);
    }
}
