//! Pseudo-arclength continuation over the paper's low-Ω range at V = 0.03, where a 3-impact and
//! a 2-impact branch meet at a grazing corner: the branch is traced through it, and every
//! traced stretch of a branch appears once.

mod common;

use bistable_analysis::arclength::covers;
use bistable_analysis::Model;
use common::{model_at, p1_traces};

/// Max-norm distance in `(x, x')` within which two orbits at one Ω are the same.
const SAME: f64 = 5e-3;

#[test]
fn no_trace_runs_along_an_earlier_one() {
    let models: Vec<Model> = (0..21)
        .map(|i| model_at(0.6 + 0.02 * f64::from(i), 0.03))
        .collect();
    let traces = p1_traces(&models);
    // Both impact counts of the grazing corner are on one trace: it passes through the corner
    // (before continuation through grazing, the corner split the branch into two traces).
    assert!(
        traces.iter().any(|t| {
            let impacts: Vec<u64> = t.iter().map(|p| p.impacts).collect();
            impacts.contains(&3) && impacts.contains(&2)
        }),
        "no trace through the corner: {} traces",
        traces.len()
    );
    for (k, t) in traces.iter().enumerate() {
        for earlier in &traces[..k] {
            // A later trace may touch an earlier one at its ends (where it joined it), no more.
            let shared = t[1..t.len() - 1]
                .iter()
                .filter(|p| covers(earlier, p.omega, p.x0, p.v0, SAME))
                .count();
            assert_eq!(shared, 0, "trace {k} runs along an earlier trace");
        }
    }
}
