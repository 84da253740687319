//! What the simulation loop reads between its steps: shaker commands and service requests,
//! and the `/diagnostics` reports it publishes while it is there; and its sleep.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use bistable_impact_node::diagnostics::{self, DiagnosticsClock};
use bistable_impact_node::inbox::{take_commands, Taken, Throttle, MAX_COMMANDS_PER_CALL};
use bistable_impact_node::logging::{Log, LogLevel};
use bistable_impact_node::msg::{
    ResetStateResponse, SetBoolResponse, ShakerCommand, StepResponse, TriggerResponse,
};
use bistable_impact_node::paramset::{self, Changes};
use bistable_impact_node::paramsrv;
use bistable_impact_node::state::{LoopState, LOG_BUDGET};
use ros2_client::dds::rustdds::mio1::{Events, Interest, Poll, Token};
use ros2_client::parameters::{raw, Parameter};
use ros2_client::rcl_interfaces::{
    DescribeParametersResponse, GetParameterTypesResponse, GetParametersResponse,
    ListParametersResponse, SetParametersAtomicallyResponse, SetParametersResponse,
};
use ros2_client::service::RmwRequestId;
use ros2_client::{ParameterValue, Server, Subscription, WriteError};

use super::dds::{Logger, Services};
use super::publish::answer_step;

/// The loop's state in the node (step requests answered by their request id).
pub type State = LoopState<RmwRequestId>;

/// How often at most the loop looks for service requests (running free, it takes commands
/// between all its steps); also how long it sleeps while commands or requests are left unread.
const POLL: Duration = Duration::from_millis(1);
/// Most requests taken from one service in one call of [`Inbox::serve`].
const MAX_REQUESTS_PER_CALL: usize = 100;

/// [`Wakeup`] tokens: the shaker command subscription, the service servers, the stop signal.
const COMMAND_TOKEN: Token = Token(0);
const REQUEST_TOKEN: Token = Token(1);
pub const STOP_TOKEN: Token = Token(2);

/// The loop's sleep: it ends when a shaker command or a service request arrives, at a stop
/// signal, or at a deadline, so that a waiting node costs nothing between its ticks (before,
/// it looked at its 11 DDS readers every millisecond: 4 % of a core at 100 Hz, no subscriber).
struct Wakeup {
    poll: Poll,
    events: Events,
}

impl Wakeup {
    /// Sleeps up to `timeout` or until an event; returns whether a service request arrived.
    fn sleep(&mut self, timeout: Duration) -> bool {
        if let Err(e) = self.poll.poll(&mut self.events, Some(timeout)) {
            // Interrupted (a signal): the caller looks at the stop flag and sleeps again.
            if e.kind() != std::io::ErrorKind::Interrupted {
                std::thread::sleep(timeout.min(POLL));
            }
            return false;
        }
        self.events.iter().any(|e| e.token() == REQUEST_TOKEN)
    }
}

/// Registers the command subscription and the service servers with `poll` (the loop's
/// [`Wakeup`]).
pub fn register_wakeups(
    poll: &Poll,
    commands: &mut Subscription<ShakerCommand>,
    sv: &mut Services,
) -> std::io::Result<()> {
    let registry = poll.registry();
    registry.register(commands, COMMAND_TOKEN, Interest::READABLE)?;
    registry.register(&mut sv.get, REQUEST_TOKEN, Interest::READABLE)?;
    registry.register(&mut sv.types, REQUEST_TOKEN, Interest::READABLE)?;
    registry.register(&mut sv.list, REQUEST_TOKEN, Interest::READABLE)?;
    registry.register(&mut sv.set, REQUEST_TOKEN, Interest::READABLE)?;
    registry.register(&mut sv.set_atomically, REQUEST_TOKEN, Interest::READABLE)?;
    registry.register(&mut sv.describe, REQUEST_TOKEN, Interest::READABLE)?;
    registry.register(&mut sv.pause, REQUEST_TOKEN, Interest::READABLE)?;
    registry.register(&mut sv.step, REQUEST_TOKEN, Interest::READABLE)?;
    registry.register(&mut sv.reset, REQUEST_TOKEN, Interest::READABLE)?;
    registry.register(&mut sv.reset_state, REQUEST_TOKEN, Interest::READABLE)
}

