//! Numbers in messages: plain decimals where they are short, scientific notation otherwise
//! (Rust's `{}` writes `1e300` with 301 digits and `5e-324` with 324 decimals). Both forms are
//! the shortest that read back to the same double.

use std::fmt;

/// A value (any unit) formatted for a log message.
#[derive(Debug, Clone, Copy)]
pub struct Num(pub f64);

impl fmt::Display for Num {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let a = self.0.abs();
        if !a.is_finite() || a == 0.0 || (1e-4..1e16).contains(&a) {
            write!(f, "{}", self.0)
        } else {
            write!(f, "{:e}", self.0)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::Num;

    #[test]
    fn short_forms_that_read_back() {
        for (v, s) in [
            (0.07, "0.07"),
            (1e300, "1e300"),
            (5e-324, "5e-324"),
            (-1e-12, "-1e-12"),
            (1e12, "1000000000000"),
            (f64::NAN, "NaN"),
            (f64::NEG_INFINITY, "-inf"),
            (0.0, "0"),
        ] {
            let text = Num(v).to_string();
            assert_eq!(text, s);
            if v.is_finite() {
                assert_eq!(text.parse::<f64>().unwrap(), v);
            }
        }
    }
}
