//! Periods and distinct values of recorded steady states.

/// Largest period (shaker periods) the analyses look for on a recorded steady state.
pub const MAX_PERIOD: usize = 16;
/// Relative agreement of section points a period apart that counts as periodic, for recorded
/// steady states (see [`detect_period`]).
pub const PERIOD_TOL: f64 = 1e-7;

/// Smallest `p <= max_p` with which the last `2p + 4` section points `(x, x')` repeat to `tol`
/// (relative to `max(1, |y|)`), needing at least `3p + 4` points; `None` if there is none.
pub fn detect_period(sections: &[(f64, f64)], max_p: usize, tol: f64) -> Option<usize> {
    let n = sections.len();
    (1..=max_p).find(|&p| {
        let need = 3 * p + 4;
        n >= need
            && (n - (2 * p + 4)..n).all(|i| {
                let (a, b) = (sections[i], sections[i - p]);
                let scale = a.0.abs().max(a.1.abs()).max(1.0);
                (a.0 - b.0).abs().max((a.1 - b.1).abs()) <= tol * scale
            })
    })
}

/// Number of distinct finite values, counting values within `tol·max(1, |x|)` of their sorted
/// neighbour as one.
pub fn distinct(values: &[f64], tol: f64) -> usize {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    v.sort_by(f64::total_cmp);
    v.windows(2)
        .filter(|w| w[1] - w[0] > tol * w[1].abs().max(1.0))
        .count()
        + usize::from(!v.is_empty())
}

/// A steady state's period as the analyses write it: `P-n` for period `n`, else `chaotic` or
/// `aperiodic` (in the map's outcomes, the basins' attractor labels and the sensitivity
/// test's outcome keys).
pub fn label(period: Option<u32>, chaotic: bool) -> String {
    match (period, chaotic) {
        (Some(p), _) => format!("P-{p}"),
        (None, true) => "chaotic".into(),
        (None, false) => "aperiodic".into(),
    }
}

/// The period and chaos verdict of a [`label`] (`None` for any other text).
pub fn parse_label(text: &str) -> Option<(Option<u32>, bool)> {
    match text {
        "chaotic" => Some((None, true)),
        "aperiodic" => Some((None, false)),
        p => Some((Some(p.strip_prefix("P-")?.parse().ok()?), false)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn periods_and_distinct_values() {
        let p2: Vec<(f64, f64)> = (0..40)
            .map(|i| if i % 2 == 0 { (0.1, 0.2) } else { (0.3, -0.1) })
            .collect();
        assert_eq!(detect_period(&p2, 16, 1e-9), Some(2));
        let drift: Vec<(f64, f64)> = (0..40).map(|i| (0.1 + 1e-3 * f64::from(i), 0.0)).collect();
        assert_eq!(detect_period(&drift, 16, 1e-9), None);
        assert_eq!(distinct(&[0.1, 0.1 + 1e-12, 0.2, 0.3, 0.2], 1e-9), 3);
        assert_eq!(distinct(&[], 1e-9), 0);
    }

    #[test]
    fn labels_read_back() {
        for (period, chaotic) in [
            (Some(1), false),
            (Some(12), false),
            (None, true),
            (None, false),
        ] {
            assert_eq!(
                parse_label(&label(period, chaotic)),
                Some((period, chaotic))
            );
        }
        assert_eq!(label(Some(3), false), "P-3");
        assert_eq!(parse_label("P-x"), None);
        assert_eq!(parse_label("periodic"), None);
    }
}