/// Takes up to [`MAX_REQUESTS_PER_CALL`] requests from `server` and answers each with
/// `answer`; a request that cannot be read is logged and skipped. Returns whether requests may
/// be left (the limit was reached).
fn serve_requests<Req: ros2_client::Message + 'static, Resp: ros2_client::Message + 'static>(
    server: &Server<Req, Resp>,
    what: &str,
    log: &Logger,
    mut answer: impl FnMut(RmwRequestId, Req) -> Option<Resp>,
) -> bool {
    for _ in 0..MAX_REQUESTS_PER_CALL {
        match server.receive_request() {
            Ok(Some((id, req))) => {
                if let Some(resp) = answer(id, req) {
                    if let Err(e) = server.send_response(id, resp) {
                        log.log(LogLevel::Warn, &format!("{what}: response not sent: {e}"));
                    }
                }
            }
            Ok(None) => return false,
            Err(e) => log.log(
                LogLevel::Warn,
                &format!("{what}: unreadable request ignored: {e}"),
            ),
        }
    }
    true
}

/// What the simulation loop reads between steps: shaker commands and service requests.
pub struct Inbox<'a> {
    commands: &'a Subscription<ShakerCommand>,
    services: &'a Services,
    throttle: Throttle,
    diagnostics: DiagnosticsClock,
    /// When the service requests are polled next.
    next_service_poll: Instant,
    /// What the loop sleeps on while it waits for wall time.
    wakeup: Wakeup,
    /// The last call left commands or requests unread (it took its limit of them).
    unread: bool,
    /// A request arrived that the service polling has not taken yet.
    requests_waiting: bool,
}

impl<'a> Inbox<'a> {
    /// Reads `commands` and the requests of `services`, sleeping on `poll` (registered with
    /// [`register_wakeups`]).
    pub fn new(
        commands: &'a Subscription<ShakerCommand>,
        services: &'a Services,
        poll: Poll,
    ) -> Self {
        let now = Instant::now();
        Self {
            commands,
            services,
            throttle: Throttle::new(LOG_BUDGET, Duration::from_secs(1), now),
            diagnostics: DiagnosticsClock::new(now),
            next_service_poll: now,
            wakeup: Wakeup {
                poll,
                events: Events::with_capacity(64),
            },
            unread: false,
            requests_waiting: false,
        }
    }

    /// Takes the waiting commands and service requests and applies them, and publishes
    /// `/diagnostics` when due; returns whether the pacing changed (a parameter or a control
    /// request restarted the schedule). `waiting`: called from [`Inbox::wait_until`] after a
    /// sleep of its [`Wakeup`], which then knows whether a request arrived.
    pub fn serve(&mut self, st: &mut State, log: &Logger, waiting: bool) -> bool {
        self.take_commands(st, log);
        // The services at most once per POLL (the loop calls this between all its steps, far
        // more often when it runs as fast as possible), and only when the Wakeup saw a request
        // arrive: after a sleep (`waiting`) it knows, otherwise it is asked without sleeping.
        let now = Instant::now();
        let mut repaced = false;
        if now >= self.next_service_poll {
            self.next_service_poll = now + POLL;
            if !waiting && self.wakeup.sleep(Duration::ZERO) {
                self.requests_waiting = true;
            }
            if std::mem::take(&mut self.requests_waiting) {
                repaced = self.serve_parameters(st, log) | self.serve_control(st, log);
            }
        }
        if let Some((k, window)) = st.request_log.flush(now) {
            log.log(
                LogLevel::Warn,
                &format!(
                    "{k} more service request messages in the last {:.1} s not logged (at most \
                     {LOG_BUDGET} a second; so far {} requests refused)",
                    window.as_secs_f64(),
                    st.n.requests_refused
                ),
            );
        }
        self.publish_diagnostics(st, log);
        repaced
    }

