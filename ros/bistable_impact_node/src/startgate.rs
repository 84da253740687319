//! The start gate: the simulation stays at t = 0 until a number of impact subscriptions are
//! matched, or a wall-clock timeout passes (`wait_for_impact_subscriptions`,
//! `wait_for_impact_subscriptions_timeout`), so that subscribers started together with the node
//! (e.g. by one launch file) get every impact from index 0 however long discovery takes. Free
//! of DDS: the node passes in the impact writer's matched-subscription count.

use std::time::{Duration, Instant};

/// A closed gate: how many subscriptions it waits for, until when, and how many were matched
/// when last checked.
#[derive(Debug, Clone)]
pub struct StartGate {
    want: usize,
    since: Instant,
    deadline: Option<Instant>,
    matched: usize,
}

/// How a gate opened.
#[derive(Debug, Clone, PartialEq)]
pub struct Opened {
    /// Subscriptions matched when it opened.
    pub matched: usize,
    /// Subscriptions it waited for.
    pub want: usize,
    /// Wall time it was closed.
    pub waited: Duration,
}

impl Opened {
    /// Whether the timeout opened it (fewer than `want` matched).
    pub fn timed_out(&self) -> bool {
        self.matched < self.want
    }

    /// The log line: what was matched after how long.
    pub fn message(&self) -> String {
        let secs = self.waited.as_secs_f64();
        if self.timed_out() {
            format!(
                "starting the simulation with {} of {} impact subscriptions matched: \
                 wait_for_impact_subscriptions_timeout ({secs:.3} s) passed; impacts published \
                 before a subscription matches reach it only as the last history_depth",
                self.matched, self.want
            )
        } else {
            format!(
                "starting the simulation: {} impact subscriptions matched after {secs:.3} s \
                 (waited for {})",
                self.matched, self.want
            )
        }
    }
}

impl StartGate {
    /// A gate closed from `now` until `want` subscriptions are matched or `timeout_s` wall
    /// seconds have passed (0: no limit); `None` when `want` is 0 (start at once).
    pub fn new(want: i64, timeout_s: f64, now: Instant) -> Option<Self> {
        let want = usize::try_from(want).ok().filter(|&w| w > 0)?;
        let deadline = (timeout_s > 0.0)
            .then(|| Duration::try_from_secs_f64(timeout_s).ok())
            .flatten()
            .and_then(|d| now.checked_add(d));
        Some(Self {
            want,
            since: now,
            deadline,
            matched: 0,
        })
    }

    /// Notes `matched` subscriptions at `now`: how the gate opened, or `None` while it stays
    /// closed.
    pub fn check(&mut self, matched: usize, now: Instant) -> Option<Opened> {
        self.matched = matched;
        let timed_out = self.deadline.is_some_and(|d| now >= d);
        (matched >= self.want || timed_out).then(|| Opened {
            matched,
            want: self.want,
            waited: now.saturating_duration_since(self.since),
        })
    }

    /// The status while closed, e.g. `waiting for impact subscriptions (1 of 2 matched)`.
    pub fn status(&self) -> String {
        format!(
            "waiting for impact subscriptions ({} of {} matched)",
            self.matched, self.want
        )
    }

    /// The log line when the gate closes at start-up.
    pub fn announcement(&self) -> String {
        let limit = match self.deadline {
            Some(d) => format!(
                "at most {:.3} s",
                d.saturating_duration_since(self.since).as_secs_f64()
            ),
            None => "without a time limit".to_owned(),
        };
        format!(
            "holding the simulation at t = 0 until {} impact subscriptions are matched \
             ({limit})",
            self.want
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zero_wants_no_gate() {
        assert!(StartGate::new(0, 5.0, Instant::now()).is_none());
        assert!(StartGate::new(-3, 5.0, Instant::now()).is_none());
    }

    #[test]
    fn opens_when_enough_are_matched() {
        let t0 = Instant::now();
        let mut g = StartGate::new(2, 0.0, t0).unwrap();
        assert!(g.announcement().contains("without a time limit"));
        // No limit: however long it takes.
        assert_eq!(g.check(1, t0 + Duration::from_secs(3600)), None);
        assert_eq!(
            g.status(),
            "waiting for impact subscriptions (1 of 2 matched)"
        );
        let o = g.check(3, t0 + Duration::from_millis(3_601_500)).unwrap();
        assert_eq!((o.matched, o.want, o.timed_out()), (3, 2, false));
        assert_eq!(o.waited, Duration::from_millis(3_601_500));
        assert!(o
            .message()
            .contains("3 impact subscriptions matched after 3601.500 s"));
    }

    #[test]
    fn the_timeout_opens_it_with_fewer() {
        let t0 = Instant::now();
        let mut g = StartGate::new(2, 1.5, t0).unwrap();
        assert!(g.announcement().contains("at most 1.500 s"));
        assert_eq!(g.check(1, t0 + Duration::from_millis(1499)), None);
        let o = g.check(1, t0 + Duration::from_millis(1500)).unwrap();
        assert!(o.timed_out());
        assert!(o
            .message()
            .starts_with("starting the simulation with 1 of 2"));
    }

    #[test]
    fn absurd_timeouts_mean_no_limit() {
        let t0 = Instant::now();
        let mut g = StartGate::new(1, 1e300, t0).unwrap();
        assert_eq!(g.check(0, t0 + Duration::from_secs(1 << 40)), None);
    }
}
