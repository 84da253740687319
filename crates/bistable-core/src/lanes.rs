//! Lane types: the number types the integrator's kernels are written over.
//!
//! A kernel generic over [`Lane`] computes one trajectory with `f64` and `N` independent
//! trajectories at once with [`F64x4`] or [`F64x8`], one per SIMD lane ([`F64x16`], two AVX-512
//! registers, for evaluations whose latency two independent chains hide). Every operation is
//! the IEEE operation of each lane on its own (no fused multiply-add, no reassociation), so
//! lane `i` of a batch computes bit for bit what the `f64` kernel computes for trajectory
//! `i`: the batch is the same integrator, not a second one. Functions whose vector versions
//! would round differently (`ln`, `exp`, `sin_cos`) are not lane operations; callers apply the
//! scalar function to each lane ([`Lane::map`]).

use std::ops::{Add, AddAssign, Div, Mul, MulAssign, Neg, Sub};

/// A number type of `LANES` doubles with lane-wise IEEE arithmetic.
pub trait Lane:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + AddAssign
    + MulAssign
{
    /// Lanes.
    const LANES: usize;
    /// Per-lane booleans.
    type Mask: Copy + Default;

    /// Every lane `v`.
    fn splat(v: f64) -> Self;
    /// `|x|` in each lane.
    fn abs(self) -> Self;
    /// [`f64::max`] in each lane.
    fn max(self, other: Self) -> Self;
    /// [`f64::min`] in each lane.
    fn min(self, other: Self) -> Self;
    /// `self > other` in each lane.
    fn gt(self, other: Self) -> Self::Mask;
    /// `self < other` in each lane.
    fn lt(self, other: Self) -> Self::Mask;
    /// `self == other` in each lane.
    fn equal(self, other: Self) -> Self::Mask;
    /// Lane-wise `a && b`.
    fn and(a: Self::Mask, b: Self::Mask) -> Self::Mask;
    /// Lane-wise `a || b`.
    fn or(a: Self::Mask, b: Self::Mask) -> Self::Mask;
    /// Whether lane `i` of `mask` is set.
    fn test_lane(mask: Self::Mask, i: usize) -> bool;
    /// Lane `i`.
    fn lane(&self, i: usize) -> f64;
    /// Sets lane `i` to `v`.
    fn set_lane(&mut self, i: usize, v: f64);
    /// Lane-wise `if mask { yes } else { no }`.
    fn select(mask: Self::Mask, yes: Self, no: Self) -> Self;
    /// `f` applied to each lane (for functions that are not lane operations).
    fn map(self, f: impl Fn(f64) -> f64) -> Self;
}

impl Lane for f64 {
    const LANES: usize = 1;
    type Mask = bool;

    #[inline(always)]
    fn splat(v: f64) -> Self {
        v
    }
    #[inline(always)]
    fn abs(self) -> Self {
        f64::abs(self)
    }
    #[inline(always)]
    fn max(self, other: Self) -> Self {
        f64::max(self, other)
    }
    #[inline(always)]
    fn min(self, other: Self) -> Self {
        f64::min(self, other)
    }
    #[inline(always)]
    fn gt(self, other: Self) -> bool {
        self > other
    }
    #[inline(always)]
    fn lt(self, other: Self) -> bool {
        self < other
    }
    #[inline(always)]
    fn equal(self, other: Self) -> bool {
        self == other
    }
    #[inline(always)]
    fn and(a: bool, b: bool) -> bool {
        a && b
    }
    #[inline(always)]
    fn or(a: bool, b: bool) -> bool {
        a || b
    }
    #[inline(always)]
    fn test_lane(mask: bool, _: usize) -> bool {
        mask
    }
    #[inline(always)]
    fn lane(&self, _: usize) -> f64 {
        *self
    }
    #[inline(always)]
    fn set_lane(&mut self, _: usize, v: f64) {
        *self = v;
    }
    #[inline(always)]
    fn select(mask: bool, yes: Self, no: Self) -> Self {
        if mask {
            yes
        } else {
            no
        }
    }
    #[inline(always)]
    fn map(self, f: impl Fn(f64) -> f64) -> Self {
        f(self)
    }
}