    /// Takes up to [`MAX_COMMANDS_PER_CALL`] shaker commands and logs them (throttled).
    fn take_commands(&mut self, st: &mut State, log: &Logger) {
        let throttle = &mut self.throttle;
        let commands = self.commands;
        let taken = {
            let LoopState { runner, n, .. } = &mut *st;
            take_commands(
                || commands.take().map(|s| s.map(|(cmd, _)| cmd)),
                runner,
                MAX_COMMANDS_PER_CALL,
                |taken| {
                    let (level, msg) = match taken {
                        Taken::Accepted(what) => {
                            n.commands += 1;
                            (LogLevel::Info, format!("accepted command: {what}"))
                        }
                        Taken::Refused(why) => {
                            n.commands_refused += 1;
                            (LogLevel::Warn, format!("refused shaker command: {why}"))
                        }
                    };
                    if throttle.allow(Instant::now()) {
                        log.log(level, &msg);
                    }
                },
            )
        };
        self.unread = taken == MAX_COMMANDS_PER_CALL;
        for note in st.runner.take_notes() {
            if self.throttle.allow(Instant::now()) {
                log.log(LogLevel::Info, &note);
            }
        }
        if let Some((k, window)) = self.throttle.flush(Instant::now()) {
            log.log(
                LogLevel::Warn,
                &format!(
                    "{k} more shaker command messages in the last {:.1} s not logged (at most \
                     {LOG_BUDGET} a second; so far {} commands accepted, {} refused)",
                    window.as_secs_f64(),
                    st.n.commands,
                    st.n.commands_refused
                ),
            );
        }
    }

    /// The `rcl_interfaces` parameter services; returns whether the pacing changed.
    fn serve_parameters(&mut self, st: &mut State, log: &Logger) -> bool {
        let sv = self.services;
        let mut more = false;
        more |= serve_requests(&sv.list, "list_parameters", log, |_, req| {
            Some(ListParametersResponse {
                result: paramsrv::list(&req.prefixes, req.depth),
            })
        });
        more |= serve_requests(&sv.get, "get_parameters", log, |_, req| {
            Some(GetParametersResponse {
                values: req
                    .names
                    .iter()
                    .map(|n| paramsrv::get(&st.settings, n).into())
                    .collect(),
            })
        });
        more |= serve_requests(&sv.types, "get_parameter_types", log, |_, req| {
            Some(GetParameterTypesResponse {
                values: req
                    .names
                    .iter()
                    .map(|n| ParameterValue::to_parameter_type_raw(&paramsrv::get(&st.settings, n)))
                    .collect(),
            })
        });
        more |= serve_requests(&sv.describe, "describe_parameters", log, |_, req| {
            Some(DescribeParametersResponse {
                values: req.names.iter().map(|n| paramsrv::describe(n)).collect(),
            })
        });
        let mut changes = Changes::default();
        more |= serve_requests(&sv.set, "set_parameters", log, |_, req| {
            let params = req.parameter.into_iter().map(Parameter::from);
            let results = paramset::set_each(st, params, log, &mut changes);
            Some(SetParametersResponse {
                results: results.into_iter().map(Into::into).collect(),
            })
        });
        more |= serve_requests(
            &sv.set_atomically,
            "set_parameters_atomically",
            log,
            |_, req| {
                let params = req.parameter.into_iter().map(Parameter::from).collect();
                let result = paramset::set_atomically(st, params, log, &mut changes);
                Some(SetParametersAtomicallyResponse {
                    result: result.into(),
                })
            },
        );
        if !changes.changed.is_empty() {
            let event = raw::ParameterEvent {
                stamp: ros2_client::builtin_interfaces::Time::now(),
                node: sv.fully_qualified.clone(),
                new_parameters: Vec::new(),
                changed_parameters: changes
                    .changed
                    .into_iter()
                    .map(raw::Parameter::from)
                    .collect(),
                deleted_parameters: Vec::new(),
            };
            if let Err(e) = sv.parameter_events.publish(event) {
                log.log(
                    LogLevel::Warn,
                    &format!("parameter event not published: {e}"),
                );
            }
        }
        self.requests_waiting |= more;
        changes.repaced
    }

