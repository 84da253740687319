//! The rule that ends a chatter sequence (impacts accumulating in finite time) with sticking.
//!
//! After an impact with rebound relative velocity `w₊ > 0` while the plate pushes with contact
//! force `N > 0` (Eq. 9), the following flights are short parabolas of duration `≈ 2w/N`, each
//! rebound `e` times slower, so the sequence accumulates after `Δ = 2w₊/(N(1−e))` (Budd & Dux
//! 1994). [`ChatterRule::Accumulation`] resolves every impact individually until `Δ` falls below
//! its horizon and then jumps to the accumulation point; the error of that jump is of order
//! `Δ²·|N'/N|`, far below the horizon itself. [`ChatterRule::FixedGap`] is the paper's rule.

use crate::events::StickCause;
use crate::params::ChatterRule;

/// What follows an impact.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Decision {
    /// Free flight with the rebound velocity.
    Fly,
    /// Ride on the plate for this long (time units, possibly 0), then stick.
    StickAfter(f64, StickCause),
    /// The Zeno guard fired while the plate pulls away: no consistent continuation.
    Zeno,
}

/// Decides after an impact with rebound relative velocity `w_plus ≥ 0`, contact force `force`,
/// time since the previous impact `since`, and whether the Zeno guard's count is exhausted.
pub(crate) fn decide(
    rule: ChatterRule,
    e: f64,
    w_plus: f64,
    force: f64,
    since: Option<f64>,
    zeno: bool,
) -> Decision {
    if let Some((delay, cause)) = rule.stick_delay(e, w_plus, force, since) {
        return Decision::StickAfter(delay, cause);
    }
    if w_plus == 0.0 {
        return Decision::Fly;
    }
    if zeno {
        return if force >= 0.0 {
            Decision::StickAfter(0.0, StickCause::ZenoGuard)
        } else {
            Decision::Zeno
        };
    }
    Decision::Fly
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn accumulation_point_prediction() {
        let rule = ChatterRule::Accumulation { horizon: 1e-6 };
        // Δ = 2·1e-8/(0.25·0.15) ≈ 5.3e-7 ≤ 1e-6.
        match decide(rule, 0.85, 1e-8, 0.25, Some(1.0), false) {
            Decision::StickAfter(d, StickCause::Accumulation) => {
                assert!((d - 2e-8 / (0.25 * 0.15)).abs() < 1e-20)
            }
            other => panic!("{other:?}"),
        }
        assert_eq!(decide(rule, 0.85, 1e-3, 0.25, None, false), Decision::Fly);
        // Pulled away: no sticking, whatever the velocity.
        assert_eq!(decide(rule, 0.85, 1e-12, -0.25, None, false), Decision::Fly);
        // e = 1 never accumulates.
        assert_eq!(decide(rule, 1.0, 1e-12, 0.25, None, false), Decision::Fly);
    }

    #[test]
    fn paper_rule_and_guards() {
        let rule = ChatterRule::paper();
        assert_eq!(
            decide(rule, 0.85, 1e-5, 0.0, Some(5e-10), false),
            Decision::StickAfter(0.0, StickCause::FixedGap)
        );
        assert_eq!(
            decide(rule, 0.85, 1e-5, 0.1, Some(2e-9), false),
            Decision::Fly
        );
        assert_eq!(
            decide(rule, 0.0, 0.0, 0.1, None, false),
            Decision::StickAfter(0.0, StickCause::Plastic)
        );
        assert_eq!(
            decide(rule, 0.9, 1e-5, -0.1, Some(2e-9), true),
            Decision::Zeno
        );
        assert_eq!(
            decide(rule, 0.9, 1e-5, 0.1, Some(2e-9), true),
            Decision::StickAfter(0.0, StickCause::ZenoGuard)
        );
    }
}
