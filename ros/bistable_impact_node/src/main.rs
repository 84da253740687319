//! `bistable_impact_node`: the bistable impact oscillator as a ROS 2 node (see `ros/README.md`).

use std::collections::{BTreeSet, VecDeque};
use std::net::Ipv4Addr;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use bistable_impact_node::args::{self, Config, DiscoveryRange, Parsed};
use bistable_impact_node::control::{Control, StepJob};
use bistable_impact_node::inbox::{take_commands, Taken, Throttle, MAX_COMMANDS_PER_CALL};
use bistable_impact_node::msg::{
    Clock, DiagnosticArray, DiagnosticStatus, Header, ImpactEvent, KeyValue, MassState,
    ResetStateRequest, ResetStateResponse, SetBoolRequest, SetBoolResponse, ShakerCommand,
    StepRequest, StepResponse, Time, TriggerRequest, TriggerResponse,
};
use bistable_impact_node::names::{Kind, Names};
use bistable_impact_node::params::{Settings, MAX_HISTORY_DEPTH, SPECS};
use bistable_impact_node::paramsrv::{self, USE_SIM_TIME, USE_SIM_TIME_REFUSED};
use bistable_impact_node::sim::{Outcome, Runner};
use ros2_client::dds::rustdds::mio1::{Events, Interest, Poll, Token, Waker};
use ros2_client::dds::rustdds::{
    DomainParticipantBuilder, DomainParticipantStatusEvent, DomainParticipantStatusListener,
    StatusEvented, GUID,
};
use ros2_client::log::LogLevel;
use ros2_client::parameters::{raw, Parameter};
use ros2_client::qos::{Durability, History, Reliability, WhenFull};
use ros2_client::rcl_interfaces::{
    DescribeParametersRequest, DescribeParametersResponse, GetParameterTypesRequest,
    GetParameterTypesResponse, GetParametersRequest, GetParametersResponse, ListParametersRequest,
    ListParametersResponse, SetParametersAtomicallyResponse, SetParametersRequest,
    SetParametersResponse,
};
use ros2_client::rosout::{NodeLoggingHandle, RosoutRaw};
use ros2_client::service::RmwRequestId;
use ros2_client::{
    Context, MessageTypeName, Name, Node, NodeName, NodeOptions, ParameterValue, Publisher,
    QosProfile, Server, ServiceMapping, ServiceTypeName, Subscription, WriteError,
};

/// QoS of `/bistable/mass_state` and `/clock`: reliable (matches reliable and best-effort
/// subscribers) but a full send window drops the sample instead of stalling the simulation.
const fn sample_qos(depth: usize) -> QosProfile {
    QosProfile::subscription_default()
        .reliability(Reliability::Reliable {
            when_full: WhenFull::Fail,
        })
        .durability(Durability::Volatile)
        .history(History::KeepLast { depth })
}

/// QoS of `/bistable/impacts`: reliable; when RustDDS's window of unacknowledged samples
/// (8192) is full the simulation waits for the subscribers instead of dropping an impact.
/// Transient local with KEEP_LAST `depth` (the `history_depth` parameter, at most 8192 so that
/// RustDDS's cache cleaning, which keeps the last 8192 + 1, never removes one of them): a
/// subscriber that joins late (e.g. after impact 0 at t = 0) first receives the last `depth`
/// impacts (RustDDS patched to offer exactly those, see `ros/patches/README.md`), then the
/// live stream.
const fn impact_qos(depth: usize) -> QosProfile {
    QosProfile::subscription_default()
        .reliability(Reliability::Reliable {
            when_full: WhenFull::Wait(Duration::from_millis(20)),
        })
        .durability(Durability::TransientLocal)
        .history(History::KeepLast { depth })
}

/// QoS of `/bistable/shaker_command`: reliable, keeps the last 10,000 commands not yet taken
/// (at ~46,000 commands/s from two publishers on two cores the loop was at times starved of
/// the CPU long enough for 1000 to overflow: 0.1 % lost).
const COMMAND_QOS: QosProfile = QosProfile::subscription_default()
    .reliability(Reliability::Reliable {
        when_full: WhenFull::DEFAULT,
    })
    .history(History::KeepLast { depth: 10000 });

/// The node's topics as named in the code (relative to the node namespace, `/clock`
/// absolute), resolved with [`Names::resolve`].
const MASS_STATE: &str = "bistable/mass_state";
const IMPACTS: &str = "bistable/impacts";
const SHAKER_COMMAND: &str = "bistable/shaker_command";
const CLOCK: &str = "/clock";
const DIAGNOSTICS: &str = "/diagnostics";
const TOPICS: [&str; 5] = [MASS_STATE, IMPACTS, SHAKER_COMMAND, CLOCK, DIAGNOSTICS];
/// The control services (relative to the node namespace, resolved like the topics).
const PAUSE: &str = "bistable/pause";
const STEP: &str = "bistable/step";
const RESET: &str = "bistable/reset";
const RESET_STATE: &str = "bistable/reset_state";
const SERVICES: [&str; 4] = [PAUSE, STEP, RESET, RESET_STATE];

