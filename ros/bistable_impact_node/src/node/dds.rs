//! The node's DDS endpoints: QoS, names, the logger, the topics, publishers, subscription and
//! service servers, created once at start-up.

use std::net::Ipv4Addr;
use std::time::Duration;

use bistable_impact_node::args::{Config, DiscoveryRange};
use bistable_impact_node::logging::{Log, LogLevel};
use bistable_impact_node::msg::{
    Clock, DiagnosticArray, ImpactEvent, MassState, ResetStateRequest, ResetStateResponse,
    SetBoolRequest, SetBoolResponse, ShakerCommand, StepRequest, StepResponse, TriggerRequest,
    TriggerResponse,
};
use bistable_impact_node::names::{Kind, Names};
use bistable_impact_node::params::MAX_HISTORY_DEPTH;
use bistable_impact_node::paramsrv::USE_SIM_TIME_REFUSED;
use ros2_client::dds::rustdds::{DomainParticipantBuilder, DomainParticipantStatusListener};
use ros2_client::parameters::raw;
use ros2_client::qos::{Durability, History, Reliability, WhenFull};
use ros2_client::rcl_interfaces::{
    DescribeParametersRequest, DescribeParametersResponse, GetParameterTypesRequest,
    GetParameterTypesResponse, GetParametersRequest, GetParametersResponse, ListParametersRequest,
    ListParametersResponse, SetParametersAtomicallyResponse, SetParametersRequest,
    SetParametersResponse,
};
use ros2_client::rosout::{NodeLoggingHandle, RosoutRaw};
use ros2_client::{
    Context, MessageTypeName, Name, Node, NodeName, NodeOptions, Publisher, QosProfile, Server,
    ServiceMapping, ServiceTypeName, Subscription,
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
pub struct Logger {
    handle: NodeLoggingHandle,
    name: String,
    level: u8,
    rosout: bool,
    stdout: bool,
}

impl Log for Logger {
    fn log(&self, level: LogLevel, msg: &str) {
        if (level as u8) < self.level {
            return;
        }
        if self.stdout {
            stderr_line(level, &self.name, format_args!("{msg}"));
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

/// Writes one log line of node `name` to standard error in the ROS console format,
/// `[LEVEL] [unix time s] [name]: msg`.
pub fn stderr_line(level: LogLevel, name: &str, msg: std::fmt::Arguments) {
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
    eprintln!("[{tag}] [{now:.9}] [{name}]: {msg}");
}

/// The node's service servers (parameter services of `rcl_interfaces` and the control
/// services) and the publishers they feed (`/parameter_events`, `/diagnostics`).
pub struct Services {
    pub get: Server<GetParametersRequest, GetParametersResponse>,
    pub types: Server<GetParameterTypesRequest, GetParameterTypesResponse>,
    pub list: Server<ListParametersRequest, ListParametersResponse>,
    pub set: Server<SetParametersRequest, SetParametersResponse>,
    pub set_atomically: Server<SetParametersRequest, SetParametersAtomicallyResponse>,
    pub describe: Server<DescribeParametersRequest, DescribeParametersResponse>,
    pub parameter_events: Publisher<raw::ParameterEvent>,
    pub pause: Server<SetBoolRequest, SetBoolResponse>,
    pub step: Server<StepRequest, StepResponse>,
    pub reset: Server<TriggerRequest, TriggerResponse>,
    pub reset_state: Server<ResetStateRequest, ResetStateResponse>,
    pub diagnostics: Publisher<DiagnosticArray>,
    pub fully_qualified: String,
}

/// Everything the node has in DDS. Fields drop in order: the services and the node first,
/// the participant's context last.
pub struct Dds {
    pub services: Services,
    /// The node the endpoints belong to (announced in the ROS graph while it lives).
    _node: Node,
    pub command_sub: Subscription<ShakerCommand>,
    pub clock_pub: Publisher<Clock>,
    pub impact_pub: Publisher<ImpactEvent>,
    pub state_pub: Publisher<MassState>,
    pub log: Logger,
    /// The participant's status events (only emptied: the writers count their matches).
    pub status: DomainParticipantStatusListener,
    pub fully_qualified: String,
    /// Kept alive as long as the node.
    _context: Context,
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

/// Joins the DDS domain of `cfg` and creates the node (no ros2-client spinner).
fn join(cfg: &Config, range: DiscoveryRange) -> Result<(Context, Node), String> {
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
    let node = context
        .new_node(node_name, options)
        .map_err(|e| format!("cannot create the node: {e}"))?;
    Ok((context, node))
}

impl Dds {
    /// Joins the domain, creates the node and all its endpoints.
    pub fn connect(cfg: &Config, range: DiscoveryRange) -> Result<Self, String> {
        let (context, mut node) = join(cfg, range)?;
        let status = context.domain_participant().status_listener();
        let names = &cfg.names;
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
        let depth = cfg.settings.history_depth.clamp(1, MAX_HISTORY_DEPTH) as usize;
        let impact_qos = impact_qos(depth);
        let impact_topic = create(&mut node, IMPACTS, msgs, "ImpactEvent", &impact_qos)?;
        let command_topic = create(
            &mut node,
            SHAKER_COMMAND,
            msgs,
            "ShakerCommand",
            &COMMAND_QOS,
        )?;
        let clock_topic = create(&mut node, CLOCK, "rosgraph_msgs", "Clock", &clock_qos)?;
        let state_pub = node
            .create_publisher(&state_topic, Some(state_qos.clone()))
            .map_err(err("mass state publisher"))?;
        let impact_pub = node
            .create_publisher(&impact_topic, Some(impact_qos))
            .map_err(err("impact publisher"))?;
        let clock_pub = node
            .create_publisher(&clock_topic, Some(clock_qos))
            .map_err(err("clock publisher"))?;
        let command_sub = node
            .create_subscription::<ShakerCommand>(&command_topic, Some(COMMAND_QOS))
            .map_err(err("command subscription"))?;
        let fully_qualified = node.fully_qualified_name();
        let services = services(&mut node, names, &fully_qualified)?;
        Ok(Self {
            services,
            _node: node,
            command_sub,
            clock_pub,
            impact_pub,
            state_pub,
            log,
            status,
            fully_qualified,
            _context: context,
        })
    }

    /// Logs the settings, the resolved names, the discovery range and the start-up warnings.
    pub fn log_startup(&self, cfg: &Config, range: DiscoveryRange) {
        let log = &self.log;
        let s = &cfg.settings;
        log.log(
            LogLevel::Info,
            &format!(
                "started {} in DDS domain {}: zeta = {}, e = {}, omega0 = {} rad/s, delta_x = {} m, \
                 Omega = {}, V = {}, publish_rate = {} Hz, real_time_factor = {}, frame_id = '{}', history_depth = {}",
                self.fully_qualified,
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
                .map(|t| format!("{t} -> {}", cfg.names.resolve(t, kind).unwrap_or_default()))
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
        if std::env::var("ROS_STATIC_PEERS").is_ok_and(|p| !p.trim().is_empty()) {
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
    }
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
