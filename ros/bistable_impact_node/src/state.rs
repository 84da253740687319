//! What the simulation loop changes as it runs and as commands and requests arrive, free of
//! DDS: the simulation, the parameters, the pacing, the counters, pause/step, the impacts not
//! yet published; and the reset request. `Id` identifies a step request (the service request
//! id in the node).

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use crate::control::{Control, StepJob};
use crate::diagnostics::Counters;
use crate::inbox::Throttle;
use crate::logging::{Log, LogLevel};
use crate::msg::ImpactEvent;
use crate::pacer::Pacer;
use crate::params::Settings;
use crate::sim::Runner;
use crate::startgate::StartGate;

/// Per-message log lines (commands accepted, refused, applied; service requests) let through
/// per second; the others are counted and summarised once a second (the totals are in the
/// shutdown summary).
pub const LOG_BUDGET: u32 = 50;

/// The loop's state.
pub struct LoopState<Id> {
    pub runner: Runner,
    pub settings: Settings,
    pub pacer: Pacer,
    pub n: Counters,
    pub control: Control<Id>,
    /// Impacts located and not yet published (a reliable subscriber is behind).
    pub impacts: VecDeque<ImpactEvent>,
    /// A reset happened: publish the new state and clock now.
    pub reset_tick: bool,
    /// Wall-clock instant the current paced tick was due, for its lateness.
    pub last_due: Option<Instant>,
    /// Log lines about service requests, limited to [`LOG_BUDGET`] a second.
    pub request_log: Throttle,
    /// Closed while the simulation waits at t = 0 for its impact subscriptions.
    pub gate: Option<StartGate>,
}

impl<Id> LoopState<Id> {
    /// Running, unpaused, at the start of `runner`'s simulation with `settings`; held at the
    /// start gate if `settings` ask for impact subscriptions first.
    pub fn new(runner: Runner, settings: Settings) -> Self {
        Self {
            gate: StartGate::new(
                settings.wait_for_impact_subscriptions,
                settings.wait_for_impact_subscriptions_timeout,
                Instant::now(),
            ),
            pacer: Pacer::new(settings.real_time_factor, runner.now()),
            settings,
            runner,
            n: Counters::default(),
            control: Control::default(),
            impacts: VecDeque::new(),
            reset_tick: false,
            last_due: None,
            request_log: Throttle::new(LOG_BUDGET, Duration::from_secs(1), Instant::now()),
        }
    }

    /// Restarts the pacing schedule from the current simulation time, due now.
    pub fn repace(&mut self) {
        self.pacer = Pacer::new(self.settings.real_time_factor, self.runner.now());
    }

    /// Counts the lateness of a tick published at `now` whose predecessor was due at
    /// [`LoopState::last_due`] (nothing if it was not paced).
    pub fn record_lateness(&mut self, now: Instant) {
        if let Some(due) = self.last_due.take() {
            self.n.record_lateness(now.saturating_duration_since(due));
        }
    }

    /// Logs a line about a service request unless over the budget (then it is counted and
    /// summarised once a second).
    pub fn log_throttled(&mut self, log: &impl Log, level: LogLevel, msg: &str) {
        if self.request_log.allow(Instant::now()) {
            log.log(level, msg);
        }
    }

    /// Logs a control request's outcome (refusals are counted).
    pub fn log_request(&mut self, log: &impl Log, what: &str, success: bool, message: &str) {
        if success {
            self.log_throttled(log, LogLevel::Info, &format!("{what}: {message}"));
        } else {
            self.n.requests_refused += 1;
            self.log_throttled(
                log,
                LogLevel::Warn,
                &format!("refused {what} request: {message}"),
            );
        }
    }

