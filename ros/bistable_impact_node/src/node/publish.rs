//! What the loop publishes (state, clock, impacts, step answers) and the shutdown's wait for
//! the impact subscribers' acknowledgements.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use bistable_impact_node::control::StepJob;
use bistable_impact_node::diagnostics::Counters;
use bistable_impact_node::logging::{Log, LogLevel};
use bistable_impact_node::msg::{Clock, ImpactEvent, MassState, StepResponse};
use bistable_impact_node::sim::Runner;
use ros2_client::dds::rustdds::{DomainParticipantStatusListener, StatusEvented};
use ros2_client::service::RmwRequestId;
use ros2_client::{Publisher, WriteError};

use super::dds::{Logger, Services};
use super::serve::State;

/// Publishes the state and the clock, each only while a subscription is matched.
pub fn publish_tick(
    runner: &Runner,
    state_pub: &Publisher<MassState>,
    clock_pub: &Publisher<Clock>,
    n: &mut Counters,
    log: &Logger,
) {
    // Nothing is built or serialized for a topic without a matched subscription (volatile: a
    // later subscriber would not get it anyway).
    let state_wanted = state_pub.matched_reader_count() > 0;
    let clock_wanted = clock_pub.matched_reader_count() > 0;
    n.states_unsubscribed += u64::from(!state_wanted);
    if !state_wanted && !clock_wanted {
        return;
    }
    let state = runner.state();
    let clock = Clock {
        clock: state.header.stamp,
    };
    if state_wanted {
        match state_pub.publish(state) {
            Ok(()) => n.states += 1,
            Err(WriteError::WouldBlock { .. }) => n.states_dropped += 1,
            Err(e) => {
                n.states_dropped += 1;
                log.log(LogLevel::Warn, &format!("mass state not published: {e}"));
            }
        }
    }
    if !clock_wanted {
        return;
    }
    if let Err(e) = clock_pub.publish(clock) {
        if !matches!(e, WriteError::WouldBlock { .. }) {
            log.log(LogLevel::Warn, &format!("clock not published: {e}"));
        }
    }
}

/// Publishes the queued impacts in order; stops at the first one the subscribers cannot take
/// yet (it stays queued).
pub fn publish_impacts(
    publisher: &Publisher<ImpactEvent>,
    queue: &mut VecDeque<ImpactEvent>,
    n: &mut Counters,
    log: &Logger,
) {
    while let Some(msg) = queue.pop_front() {
        let index = msg.index;
        match publisher.publish(msg) {
            Ok(()) => n.impacts += 1,
            Err(WriteError::WouldBlock { data }) => {
                queue.push_front(data);
                return;
            }
            Err(e) => {
                n.impacts_failed += 1;
                log.log(
                    LogLevel::Error,
                    &format!("impact {index} not published: {e}"),
                );
            }
        }
    }
}

/// Answers a step request that ended before all its ticks were done.
pub fn answer_step(sv: &Services, st: &State, job: StepJob<RmwRequestId>, why: &str, log: &Logger) {
    let message = format!(
        "step stopped after {} of {} ticks at t = {} s: {why}",
        job.done,
        job.ticks,
        st.runner.now()
    );
    log.log(LogLevel::Warn, &message);
    let resp = StepResponse {
        success: false,
        message,
        t: st.runner.now(),
        impact_count: st.runner.impact_count(),
    };
    if let Err(e) = sv.step.send_response(job.id, resp) {
        log.log(LogLevel::Warn, &format!("step: response not sent: {e}"));
    }
}

/// Answers a step request whose ticks are all done.
pub fn answer_step_done(sv: &Services, st: &State, job: StepJob<RmwRequestId>, log: &Logger) {
    let t = st.runner.now();
    let resp = StepResponse {
        success: true,
        message: format!("stepped {} ticks to t = {t} s", job.ticks),
        t,
        impact_count: st.runner.impact_count(),
    };
    log.log(LogLevel::Info, &resp.message);
    if let Err(e) = sv.step.send_response(job.id, resp) {
        log.log(LogLevel::Warn, &format!("step: response not sent: {e}"));
    }
}

/// How often the loop empties the participant's status event channel.
pub const STATUS_POLL: Duration = Duration::from_millis(100);

/// Empties the participant's status event channel (the node runs no ros2-client spinner to
/// read it; a full channel makes RustDDS log an error for every further event). The node
/// counts matched subscriptions from the writers themselves (`matched_reader_count`), which
/// loses nothing when events are dropped.
pub fn drain_status(status: &DomainParticipantStatusListener) {
    while status.try_recv_status().is_some() {}
}

