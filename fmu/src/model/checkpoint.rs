//! FMU states of the co-simulation model: the parts a state keeps ([`SavedModel`]), the phase
//! reference saved and restored, and the checks a restored core checkpoint must pass beyond
//! the core's own.

use bistable_core::{
    Checkpoint, Event, Instant, Observer, PlateRecord, Sample, SimError, Simulator, Sinusoid,
    StepView,
};
use std::ops::ControlFlow;

use super::plate::origin_in_range;
use super::si::{describe_param, Scale};
use crate::md::var;

/// The plate record of a sinusoid.
pub(crate) fn sinusoid_record(s: &Sinusoid) -> PlateRecord {
    let (origin, phase0, offset) = s.origin();
    PlateRecord::Sinusoid {
        omega: s.omega(),
        velocity: s.velocity(),
        origin: origin.parts(),
        phase0,
        offset,
    }
}

/// A saved phase reference (see [`SavedModel::phase_ref`]) checked against the `(Ω, V)` in
/// force `applied` and the current instant `now`.
pub fn restore_phase_ref(
    scale: &Scale,
    (omega, v, hi, lo, phase0, offset): (f64, f64, f64, f64, f64, f64),
    applied: (f64, f64),
    now: Instant,
) -> Result<Sinusoid, String> {
    let origin = Instant::from_parts(hi, lo).ok_or("invalid phase origin in the FMU state")?;
    if !(phase0.abs() <= std::f64::consts::PI && origin_in_range(omega, origin, now)) {
        return Err(format!(
            "the FMU state's phase reference (origin {} s, phase {phase0} rad) is out of range",
            scale.time(origin.to_f64())
        ));
    }
    // `(Ω, V)` in force were values of the parameters, so within their ranges.
    let in_range =
        |i: usize, x: f64| (crate::md::VARS[i].min..=crate::md::VARS[i].max).contains(&x);
    let applied_ok = in_range(var::Omega, omega) && in_range(var::V, v);
    if (omega, v) != applied || !applied_ok {
        return Err("the FMU state's phase reference does not match its shaker or plate".into());
    }
    Sinusoid::new(omega, v)
        .and_then(|s| s.with_origin(origin, phase0, offset))
        .map_err(|e| describe_param(&e))
}

/// The parts of a phase reference an FMU state keeps (see [`SavedModel::phase_ref`]).
pub fn save_phase_ref(s: &Sinusoid) -> (f64, f64, f64, f64, f64, f64) {
    let (origin, phase0, offset) = s.origin();
    let (hi, lo) = origin.parts();
    (s.omega(), s.velocity(), hi, lo, phase0, offset)
}

/// Checks of a saved core state beyond the core's own (`Simulator::from_checkpoint`): angles
/// reduced as the core leaves them, the last impact not after the current time.
pub(crate) fn check_checkpoint(cp: &Checkpoint) -> Result<(), String> {
    // Malformed instants are refused by the core.
    let Some(now) = Instant::from_parts(cp.now.0, cp.now.1) else {
        return Ok(());
    };
    if let PlateRecord::Sinusoid {
        omega,
        origin: (hi, lo),
        phase0,
        ..
    } = cp.plate
    {
        let in_range =
            Instant::from_parts(hi, lo).is_none_or(|origin| origin_in_range(omega, origin, now));
        if !(phase0.abs() <= std::f64::consts::PI && in_range) {
            return Err(format!(
                "the FMU state's plate sinusoid (origin {hi}, phase {phase0} rad) is out of range"
            ));
        }
    }
    let last = cp
        .last_impact_t
        .and_then(|(hi, lo)| Instant::from_parts(hi, lo));
    if last.is_some_and(|last| last > now) {
        return Err("the FMU state's last impact is after its current time".into());
    }
    // Counters far beyond any run (2^53 steps take decades) would overflow as the run goes on.
    let s = cp.stats;
    let limit = 1u64 << 53;
    if [s.steps, s.impacts, s.sticks, s.snap_throughs]
        .iter()
        .any(|&n| n > limit)
        || cp.short_flights > cp.max_chatter_impacts
    {
        return Err("the FMU state's counters are out of range".into());
    }
    // The last impact is the one counted last, at the recorded instant.
    let counted = match (cp.last_impact, last) {
        (Some(i), Some(t)) => i.index.checked_add(1) == Some(cp.stats.impacts) && i.t == t.to_f64(),
        (None, None) => cp.stats.impacts == 0,
        _ => false,
    };
    if !counted {
        return Err("the FMU state's last impact does not match its impact count".into());
    }
    Ok(())
}

