//! Sample times on a fixed grid: the multiples `k·step` of a time step inside an interval,
//! computed from `k` (no accumulated drift), for traces and stroboscopic samples of a run.

/// The times `k·step` for `k = next, next+1, …, last`, all inside `[from, t_end]`; taken one by
/// one as a run reaches them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Schedule {
    step: f64,
    next: u64,
    last: u64,
    active: bool,
}

impl Schedule {
    /// The multiples of `step` (> 0, time units) in `[from, t_end]`.
    pub fn new(step: f64, from: f64, t_end: f64) -> Self {
        let mut last = (t_end / step).floor().max(0.0) as u64;
        while last > 0 && last as f64 * step > t_end {
            last -= 1;
        }
        while ((last + 1) as f64 * step) <= t_end {
            last += 1;
        }
        let mut next = (from / step).ceil().max(0.0) as u64;
        while next > 0 && ((next - 1) as f64 * step) >= from {
            next -= 1;
        }
        while (next as f64 * step) < from {
            next += 1;
        }
        Self {
            step,
            next,
            last,
            active: true,
        }
    }

    /// No times at all.
    pub fn none() -> Self {
        Self {
            step: 1.0,
            next: 1,
            last: 0,
            active: false,
        }
    }

    /// The next time not yet taken.
    pub fn peek(&self) -> Option<f64> {
        (self.active && self.next <= self.last).then_some(self.next as f64 * self.step)
    }

    /// Whether the next time is `t`; if so, moves past it.
    pub fn take(&mut self, t: f64) -> bool {
        if self.peek() == Some(t) {
            self.next += 1;
            true
        } else {
            false
        }
    }
}

/// The earliest time not yet taken of any of `schedules`.
pub fn earliest(schedules: &[&Schedule]) -> Option<f64> {
    schedules.iter().filter_map(|s| s.peek()).reduce(f64::min)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn schedule_covers_multiples_up_to_the_end() {
        let s = Schedule::new(0.1, 0.0, 1.0);
        assert_eq!((s.next, s.last), (0, 10));
        let s = Schedule::new(0.1, 0.25, 0.95);
        assert_eq!((s.next, s.last), (3, 9));
        let s = Schedule::new(0.3, 0.0, 0.9);
        // 3 * 0.3 = 0.8999999999999999 <= 0.9.
        assert_eq!(s.last, 3);
        let mut s = Schedule::new(0.5, 0.0, 1.0);
        assert!(s.take(0.0) && s.take(0.5) && s.take(1.0));
        assert_eq!(s.peek(), None);
        assert_eq!(Schedule::none().peek(), None);
        let a = Schedule::new(0.3, 0.1, 1.0);
        assert_eq!(earliest(&[&a, &Schedule::new(0.25, 0.0, 1.0)]), Some(0.0));
        assert_eq!(earliest(&[&a, &Schedule::none()]), Some(0.3));
        assert_eq!(earliest(&[&Schedule::none()]), None);
    }
}