/// At shutdown DDS keeps running while the matched reliable impact subscribers acknowledge the
/// published impacts: until all are acknowledged, or no further acknowledgement came for
/// [`SHUTDOWN_ACK_STALL`] (a subscriber that vanished without a goodbye acknowledges nothing
/// until DDS drops it at its lease expiry), or [`SHUTDOWN_ACK_LIMIT`] in all.
const SHUTDOWN_ACK_STALL: Duration = Duration::from_secs(2);
/// See [`SHUTDOWN_ACK_STALL`].
const SHUTDOWN_ACK_LIMIT: Duration = Duration::from_secs(10);

/// How long a wait at shutdown goes on: it gives up after [`SHUTDOWN_ACK_STALL`] without
/// progress (fewer items left than ever before) or [`SHUTDOWN_ACK_LIMIT`] in all.
struct Patience {
    start: Instant,
    progress: Instant,
    left: u64,
}

impl Patience {
    /// A wait starting now with `left` items to go.
    fn new(left: u64) -> Self {
        let now = Instant::now();
        Self {
            start: now,
            progress: now,
            left,
        }
    }

    /// Notes that `left` items are still to go; whether the wait should give up.
    fn exhausted(&mut self, left: u64) -> bool {
        let now = Instant::now();
        if left < self.left {
            self.left = left;
            self.progress = now;
        }
        now - self.progress >= SHUTDOWN_ACK_STALL || now - self.start >= SHUTDOWN_ACK_LIMIT
    }

    /// Seconds since the wait started.
    fn waited(&self) -> f64 {
        self.start.elapsed().as_secs_f64()
    }

    /// Seconds since the last progress.
    fn stalled(&self) -> f64 {
        self.progress.elapsed().as_secs_f64()
    }
}

/// Publishes at shutdown the impacts still waiting for the send window (a reliable subscriber
/// was behind when the stop came), as acknowledgements open it: they were located, so every
/// subscriber must get them. Gives up, with a warning, as [`Patience`] says.
pub fn flush_impacts(
    publisher: &Publisher<ImpactEvent>,
    queue: &mut VecDeque<ImpactEvent>,
    n: &mut Counters,
    log: &Logger,
) {
    let mut patience = Patience::new(queue.len() as u64);
    loop {
        publish_impacts(publisher, queue, n, log);
        if queue.is_empty() {
            return;
        }
        if patience.exhausted(queue.len() as u64) {
            log.log(
                LogLevel::Warn,
                &format!(
                    "impacts: {} located not published: the send window stayed full for {:.3} s",
                    queue.len(),
                    patience.stalled()
                ),
            );
            return;
        }
        // Returns as soon as everything sent is acknowledged, which opens the window.
        if publisher
            .wait_for_acknowledgments(Duration::from_millis(10))
            .is_err()
        {
            std::thread::sleep(Duration::from_millis(10));
        }
    }
}

/// Waits for the impact subscribers' acknowledgements at shutdown (as long as [`Patience`]
/// lasts) and logs the outcome: all `published` impacts acknowledged, or how many were not.
pub fn await_acknowledgements(
    publisher: &Publisher<ImpactEvent>,
    subscribers: usize,
    published: u64,
    log: &Logger,
) {
    let mut patience = Patience::new(publisher.unacknowledged_count());
    loop {
        match publisher.wait_for_acknowledgments(Duration::from_millis(100)) {
            Ok(true) => {
                if subscribers > 0 {
                    log.log(
                        LogLevel::Info,
                        &format!(
                            "impacts: all {published} published acknowledged by the {subscribers} \
                             matched subscriptions in {:.3} s",
                            patience.waited()
                        ),
                    );
                }
                return;
            }
            Ok(false) => {}
            Err(e) => {
                log.log(
                    LogLevel::Warn,
                    &format!("impacts: cannot wait for acknowledgements: {e}"),
                );
                return;
            }
        }
        let left = publisher.unacknowledged_count();
        if patience.exhausted(left) {
            log.log(
                LogLevel::Warn,
                &format!(
                    "impacts: {left} of {published} published not acknowledged by every matched \
                     subscription after {:.3} s ({} s without progress, or {} s in all)",
                    patience.waited(),
                    SHUTDOWN_ACK_STALL.as_secs(),
                    SHUTDOWN_ACK_LIMIT.as_secs()
                ),
            );
            return;
        }
    }
}