macro_rules! lanes {
    ($name:ident, $n:literal, $align:literal) => {
        #[doc = concat!($n, " doubles, one trajectory per lane.")]
        #[derive(Debug, Clone, Copy, PartialEq)]
        #[repr(C, align($align))]
        pub struct $name(pub [f64; $n]);

        impl Default for $name {
            fn default() -> Self {
                Self([0.0; $n])
            }
        }

        impl From<f64> for $name {
            /// Every lane `v`.
            #[inline(always)]
            fn from(v: f64) -> Self {
                Self([v; $n])
            }
        }

        impl $name {
            #[inline(always)]
            fn zip(self, o: Self, f: impl Fn(f64, f64) -> f64) -> Self {
                let mut r = [0.0; $n];
                for i in 0..$n {
                    r[i] = f(self.0[i], o.0[i]);
                }
                Self(r)
            }

            #[inline(always)]
            fn test(self, o: Self, f: impl Fn(f64, f64) -> bool) -> [bool; $n] {
                let mut r = [false; $n];
                for i in 0..$n {
                    r[i] = f(self.0[i], o.0[i]);
                }
                r
            }
        }

        impl Add for $name {
            type Output = Self;
            #[inline(always)]
            fn add(self, o: Self) -> Self {
                self.zip(o, |a, b| a + b)
            }
        }
        impl Sub for $name {
            type Output = Self;
            #[inline(always)]
            fn sub(self, o: Self) -> Self {
                self.zip(o, |a, b| a - b)
            }
        }
        impl Mul for $name {
            type Output = Self;
            #[inline(always)]
            fn mul(self, o: Self) -> Self {
                self.zip(o, |a, b| a * b)
            }
        }
        impl Div for $name {
            type Output = Self;
            #[inline(always)]
            fn div(self, o: Self) -> Self {
                self.zip(o, |a, b| a / b)
            }
        }
        impl Neg for $name {
            type Output = Self;
            #[inline(always)]
            fn neg(self) -> Self {
                self.map(|a| -a)
            }
        }
        impl AddAssign for $name {
            #[inline(always)]
            fn add_assign(&mut self, o: Self) {
                *self = *self + o;
            }
        }
        impl MulAssign for $name {
            #[inline(always)]
            fn mul_assign(&mut self, o: Self) {
                *self = *self * o;
            }
        }

        impl Lane for $name {
            const LANES: usize = $n;
            type Mask = [bool; $n];

            #[inline(always)]
            fn splat(v: f64) -> Self {
                Self([v; $n])
            }
            #[inline(always)]
            fn abs(self) -> Self {
                self.map(f64::abs)
            }
            #[inline(always)]
            fn max(self, o: Self) -> Self {
                self.zip(o, f64::max)
            }
            #[inline(always)]
            fn min(self, o: Self) -> Self {
                self.zip(o, f64::min)
            }
            #[inline(always)]
            fn gt(self, o: Self) -> [bool; $n] {
                self.test(o, |a, b| a > b)
            }
            #[inline(always)]
            fn lt(self, o: Self) -> [bool; $n] {
                self.test(o, |a, b| a < b)
            }
            #[inline(always)]
            fn equal(self, o: Self) -> [bool; $n] {
                self.test(o, |a, b| a == b)
            }
            #[inline(always)]
            fn and(a: [bool; $n], b: [bool; $n]) -> [bool; $n] {
                let mut r = [false; $n];
                for i in 0..$n {
                    r[i] = a[i] && b[i];
                }
                r
            }
            #[inline(always)]
            fn or(a: [bool; $n], b: [bool; $n]) -> [bool; $n] {
                let mut r = [false; $n];
                for i in 0..$n {
                    r[i] = a[i] || b[i];
                }
                r
            }
            #[inline(always)]
            fn test_lane(mask: [bool; $n], i: usize) -> bool {
                mask[i]
            }
            #[inline(always)]
            fn lane(&self, i: usize) -> f64 {
                self.0[i]
            }
            #[inline(always)]
            fn set_lane(&mut self, i: usize, v: f64) {
                self.0[i] = v;
            }
            #[inline(always)]
            fn select(m: [bool; $n], yes: Self, no: Self) -> Self {
                let mut r = [0.0; $n];
                for i in 0..$n {
                    r[i] = if m[i] { yes.0[i] } else { no.0[i] };
                }
                Self(r)
            }
            #[inline(always)]
            fn map(self, f: impl Fn(f64) -> f64) -> Self {
                let mut r = [0.0; $n];
                for i in 0..$n {
                    r[i] = f(self.0[i]);
                }
                Self(r)
            }
        }
    };
}

