//! Taking shaker commands from the subscription, and keeping a flood of them from flooding the
//! log: the loop-side logic of the node, free of DDS so that it can be tested.

use std::fmt::Display;
use std::time::{Duration, Instant};

use crate::msg::ShakerCommand;
use crate::sim::Runner;

/// Most samples taken from the command subscription in one call of [`take_commands`] (the
/// simulation loop calls it again at least every millisecond while it waits for wall time).
pub const MAX_COMMANDS_PER_CALL: usize = 1000;

/// What became of one sample taken from the command subscription.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Taken {
    /// A valid command, queued; what was scheduled.
    Accepted(String),
    /// A command refused by [`Runner::command`], or a sample that could not be read as a
    /// `ShakerCommand` (malformed CDR); why.
    Refused(String),
}

/// Takes up to `limit` samples with `take` (the subscription's `take`), hands each command to
/// `runner` and reports it to `on`; returns how many samples were taken. A sample that cannot
/// be deserialized is refused and the next one is taken: the reader has already moved past
/// it, so stopping there would only leave the valid commands behind it waiting (and, with a
/// keep-last reader history, lost when more arrive than it holds).
pub fn take_commands<E: Display>(
    mut take: impl FnMut() -> Result<Option<ShakerCommand>, E>,
    runner: &mut Runner,
    limit: usize,
    mut on: impl FnMut(Taken),
) -> usize {
    let mut taken = 0;
    while taken < limit {
        match take() {
            Ok(Some(cmd)) => on(match runner.command(&cmd) {
                Ok(what) => Taken::Accepted(what),
                Err(why) => Taken::Refused(why),
            }),
            Ok(None) => break,
            Err(e) => on(Taken::Refused(e.to_string())),
        }
        taken += 1;
    }
    taken
}

/// Lets through at most `budget` messages per `window`; the others are counted and reported
/// by [`Throttle::flush`] once the window is over. Used for the per-command log lines, so
/// that a flood of commands does not become a flood of `/rosout` messages.
#[derive(Debug)]
pub struct Throttle {
    budget: u32,
    window: Duration,
    start: Instant,
    used: u32,
    suppressed: u64,
}

impl Throttle {
    pub fn new(budget: u32, window: Duration, now: Instant) -> Self {
        Self {
            budget,
            window,
            start: now,
            used: 0,
            suppressed: 0,
        }
    }

    /// Whether a message may be logged at `now` (otherwise it is counted as suppressed).
    pub fn allow(&mut self, now: Instant) -> bool {
        if now.duration_since(self.start) >= self.window && self.suppressed == 0 {
            self.start = now;
            self.used = 0;
        }
        if self.used < self.budget && self.suppressed == 0 {
            self.used += 1;
            true
        } else {
            self.suppressed += 1;
            false
        }
    }

    /// Once the window is over: the number of messages suppressed in it and its length, if
    /// any were (a new window starts).
    pub fn flush(&mut self, now: Instant) -> Option<(u64, Duration)> {
        let elapsed = now.duration_since(self.start);
        if self.suppressed == 0 || elapsed < self.window {
            return None;
        }
        let n = self.suppressed;
        self.start = now;
        self.used = 0;
        self.suppressed = 0;
        Some((n, elapsed))
    }
}

/// A number for a log message: plain decimals in the usual range, scientific notation for
/// very large or small magnitudes (Rust's `{}` would print all 309 digits of `1e308`).
pub fn num(x: f64) -> impl Display {
    struct Num(f64);
    impl Display for Num {
        fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            let a = self.0.abs();
            if a == 0.0 || !a.is_finite() || (1e-6..1e15).contains(&a) {
                write!(f, "{}", self.0)
            } else {
                write!(f, "{:e}", self.0)
            }
        }
    }
    Num(x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::Settings;

    #[test]
    fn samples_after_an_unreadable_one_are_taken_in_the_same_call() {
        // A loop that stopped at the first sample that failed to deserialize would take a few
        // of a mix of malformed and valid samples per publish tick, and the reader's keep-last
        // history would drop the rest (valid commands lost).
        let mut runner = Runner::new(&Settings::default()).unwrap();
        let valid = ShakerCommand {
            mode: ShakerCommand::MODE_SINUSOID,
            omega: 1.5,
            velocity: 0.05,
            ..ShakerCommand::default()
        };
        let invalid = ShakerCommand {
            omega: f64::NAN,
            ..valid.clone()
        };
        let mut samples = vec![
            Err("malformed"),
            Ok(valid.clone()),
            Err("malformed"),
            Err("malformed"),
            Ok(invalid),
            Ok(valid),
        ]
        .into_iter();
        let mut seen = Vec::new();
        let n = take_commands(
            || samples.next().transpose(),
            &mut runner,
            MAX_COMMANDS_PER_CALL,
            |t| seen.push(t),
        );
        assert_eq!(n, 6);
        let accepted = seen
            .iter()
            .filter(|t| matches!(t, Taken::Accepted(_)))
            .count();
        assert_eq!(accepted, 2, "{seen:?}");
        assert_eq!(seen[0], Taken::Refused("malformed".into()));
        assert!(matches!(&seen[4], Taken::Refused(why) if why.contains("omega = NaN")));
        // The limit bounds one call.
        let mut endless = std::iter::repeat(Err::<Option<ShakerCommand>, _>("bad"));
        let n = take_commands(|| endless.next().unwrap(), &mut runner, 10, |_| {});
        assert_eq!(n, 10);
    }

    #[test]
    fn throttle_lets_the_budget_through_then_reports_the_rest_once_per_window() {
        let t0 = Instant::now();
        let ms = Duration::from_millis;
        let mut th = Throttle::new(3, ms(1000), t0);
        let passed = (0..10).filter(|k| th.allow(t0 + ms(*k))).count();
        assert_eq!(passed, 3);
        assert_eq!(th.flush(t0 + ms(500)), None);
        // Still in the reporting state until flushed: nothing passes.
        assert!(!th.allow(t0 + ms(1500)));
        assert_eq!(th.flush(t0 + ms(1600)), Some((8, ms(1600))));
        assert!(th.allow(t0 + ms(1601)));
        assert_eq!(th.flush(t0 + ms(3000)), None);
        // A quiet window renews the budget without a report.
        let mut quiet = Throttle::new(1, ms(10), t0);
        assert!(quiet.allow(t0));
        assert!(quiet.allow(t0 + ms(20)));
        assert_eq!(quiet.flush(t0 + ms(40)), None);
    }

    #[test]
    fn numbers_in_log_messages_stay_short() {
        assert_eq!(num(1.75).to_string(), "1.75");
        assert_eq!(num(-0.07).to_string(), "-0.07");
        assert_eq!(num(0.0).to_string(), "0");
        assert_eq!(num(1e300).to_string(), "1e300");
        assert_eq!(num(5e-324).to_string(), "5e-324");
        assert_eq!(num(f64::NAN).to_string(), "NaN");
        assert_eq!(num(f64::NEG_INFINITY).to_string(), "-inf");
        assert_eq!(num(2147483647.0).to_string(), "2147483647");
    }
}
