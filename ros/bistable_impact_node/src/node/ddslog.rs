//! Warnings and errors of the DDS layer (RustDDS and ros2-client write them through the `log`
//! crate) in the node's log, in its format, so that a discovery or transport problem shows
//! where users look. Each source line of the DDS code is shown at most [`PER_SITE`] times: some
//! warnings repeat at every send while a peer is unreachable. `BISTABLE_DDS_LOG=info` (or
//! `debug`, `trace`) shows the DDS layer's lower levels as well, every line, for diagnosis.

use std::collections::HashMap;
use std::sync::Mutex;

use bistable_impact_node::logging::LogLevel;

use super::dds::stderr_line;

/// How many times one warning site of the DDS layer is shown.
const PER_SITE: u32 = 3;

/// Warnings that say nothing is wrong (target, a part of the message): RustDDS warns of every
/// datagram over 1,500 bytes, which loopback (MTU 64 KiB) and large impact batches send as a
/// rule, and ros2-client that `ROS_DISTRO` is unset, which a node started outside a ROS
/// installation always is.
const BENIGN: [(&str, &str); 2] = [
    ("rustdds::network::udp_sender", ": Message size = "),
    ("ros2_client::distributions", "ROS_DISTRO is not set"),
];

struct DdsLog {
    node: String,
    /// The most detailed level shown (warnings unless `BISTABLE_DDS_LOG` says more).
    level: log::LevelFilter,
    /// How often each warning or error site (target, line) has logged.
    shown: Mutex<HashMap<(String, u32), u32>>,
}

impl log::Log for DdsLog {
    fn enabled(&self, meta: &log::Metadata) -> bool {
        meta.level() <= self.level
    }

    fn log(&self, record: &log::Record) {
        if !self.enabled(record.metadata()) || is_benign(record) {
            return;
        }
        let limited = record.level() <= log::Level::Warn;
        let mut more = "";
        if limited {
            let site = (record.target().to_owned(), record.line().unwrap_or(0));
            let mut shown = self.shown.lock().unwrap_or_else(|e| e.into_inner());
            let count = shown.entry(site).or_insert(0);
            *count = count.saturating_add(1);
            if *count > PER_SITE {
                return;
            }
            if *count == PER_SITE {
                more = " (not shown again from this place)";
            }
        }
        let level = match record.level() {
            log::Level::Error => LogLevel::Error,
            log::Level::Warn => LogLevel::Warn,
            log::Level::Info => LogLevel::Info,
            log::Level::Debug | log::Level::Trace => LogLevel::Debug,
        };
        stderr_line(
            level,
            &self.node,
            format_args!("DDS ({}): {}{more}", record.target(), record.args()),
        );
    }

    fn flush(&self) {}
}

/// Whether `record` is one of the [`BENIGN`] warnings.
fn is_benign(record: &log::Record) -> bool {
    record.level() == log::Level::Warn
        && BENIGN.iter().any(|(target, part)| {
            record.target() == *target && record.args().to_string().contains(part)
        })
}

/// Routes the DDS layer's warnings and errors (and the lower levels `BISTABLE_DDS_LOG` asks
/// for) to standard error as lines of node `node`. Called once, before the participant is
/// created; a second call changes nothing.
pub fn install(node: &str) {
    let level = std::env::var("BISTABLE_DDS_LOG")
        .ok()
        .and_then(|v| v.parse::<log::LevelFilter>().ok())
        .map_or(log::LevelFilter::Warn, |l| l.max(log::LevelFilter::Warn));
    let logger = DdsLog {
        node: node.to_owned(),
        level,
        shown: Mutex::new(HashMap::new()),
    };
    if log::set_boxed_logger(Box::new(logger)).is_ok() {
        log::set_max_level(level);
    }
}
