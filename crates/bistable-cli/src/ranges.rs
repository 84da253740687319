//! Parameter ranges `A:B:N` (N evenly spaced values from A to B, both included) and lists of
//! numbers, as parsed from the command line.

use std::fmt;
use std::str::FromStr;

use bistable_core::{MAX_VELOCITY, OMEGA_RANGE};

use crate::error::CliError;

/// Most values one range may have.
pub use bistable_analysis::grid::MAX_POINTS;

/// `N` evenly spaced values from `A` to `B`, both ends included (`N = 1`: just `A`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Range {
    /// First value.
    pub start: f64,
    /// Last value.
    pub end: f64,
    /// Number of values (>= 1).
    pub n: usize,
}

impl Range {
    /// The `i`-th value; exactly `start` and `end` at the ends.
    pub fn value(&self, i: usize) -> f64 {
        bistable_analysis::grid::value(self.start, self.end, self.n, i)
    }

    /// All values in order.
    pub fn values(&self) -> Vec<f64> {
        (0..self.n).map(|i| self.value(i)).collect()
    }

    /// Spacing of the values (0 for a single value).
    pub fn step(&self) -> f64 {
        if self.n > 1 {
            (self.end - self.start) / (self.n - 1) as f64
        } else {
            0.0
        }
    }

    /// Smallest and largest value.
    pub fn bounds(&self) -> (f64, f64) {
        (self.start.min(self.end), self.start.max(self.end))
    }

    /// [`Range::check`] for shaker frequency ratios: `Ω` in the core's [`OMEGA_RANGE`].
    pub fn omegas(&self, option: &str) -> Result<Self, CliError> {
        self.check(
            option,
            |w| OMEGA_RANGE.contains(&w),
            "Ω must be in [1e-6, 1e6]",
        )
    }

    /// [`Range::check`] for shaker velocity amplitudes: `V` in `[0, `[`MAX_VELOCITY`]`]`.
    pub fn velocities(&self, option: &str) -> Result<Self, CliError> {
        self.check(
            option,
            |v| (0.0..=MAX_VELOCITY).contains(&v),
            "V must be in [0, 1e6]",
        )
    }

    /// Checks that every value satisfies `ok`; the error names `option` and states `rule`.
    pub fn check(
        &self,
        option: &str,
        ok: impl Fn(f64) -> bool,
        rule: &str,
    ) -> Result<Self, CliError> {
        if ok(self.start) && ok(self.end) {
            Ok(*self)
        } else {
            Err(CliError::invalid_text(option, self, rule))
        }
    }
}

impl fmt::Display for Range {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}:{}", self.start, self.end, self.n)
    }
}

impl FromStr for Range {
    type Err = String;

    /// `A:B:N` with finite `A`, `B` and an integer `1 <= N <= 10^7` (`A = B` when `N = 1`).
    fn from_str(s: &str) -> Result<Self, String> {
        let parts: Vec<&str> = s.split(':').map(str::trim).collect();
        let [a, b, n] = parts[..] else {
            return Err(
                "expected A:B:N (first value, last value, number of values), e.g. \
                        0.2:3.5:300"
                    .to_string(),
            );
        };
        let number = |t: &str, what: &str| -> Result<f64, String> {
            match t.parse::<f64>() {
                Ok(x) if x.is_finite() => Ok(x),
                _ => Err(format!("{what} '{t}' is not a finite number")),
            }
        };
        let start = number(a, "A")?;
        let end = number(b, "B")?;
        let n: usize = n
            .parse()
            .map_err(|_| format!("N '{n}' is not a whole number >= 1"))?;
        if n == 0 || n > MAX_POINTS {
            return Err(format!("N must be in [1, {MAX_POINTS}], got {n}"));
        }
        if n == 1 && start != end {
            return Err("N = 1 needs A = B (a single value)".to_string());
        }
        if n > 1 && start == end {
            return Err("A = B needs N = 1".to_string());
        }
        Ok(Self { start, end, n })
    }
}

/// A pair `X,V` of finite numbers (e.g. an initial guess `x,x'`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pair(pub f64, pub f64);

impl FromStr for Pair {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        let parts: Vec<&str> = s.split(',').map(str::trim).collect();
        let [a, b] = parts[..] else {
            return Err("expected two numbers separated by a comma, e.g. 0.05,0.1".to_string());
        };
        let number = |t: &str| -> Result<f64, String> {
            match t.parse::<f64>() {
                Ok(x) if x.is_finite() => Ok(x),
                _ => Err(format!("'{t}' is not a finite number")),
            }
        };
        Ok(Pair(number(a)?, number(b)?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_and_spaces_values() {
        let r: Range = "0.001:0.2:200".parse().unwrap();
        assert_eq!(r.n, 200);
        assert_eq!(r.value(0), 0.001);
        assert_eq!(r.value(199), 0.2);
        assert!((r.value(69) - 0.07).abs() < 1e-15);
        assert!((r.step() - 0.001).abs() < 1e-15);
        let one: Range = "0.5:0.5:1".parse().unwrap();
        assert_eq!(one.values(), vec![0.5]);
        let down: Range = "3:1:3".parse().unwrap();
        assert_eq!(down.values(), vec![3.0, 2.0, 1.0]);
        assert_eq!(down.bounds(), (1.0, 3.0));
    }

    #[test]
    fn rejects_malformed_ranges() {
        for bad in [
            "", "1:2", "1:2:3:4", "a:2:3", "1:2:0", "1:2:-1", "1:2:2.5", "1:2:1", "1:1:5",
            "nan:2:3", "1:inf:3",
        ] {
            assert!(bad.parse::<Range>().is_err(), "{bad}");
        }
        assert!("1,2,3".parse::<Pair>().is_err());
        assert_eq!("0.1, -2".parse::<Pair>().unwrap(), Pair(0.1, -2.0));
    }
}