lanes!(F64x4, 4, 32);
lanes!(F64x8, 8, 64);
lanes!(F64x16, 16, 64);

/// Lane width of a batch: how many trajectories advance together.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Width {
    /// One trajectory at a time: the scalar [`crate::Simulator`] path.
    One,
    /// Four lanes (AVX2 registers; the portable build when the CPU has neither).
    Four,
    /// Eight lanes (AVX-512 registers).
    Eight,
}

impl Width {
    /// The width sweeps use unless told otherwise: 4. Measured on an AMD EPYC (Zen 4, whose AVX-512 units execute
    /// each 512-bit operation as two 256-bit halves), 8 lanes cost as much per lane-step as 4
    /// and leave more lanes idle in a sweep, so the `map` is slower with 8
    /// (`docs/benchmarks.md`); 4 lanes run in AVX2 registers where the CPU has them.
    pub fn preferred() -> Self {
        Width::Four
    }

    /// The width with `n` lanes (1, 4 or 8).
    pub fn from_lanes(n: usize) -> Option<Self> {
        match n {
            1 => Some(Width::One),
            4 => Some(Width::Four),
            8 => Some(Width::Eight),
            _ => None,
        }
    }

    /// The narrower of `self` and `other`.
    pub fn min_with(self, other: Width) -> Width {
        if self.lanes() <= other.lanes() {
            self
        } else {
            other
        }
    }

    /// The fewest lanes needing a free step for which a batch runs its kernel; fewer take the
    /// lone simulator's step. A pass costs about 1.5 lone steps with 4 lanes and 3 with 8
    /// whatever the number of lanes it carries (one trajectory alone in a batch, on the
    /// Zen 4 machine of `docs/benchmarks.md`).
    pub(crate) fn min_kernel_lanes(self) -> usize {
        match self {
            Width::One => usize::MAX,
            Width::Four => 2,
            Width::Eight => 3,
        }
    }

    /// Lanes: 1, 4 or 8.
    pub fn lanes(self) -> usize {
        match self {
            Width::One => 1,
            Width::Four => 4,
            Width::Eight => 8,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lane_operations_are_the_scalar_ones() {
        let a = F64x4([1.5, -0.0, f64::NAN, 3e-310]);
        let b = F64x4([0.1, 0.0, 2.0, -7.0]);
        let check = |v: F64x4, f: &dyn Fn(f64, f64) -> f64| {
            for i in 0..4 {
                assert_eq!(v.0[i].to_bits(), f(a.0[i], b.0[i]).to_bits(), "lane {i}");
            }
        };
        check(a + b, &|x, y| x + y);
        check(a - b, &|x, y| x - y);
        check(a * b, &|x, y| x * y);
        check(a / b, &|x, y| x / y);
        check(a.max(b), &f64::max);
        check(a.min(b), &f64::min);
        check(-a.abs(), &|x, _| -x.abs());
        let m = a.gt(b);
        check(F64x4::select(m, a, b), &|x, y| if x > y { x } else { y });
        assert_eq!(Width::from_lanes(8), Some(Width::Eight));
        assert_eq!(Width::from_lanes(3), None);
        assert!(Width::preferred().lanes() >= 4);
    }
}