/// QoS of the services (requests and replies): reliable, volatile, keep last 100 (ROS's
/// service default keeps 10; more here so that a burst of requests from several clients
/// between two polls of the loop is not overwritten).
const SERVICE_QOS: QosProfile = QosProfile::subscription_default()
    .reliability(Reliability::Reliable {
        when_full: WhenFull::DEFAULT,
    })
    .durability(Durability::Volatile)
    .history(History::KeepLast { depth: 100 });

/// QoS of `/parameter_events` (ROS's parameter events profile: reliable, keep last 1000).
const PARAMETER_EVENTS_QOS: QosProfile = QosProfile::subscription_default()
    .reliability(Reliability::Reliable {
        when_full: WhenFull::Fail,
    })
    .durability(Durability::Volatile)
    .history(History::KeepLast { depth: 1000 });

/// QoS of `/diagnostics`: as the state (a full send window drops a report, never stalls).
const DIAGNOSTICS_QOS: QosProfile = sample_qos(10);

/// Logs to standard error and `/rosout`.
struct Logger {
    handle: NodeLoggingHandle,
    name: String,
    level: u8,
    rosout: bool,
    stdout: bool,
}

impl Logger {
    fn log(&self, level: LogLevel, msg: &str) {
        if (level as u8) < self.level {
            return;
        }
        if self.stdout {
            let tag = match level {
                LogLevel::Debug => "DEBUG",
                LogLevel::Info => "INFO",
                LogLevel::Warn => "WARN",
                LogLevel::Error => "ERROR",
                LogLevel::Fatal => "FATAL",
            };
            let now = std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(0.0, |d| d.as_secs_f64());
            eprintln!("[{tag}] [{now:.9}] [{}]: {msg}", self.name);
        }
        if self.rosout {
            self.handle.rosout_raw(
                ros2_client::builtin_interfaces::Time::now(),
                level,
                &self.name,
                msg,
                file!(),
                "bistable_impact_node",
                line!(),
            );
        }
    }
}

/// Counters reported at shutdown and in `/diagnostics`.
#[derive(Default)]
struct Counters {
    states: u64,
    states_dropped: u64,
    /// State ticks with no subscription matched (nothing built or published).
    states_unsubscribed: u64,
    impacts: u64,
    impacts_failed: u64,
    commands: u64,
    commands_refused: u64,
    /// Service requests refused (control services and parameter sets).
    requests_refused: u64,
    /// Paced ticks (real_time_factor > 0) whose lateness was measured.
    paced_ticks: u64,
    /// Largest lateness of a state publication: from the wall-clock instant the previous state
    /// was due to the publication of the next one (the loop publishes a state as soon as it is
    /// computed, then waits for it to become due).
    max_lateness: Duration,
    /// The same, since the last `/diagnostics` report.
    window_lateness: Duration,
    /// Paced ticks more than 10 ms late.
    late_ticks: u64,
    /// Simulation time advanced [s] (resets do not count back).
    advanced: f64,
    /// Resets done.
    resets: u64,
}

/// Keeps simulation time at `real_time_factor` times wall-clock time.
struct Pacer {
    rtf: f64,
    wall: Instant,
    sim: f64,
}

impl Pacer {
    fn new(rtf: f64, sim: f64) -> Self {
        Self {
            rtf,
            wall: Instant::now(),
            sim,
        }
    }

    /// The wall-clock instant at which simulation time `t` [s] is due; `None` when `rtf` is 0
    /// (as fast as possible) or when more than a second behind (then the schedule restarts
    /// from now).
    fn due(&mut self, t: f64) -> Option<Instant> {
        if self.rtf <= 0.0 {
            return None;
        }
        let due = (t - self.sim) / self.rtf;
        let elapsed = self.wall.elapsed().as_secs_f64();
        if elapsed > due + 1.0 || !due.is_finite() {
            *self = Self::new(self.rtf, t);
            return None;
        }
        Some(self.wall + Duration::from_secs_f64(due.max(0.0)))
    }
}

/// How often at most the loop looks for service requests (running free, it takes commands
/// between all its steps); also how long it sleeps while commands or requests are left unread.
const POLL: Duration = Duration::from_millis(1);
/// Per-command log lines (accepted, refused, applied) let through per second; the others are
/// counted and summarised once a second (the totals are in the shutdown summary).
const COMMAND_LOG_BUDGET: u32 = 50;
/// Most requests taken from one service in one call of [`Inbox::serve`].
const MAX_REQUESTS_PER_CALL: usize = 100;
/// Period of the `/diagnostics` reports (wall clock).
const DIAGNOSTICS_PERIOD: Duration = Duration::from_secs(1);

/// What the simulation loop changes as commands and requests arrive.
struct LoopState {
    runner: Runner,
    settings: Settings,
    pacer: Pacer,
    n: Counters,
    control: Control<RmwRequestId>,
    /// Impacts located and not yet published (a reliable subscriber is behind).
    impacts: VecDeque<ImpactEvent>,
    /// A reset happened: publish the new state and clock now.
    reset_tick: bool,
    /// Wall-clock instant the current paced tick was due, for its lateness.
    last_due: Option<Instant>,
    /// Log lines about service requests, limited as those about commands.
    request_log: Throttle,
}

impl LoopState {
    /// Logs a line about a service request unless over the budget (then it is counted and
    /// summarised once a second).
    fn log_throttled(&mut self, log: &Logger, level: LogLevel, msg: &str) {
        if self.request_log.allow(Instant::now()) {
            log.log(level, msg);
        }
    }
}

