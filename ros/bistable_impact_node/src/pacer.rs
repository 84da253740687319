//! Real-time pacing of the simulation loop, free of DDS: when each publish tick is due on the
//! wall clock for a given `real_time_factor`, and how late a tick was.

use std::time::{Duration, Instant};

/// How far behind its schedule [s of wall time] the pacer may fall before it gives up
/// catching up and restarts the schedule from the present.
pub const MAX_BEHIND: f64 = 1.0;
/// A paced tick later than this counts as late ([`crate::diagnostics::Counters::late_ticks`]).
pub const LATE_TICK: Duration = Duration::from_millis(10);

/// Keeps simulation time at `real_time_factor` times wall-clock time: simulation time `sim`
/// \[s\] is due at wall instant `wall`, and `t` at `wall + (t − sim)/rtf`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pacer {
    rtf: f64,
    wall: Instant,
    sim: f64,
}

impl Pacer {
    /// A schedule on which simulation time `sim` \[s\] is due now.
    pub fn new(rtf: f64, sim: f64) -> Self {
        Self::starting_at(rtf, sim, Instant::now())
    }

    /// A schedule on which simulation time `sim` \[s\] is due at `wall`.
    pub fn starting_at(rtf: f64, sim: f64, wall: Instant) -> Self {
        Self { rtf, wall, sim }
    }

    /// The real-time factor (simulated seconds per wall second; 0 or less: unpaced).
    pub fn rtf(&self) -> f64 {
        self.rtf
    }

    /// [`Pacer::due_at`] now.
    pub fn due(&mut self, t: f64) -> Option<Instant> {
        self.due_at(t, Instant::now())
    }

    /// The wall-clock instant at which simulation time `t` \[s\] is due, `now` being the present;
    /// `None` when `rtf` is 0 or less (as fast as possible), or when `now` is more than
    /// [`MAX_BEHIND`] past it or it is not finite (then the schedule restarts: `t` is due `now`).
    pub fn due_at(&mut self, t: f64, now: Instant) -> Option<Instant> {
        if self.rtf <= 0.0 {
            return None;
        }
        let due = (t - self.sim) / self.rtf;
        let elapsed = now.saturating_duration_since(self.wall).as_secs_f64();
        if elapsed > due + MAX_BEHIND || !due.is_finite() {
            *self = Self::starting_at(self.rtf, t, now);
            return None;
        }
        Some(self.wall + Duration::from_secs_f64(due.max(0.0)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ms(x: u64) -> Duration {
        Duration::from_millis(x)
    }

    #[test]
    fn unpaced_never_waits() {
        let w = Instant::now();
        for rtf in [0.0, -1.0] {
            let mut p = Pacer::starting_at(rtf, 0.0, w);
            assert_eq!(p.due_at(5.0, w), None);
            assert_eq!(p.due_at(0.0, w + ms(10_000)), None);
        }
    }

    #[test]
    fn ticks_are_due_at_sim_time_over_rtf() {
        let w = Instant::now();
        let mut real = Pacer::starting_at(1.0, 2.0, w);
        assert_eq!(real.due_at(2.5, w), Some(w + ms(500)));
        let mut fast = Pacer::starting_at(10.0, 2.0, w);
        assert_eq!(fast.due_at(3.0, w + ms(50)), Some(w + ms(100)));
        let mut slow = Pacer::starting_at(0.5, 0.0, w);
        assert_eq!(slow.due_at(0.25, w), Some(w + ms(500)));
    }

    #[test]
    fn past_times_are_due_at_the_start_not_before() {
        let w = Instant::now();
        let mut p = Pacer::starting_at(1.0, 2.0, w);
        assert_eq!(p.due_at(1.5, w), Some(w));
    }

    #[test]
    fn behind_by_up_to_a_second_catches_up() {
        let w = Instant::now();
        let mut p = Pacer::starting_at(1.0, 0.0, w);
        // 0.9 s late: still on the old schedule (due in the past, no wait).
        assert_eq!(p.due_at(0.1, w + ms(1000)), Some(w + ms(100)));
        assert_eq!(p, Pacer::starting_at(1.0, 0.0, w));
    }

    #[test]
    fn behind_by_more_than_a_second_restarts_the_schedule() {
        let w = Instant::now();
        let mut p = Pacer::starting_at(1.0, 0.0, w);
        let now = w + ms(1200);
        assert_eq!(p.due_at(0.1, now), None);
        // The schedule now starts at (0.1 s, now).
        assert_eq!(p, Pacer::starting_at(1.0, 0.1, now));
        assert_eq!(p.due_at(0.35, now), Some(now + ms(250)));
    }

    #[test]
    fn non_finite_times_restart_the_schedule() {
        let w = Instant::now();
        let mut p = Pacer::starting_at(1.0, 0.0, w);
        assert_eq!(p.due_at(f64::INFINITY, w), None);
        assert_eq!(p.rtf(), 1.0);
        let mut p = Pacer::starting_at(1.0, 0.0, w);
        assert_eq!(p.due_at(f64::NAN, w + ms(5)), None);
        // A NaN origin makes the next time restart the schedule again, from that time.
        assert_eq!(p.due_at(1.0, w + ms(5)), None);
        assert_eq!(p.due_at(1.5, w + ms(5)), Some(w + ms(505)));
    }
}
