//! The contact laws at an event (`model.md` Sec. 3): the impact law with its record, and the
//! events of sticking, release and snap-through. Small pure functions, so that the simulator
//! and the FMU's Model Exchange (which locates events with the host's integrator) apply them
//! with the same operations in the same order.

use crate::events::{Event, Impact, StickCause, Well};
use crate::params::Params;

/// Where and how an impact happens: the plate at the impact and the mass's approach.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Contact {
    /// Number of the impact (impacts before it).
    pub index: u64,
    /// Time `τ`.
    pub t: f64,
    /// Shaker phase in cycles, when the plate has one.
    pub phase: Option<f64>,
    /// Plate position `z` (the mass's position).
    pub z: f64,
    /// Plate velocity `ż`.
    pub zdot: f64,
    /// Relative velocity `w₋ = v₋ − ż ≤ 0` before the impact.
    pub w_minus: f64,
    /// Mass velocity `v₋` before the impact.
    pub v_before: f64,
}

/// The impact law `w₊ = −e·w₋`: the impact's record (velocities, `ΔK`) and `w₊`.
pub fn impact_law(params: &Params, c: &Contact) -> (Impact, f64) {
    let w_plus = params.rebound(c.w_minus);
    let v_after = w_plus + c.zdot;
    let imp = Impact {
        index: c.index,
        t: c.t,
        phase: c.phase,
        x: c.z,
        v_before: c.v_before,
        v_after,
        zdot: c.zdot,
        delta_k: 0.5 * (v_after * v_after - c.v_before * c.v_before),
    };
    (imp, w_plus)
}

/// The start of sticking at `t`, the mass at `x` on the plate, after `impacts` impacts.
pub fn stick_start(t: f64, x: f64, cause: StickCause, impacts: u64) -> Event {
    Event::StickStart {
        t,
        x,
        cause,
        impacts,
    }
}

/// The release at `t` from the plate at `z` moving with `zdot`: the mass leaves with it.
pub fn release(t: f64, z: f64, zdot: f64) -> Event {
    Event::StickEnd { t, x: z, v: zdot }
}

/// The snap-through at `t` with velocity `v` into the well `to`.
pub fn snap_through(t: f64, v: f64, to: Well) -> Event {
    Event::SnapThrough { t, v, to }
}
