//! The node's counters and its `/diagnostics` report, free of DDS: the status (halted,
//! stepping, paused, behind schedule, running), the figures, and when a report is due.

use std::time::{Duration, Instant};

use crate::msg::{DiagnosticArray, DiagnosticStatus, Header, KeyValue, Time};
use crate::pacer::LATE_TICK;
use crate::state::LoopState;

/// Period of the `/diagnostics` reports (wall clock).
pub const PERIOD: Duration = Duration::from_secs(1);
/// Worst lateness in the last period above which the status is WARN ("behind").
pub const BEHIND: Duration = Duration::from_millis(100);

/// Counters reported at shutdown and in `/diagnostics`.
#[derive(Debug, Default)]
pub struct Counters {
    pub states: u64,
    pub states_dropped: u64,
    /// State ticks with no subscription matched (nothing built or published).
    pub states_unsubscribed: u64,
    pub impacts: u64,
    pub impacts_failed: u64,
    pub commands: u64,
    pub commands_refused: u64,
    /// Service requests refused (control services and parameter sets).
    pub requests_refused: u64,
    /// Paced ticks (real_time_factor > 0) whose lateness was measured.
    pub paced_ticks: u64,
    /// Largest lateness of a state publication: from the wall-clock instant the previous state
    /// was due to the publication of the next one (the loop publishes a state as soon as it is
    /// computed, then waits for it to become due).
    pub max_lateness: Duration,
    /// The same, since the last `/diagnostics` report.
    pub window_lateness: Duration,
    /// Paced ticks more than [`LATE_TICK`] late.
    pub late_ticks: u64,
    /// Simulation time advanced \[s\] (resets do not count back).
    pub advanced: f64,
    /// Resets done.
    pub resets: u64,
}

impl Counters {
    /// Counts a paced tick published `late` after it was due.
    pub fn record_lateness(&mut self, late: Duration) {
        self.paced_ticks += 1;
        self.max_lateness = self.max_lateness.max(late);
        self.window_lateness = self.window_lateness.max(late);
        self.late_ticks += u64::from(late > LATE_TICK);
    }
}

/// When the next `/diagnostics` report is due and what the last one saw.
#[derive(Debug, Clone, Copy)]
pub struct DiagnosticsClock {
    /// Wall-clock instant the next report is due.
    pub next: Instant,
    last_wall: Instant,
    last_advanced: f64,
}

impl DiagnosticsClock {
    /// The first report due one [`PERIOD`] after `now`, with nothing advanced yet.
    pub fn new(now: Instant) -> Self {
        Self {
            next: now + PERIOD,
            last_wall: now,
            last_advanced: 0.0,
        }
    }

    /// If a report is due at `now`: the real-time factor achieved since the last one
    /// (simulation time `advanced` \[s\] in all, over the wall time in between; 0 for no wall
    /// time), and the next report is scheduled one [`PERIOD`] later.
    pub fn due(&mut self, now: Instant, advanced: f64) -> Option<f64> {
        if now < self.next {
            return None;
        }
        let wall = now.duration_since(self.last_wall).as_secs_f64();
        let rtf = if wall > 0.0 {
            (advanced - self.last_advanced) / wall
        } else {
            0.0
        };
        self.last_wall = now;
        self.last_advanced = advanced;
        self.next = now + PERIOD;
        Some(rtf)
    }
}

/// The status level and message: ERROR when halted, else OK stepping, paused or held at the
/// start gate (`held`: its status), WARN when a tick of the last period was more than
/// [`BEHIND`] late, else OK running.
pub fn status(
    halted: Option<&str>,
    stepping: bool,
    paused: bool,
    held: Option<String>,
    window_lateness: Duration,
) -> (u8, String) {
    if let Some(why) = halted {
        (DiagnosticStatus::ERROR, format!("halted: {why}"))
    } else if stepping {
        (DiagnosticStatus::OK, "stepping".to_owned())
    } else if paused {
        (DiagnosticStatus::OK, "paused".to_owned())
    } else if let Some(held) = held {
        (DiagnosticStatus::OK, held)
    } else if window_lateness > BEHIND {
        (
            DiagnosticStatus::WARN,
            "running, behind its real-time schedule".to_owned(),
        )
    } else {
        (DiagnosticStatus::OK, "running".to_owned())
    }
}

