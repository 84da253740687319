//! The node's life: start-up (stop signal, simulation, DDS), the simulation loop (serve,
//! advance, publish, pace) and the shutdown (summary, acknowledgements).

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use bistable_impact_node::args::{Config, DiscoveryRange};
use bistable_impact_node::logging::{Log, LogLevel};
use bistable_impact_node::msg::ImpactEvent;
use bistable_impact_node::sim::{Outcome, Runner};
use bistable_impact_node::state::LoopState;
use ros2_client::dds::rustdds::mio1::{Poll, Waker};

use super::dds::Dds;
use super::publish::{
    answer_step, answer_step_done, await_acknowledgements, drain_status, flush_impacts,
    publish_impacts, publish_tick, STATUS_POLL,
};
use super::serve::{register_wakeups, Inbox, State, STOP_TOKEN};

/// How often a wait for the next tick publishes impacts still queued for the send window.
const QUEUE_POLL: Duration = Duration::from_millis(1);

/// Runs the node until SIGINT/SIGTERM; the error that kept it from starting.
pub fn run(cfg: Config, range: DiscoveryRange) -> Result<(), String> {
    let stop = Arc::new(AtomicBool::new(false));
    let poll = Poll::new().map_err(|e| format!("cannot create the event poll: {e}"))?;
    {
        let stop = Arc::clone(&stop);
        let waker = Waker::new(poll.registry(), STOP_TOKEN)
            .map_err(|e| format!("cannot create the stop waker: {e}"))?;
        ctrlc::set_handler(move || {
            stop.store(true, Ordering::SeqCst);
            // A failed wake only delays the stop to the loop's next look at the flag.
            let _ = waker.wake();
        })
        .map_err(|e| format!("cannot install the signal handler: {e}"))?;
    }
    let runner = Runner::new(&cfg.settings)?;
    if cfg.stdout {
        super::ddslog::install(cfg.names.node());
    }
    let mut dds = Dds::connect(&cfg, range)?;
    register_wakeups(&poll, &mut dds.command_sub, &mut dds.services)
        .map_err(|e| format!("cannot register the readers with the event poll: {e}"))?;
    dds.log_startup(&cfg, range);

    let mut st = LoopState::new(runner, cfg.settings.clone());
    let mut lp = Loop {
        dds: &dds,
        stop: &stop,
        inbox: Inbox::new(&dds.command_sub, &dds.services, poll),
        next_status_poll: Instant::now(),
        last_outcome: Outcome::Tick,
        fresh: Vec::new(),
    };
    lp.publish_tick(&mut st);
    if let Some(gate) = &st.gate {
        dds.log.log(LogLevel::Info, &gate.announcement());
    }
    while !stop.load(Ordering::Relaxed) {
        lp.iterate(&mut st);
    }
    lp.shutdown(st);
    drop(lp);
    drop(dds);
    Ok(())
}

/// The simulation loop's DDS side and what it remembers between iterations.
struct Loop<'a> {
    dds: &'a Dds,
    stop: &'a AtomicBool,
    inbox: Inbox<'a>,
    /// When the participant's status events are emptied next.
    next_status_poll: Instant,
    /// What the last advance ended with (a change to blocked or halted is logged).
    last_outcome: Outcome,
    /// Impacts located by the last advance.
    fresh: Vec<ImpactEvent>,
}

