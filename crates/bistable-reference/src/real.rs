//! The high-precision number type and the few helpers the solver needs.
//!
//! Every number the solver works with is a binary floating-point number with `bits` bits of
//! mantissa, rounded to nearest (ties to even) after every operation. `dashu-float` propagates the
//! larger of the two operands' precisions, so it suffices that every *leaf* value (parameters,
//! constants, `sin`/`cos`) is created with the working precision; integers mixed into an
//! operation (precision 0 = exact) do not lower it.

use dashu_float::{round::mode::HalfEven, FBig};

/// Arbitrary-precision binary float, rounding to nearest-even. The precision (in bits) travels
/// with each value.
pub type Real = FBig<HalfEven, 2>;

/// Working precision: creates leaf values with the right number of bits.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Prec {
    /// Mantissa bits.
    pub bits: usize,
}

impl Prec {
    /// The exact value of a finite `f64`, carried at the working precision.
    pub fn exact(&self, x: f64) -> Real {
        Real::try_from(x)
            .expect("finite f64 (validated by the caller)")
            .with_precision(self.bits)
            .value()
    }

    /// An integer, exactly, at the working precision.
    pub fn int(&self, i: i64) -> Real {
        Real::from(i).with_precision(self.bits).value()
    }

    /// Zero at the working precision.
    pub fn zero(&self) -> Real {
        self.int(0)
    }

    /// `2^-k` at the working precision (exact).
    pub fn pow2_neg(&self, k: usize) -> Real {
        self.int(1) >> (k as isize)
    }

    /// Number of significant decimal digits carried (`bits · log10 2`, rounded down).
    pub fn digits(&self) -> usize {
        (self.bits as f64 * std::f64::consts::LOG10_2).floor() as usize
    }
}

/// Sign of `x` as -1, 0 or +1 (a signed zero is 0).
pub(crate) fn sgn(x: &Real) -> i32 {
    if x.repr().significand().is_zero() {
        0
    } else if *x > Real::ZERO {
        1
    } else {
        -1
    }
}

/// Sign used for root isolation: zero counts as positive, so "a sign change" always means a
/// transition between `>= 0` and `< 0`.
pub(crate) fn sgn_nonneg(x: &Real) -> i32 {
    if sgn(x) < 0 {
        -1
    } else {
        1
    }
}

/// Absolute value.
pub(crate) fn abs(x: &Real) -> Real {
    if sgn(x) < 0 {
        -x.clone()
    } else {
        x.clone()
    }
}

/// Nearest `f64` (ties to even).
pub(crate) fn to_f64(x: &Real) -> f64 {
    x.to_f64().value()
}

/// Decimal representation with `digits` significant digits (rounded to nearest).
pub(crate) fn to_decimal_string(x: &Real, digits: usize) -> String {
    if sgn(x) == 0 {
        return "0".to_string();
    }
    format!(
        "{}",
        x.clone().with_base_and_precision::<10>(digits).value()
    )
}