/// Longest span `max(Ω, 1)·(τ − τ_step start)` between the start of the core's current Taylor step
/// and its current time in a saved state: its steps are at most 8 time units long
/// (`taylor::MAX_STEP`) and cover about 2 radians of a sinusoidal plate; the margin keeps this
/// check independent of those choices while bounding the work below.
const MAX_SAVED_STEP: f64 = 64.0;

/// Counts what an advance computes, stopping at the first event (its time kept).
#[derive(Default)]
struct Probe {
    steps: u32,
    events: u32,
    first_event: Option<f64>,
}

impl Observer for Probe {
    fn event(&mut self, e: &Event) -> ControlFlow<()> {
        self.events += 1;
        self.first_event.get_or_insert(e.t());
        ControlFlow::Break(())
    }

    fn step(&mut self, _: &StepView<'_>) {
        self.steps += 1;
    }
}

/// A saved core state is inside its current Taylor step (as every state the core stops at is):
/// going on from the saved step start to the saved time needs at most the one step and meets no
/// event before that time (a state where the core stopped with a Discard may fail that step
/// again). An event at the saved time itself, reached without a step, is one still pending at
/// that instant: a state saved at an early return between two events of one instant (an impact
/// with `e = 0` and the plastic start of sticking it causes) is the FMU's own. A state whose time lies beyond its step (e.g. a step start moved far
/// back) would otherwise report an extrapolated state or integrate across the gap.
pub(crate) fn check_inside_step(sim: &Simulator, omega: f64) -> Result<(), String> {
    let cp = sim.checkpoint();
    let (t0, now) = (cp.t0, sim.instant());
    let span = Instant::from_parts(t0.0, t0.1).map_or(f64::INFINITY, |t0| now.since(t0));
    let mut probe = Probe::default();
    let reached = span * omega.max(1.0) <= MAX_SAVED_STEP
        && match sim.clone().advance_instant(now, &mut probe) {
            Ok(_) | Err(SimError::Zeno { .. } | SimError::NonFinite { .. }) => true,
            Err(_) => false,
        };
    let pending_now = probe.steps == 0 && probe.first_event == Some(sim.time());
    let inside = reached && probe.steps <= 1 && (probe.events == 0 || pending_now);
    if inside {
        Ok(())
    } else {
        Err(format!(
            "the FMU state's simulator time is not inside its current step (step start {} before it)",
            span
        ))
    }
}

/// The parts of a [`Model`](super::Model) an FMU state keeps (plain numbers).
#[derive(Debug, Clone, PartialEq)]
pub struct SavedModel {
    /// Core checkpoint.
    pub checkpoint: Checkpoint,
    /// Phase reference: `Ω`, `V`, origin `(hi, lo)`, phase at origin (rad), offset.
    pub phase_ref: (f64, f64, f64, f64, f64, f64),
    /// `(Ω, V)` in force.
    pub applied: (f64, f64),
    /// Communication time (s).
    pub time: f64,
    /// External mode: plate samples `(sample, joined)`, oldest first (see [`SampleHistory`](bistable_core::SampleHistory)).
    pub history: Vec<(Sample, bool)>,
    /// Momentum per unit mass given to the plate in the last step (see [`Model::impulse`](super::Model::impulse)).
    pub impulse: f64,
    /// The last step stopped at an event (see [`Model::at_event`](super::Model::at_event)).
    pub at_event: bool,
}