    /// The `reset` (`state` `None`) and `reset_state` (`Some((x \[m\], v \[m/s\]))`) requests:
    /// restarts the simulation at t = 0 (see [`Runner::reset`]) and its pacing, queues the held
    /// back impact, and hands a step in progress to `aborted` (to be answered) first. Returns
    /// the success and the message of the response (logged; a refusal counted).
    pub fn reset(
        &mut self,
        state: Option<(f64, f64)>,
        log: &impl Log,
        aborted: impl FnOnce(&Self, StepJob<Id>),
    ) -> (bool, String) {
        let mut flushed = Vec::new();
        match self.runner.reset(&self.settings, state, &mut flushed) {
            Ok(message) => {
                self.impacts.extend(flushed);
                if let Some(job) = self.control.abort_step() {
                    aborted(self, job);
                }
                self.n.resets += 1;
                self.reset_tick = true;
                self.last_due = None;
                self.pacer = Pacer::new(self.settings.real_time_factor, 0.0);
                self.log_request(log, "reset", true, &message);
                (true, message)
            }
            Err(why) => {
                let message = format!("reset refused: {why}");
                self.log_request(log, "reset", false, &message);
                (false, message)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::logging::Recorder;
    use crate::sim::Outcome;

    fn state() -> LoopState<u32> {
        let settings = Settings::default();
        LoopState::new(Runner::new(&settings).unwrap(), settings)
    }

    /// Advances to the first tick after `t` \[s\].
    fn run_to(st: &mut LoopState<u32>, t: f64) {
        let mut impacts = Vec::new();
        while st.runner.now() < t {
            assert_ne!(st.runner.advance(&mut impacts), Outcome::Halted);
        }
    }

    #[test]
    fn reset_restarts_time_counts_and_answers_the_step() {
        let mut st = state();
        run_to(&mut st, 0.5);
        st.control.set_paused(true, st.runner.now());
        st.control.start_step(7, 3, None).unwrap();
        st.last_due = Some(Instant::now());
        let log = Recorder::default();
        let mut answered = None;
        let (ok, msg) = st.reset(Some((0.5, 0.0)), &log, |_, job| answered = Some(job));
        assert!(ok, "{msg}");
        assert_eq!(st.runner.now(), 0.0);
        assert_eq!(answered.map(|j| j.id), Some(7));
        assert!(!st.control.stepping());
        assert_eq!((st.n.resets, st.n.requests_refused), (1, 0));
        assert!(st.reset_tick && st.last_due.is_none());
        assert_eq!(log.at(LogLevel::Info), [format!("reset: {msg}")]);
    }

    #[test]
    fn refused_reset_changes_nothing_but_the_count() {
        let mut st = state();
        run_to(&mut st, 0.2);
        let t = st.runner.now();
        let log = Recorder::default();
        let (ok, msg) = st.reset(Some((f64::NAN, 0.0)), &log, |_, _| panic!("no step"));
        assert!(!ok);
        assert!(msg.starts_with("reset refused: x = "), "{msg}");
        assert_eq!(st.runner.now(), t);
        assert_eq!((st.n.resets, st.n.requests_refused), (0, 1));
        assert!(!st.reset_tick);
        assert_eq!(
            log.at(LogLevel::Warn),
            [format!("refused reset request: {msg}")]
        );
    }

    #[test]
    fn lateness_is_counted_only_for_paced_ticks() {
        let mut st = state();
        let now = Instant::now();
        st.record_lateness(now);
        assert_eq!(st.n.paced_ticks, 0);
        st.last_due = Some(now);
        st.record_lateness(now + Duration::from_millis(30));
        assert_eq!(st.n.paced_ticks, 1);
        assert_eq!(st.n.late_ticks, 1);
        assert_eq!(st.n.max_lateness, Duration::from_millis(30));
        assert!(st.last_due.is_none());
    }

    #[test]
    fn request_log_lines_are_throttled() {
        let mut st = state();
        let log = Recorder::default();
        for _ in 0..2 * LOG_BUDGET {
            st.log_request(&log, "pause", false, "no");
        }
        assert_eq!(st.n.requests_refused, u64::from(2 * LOG_BUDGET));
        assert_eq!(log.0.borrow().len(), LOG_BUDGET as usize);
    }
}
