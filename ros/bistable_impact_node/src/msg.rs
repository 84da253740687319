//! Message types, field for field as in `bistable_impact_msgs/msg/*.msg` (and the standard
//! `std_msgs/Header`, `builtin_interfaces/Time`, `rosgraph_msgs/Clock`). Serde's field order is
//! the CDR order, so these structs are the wire format.

use serde::{Deserialize, Serialize};

/// `builtin_interfaces/Time`: seconds and nanoseconds.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
pub struct Time {
    /// Whole seconds \[s\].
    pub sec: i32,
    /// Nanoseconds, `0..1_000_000_000` \[ns\].
    pub nanosec: u32,
}

impl Time {
    /// The instant `t` seconds, rounded to the nearest nanosecond; saturates at the ends of the
    /// representable range (`[0, i32::MAX]` s here: simulation time is never negative), NaN
    /// gives zero.
    pub fn from_seconds(t: f64) -> Self {
        if t.is_nan() || t <= 0.0 {
            return Self::default();
        }
        if t >= f64::from(i32::MAX) {
            return Self {
                sec: i32::MAX,
                nanosec: 999_999_999,
            };
        }
        let mut sec = t.floor();
        let mut nanos = ((t - sec) * 1e9).round();
        if nanos >= 1e9 {
            sec += 1.0;
            nanos -= 1e9;
        }
        // In range by the checks above: 0 <= sec < 2^31, 0 <= nanos < 1e9.
        Self {
            sec: sec as i32,
            nanosec: nanos as u32,
        }
    }

    /// The instant in seconds (nearest double).
    pub fn to_seconds(self) -> f64 {
        f64::from(self.sec) + f64::from(self.nanosec) * 1e-9
    }

    /// Whether this is the zero time (used by commands to mean "now").
    pub fn is_zero(self) -> bool {
        self.sec == 0 && self.nanosec == 0
    }
}

/// `std_msgs/Header`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Header {
    /// Simulation time of the data.
    pub stamp: Time,
    /// Coordinate frame.
    pub frame_id: String,
}

/// `rosgraph_msgs/Clock`: the simulation time published on `/clock`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Clock {
    /// Current simulation time.
    pub clock: Time,
}

/// `bistable_impact_msgs/MassState` (see `msg/MassState.msg`; SI units, specific energies).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct MassState {
    /// Stamp = simulation time; frame = `frame_id` parameter.
    pub header: Header,
    /// Simulation time \[s\].
    pub t: f64,
    /// Mass position \[m\].
    pub x: f64,
    /// Mass velocity \[m/s\].
    pub v: f64,
    /// Plate position \[m\].
    pub z: f64,
    /// Plate velocity \[m/s\].
    pub zdot: f64,
    /// Kinetic energy per unit mass [J/kg].
    pub kinetic_energy: f64,
    /// Potential energy per unit mass [J/kg].
    pub potential_energy: f64,
    /// Well 1 or 2.
    pub well: u8,
    /// Riding on the plate (sticking).
    pub in_contact: bool,
    /// Impacts so far.
    pub impact_count: u64,
    /// [`ShakerCommand::MODE_SINUSOID`] or [`ShakerCommand::MODE_EXTERNAL`].
    pub shaker_mode: u8,
    /// Sinusoid angular frequency \[rad/s\] (NaN in external mode).
    pub shaker_omega: f64,
    /// Sinusoid velocity amplitude \[m/s\] (NaN in external mode).
    pub shaker_velocity: f64,
}

/// `bistable_impact_msgs/ImpactEvent` (see `msg/ImpactEvent.msg`).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct ImpactEvent {
    /// Stamp = located impact time.
    pub header: Header,
    /// Running number from 0.
    pub index: u64,
    /// Impact time \[s\].
    pub t: f64,
    /// Shaker phase \[cycles\] (NaN for external plate motion).
    pub phase: f64,
    /// Position \[m\].
    pub x: f64,
    /// Mass velocity before \[m/s\].
    pub v_before: f64,
    /// Mass velocity after \[m/s\].
    pub v_after: f64,
    /// Plate velocity \[m/s\].
    pub zdot: f64,
    /// Specific kinetic energy change [J/kg].
    pub delta_k: f64,
    /// The impact ended a chatter sequence in sticking.
    pub ended_in_sticking: bool,
}

/// `bistable_impact_msgs/ShakerCommand` (see `msg/ShakerCommand.msg`).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct ShakerCommand {
    /// Stamp = simulation time at which the command applies (zero: now).
    pub header: Header,
    /// [`Self::MODE_SINUSOID`] or [`Self::MODE_EXTERNAL`].
    pub mode: u8,
    /// Sinusoid angular frequency \[rad/s\].
    pub omega: f64,
    /// Sinusoid velocity amplitude \[m/s\].
    pub velocity: f64,
    /// External plate position \[m\].
    pub z: f64,
    /// External plate velocity \[m/s\].
    pub zdot: f64,
}

