//! What the simulator reports: impacts, sticking intervals and snap-throughs.

use std::fmt;

/// Which potential well the mass is in: well 1 is `x < ½`, well 2 is `x > ½`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Well {
    /// `x < ½` (contains the rest position `x = 0`).
    One,
    /// `x > ½` (contains the second equilibrium `x = 1`).
    Two,
}

impl Well {
    /// The well that contains `x` (the barrier itself counts as well 2).
    pub fn of(x: f64) -> Self {
        if x < crate::potential::BARRIER {
            Well::One
        } else {
            Well::Two
        }
    }

    /// 1 or 2.
    pub fn number(self) -> u8 {
        match self {
            Well::One => 1,
            Well::Two => 2,
        }
    }

    /// The other well.
    pub fn other(self) -> Self {
        match self {
            Well::One => Well::Two,
            Well::Two => Well::One,
        }
    }
}

/// Whether the mass flies free or rides on the plate.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ContactMode {
    /// `x > z` (or touching with a rebound velocity): Eq. 4 holds.
    Free,
    /// `x = z`, `x' = ż` while the contact force `N ≥ 0` (Eq. 9).
    Sticking,
}

/// One collision of the mass with the plate (Eq. 5). Velocities in units of `ω0 Δx`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Impact {
    /// Running number; the impact at `τ = 0` of the paper's initial condition is 0.
    pub index: u64,
    /// Instant (time units).
    pub t: f64,
    /// Shaker phase in cycles `∈ [0, 1)` (Eq. 12), for a sinusoidal shaker.
    pub phase: Option<f64>,
    /// Position of mass and plate.
    pub x: f64,
    /// Mass velocity just before.
    pub v_before: f64,
    /// Mass velocity just after.
    pub v_after: f64,
    /// Plate velocity.
    pub zdot: f64,
    /// Kinetic energy change `½(v_after² − v_before²)` (Eq. 10).
    pub delta_k: f64,
}

/// Why a sticking phase began.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StickCause {
    /// The accumulation point of a chatter sequence was predicted and jumped to.
    Accumulation,
    /// Two impacts closer than the fixed gap (the paper's rule).
    FixedGap,
    /// The mass met the plate with no relative velocity while pushed (e.g. `e = 0`).
    Plastic,
    /// The Zeno guard ended an unending chatter sequence.
    ZenoGuard,
}

/// Something that happened at an instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Event {
    /// A collision.
    Impact(Impact),
    /// The mass came to rest on the plate.
    StickStart {
        /// Instant.
        t: f64,
        /// Position of mass and plate.
        x: f64,
        /// Rule that ended the chatter.
        cause: StickCause,
        /// Number of impacts so far (the last one has index `impacts − 1`).
        impacts: u64,
    },
    /// The contact force turned negative and the mass left the plate.
    StickEnd {
        /// Instant.
        t: f64,
        /// Position of mass and plate.
        x: f64,
        /// Velocity of mass and plate.
        v: f64,
    },
    /// The mass crossed the barrier `x = ½`.
    SnapThrough {
        /// Instant.
        t: f64,
        /// Velocity at the crossing.
        v: f64,
        /// The well entered.
        to: Well,
    },
}

impl Event {
    /// The impact, if this event is one (`events.iter().filter_map(Event::impact)`).
    pub fn impact(&self) -> Option<Impact> {
        match self {
            Event::Impact(i) => Some(*i),
            _ => None,
        }
    }

    /// Instant of the event.
    pub fn t(&self) -> f64 {
        match *self {
            Event::Impact(i) => i.t,
            Event::StickStart { t, .. }
            | Event::StickEnd { t, .. }
            | Event::SnapThrough { t, .. } => t,
        }
    }
}

impl fmt::Display for Event {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Event::Impact(i) => write!(
                f,
                "impact {} at t={:.15} x={:.15} v {:.15} -> {:.15}",
                i.index, i.t, i.x, i.v_before, i.v_after
            ),
            Event::StickStart { t, cause, .. } => write!(f, "stick start at t={t:.15} ({cause:?})"),
            Event::StickEnd { t, .. } => write!(f, "stick end at t={t:.15}"),
            Event::SnapThrough { t, to, .. } => {
                write!(f, "snap-through to well {} at t={t:.15}", to.number())
            }
        }
    }
}