/// The `/diagnostics` report: one status, `<node>: simulation`, with the figures; `rtf` is the
/// real-time factor achieved, `stamp` the wall-clock time of the report [s since the epoch].
pub fn report<Id>(
    st: &LoopState<Id>,
    fully_qualified: &str,
    rtf: f64,
    stamp: f64,
) -> DiagnosticArray {
    let n = &st.n;
    let r = &st.runner;
    let (level, status) = status(
        r.halted(),
        st.control.stepping(),
        st.control.paused(),
        st.gate.as_ref().map(|g| g.status()),
        n.window_lateness,
    );
    let kv = |key: &str, value: String| KeyValue {
        key: key.to_owned(),
        value,
    };
    let ms = |d: Duration| format!("{:.3}", d.as_secs_f64() * 1e3);
    DiagnosticArray {
        header: Header {
            stamp: Time::from_seconds(stamp),
            frame_id: String::new(),
        },
        status: vec![DiagnosticStatus {
            level,
            name: format!("{}: simulation", fully_qualified.trim_start_matches('/')),
            message: status.clone(),
            hardware_id: fully_qualified.to_owned(),
            values: vec![
                kv("integrator status", status),
                kv("simulation time [s]", format!("{}", r.now())),
                kv("real-time factor achieved", format!("{rtf:.6}")),
                kv(
                    "real-time factor set",
                    format!("{}", st.settings.real_time_factor),
                ),
                kv("worst lateness, last period [ms]", ms(n.window_lateness)),
                kv("worst lateness [ms]", ms(n.max_lateness)),
                kv("ticks over 10 ms late", n.late_ticks.to_string()),
                kv("states published", n.states.to_string()),
                kv("states dropped", n.states_dropped.to_string()),
                kv(
                    "states without subscriber",
                    n.states_unsubscribed.to_string(),
                ),
                kv("impact count", r.impact_count().to_string()),
                kv("impacts published", n.impacts.to_string()),
                kv("impacts waiting", st.impacts.len().to_string()),
                kv("commands accepted", n.commands.to_string()),
                kv("commands refused", n.commands_refused.to_string()),
                kv(
                    "commands dropped when due",
                    r.commands_dropped().to_string(),
                ),
                kv("requests refused", n.requests_refused.to_string()),
                kv("resets", n.resets.to_string()),
            ],
        }],
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::Settings;
    use crate::sim::Runner;

    const OK: u8 = DiagnosticStatus::OK;
    const WARN: u8 = DiagnosticStatus::WARN;
    const ERROR: u8 = DiagnosticStatus::ERROR;

    #[test]
    fn status_precedence() {
        let ms = Duration::from_millis;
        let late = ms(500);
        assert_eq!(
            status(Some("boom"), true, true, None, late),
            (ERROR, "halted: boom".to_owned())
        );
        assert_eq!(
            status(None, true, true, None, late),
            (OK, "stepping".to_owned())
        );
        assert_eq!(
            status(None, false, true, None, late),
            (OK, "paused".to_owned())
        );
        assert_eq!(status(None, false, false, None, late).0, WARN);
        assert_eq!(
            status(None, false, false, None, BEHIND),
            (OK, "running".to_owned())
        );
        assert_eq!(status(None, false, false, None, BEHIND + ms(1)).0, WARN);
        let held = || Some("waiting for impact subscriptions (0 of 1 matched)".to_owned());
        assert_eq!(
            status(None, false, false, held(), late),
            (OK, held().unwrap())
        );
        assert_eq!(status(None, false, true, held(), late).1, "paused");
    }

    #[test]
    fn lateness_counts_late_ticks_and_keeps_the_worst() {
        let mut n = Counters::default();
        let ms = Duration::from_millis;
        for late in [ms(3), LATE_TICK, ms(40), ms(11)] {
            n.record_lateness(late);
        }
        assert_eq!(n.paced_ticks, 4);
        assert_eq!(n.late_ticks, 2, "strictly over 10 ms");
        assert_eq!((n.max_lateness, n.window_lateness), (ms(40), ms(40)));
    }

    #[test]
    fn clock_reports_once_a_period_with_the_achieved_rtf() {
        let t0 = Instant::now();
        let mut c = DiagnosticsClock::new(t0);
        assert_eq!(c.due(t0 + PERIOD / 2, 0.3), None);
        let r = c.due(t0 + 2 * PERIOD, 4.0).unwrap();
        assert!((r - 2.0).abs() < 1e-12, "{r}");
        assert_eq!(c.next, t0 + 3 * PERIOD);
        assert_eq!(c.due(t0 + 2 * PERIOD + PERIOD / 2, 5.0), None);
        let r = c.due(t0 + 3 * PERIOD, 4.5).unwrap();
        assert!((r - 0.5).abs() < 1e-12, "{r}");
    }

    #[test]
    fn report_names_the_node_and_carries_the_figures() {
        let settings = Settings::default();
        let mut st: LoopState<()> = LoopState::new(Runner::new(&settings).unwrap(), settings);
        st.n.states = 12;
        st.n.requests_refused = 3;
        st.n.window_lateness = Duration::from_millis(250);
        st.control.set_paused(true, 0.0);
        let a = report(&st, "/rig1/bistable_impact", 0.75, 1.5);
        assert_eq!(a.header.stamp, Time::from_seconds(1.5));
        let [s] = &a.status[..] else {
            panic!("one status expected: {:?}", a.status);
        };
        assert_eq!(s.name, "rig1/bistable_impact: simulation");
        assert_eq!(s.hardware_id, "/rig1/bistable_impact");
        assert_eq!((s.level, s.message.as_str()), (OK, "paused"));
        let value = |k: &str| {
            s.values
                .iter()
                .find(|kv| kv.key == k)
                .map(|kv| kv.value.clone())
                .unwrap_or_else(|| panic!("no {k}"))
        };
        assert_eq!(value("integrator status"), "paused");
        assert_eq!(value("real-time factor achieved"), "0.750000");
        assert_eq!(value("real-time factor set"), "1");
        assert_eq!(value("worst lateness, last period [ms]"), "250.000");
        assert_eq!(value("states published"), "12");
        assert_eq!(value("requests refused"), "3");
        assert_eq!(value("impact count"), st.runner.impact_count().to_string());
        assert_eq!(s.values.len(), 18);
    }
}