impl Loop<'_> {
    fn publish_tick(&self, st: &mut State) {
        let d = self.dds;
        publish_tick(&st.runner, &d.state_pub, &d.clock_pub, &mut st.n, &d.log);
    }

    /// Serves commands and requests for `ms` milliseconds, then restarts the pacing.
    fn wait(&mut self, st: &mut State, ms: u64) {
        let until = Instant::now() + Duration::from_millis(ms);
        self.inbox.wait_until(until, self.stop, st, &self.dds.log);
        st.repace();
    }

    /// One pass: serve, publish what waits, then advance to the next tick, command or block
    /// unless paused or held up by a slow impact subscriber.
    fn iterate(&mut self, st: &mut State) {
        let d = self.dds;
        // The status events are read under the participant's discovery lock: a few times a
        // second, not at every step of a free-running loop (that starved discovery, so that
        // departed subscribers stayed matched and held up the reliable writers).
        if Instant::now() >= self.next_status_poll {
            drain_status(&d.status);
            self.next_status_poll = Instant::now() + STATUS_POLL;
        }
        self.inbox.serve(st, &d.log, false);
        if std::mem::take(&mut st.reset_tick) {
            self.publish_tick(st);
            self.last_outcome = Outcome::Tick;
        }
        if self.held(st) {
            return;
        }
        publish_impacts(&d.impact_pub, &mut st.impacts, &mut st.n, &d.log);
        if !st.impacts.is_empty() {
            // A reliable subscriber is behind: wait for it rather than lose an impact.
            self.wait(st, 1);
            return;
        }
        if !st.control.advancing() {
            // Paused: no tick, no /clock; commands and requests are served.
            self.wait(st, 2);
            st.last_due = None;
            return;
        }
        let before = st.runner.now();
        let outcome = st.runner.advance(&mut self.fresh);
        st.n.advanced += (st.runner.now() - before).max(0.0);
        st.impacts.extend(self.fresh.drain(..));
        publish_impacts(&d.impact_pub, &mut st.impacts, &mut st.n, &d.log);
        match outcome {
            Outcome::Tick => self.ticked(st),
            Outcome::Command => {}
            Outcome::Blocked | Outcome::Halted => self.stalled(st, outcome),
        }
        self.last_outcome = outcome;
    }

    /// Whether the simulation is still held at the start gate (commands and requests are
    /// served meanwhile, for a few ms); logs how the gate opened.
    fn held(&mut self, st: &mut State) -> bool {
        let Some(gate) = st.gate.as_mut() else {
            return false;
        };
        let matched = self.dds.impact_pub.matched_reader_count();
        match gate.check(matched, Instant::now()) {
            None => {
                self.wait(st, 5);
                true
            }
            Some(opened) => {
                let level = if opened.timed_out() {
                    LogLevel::Warn
                } else {
                    LogLevel::Info
                };
                self.dds.log.log(level, &opened.message());
                st.gate = None;
                st.repace();
                false
            }
        }
    }

    /// After a tick: publish it, count its lateness, then finish a step or wait until due.
    fn ticked(&mut self, st: &mut State) {
        let d = self.dds;
        self.publish_tick(st);
        st.record_lateness(Instant::now());
        if st.control.stepping() {
            if let Some(job) = st.control.ticked() {
                answer_step_done(&d.services, st, job, &d.log);
            }
            st.repace();
        } else if let Some(due) = st.pacer.due(st.runner.now()) {
            self.wait_due(st, due);
            st.last_due = Some(due);
        }
    }

    /// Waits until the next tick is due at wall-clock instant `due` (or a stop or a change of
    /// pacing), serving commands and requests. Impacts still queued for the send window are
    /// published meanwhile, every [`QUEUE_POLL`], as the subscribers' acknowledgements open
    /// it: a paced or frozen node (`real_time_factor` near 0) does not hold them back until
    /// its next tick.
    fn wait_due(&mut self, st: &mut State, due: Instant) {
        let d = self.dds;
        loop {
            publish_impacts(&d.impact_pub, &mut st.impacts, &mut st.n, &d.log);
            let until = if st.impacts.is_empty() {
                due
            } else {
                due.min(Instant::now() + QUEUE_POLL)
            };
            if !self.inbox.wait_until(until, self.stop, st, &d.log) || until == due {
                return;
            }
        }
    }

    /// Blocked on the next external plate sample, or halted: log the change, end a step, wait.
    fn stalled(&mut self, st: &mut State, outcome: Outcome) {
        let d = self.dds;
        let why = match st.runner.halted() {
            Some(why) => why.to_owned(),
            None => format!(
                "waiting at t = {} s for the next external plate sample",
                st.runner.now()
            ),
        };
        if outcome != self.last_outcome {
            let level = if outcome == Outcome::Halted {
                LogLevel::Error
            } else {
                LogLevel::Info
            };
            d.log.log(level, &why);
        }
        if let Some(job) = st.control.abort_step() {
            answer_step(&d.services, st, job, &why, &d.log);
        }
        self.wait(st, 2);
    }

    /// Answers a step in progress, logs the summary and waits for the impact subscribers'
    /// acknowledgements.
    fn shutdown(&mut self, mut st: State) {
        let d = self.dds;
        if let Some(job) = st.control.abort_step() {
            answer_step(&d.services, &st, job, "the node is stopping", &d.log);
        }
        flush_impacts(&d.impact_pub, &mut st.impacts, &mut st.n, &d.log);
        let LoopState { runner, n, .. } = st;
        d.log.log(
            LogLevel::Info,
            &format!(
                "stopping at t = {} s: {} impacts located, {} published ({} failed), {} states \
                 published ({} dropped, {} without subscriber), {} commands accepted, {} refused, \
                 {} dropped when due; {} requests refused, {} resets; {} paced ticks, lateness max \
                 {:.3} ms, {} over 10 ms",
                runner.now(),
                runner.impact_count(),
                n.impacts,
                n.impacts_failed,
                n.states,
                n.states_dropped,
                n.states_unsubscribed,
                n.commands,
                n.commands_refused,
                runner.commands_dropped(),
                n.requests_refused,
                n.resets,
                n.paced_ticks,
                n.max_lateness.as_secs_f64() * 1e3,
                n.late_ticks
            ),
        );
        // Reliable subscribers may still be missing some of the last impacts (up to the send
        // window of 8192 at a high impact rate): DDS keeps running until they have
        // acknowledged them all.
        await_acknowledgements(
            &d.impact_pub,
            d.impact_pub.matched_reader_count(),
            n.impacts,
            &d.log,
        );
    }
}
