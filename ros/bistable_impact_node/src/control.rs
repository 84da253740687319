//! Pause, resume and step (the node's `bistable/pause` and `bistable/step` services), free of
//! DDS: which requests are accepted, and when a step is complete. `Id` identifies the request
//! a step answers when it ends (the service request id in the node).

/// Most publish ticks one step request may ask for.
pub const MAX_STEP_TICKS: u32 = 100_000;

/// A step request being carried out.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct StepJob<Id> {
    /// The request to answer.
    pub id: Id,
    /// Ticks asked for.
    pub ticks: u64,
    /// Ticks done so far.
    pub done: u64,
}

/// Whether the simulation runs, and the step in progress.
#[derive(Debug)]
pub struct Control<Id> {
    paused: bool,
    step: Option<StepJob<Id>>,
}

impl<Id> Default for Control<Id> {
    fn default() -> Self {
        Self {
            paused: false,
            step: None,
        }
    }
}

impl<Id> Control<Id> {
    /// Whether the simulation is paused (a step may still be running).
    pub fn paused(&self) -> bool {
        self.paused
    }

    /// Whether the simulation should advance now: not paused, or a step is running.
    pub fn advancing(&self) -> bool {
        !self.paused || self.step.is_some()
    }

    /// Whether a step is running (it advances as fast as possible, without pacing).
    pub fn stepping(&self) -> bool {
        self.step.is_some()
    }

    /// `bistable/pause` (`std_srvs/SetBool`): `pause` true pauses, false resumes. Returns the
    /// response (success, message).
    pub fn set_paused(&mut self, pause: bool, now: f64) -> (bool, String) {
        match (pause, self.paused) {
            (true, true) => (true, format!("already paused at t = {now} s")),
            (true, false) => {
                self.paused = true;
                (true, format!("paused at t = {now} s"))
            }
            (false, false) => (true, format!("already running at t = {now} s")),
            (false, true) => match &self.step {
                Some(job) => (
                    false,
                    format!(
                        "a step of {} ticks is running ({} done): resume when it has ended",
                        job.ticks, job.done
                    ),
                ),
                None => {
                    self.paused = false;
                    (true, format!("resumed at t = {now} s"))
                }
            },
        }
    }

    /// `bistable/step`: starts a step of `ticks` publish ticks, or says why not. `waiting` is
    /// the reason the simulation cannot advance now, if any (waiting for external plate
    /// samples, halted on an error).
    pub fn start_step(&mut self, id: Id, ticks: u32, waiting: Option<&str>) -> Result<(), String> {
        if !self.paused {
            return Err("the simulation is running: pause it first (bistable/pause)".to_owned());
        }
        if let Some(job) = &self.step {
            return Err(format!(
                "a step of {} ticks is running ({} done)",
                job.ticks, job.done
            ));
        }
        if ticks == 0 || ticks > MAX_STEP_TICKS {
            return Err(format!("ticks = {ticks} must be in 1..={MAX_STEP_TICKS}"));
        }
        if let Some(why) = waiting {
            return Err(format!("cannot step: {why}"));
        }
        self.step = Some(StepJob {
            id,
            ticks: u64::from(ticks),
            done: 0,
        });
        Ok(())
    }

    /// One publish tick was done; the finished step, if this tick ended it.
    pub fn ticked(&mut self) -> Option<StepJob<Id>> {
        let job = self.step.as_mut()?;
        job.done += 1;
        if job.done >= job.ticks {
            self.step.take()
        } else {
            None
        }
    }

    /// Ends the running step early (the simulation cannot go on, or was reset): the job, to be
    /// answered with a failure.
    pub fn abort_step(&mut self) -> Option<StepJob<Id>> {
        self.step.take()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pause_step_resume() {
        let mut c = Control::<u32>::default();
        assert!(c.advancing() && !c.paused());
        let err = c.start_step(1, 5, None).unwrap_err();
        assert!(err.contains("pause it first"), "{err}");
        assert!(c.set_paused(false, 0.0).0);
        assert!(c.set_paused(true, 1.5).1.contains("paused at t = 1.5 s"));
        assert!(!c.advancing());
        assert!(c.set_paused(true, 1.5).1.contains("already"));
        for bad in [0, MAX_STEP_TICKS + 1, u32::MAX] {
            assert!(c.start_step(1, bad, None).unwrap_err().contains("1..="));
        }
        assert!(c
            .start_step(1, 3, Some("waiting for the next external plate sample"))
            .unwrap_err()
            .contains("external"));
        c.start_step(7, 3, None).unwrap();
        assert!(c.advancing() && c.stepping());
        assert!(c.start_step(8, 1, None).unwrap_err().contains("running"));
        let (ok, why) = c.set_paused(false, 1.5);
        assert!(!ok && why.contains("step"), "{why}");
        assert_eq!(c.ticked(), None);
        assert_eq!(c.ticked(), None);
        assert_eq!(
            c.ticked(),
            Some(StepJob {
                id: 7,
                ticks: 3,
                done: 3
            })
        );
        assert!(!c.advancing() && c.paused());
        assert_eq!(c.ticked(), None);
        c.start_step(9, 2, None).unwrap();
        assert_eq!(c.abort_step().map(|j| (j.id, j.done)), Some((9, 0)));
        assert!(c.set_paused(false, 2.0).0 && c.advancing());
    }
}
