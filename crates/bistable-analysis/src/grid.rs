//! Evenly spaced parameter values, the `A:B:N` ranges of the CLI and the Python package: `N`
//! values from `A` to `B`, both ends included exactly.

/// Most values one range may have.
pub const MAX_POINTS: usize = 10_000_000;

/// The `i`-th of `n` evenly spaced values from `start` to `end`: exactly `start` at `i = 0` (and
/// for `n = 1`), exactly `end` at `i = n − 1`, `start + (end − start)·i/(n − 1)` in between.
pub fn value(start: f64, end: f64, n: usize, i: usize) -> f64 {
    if n == 1 || i == 0 {
        start
    } else if i + 1 == n {
        end
    } else {
        start + (end - start) * (i as f64 / (n - 1) as f64)
    }
}

/// The `n` evenly spaced values from `start` to `end` (see [`value`]).
pub fn linspace(start: f64, end: f64, n: usize) -> Vec<f64> {
    (0..n).map(|i| value(start, end, n, i)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ends_are_exact() {
        let v = linspace(0.001, 0.2, 200);
        assert_eq!((v[0], v[199]), (0.001, 0.2));
        assert!((v[69] - 0.07).abs() < 1e-15);
        assert_eq!(linspace(0.5, 0.5, 1), vec![0.5]);
        assert_eq!(linspace(3.0, 1.0, 3), vec![3.0, 2.0, 1.0]);
        assert!(linspace(1.0, 2.0, 0).is_empty());
    }
}