    /// Pause, step and reset; returns whether the pacing changed.
    fn serve_control(&mut self, st: &mut State, log: &Logger) -> bool {
        let sv = self.services;
        let mut more = false;
        let mut repaced = false;
        more |= serve_requests(&sv.pause, "pause", log, |_, req| {
            let (success, message) = st.control.set_paused(req.data, st.runner.now());
            repaced = true;
            st.log_request(log, "pause", success, &message);
            Some(SetBoolResponse { success, message })
        });
        more |= serve_requests(&sv.step, "step", log, |id, req| {
            let halted = st.runner.halted().map(str::to_owned);
            match st.control.start_step(id, req.ticks, halted.as_deref()) {
                Ok(()) => {
                    let msg = format!("step of {} ticks from t = {} s", req.ticks, st.runner.now());
                    st.log_throttled(log, LogLevel::Info, &msg);
                    None
                }
                Err(message) => {
                    st.log_request(log, "step", false, &message);
                    Some(StepResponse {
                        success: false,
                        message,
                        t: st.runner.now(),
                        impact_count: st.runner.impact_count(),
                    })
                }
            }
        });
        let mut reset = |st: &mut State, state: Option<(f64, f64)>| {
            let answer = |st: &State, job| answer_step(sv, st, job, "interrupted by a reset", log);
            let (success, message) = st.reset(state, log, answer);
            repaced |= success;
            (success, message)
        };
        more |= serve_requests(&sv.reset, "reset", log, |_, _| {
            let (success, message) = reset(st, None);
            Some(TriggerResponse { success, message })
        });
        more |= serve_requests(&sv.reset_state, "reset_state", log, |_, req| {
            let (success, message) = reset(st, Some((req.x, req.v)));
            Some(ResetStateResponse { success, message })
        });
        self.requests_waiting |= more;
        repaced
    }

    /// Publishes `/diagnostics` if a report is due (to a matched subscription only).
    fn publish_diagnostics(&mut self, st: &mut State, log: &Logger) {
        let Some(rtf) = self.diagnostics.due(Instant::now(), st.n.advanced) else {
            return;
        };
        let publisher = &self.services.diagnostics;
        if publisher.matched_reader_count() == 0 {
            st.n.window_lateness = Duration::ZERO;
            return;
        }
        let stamp = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0.0, |d| d.as_secs_f64());
        let report = diagnostics::report(st, &self.services.fully_qualified, rtf, stamp);
        st.n.window_lateness = Duration::ZERO;
        if let Err(e) = publisher.publish(report) {
            if !matches!(e, WriteError::WouldBlock { .. }) {
                log.log(LogLevel::Warn, &format!("diagnostics not published: {e}"));
            }
        }
    }

    /// Serves commands and requests until wall-clock instant `until` (or a stop request, or a
    /// change of pacing), sleeping in between until something arrives; whether `until` was
    /// reached (false: stopped or repaced before).
    pub fn wait_until(
        &mut self,
        until: Instant,
        stop: &AtomicBool,
        st: &mut State,
        log: &Logger,
    ) -> bool {
        while !stop.load(Ordering::Relaxed) {
            if self.serve(st, log, true) {
                return false;
            }
            let now = Instant::now();
            if now >= until {
                return true;
            }
            let mut wake = until.min(self.diagnostics.next);
            if self.unread {
                wake = wake.min(now + POLL);
            }
            if self.requests_waiting {
                wake = wake.min(self.next_service_poll);
            }
            if self.wakeup.sleep(wake.saturating_duration_since(now)) {
                self.requests_waiting = true;
            }
        }
        false
    }
}