impl ShakerCommand {
    /// Internal sinusoid with set-point `omega`, `velocity`.
    pub const MODE_SINUSOID: u8 = 0;
    /// External plate motion sample `z`, `zdot`.
    pub const MODE_EXTERNAL: u8 = 1;
}

/// `std_srvs/srv/SetBool` request (the node's `bistable/pause`: true pauses, false resumes).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct SetBoolRequest {
    /// The value to set.
    pub data: bool,
}

/// `std_srvs/srv/SetBool` response.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct SetBoolResponse {
    /// Whether the request was carried out.
    pub success: bool,
    /// What was done, or why not.
    pub message: String,
}

/// `std_srvs/srv/Trigger` request: no fields (rosidl gives an empty structure one placeholder
/// byte).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct TriggerRequest {
    /// rosidl's placeholder member of an empty structure (0).
    pub structure_needs_at_least_one_member: u8,
}

/// `std_srvs/srv/Trigger` response.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct TriggerResponse {
    /// Whether the request was carried out.
    pub success: bool,
    /// What was done, or why not.
    pub message: String,
}

/// `bistable_impact_msgs/srv/Step` request (see `srv/Step.srv`).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct StepRequest {
    /// Publish ticks to advance, `1..=MAX_STEP_TICKS`.
    pub ticks: u32,
}

/// `bistable_impact_msgs/srv/Step` response.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct StepResponse {
    /// Whether all the ticks were done.
    pub success: bool,
    /// What was done, or why not.
    pub message: String,
    /// Simulation time after the step \[s\].
    pub t: f64,
    /// Impacts located so far.
    pub impact_count: u64,
}

/// `bistable_impact_msgs/srv/ResetState` request (see `srv/ResetState.srv`).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct ResetStateRequest {
    /// Mass position \[m\].
    pub x: f64,
    /// Mass velocity \[m/s\].
    pub v: f64,
}

/// `bistable_impact_msgs/srv/ResetState` response.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct ResetStateResponse {
    /// Whether the simulation was reset.
    pub success: bool,
    /// What was done, or why not.
    pub message: String,
}

/// `diagnostic_msgs/KeyValue`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct KeyValue {
    /// Name of the value.
    pub key: String,
    /// The value, as text.
    pub value: String,
}

/// `diagnostic_msgs/DiagnosticStatus`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct DiagnosticStatus {
    /// [`Self::OK`], [`Self::WARN`], [`Self::ERROR`] or [`Self::STALE`].
    pub level: u8,
    /// What is described (`node name: task`, as diagnostic_updater names it).
    pub name: String,
    /// Summary of the status.
    pub message: String,
    /// The hardware's name (here the node's fully qualified name).
    pub hardware_id: String,
    /// The figures.
    pub values: Vec<KeyValue>,
}

impl DiagnosticStatus {
    pub const OK: u8 = 0;
    pub const WARN: u8 = 1;
    pub const ERROR: u8 = 2;
    pub const STALE: u8 = 3;
}

/// `diagnostic_msgs/DiagnosticArray`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct DiagnosticArray {
    /// Stamp = wall-clock time of the report.
    pub header: Header,
    /// One status per task.
    pub status: Vec<DiagnosticStatus>,
}

impl ros2_client::Message for Clock {}
impl ros2_client::Message for MassState {}
impl ros2_client::Message for ImpactEvent {}
impl ros2_client::Message for ShakerCommand {}
impl ros2_client::Message for SetBoolRequest {}
impl ros2_client::Message for SetBoolResponse {}
impl ros2_client::Message for TriggerRequest {}
impl ros2_client::Message for TriggerResponse {}
impl ros2_client::Message for StepRequest {}
impl ros2_client::Message for StepResponse {}
impl ros2_client::Message for ResetStateRequest {}
impl ros2_client::Message for ResetStateResponse {}
impl ros2_client::Message for DiagnosticArray {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn time_rounds_to_nanoseconds_and_saturates() {
        assert_eq!(
            Time::from_seconds(1.5),
            Time {
                sec: 1,
                nanosec: 500_000_000
            }
        );
        // 0.9999999999 s rounds up into the next second.
        assert_eq!(
            Time::from_seconds(0.999_999_999_9),
            Time { sec: 1, nanosec: 0 }
        );
        assert_eq!(Time::from_seconds(-3.0), Time::default());
        assert_eq!(Time::from_seconds(f64::NAN), Time::default());
        assert_eq!(Time::from_seconds(f64::INFINITY).sec, i32::MAX);
        let t = Time::from_seconds(12.345_678_901);
        assert_eq!(t.nanosec, 345_678_901);
        assert!((t.to_seconds() - 12.345_678_901).abs() < 1e-15 * 13.0);
        assert!(Time::default().is_zero() && !t.is_zero());
    }
}