/// The node's service servers (parameter services of `rcl_interfaces` and the control
/// services) and the publishers they feed (`/parameter_events`, `/diagnostics`).
struct Services {
    get: Server<GetParametersRequest, GetParametersResponse>,
    types: Server<GetParameterTypesRequest, GetParameterTypesResponse>,
    list: Server<ListParametersRequest, ListParametersResponse>,
    set: Server<SetParametersRequest, SetParametersResponse>,
    set_atomically: Server<SetParametersRequest, SetParametersAtomicallyResponse>,
    describe: Server<DescribeParametersRequest, DescribeParametersResponse>,
    parameter_events: Publisher<raw::ParameterEvent>,
    pause: Server<SetBoolRequest, SetBoolResponse>,
    step: Server<StepRequest, StepResponse>,
    reset: Server<TriggerRequest, TriggerResponse>,
    reset_state: Server<ResetStateRequest, ResetStateResponse>,
    diagnostics: Publisher<DiagnosticArray>,
    fully_qualified: String,
}

/// What the simulation loop reads between steps: shaker commands and service requests.
struct Inbox<'a> {
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

/// The loop's sleep: it ends when a shaker command or a service request arrives, at a stop
/// signal, or at a deadline, so that a waiting node costs nothing between its ticks (before,
/// it looked at its 11 DDS readers every millisecond: 4 % of a core at 100 Hz, no subscriber).
struct Wakeup {
    poll: Poll,
    events: Events,
}

/// [`Wakeup`] tokens: the shaker command subscription, the service servers, the stop signal.
const COMMAND_TOKEN: Token = Token(0);
const REQUEST_TOKEN: Token = Token(1);
const STOP_TOKEN: Token = Token(2);

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

