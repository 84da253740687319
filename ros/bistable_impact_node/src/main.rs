//! `bistable_impact_node`: the bistable impact oscillator as a ROS 2 node (see `ros/README.md`).

use std::collections::VecDeque;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::sync::Arc;
use std::time::{Duration, Instant};

use bistable_impact_node::args::{self, Config, Parsed};
use bistable_impact_node::inbox::{take_commands, Taken, Throttle, MAX_COMMANDS_PER_CALL};
use bistable_impact_node::msg::{Clock, ImpactEvent, MassState, ShakerCommand};
use bistable_impact_node::names::{Kind, Names};
use bistable_impact_node::params::{Settings, MAX_HISTORY_DEPTH, SPECS};
use bistable_impact_node::sim::{Outcome, Runner};
use ros2_client::log::LogLevel;
use ros2_client::qos::{Durability, History, Reliability, WhenFull};
use ros2_client::rosout::{NodeLoggingHandle, RosoutRaw};
use ros2_client::{
    Context, ContextOptions, MessageTypeName, Name, Node, NodeName, NodeOptions, ParameterValue,
    Publisher, QosProfile, Subscription, WriteError,
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
const TOPICS: [&str; 4] = [MASS_STATE, IMPACTS, SHAKER_COMMAND, CLOCK];

/// A parameter event from the parameter services (spinner thread) to the simulation loop.
enum ParamEvent {
    Set(String, ParameterValue),
    Refused(String, String),
}

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

/// Counters reported at shutdown.
#[derive(Default)]
struct Counters {
    states: u64,
    states_dropped: u64,
    impacts: u64,
    impacts_failed: u64,
    commands: u64,
    commands_refused: u64,
    /// Paced ticks (real_time_factor > 0) whose lateness was measured.
    paced_ticks: u64,
    /// Largest lateness of a state publication: from the wall-clock instant the previous state
    /// was due to the publication of the next one (the loop publishes a state as soon as it is
    /// computed, then waits for it to become due).
    max_lateness: Duration,
    /// Paced ticks more than 10 ms late.
    late_ticks: u64,
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

/// How often the loop looks for commands and parameter changes while it waits for wall time.
const POLL: Duration = Duration::from_millis(1);
/// Per-command log lines (accepted, refused, applied) let through per second; the others are
/// counted and summarised once a second (the totals are in the shutdown summary).
const COMMAND_LOG_BUDGET: u32 = 50;

/// What the simulation loop changes as commands and parameters arrive.
struct LoopState {
    runner: Runner,
    settings: Settings,
    pacer: Pacer,
    n: Counters,
}

/// What the simulation loop reads between steps: shaker commands and parameter events.
struct Inbox<'a> {
    commands: &'a Subscription<ShakerCommand>,
    params: mpsc::Receiver<ParamEvent>,
    throttle: Throttle,
}

impl Inbox<'_> {
    /// Takes the waiting commands and parameter events and applies them; returns whether the
    /// pacing changed (a parameter restarted the schedule).
    fn serve(&mut self, st: &mut LoopState, log: &Logger) -> bool {
        let LoopState {
            runner,
            settings,
            pacer,
            n,
        } = st;
        let throttle = &mut self.throttle;
        let commands = self.commands;
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
        );
        for note in runner.take_notes() {
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
                    n.commands,
                    n.commands_refused
                ),
            );
        }
        let mut repaced = false;
        while let Ok(ev) = self.params.try_recv() {
            match ev {
                ParamEvent::Set(name, value) => {
                    repaced |= name == "real_time_factor";
                    apply_parameter(settings, runner, pacer, &name, &value, log)
                }
                ParamEvent::Refused(name, why) => {
                    log.log(LogLevel::Warn, &format!("refused parameter {name}: {why}"))
                }
            }
        }
        repaced
    }

    /// Serves commands and parameters until wall-clock instant `until` (or a stop request,
    /// or a change of pacing).
    fn wait_until(&mut self, until: Instant, stop: &AtomicBool, st: &mut LoopState, log: &Logger) {
        while !stop.load(Ordering::Relaxed) {
            if self.serve(st, log) {
                return;
            }
            let now = Instant::now();
            if now >= until {
                return;
            }
            std::thread::sleep((until - now).min(POLL));
        }
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
        Ok(Parsed::Run(cfg)) => match run(*cfg) {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => {
                eprintln!("[FATAL] [bistable_impact]: {e}");
                ExitCode::FAILURE
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

/// The ros2-client [`Name`] of the topic the node calls `name`, resolved as rcl does (node
/// namespace, remapping rules); the result is absolute.
fn topic_name(names: &Names, name: &str) -> Result<Name, String> {
    let full = names.resolve(name, Kind::Topic)?;
    let (ns, base) = full.rsplit_once('/').unwrap_or(("", &full));
    Name::new(if ns.is_empty() { "/" } else { ns }, base)
        .map_err(|e| format!("topic {name} resolves to {full}, which ros2-client refuses: {e}"))
}

fn run(cfg: Config) -> Result<(), String> {
    let stop = Arc::new(AtomicBool::new(false));
    {
        let stop = Arc::clone(&stop);
        ctrlc::set_handler(move || stop.store(true, Ordering::SeqCst))
            .map_err(|e| format!("cannot install the signal handler: {e}"))?;
    }
    let runner = Runner::new(&cfg.settings)?;
    let context = Context::with_options(ContextOptions::new().domain_id(cfg.domain_id))
        .map_err(|e| format!("cannot join DDS domain {}: {e}", cfg.domain_id))?;
    let names = &cfg.names;
    let node_name = NodeName::new(names.namespace(), names.node())
        .map_err(|e| format!("bad node name {}: {e}", names.fully_qualified()))?;

    let (param_tx, param_rx) = mpsc::channel();
    let mut options = NodeOptions::new()
        .enable_rosout(cfg.rosout)
        .start_parameter_services(true);
    for (name, value) in cfg.settings.values() {
        options = options.declare_parameter(name, value);
    }
    if let Some(b) = cfg.use_sim_time {
        options = options.declare_parameter("use_sim_time", ParameterValue::Boolean(b));
    }
    let initial = cfg.settings.clone();
    let refused_tx = param_tx.clone();
    let options = options
        .parameter_validator(Box::new(move |name, value| {
            initial.check_runtime(name, value).inspect_err(|reason| {
                let _ = refused_tx.send(ParamEvent::Refused(name.to_owned(), reason.clone()));
            })
        }))
        .parameter_set_action(Box::new(move |name, value| {
            // The loop may be gone at shutdown; nothing to do then.
            let _ = param_tx.send(ParamEvent::Set(name.to_owned(), value.clone()));
            Ok(())
        }));
    let mut node = context
        .new_node(node_name, options)
        .map_err(|e| format!("cannot create the node: {e}"))?;
    let spinner = node
        .spinner()
        .map_err(|e| format!("cannot start the parameter services: {e}"))?;
    let spin_thread = std::thread::spawn(move || futures::executor::block_on(spinner.spin()));

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
            &topic_name(names, name)?,
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
    let command_sub = node
        .create_subscription::<ShakerCommand>(&command_topic, Some(COMMAND_QOS))
        .map_err(err("command subscription"))?;

    let s = &cfg.settings;
    log.log(
        LogLevel::Info,
        &format!(
            "started {} in DDS domain {}: zeta = {}, e = {}, omega0 = {} rad/s, delta_x = {} m, \
             Omega = {}, V = {}, publish_rate = {} Hz, real_time_factor = {}, frame_id = '{}', history_depth = {}",
            node.fully_qualified_name(),
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
    let resolved: Vec<String> = TOPICS
        .iter()
        .map(|t| {
            format!(
                "{t} -> {}",
                names.resolve(t, Kind::Topic).unwrap_or_default()
            )
        })
        .collect();
    log.log(LogLevel::Info, &format!("topics: {}", resolved.join(", ")));
    for w in &cfg.warnings {
        log.log(LogLevel::Warn, w);
    }

    let mut st = LoopState {
        pacer: Pacer::new(cfg.settings.real_time_factor, 0.0),
        settings: cfg.settings.clone(),
        runner,
        n: Counters::default(),
    };
    let mut impacts: VecDeque<ImpactEvent> = VecDeque::new();
    let mut fresh = Vec::new();
    let mut inbox = Inbox {
        commands: &command_sub,
        params: param_rx,
        throttle: Throttle::new(COMMAND_LOG_BUDGET, Duration::from_secs(1), Instant::now()),
    };
    let mut last_outcome = Outcome::Tick;
    let mut last_due: Option<Instant> = None;
    publish_tick(&st.runner, &state_pub, &clock_pub, &mut st.n, &log);
    while !stop.load(Ordering::Relaxed) {
        inbox.serve(&mut st, &log);
        publish_impacts(&impact_pub, &mut impacts, &mut st.n, &log);
        if !impacts.is_empty() {
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
        let outcome = st.runner.advance(&mut fresh);
        impacts.extend(fresh.drain(..));
        publish_impacts(&impact_pub, &mut impacts, &mut st.n, &log);
        match outcome {
            Outcome::Tick => {
                publish_tick(&st.runner, &state_pub, &clock_pub, &mut st.n, &log);
                if let Some(due) = last_due.take() {
                    let late = Instant::now().saturating_duration_since(due);
                    st.n.paced_ticks += 1;
                    st.n.max_lateness = st.n.max_lateness.max(late);
                    st.n.late_ticks += u64::from(late > Duration::from_millis(10));
                }
                if let Some(due) = st.pacer.due(st.runner.now()) {
                    inbox.wait_until(due, &stop, &mut st, &log);
                    last_due = Some(due);
                }
            }
            Outcome::Command => {}
            Outcome::Blocked | Outcome::Halted => {
                if outcome != last_outcome {
                    let msg = match st.runner.halted() {
                        Some(why) => why.to_owned(),
                        None => format!(
                            "waiting at t = {} s for the next external plate sample",
                            st.runner.now()
                        ),
                    };
                    let level = if outcome == Outcome::Halted {
                        LogLevel::Error
                    } else {
                        LogLevel::Info
                    };
                    log.log(level, &msg);
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
    let LoopState { runner, n, .. } = st;
    log.log(
        LogLevel::Info,
        &format!(
            "stopping at t = {} s: {} impacts located, {} published ({} failed), {} states \
             published ({} dropped), {} commands accepted, {} refused, {} dropped when due; \
             {} paced ticks, lateness max {:.3} ms, {} over 10 ms",
            runner.now(),
            runner.impact_count(),
            n.impacts,
            n.impacts_failed,
            n.states,
            n.states_dropped,
            n.commands,
            n.commands_refused,
            runner.commands_dropped(),
            n.paced_ticks,
            n.max_lateness.as_secs_f64() * 1e3,
            n.late_ticks
        ),
    );
    // Reliable subscribers may still be missing some of the last impacts (up to the send window
    // at a high impact rate): keep DDS running a moment so that they can get them repaired, as
    // Cyclone DDS's writer linger does. ros2-client has no wait for acknowledgements.
    if impact_pub.get_subscription_count(&node) > 0 {
        std::thread::sleep(SHUTDOWN_LINGER);
    }
    node.stop_spinner();
    drop(node);
    let _ = spin_thread.join();
    Ok(())
}

/// How long DDS keeps running after the simulation loop ends (with impact subscribers).
const SHUTDOWN_LINGER: Duration = Duration::from_secs(1);

fn publish_tick(
    runner: &Runner,
    state_pub: &Publisher<MassState>,
    clock_pub: &Publisher<Clock>,
    n: &mut Counters,
    log: &Logger,
) {
    let state = runner.state();
    let clock = Clock {
        clock: state.header.stamp,
    };
    match state_pub.publish(state) {
        Ok(()) => n.states += 1,
        Err(WriteError::WouldBlock { .. }) => n.states_dropped += 1,
        Err(e) => {
            n.states_dropped += 1;
            log.log(LogLevel::Warn, &format!("mass state not published: {e}"));
        }
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

fn apply_parameter(
    settings: &mut Settings,
    runner: &mut Runner,
    pacer: &mut Pacer,
    name: &str,
    value: &ParameterValue,
    log: &Logger,
) {
    let before = settings.get(name);
    if before.as_ref() == Some(value) {
        return;
    }
    let mut next = settings.clone();
    let result = next.set(name, value).and_then(|()| match name {
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
    });
    match result {
        Ok(()) => {
            *settings = next;
            log.log(
                LogLevel::Info,
                &format!(
                    "parameter {name} changed from {before:?} to {value:?} at t = {} s",
                    runner.now()
                ),
            );
        }
        Err(why) => log.log(
            LogLevel::Error,
            &format!("parameter {name} = {value:?} could not be applied: {why}"),
        ),
    }
}
