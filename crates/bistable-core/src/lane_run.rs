//! Runs taken one stretch at a time: a [`LaneRun`] names the instant to advance its simulator to
//! next, takes the events on the way and, at that instant, gives its result or the next instant.
//! [`drive`] makes such a run alone; a lane of a [`crate::Batch`] follows the same stretches, so
//! it makes bit for bit the same run.

use crate::events::Event;
use crate::simulator::{SimError, Simulator};
use crate::time::Instant;

/// A run taken one stretch at a time, so that a caller can drive its simulator itself (alone
/// with [`drive`], or as one lane of a [`crate::Batch`]).
pub trait LaneRun {
    /// What the run gives at its end.
    type Result;

    /// The instant to advance the simulator to next.
    fn target(&self) -> Instant;

    /// Takes an event of the simulator's advance to [`LaneRun::target`].
    fn event(&mut self, e: &Event);

    /// Takes the simulator at [`LaneRun::target`]: the result when the run is over, `None`
    /// when it goes on to the next target.
    fn reached(&mut self, sim: &mut Simulator) -> Result<Option<Self::Result>, SimError>;
}

/// Advances `sim` from target to target of `run` until it gives its result.
pub fn drive<R: LaneRun>(run: &mut R, sim: &mut Simulator) -> Result<R::Result, SimError> {
    loop {
        let target = run.target();
        sim.advance_instant(target, &mut |e: &Event| run.event(e))?;
        if let Some(r) = run.reached(sim)? {
            return Ok(r);
        }
    }
}