/// When the next `/diagnostics` report is due and what the last one saw.
struct DiagnosticsClock {
    next: Instant,
    last_wall: Instant,
    last_advanced: f64,
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

impl Inbox<'_> {
    /// Takes the waiting commands and service requests and applies them, and publishes
    /// `/diagnostics` when due; returns whether the pacing changed (a parameter or a control
    /// request restarted the schedule). `waiting`: called from [`Inbox::wait_until`] after a
    /// sleep of its [`Wakeup`], which then knows whether a request arrived.
    fn serve(&mut self, st: &mut LoopState, log: &Logger, waiting: bool) -> bool {
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
                     {COMMAND_LOG_BUDGET} a second; so far {} commands accepted, {} refused)",
                    window.as_secs_f64(),
                    st.n.commands,
                    st.n.commands_refused
                ),
            );
        }
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
                     {COMMAND_LOG_BUDGET} a second; so far {} requests refused)",
                    window.as_secs_f64(),
                    st.n.requests_refused
                ),
            );
        }
        self.publish_diagnostics(st, log);
        repaced
    }

    /// The `rcl_interfaces` parameter services; returns whether the pacing changed.
    fn serve_parameters(&mut self, st: &mut LoopState, log: &Logger) -> bool {
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
        let mut repaced = false;
        let mut changed = Vec::new();
        more |= serve_requests(&sv.set, "set_parameters", log, |_, req| {
            let results = req
                .parameter
                .into_iter()
                .map(|p| {
                    let p = Parameter::from(p);
                    let r = set_parameter(st, &p.name, &p.value, log);
                    if r.is_ok() {
                        repaced |= p.name == "real_time_factor";
                        changed.push(p);
                    }
                    r.into()
                })
                .collect();
            Some(SetParametersResponse { results })
        });
        more |= serve_requests(
            &sv.set_atomically,
            "set_parameters_atomically",
            log,
            |_, req| {
                let params: Vec<Parameter> =
                    req.parameter.into_iter().map(Parameter::from).collect();
                let checked = params.iter().try_for_each(|p| {
                    paramsrv::check_set(&st.settings, &p.name, &p.value)
                        .map_err(|why| format!("parameter '{}': {why}", p.name))
                });
                let result = match checked {
                    Err(why) => {
                        st.n.requests_refused += 1;
                        st.log_throttled(
                            log,
                            LogLevel::Warn,
                            &format!("refused parameters: {why}"),
                        );
                        Err(why)
                    }
                    Ok(()) => params.into_iter().try_for_each(|p| {
                        let r = set_parameter(st, &p.name, &p.value, log);
                        if r.is_ok() {
                            repaced |= p.name == "real_time_factor";
                            changed.push(p);
                        }
                        r
                    }),
                };
                Some(SetParametersAtomicallyResponse {
                    result: result.into(),
                })
            },
        );
        if !changed.is_empty() {
            let event = raw::ParameterEvent {
                stamp: ros2_client::builtin_interfaces::Time::now(),
                node: sv.fully_qualified.clone(),
                new_parameters: Vec::new(),
                changed_parameters: changed.into_iter().map(raw::Parameter::from).collect(),
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
        repaced
    }

    /// Pause, step and reset; returns whether the pacing changed.
    fn serve_control(&mut self, st: &mut LoopState, log: &Logger) -> bool {
        let sv = self.services;
        let mut more = false;
        let mut repaced = false;
        more |= serve_requests(&sv.pause, "pause", log, |_, req| {
            let (success, message) = st.control.set_paused(req.data, st.runner.now());
            repaced = true;
            log_request(st, log, "pause", success, &message);
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
                    log_request(st, log, "step", false, &message);
                    Some(StepResponse {
                        success: false,
                        message,
                        t: st.runner.now(),
                        impact_count: st.runner.impact_count(),
                    })
                }
            }
        });
        let mut reset = |st: &mut LoopState, state: Option<(f64, f64)>| -> (bool, String) {
            let mut flushed = Vec::new();
            match st.runner.reset(&st.settings, state, &mut flushed) {
                Ok(message) => {
                    st.impacts.extend(flushed);
                    if let Some(job) = st.control.abort_step() {
                        answer_step(sv, st, job, "interrupted by a reset", log);
                    }
                    st.n.resets += 1;
                    st.reset_tick = true;
                    st.last_due = None;
                    st.pacer = Pacer::new(st.settings.real_time_factor, 0.0);
                    repaced = true;
                    log_request(st, log, "reset", true, &message);
                    (true, message)
                }
                Err(why) => {
                    let message = format!("reset refused: {why}");
                    log_request(st, log, "reset", false, &message);
                    (false, message)
                }
            }
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

    /// Publishes `/diagnostics` if a report is due.
    fn publish_diagnostics(&mut self, st: &mut LoopState, log: &Logger) {
        let now = Instant::now();
        if now < self.diagnostics.next {
            return;
        }
        let d = &mut self.diagnostics;
        let wall = now.duration_since(d.last_wall).as_secs_f64();
        let rtf = if wall > 0.0 {
            (st.n.advanced - d.last_advanced) / wall
        } else {
            0.0
        };
        d.last_wall = now;
        d.last_advanced = st.n.advanced;
        d.next = now + DIAGNOSTICS_PERIOD;
        if self.services.diagnostics.matched_reader_count() == 0 {
            st.n.window_lateness = Duration::ZERO;
            return;
        }
        let report = diagnostics(st, &self.services.fully_qualified, rtf);
        st.n.window_lateness = Duration::ZERO;
        if let Err(e) = self.services.diagnostics.publish(report) {
            if !matches!(e, WriteError::WouldBlock { .. }) {
                log.log(LogLevel::Warn, &format!("diagnostics not published: {e}"));
            }
        }
    }

    /// Serves commands and requests until wall-clock instant `until` (or a stop request, or a
    /// change of pacing), sleeping in between until something arrives.
    fn wait_until(&mut self, until: Instant, stop: &AtomicBool, st: &mut LoopState, log: &Logger) {
        while !stop.load(Ordering::Relaxed) {
            if self.serve(st, log, true) {
                return;
            }
            let now = Instant::now();
            if now >= until {
                return;
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
    }
}

/// Logs a control request's outcome (refusals are counted).
fn log_request(st: &mut LoopState, log: &Logger, what: &str, success: bool, message: &str) {
    if success {
        st.log_throttled(log, LogLevel::Info, &format!("{what}: {message}"));
    } else {
        st.n.requests_refused += 1;
        st.log_throttled(
            log,
            LogLevel::Warn,
            &format!("refused {what} request: {message}"),
        );
    }
}

/// Answers a step request that ended before all its ticks were done.
fn answer_step(sv: &Services, st: &LoopState, job: StepJob<RmwRequestId>, why: &str, log: &Logger) {
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

/// Checks and applies a runtime parameter change; the reason if refused (logged).
fn set_parameter(
    st: &mut LoopState,
    name: &str,
    value: &ParameterValue,
    log: &Logger,
) -> Result<(), String> {
    let result = paramsrv::check_set(&st.settings, name, value)
        .and_then(|()| apply_parameter(st, name, value, log));
    if let Err(why) = &result {
        st.n.requests_refused += 1;
        st.log_throttled(
            log,
            LogLevel::Warn,
            &format!("refused parameter {name}: {why}"),
        );
    }
    result
}

/// The `/diagnostics` report: one status, `<node>: simulation`, with the figures.
fn diagnostics(st: &LoopState, fully_qualified: &str, rtf: f64) -> DiagnosticArray {
    let n = &st.n;
    let r = &st.runner;
    let (level, status) = if let Some(why) = r.halted() {
        (DiagnosticStatus::ERROR, format!("halted: {why}"))
    } else if st.control.stepping() {
        (DiagnosticStatus::OK, "stepping".to_owned())
    } else if st.control.paused() {
        (DiagnosticStatus::OK, "paused".to_owned())
    } else if n.window_lateness > Duration::from_millis(100) {
        (
            DiagnosticStatus::WARN,
            "running, behind its real-time schedule".to_owned(),
        )
    } else {
        (DiagnosticStatus::OK, "running".to_owned())
    };
    let kv = |key: &str, value: String| KeyValue {
        key: key.to_owned(),
        value,
    };
    let ms = |d: Duration| format!("{:.3}", d.as_secs_f64() * 1e3);
    DiagnosticArray {
        header: Header {
            stamp: Time::from_seconds(
                std::time::SystemTime::now()
                    .duration_since(std::time::UNIX_EPOCH)
                    .map_or(0.0, |d| d.as_secs_f64()),
            ),
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

fn main() -> ExitCode {
    let argv: Vec<String> = std::env::args().skip(1).collect();
    let domain = std::env::var("ROS_DOMAIN_ID").ok();
    let read = |f: &str| std::fs::read_to_string(f).map_err(|e| e.to_string());
    match args::parse(&argv, domain.as_deref(), read) {
        Ok(Parsed::Help) => {
            println!("{}", args::USAGE);
            let d = Settings::default();
            for s in SPECS {
                let kind = match s.change {
                    bistable_impact_node::params::Change::Runtime => "runtime",
                    bistable_impact_node::params::Change::StartUp => "start-up",
                };
                let v = d.get(s.name).map(|v| format!("{v:?}")).unwrap_or_default();
                println!("  {:<17} {} ({kind}; default {v})", s.name, s.doc);
            }
            ExitCode::SUCCESS
        }
        Ok(Parsed::Run(cfg)) => match args::discovery_range(
            std::env::var("ROS_AUTOMATIC_DISCOVERY_RANGE")
                .ok()
                .as_deref(),
            std::env::var("ROS_LOCALHOST_ONLY").ok().as_deref(),
        )
        .map_err(|e| (e, ExitCode::from(2)))
        .and_then(|range| run(*cfg, range).map_err(|e| (e, ExitCode::FAILURE)))
        {
            Ok(()) => ExitCode::SUCCESS,
            Err((e, code)) => {
                eprintln!("[FATAL] [bistable_impact]: {e}");
                code
            }
        },
        Err(e) => {
            eprintln!("bistable_impact_node: {e}");
            ExitCode::from(2)
        }
    }
}

fn err<E: std::fmt::Display>(what: &'static str) -> impl Fn(E) -> String {
    move |e| format!("cannot create the {what}: {e}")
}

/// The ros2-client [`Name`] of the topic or service the node calls `name`, resolved as rcl
/// does (node namespace, remapping rules); the result is absolute.
fn ros_name(names: &Names, name: &str, kind: Kind) -> Result<Name, String> {
    let full = names.resolve(name, kind)?;
    let (ns, base) = full.rsplit_once('/').unwrap_or(("", &full));
    Name::new(if ns.is_empty() { "/" } else { ns }, base)
        .map_err(|e| format!("{name} resolves to {full}, which ros2-client refuses: {e}"))
}

/// Registers the command subscription and the service servers with `poll` (the loop's
/// [`Wakeup`]).
fn register_wakeups(
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

/// Creates the service servers and the publishers they feed.
fn services(node: &mut Node, names: &Names, fully_qualified: &str) -> Result<Services, String> {
    let mapping = ServiceMapping::Enhanced;
    let qos = SERVICE_QOS;
    let param = |base: &str| {
        Name::new(fully_qualified, base)
            .map_err(|e| format!("service {fully_qualified}/{base}: {e}"))
    };
    macro_rules! server {
        ($name:expr, $pkg:expr, $ty:expr) => {
            node.create_server(
                mapping,
                &$name,
                &ServiceTypeName::new($pkg, $ty),
                qos.clone(),
                qos.clone(),
            )
            .map_err(|e| format!("cannot create the service {}: {e}", $ty))?
        };
    }
    let rcl = "rcl_interfaces";
    let msgs = "bistable_impact_msgs";
    let control = |n: &str| ros_name(names, n, Kind::Service);
    let parameter_events_topic = node
        .create_topic(
            &Name::new("/", "parameter_events").map_err(|e| e.to_string())?,
            MessageTypeName::new(rcl, "ParameterEvent"),
            &PARAMETER_EVENTS_QOS,
        )
        .map_err(err("/parameter_events topic"))?;
    let diagnostics_topic = node
        .create_topic(
            &ros_name(names, DIAGNOSTICS, Kind::Topic)?,
            MessageTypeName::new("diagnostic_msgs", "DiagnosticArray"),
            &DIAGNOSTICS_QOS,
        )
        .map_err(err("/diagnostics topic"))?;
    Ok(Services {
        get: server!(param("get_parameters")?, rcl, "GetParameters"),
        types: server!(param("get_parameter_types")?, rcl, "GetParameterTypes"),
        list: server!(param("list_parameters")?, rcl, "ListParameters"),
        set: server!(param("set_parameters")?, rcl, "SetParameters"),
        set_atomically: server!(
            param("set_parameters_atomically")?,
            rcl,
            "SetParametersAtomically"
        ),
        describe: server!(param("describe_parameters")?, rcl, "DescribeParameters"),
        parameter_events: node
            .create_publisher(&parameter_events_topic, Some(PARAMETER_EVENTS_QOS))
            .map_err(err("/parameter_events publisher"))?,
        pause: server!(control(PAUSE)?, "std_srvs", "SetBool"),
        step: server!(control(STEP)?, msgs, "Step"),
        reset: server!(control(RESET)?, "std_srvs", "Trigger"),
        reset_state: server!(control(RESET_STATE)?, msgs, "ResetState"),
        diagnostics: node
            .create_publisher(&diagnostics_topic, Some(DIAGNOSTICS_QOS))
            .map_err(err("/diagnostics publisher"))?,
        fully_qualified: fully_qualified.to_owned(),
    })
}

fn run(cfg: Config, range: DiscoveryRange) -> Result<(), String> {
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
    let env = |name: &str| std::env::var(name).ok();
    let mut participant = DomainParticipantBuilder::new(cfg.domain_id);
    if range == DiscoveryRange::Localhost {
        // As rmw does for LOCALHOST: only the loopback interface is used and announced.
        participant = participant.with_only_networks([Ipv4Addr::LOCALHOST]);
    }
    let context = participant
        .build()
        .map_err(|e| e.to_string())
        .and_then(|dp| Context::from_domain_participant(dp).map_err(|e| e.to_string()))
        .map_err(|e| format!("cannot join DDS domain {}: {e}", cfg.domain_id))?;
    let names = &cfg.names;
    let node_name = NodeName::new(names.namespace(), names.node())
        .map_err(|e| format!("bad node name {}: {e}", names.fully_qualified()))?;

    // The node serves its parameters itself (full descriptors, use_sim_time refused) and runs
    // no ros2-client spinner, whose built-in use_sim_time would subscribe to /clock with a
    // second type (builtin_interfaces/Time).
    let options = NodeOptions::new()
        .enable_rosout(cfg.rosout)
        .start_parameter_services(false);
    let mut node = context
        .new_node(node_name, options)
        .map_err(|e| format!("cannot create the node: {e}"))?;
    // Matches of remote subscriptions (the impact subscriptions counted at shutdown).
    let status = context.domain_participant().status_listener();

    let log = Logger {
        handle: node.logging_handle(),
        name: names.node().to_owned(),
        level: cfg.log_level,
        rosout: cfg.rosout,
        stdout: cfg.stdout,
    };
    let msgs = "bistable_impact_msgs";
    let create = |node: &mut Node, name: &str, pkg: &str, ty: &str, qos: &QosProfile| {
        node.create_topic(
            &ros_name(names, name, Kind::Topic)?,
            MessageTypeName::new(pkg, ty),
            qos,
        )
        .map_err(|e| format!("cannot create topic {name}: {e}"))
    };
    let state_qos = sample_qos(10);
    let clock_qos = sample_qos(1);
    let state_topic = create(&mut node, MASS_STATE, msgs, "MassState", &state_qos)?;
    // In range by the parameter check (1..=8192).
    let impact_qos = impact_qos(cfg.settings.history_depth.clamp(1, MAX_HISTORY_DEPTH) as usize);
    let impact_topic = create(&mut node, IMPACTS, msgs, "ImpactEvent", &impact_qos)?;
    let command_topic = create(
        &mut node,
        SHAKER_COMMAND,
        msgs,
        "ShakerCommand",
        &COMMAND_QOS,
    )?;
    let clock_topic = create(&mut node, CLOCK, "rosgraph_msgs", "Clock", &clock_qos)?;
    let state_pub: Publisher<MassState> = node
        .create_publisher(&state_topic, Some(state_qos.clone()))
        .map_err(err("mass state publisher"))?;
    let impact_pub: Publisher<ImpactEvent> = node
        .create_publisher(&impact_topic, Some(impact_qos))
        .map_err(err("impact publisher"))?;
    let clock_pub: Publisher<Clock> = node
        .create_publisher(&clock_topic, Some(clock_qos))
        .map_err(err("clock publisher"))?;
    let mut command_sub = node
        .create_subscription::<ShakerCommand>(&command_topic, Some(COMMAND_QOS))
        .map_err(err("command subscription"))?;
    let fully_qualified = node.fully_qualified_name();
    let mut services = services(&mut node, names, &fully_qualified)?;
    register_wakeups(&poll, &mut command_sub, &mut services)
        .map_err(|e| format!("cannot register the readers with the event poll: {e}"))?;

    let s = &cfg.settings;
    log.log(
        LogLevel::Info,
        &format!(
            "started {} in DDS domain {}: zeta = {}, e = {}, omega0 = {} rad/s, delta_x = {} m, \
             Omega = {}, V = {}, publish_rate = {} Hz, real_time_factor = {}, frame_id = '{}', history_depth = {}",
            fully_qualified,
            cfg.domain_id,
            s.zeta,
            s.e,
            s.omega0,
            s.delta_x,
            s.omega,
            s.v,
            s.publish_rate,
            s.real_time_factor,
            s.frame_id,
            s.history_depth
        ),
    );
    let resolved = |list: &[&str], kind: Kind| {
        list.iter()
            .map(|t| format!("{t} -> {}", names.resolve(t, kind).unwrap_or_default()))
            .collect::<Vec<_>>()
            .join(", ")
    };
    log.log(
        LogLevel::Info,
        &format!("topics: {}", resolved(&TOPICS, Kind::Topic)),
    );
    log.log(
        LogLevel::Info,
        &format!("services: {}", resolved(&SERVICES, Kind::Service)),
    );
    log.log(
        LogLevel::Info,
        &format!(
            "DDS discovery range {}",
            match range {
                DiscoveryRange::Localhost => "LOCALHOST (loopback only)",
                DiscoveryRange::Subnet => "SUBNET",
                DiscoveryRange::SystemDefault => "SYSTEM_DEFAULT",
            }
        ),
    );
    if env("ROS_STATIC_PEERS").is_some_and(|p| !p.trim().is_empty()) {
        log.log(
            LogLevel::Warn,
            "ROS_STATIC_PEERS ignored: RustDDS takes no initial peer list (peers are found by \
             multicast discovery only)",
        );
    }
    for w in &cfg.warnings {
        log.log(LogLevel::Warn, w);
    }
    if cfg.use_sim_time == Some(true) {
        log.log(
            LogLevel::Warn,
            &format!("use_sim_time:=true ignored: {USE_SIM_TIME_REFUSED}"),
        );
    }

    let mut st = LoopState {
        pacer: Pacer::new(cfg.settings.real_time_factor, 0.0),
        settings: cfg.settings.clone(),
        runner,
        n: Counters::default(),
        control: Control::default(),
        impacts: VecDeque::new(),
        reset_tick: false,
        last_due: None,
        request_log: Throttle::new(COMMAND_LOG_BUDGET, Duration::from_secs(1), Instant::now()),
    };
    let mut fresh = Vec::new();
    let now = Instant::now();
    let mut inbox = Inbox {
        commands: &command_sub,
        services: &services,
        throttle: Throttle::new(COMMAND_LOG_BUDGET, Duration::from_secs(1), now),
        diagnostics: DiagnosticsClock {
            next: now + DIAGNOSTICS_PERIOD,
            last_wall: now,
            last_advanced: 0.0,
        },
        next_service_poll: now,
        wakeup: Wakeup {
            poll,
            events: Events::with_capacity(64),
        },
        unread: false,
        requests_waiting: false,
    };
    let mut impact_readers = MatchedReaders::new(impact_pub.guid());
    let mut last_outcome = Outcome::Tick;
    publish_tick(&st.runner, &state_pub, &clock_pub, &mut st.n, &log);
    let mut next_status_poll = Instant::now();
    while !stop.load(Ordering::Relaxed) {
        // The status events are read under the participant's discovery lock: a few times a
        // second, not at every step of a free-running loop (that starved discovery, so that
        // departed subscribers stayed matched and held up the reliable writers).
        if Instant::now() >= next_status_poll {
            impact_readers.update(&status);
            next_status_poll = Instant::now() + STATUS_POLL;
        }
        inbox.serve(&mut st, &log, false);
        if std::mem::take(&mut st.reset_tick) {
            publish_tick(&st.runner, &state_pub, &clock_pub, &mut st.n, &log);
            last_outcome = Outcome::Tick;
        }
        publish_impacts(&impact_pub, &mut st.impacts, &mut st.n, &log);
        if !st.impacts.is_empty() {
            // A reliable subscriber is behind: wait for it rather than lose an impact.
            inbox.wait_until(
                Instant::now() + Duration::from_millis(1),
                &stop,
                &mut st,
                &log,
            );
            st.pacer = Pacer::new(st.settings.real_time_factor, st.runner.now());
            continue;
        }
        if !st.control.advancing() {
            // Paused: no tick, no /clock; commands and requests are served.
            inbox.wait_until(
                Instant::now() + Duration::from_millis(2),
                &stop,
                &mut st,
                &log,
            );
            st.pacer = Pacer::new(st.settings.real_time_factor, st.runner.now());
            st.last_due = None;
            continue;
        }
        let before = st.runner.now();
        let outcome = st.runner.advance(&mut fresh);
        st.n.advanced += (st.runner.now() - before).max(0.0);
        st.impacts.extend(fresh.drain(..));
        publish_impacts(&impact_pub, &mut st.impacts, &mut st.n, &log);
        match outcome {
            Outcome::Tick => {
                publish_tick(&st.runner, &state_pub, &clock_pub, &mut st.n, &log);
                if let Some(due) = st.last_due.take() {
                    let late = Instant::now().saturating_duration_since(due);
                    st.n.paced_ticks += 1;
                    st.n.max_lateness = st.n.max_lateness.max(late);
                    st.n.window_lateness = st.n.window_lateness.max(late);
                    st.n.late_ticks += u64::from(late > Duration::from_millis(10));
                }
                if st.control.stepping() {
                    if let Some(job) = st.control.ticked() {
                        answer_step_done(&services, &st, job, &log);
                    }
                    st.pacer = Pacer::new(st.settings.real_time_factor, st.runner.now());
                } else if let Some(due) = st.pacer.due(st.runner.now()) {
                    inbox.wait_until(due, &stop, &mut st, &log);
                    st.last_due = Some(due);
                }
            }
            Outcome::Command => {}
            Outcome::Blocked | Outcome::Halted => {
                let why = match st.runner.halted() {
                    Some(why) => why.to_owned(),
                    None => format!(
                        "waiting at t = {} s for the next external plate sample",
                        st.runner.now()
                    ),
                };
                if outcome != last_outcome {
                    let level = if outcome == Outcome::Halted {
                        LogLevel::Error
                    } else {
                        LogLevel::Info
                    };
                    log.log(level, &why);
                }
                if let Some(job) = st.control.abort_step() {
                    answer_step(&services, &st, job, &why, &log);
                }
                inbox.wait_until(
                    Instant::now() + Duration::from_millis(2),
                    &stop,
                    &mut st,
                    &log,
                );
                st.pacer = Pacer::new(st.settings.real_time_factor, st.runner.now());
            }
        }
        last_outcome = outcome;
    }
    if let Some(job) = st.control.abort_step() {
        answer_step(&services, &st, job, "the node is stopping", &log);
    }
    let LoopState { runner, n, .. } = st;
    log.log(
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
    // Reliable subscribers may still be missing some of the last impacts (up to the send window
    // of 8192 at a high impact rate): DDS keeps running until they have acknowledged them all.
    impact_readers.update(&status);
    await_acknowledgements(&impact_pub, impact_readers.count(), n.impacts, &log);
    drop(services);
    drop(node);
    Ok(())
}

/// Answers a step request whose ticks are all done.
fn answer_step_done(sv: &Services, st: &LoopState, job: StepJob<RmwRequestId>, log: &Logger) {
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

/// The remote subscriptions matched to one local writer, from the participant's status
/// events (the node runs no ros2-client spinner, which would keep this graph).
struct MatchedReaders {
    writer: GUID,
    readers: BTreeSet<GUID>,
}

impl MatchedReaders {
    fn new(writer: GUID) -> Self {
        Self {
            writer,
            readers: BTreeSet::new(),
        }
    }

    fn update(&mut self, status: &DomainParticipantStatusListener) {
        while let Some(event) = status.try_recv_status() {
            match event {
                DomainParticipantStatusEvent::RemoteReaderMatched {
                    local_writer,
                    remote_reader,
                } if local_writer == self.writer => {
                    self.readers.insert(remote_reader);
                }
                DomainParticipantStatusEvent::ReaderLost { guid, .. } => {
                    self.readers.remove(&guid);
                }
                DomainParticipantStatusEvent::ParticipantLost { id, .. } => {
                    self.readers.retain(|g| g.prefix != id);
                }
                _ => {}
            }
        }
    }

    fn count(&self) -> usize {
        self.readers.len()
    }
}

/// How often the loop reads the participant's status events (matched subscriptions).
const STATUS_POLL: Duration = Duration::from_millis(100);

/// At shutdown DDS keeps running while the matched reliable impact subscribers acknowledge the
/// published impacts: until all are acknowledged, or no further acknowledgement came for
/// [`SHUTDOWN_ACK_STALL`] (a subscriber that vanished without a goodbye acknowledges nothing
/// until DDS drops it at its lease expiry), or [`SHUTDOWN_ACK_LIMIT`] in all.
const SHUTDOWN_ACK_STALL: Duration = Duration::from_secs(2);
/// See [`SHUTDOWN_ACK_STALL`].
const SHUTDOWN_ACK_LIMIT: Duration = Duration::from_secs(10);

/// Waits for the impact subscribers' acknowledgements at shutdown ([`SHUTDOWN_ACK_STALL`]) and
/// logs the outcome: all `published` impacts acknowledged, or how many were not.
fn await_acknowledgements(
    publisher: &Publisher<ImpactEvent>,
    subscribers: usize,
    published: u64,
    log: &Logger,
) {
    let start = Instant::now();
    let mut progress = start;
    let mut missing = publisher.unacknowledged_count();
    loop {
        match publisher.wait_for_acknowledgments(Duration::from_millis(100)) {
            Ok(true) => {
                if subscribers > 0 {
                    log.log(
                        LogLevel::Info,
                        &format!(
                            "impacts: all {published} published acknowledged by the {subscribers} \
                             matched subscriptions in {:.3} s",
                            start.elapsed().as_secs_f64()
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
        let now = Instant::now();
        let left = publisher.unacknowledged_count();
        if left < missing {
            missing = left;
            progress = now;
        }
        if now - progress >= SHUTDOWN_ACK_STALL || now - start >= SHUTDOWN_ACK_LIMIT {
            log.log(
                LogLevel::Warn,
                &format!(
                    "impacts: {left} of {published} published not acknowledged by every matched \
                     subscription after {:.3} s ({} s without progress, or {} s in all)",
                    (now - start).as_secs_f64(),
                    SHUTDOWN_ACK_STALL.as_secs(),
                    SHUTDOWN_ACK_LIMIT.as_secs()
                ),
            );
            return;
        }
    }
}

fn publish_tick(
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
fn publish_impacts(
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

/// Applies a checked runtime parameter change (logged); the reason if the simulation cannot
/// take it (nothing changes then).
fn apply_parameter(
    st: &mut LoopState,
    name: &str,
    value: &ParameterValue,
    log: &Logger,
) -> Result<(), String> {
    if name == USE_SIM_TIME {
        return Ok(());
    }
    let LoopState {
        settings,
        runner,
        pacer,
        ..
    } = st;
    let before = settings.get(name);
    if before.as_ref() == Some(value) {
        return Ok(());
    }
    let mut next = settings.clone();
    next.set(name, value).and_then(|()| match name {
        "zeta" | "e" => runner.set_params(next.zeta, next.e),
        "publish_rate" => {
            runner.set_rate(next.publish_rate);
            Ok(())
        }
        "real_time_factor" => {
            *pacer = Pacer::new(next.real_time_factor, runner.now());
            Ok(())
        }
        "frame_id" => {
            runner.set_frame_id(&next.frame_id);
            Ok(())
        }
        _ => Ok(()),
    })?;
    *settings = next;
    log.log(
        LogLevel::Info,
        &format!(
            "parameter {name} changed from {before:?} to {value:?} at t = {} s",
            runner.now()
        ),
    );
    Ok(())
}
