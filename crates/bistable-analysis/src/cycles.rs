//! The steady state seen per shaker cycle: the largest displacement in each cycle, the phases
//! of the impacts, and the stroboscopic section points (plate phase 0), for bifurcation
//! diagrams, orbit seeds and orbit analysis.

use std::num::NonZeroU32;

use bistable_core::{Event, Instant, Params, SimError, Simulator, Sinusoid, SolverOptions, Width};

use crate::ensemble::{self, drive, LaneRun, RunSpec, Single};
use crate::parallel::Threads;
use crate::progress::{OnProgress, Progress, Stage};
use crate::Model;

/// What [`record_cycles`] saw.
#[derive(Debug, Clone, Default)]
pub struct Cycles {
    /// Largest `x` in each shaker cycle (units of `Δx`).
    pub max_x: Vec<f64>,
    /// Impacts as `(cycle, phase in cycles ∈ [0, 1))`; cycles count from 0 at the first
    /// recorded one.
    pub impacts: Vec<(u32, f64)>,
    /// `(x, x')` at the start of each cycle and at the end of the last (one more than cycles).
    pub sections: Vec<(f64, f64)>,
}

/// Records `cycles` shaker cycles of `sim`, which must stand at the section instant
/// `plate.section(first)`. The maximum of `x` in a cycle comes from `samples`
/// dense-output samples per cycle, refined by the cubic Hermite interpolant of `(x, x')` on
/// each interval where `x'` changes sign from + to − with no impact in between (error
/// `O(h⁴)`). Samples sit at the same plate phases in every cycle, so a periodic response
/// repeats exactly.
pub fn record_cycles(
    sim: &mut Simulator,
    plate: Sinusoid,
    first: u64,
    cycles: u32,
    samples: NonZeroU32,
) -> Result<Cycles, SimError> {
    let mut rec = CycleRecorder::new(plate, first, cycles, samples, false);
    match rec.begin(sim) {
        Some(c) => Ok(c),
        None => drive(&mut rec, sim),
    }
}

/// [`record_cycles`] taken one sample interval at a time ([`LaneRun`]), after an optional
/// settling advance to the first recorded section.
pub struct CycleRecorder {
    plate: Sinusoid,
    first: u64,
    cycles: u32,
    samples: u32,
    /// Time between samples.
    h: f64,
    /// Advancing to `plate.section(first)` before recording.
    settling: bool,
    /// The cycle and the sample (`1..=samples`) advanced to.
    cycle: u32,
    sample: u32,
    /// The largest `x` of the cycle so far, and the state at the last sample.
    best: f64,
    x0: f64,
    v0: f64,
    /// An impact or a sticking change since the last sample.
    kinks: bool,
    out: Cycles,
}

impl CycleRecorder {
    /// A recorder of `cycles` cycles from `plate.section(first)` (see [`record_cycles`]); with
    /// `settle`, the simulator is first advanced there, else it stands there and
    /// [`CycleRecorder::begin`] comes first.
    pub fn new(
        plate: Sinusoid,
        first: u64,
        cycles: u32,
        samples: NonZeroU32,
        settle: bool,
    ) -> Self {
        let samples = samples.get();
        Self {
            plate,
            first,
            cycles,
            samples,
            h: plate.period() / f64::from(samples),
            settling: settle,
            cycle: 0,
            sample: 1,
            best: 0.0,
            x0: 0.0,
            v0: 0.0,
            kinks: false,
            out: Cycles::default(),
        }
    }

    /// Starts recording at `sim`'s state (at the first section): the record when there are
    /// no cycles to record.
    pub fn begin(&mut self, sim: &Simulator) -> Option<Cycles> {
        let st = sim.state();
        self.out.sections.push((st.x, st.v));
        (self.x0, self.v0, self.best) = (st.x, st.v, st.x);
        (self.cycles == 0).then(|| std::mem::take(&mut self.out))
    }
}

impl LaneRun for CycleRecorder {
    type Result = Cycles;

    fn target(&self) -> Instant {
        let c = self.first + u64::from(self.cycle);
        if self.settling {
            self.plate.section(self.first)
        } else if self.sample == self.samples {
            self.plate.section(c + 1)
        } else {
            self.plate.section(c) + f64::from(self.sample) * self.h
        }
    }

    fn event(&mut self, e: &Event) {
        if self.settling {
            return;
        }
        match e {
            Event::Impact(i) => {
                self.kinks = true;
                self.out
                    .impacts
                    .push((self.cycle, i.phase.unwrap_or(f64::NAN)));
            }
            Event::StickStart { .. } | Event::StickEnd { .. } => self.kinks = true,
            Event::SnapThrough { .. } => {}
        }
    }

    fn reached(&mut self, sim: &mut Simulator) -> Result<Option<Cycles>, SimError> {
        if self.settling {
            self.settling = false;
            return Ok(self.begin(sim));
        }
        let s = sim.state();
        self.best = self.best.max(s.x);
        if !self.kinks && self.v0 > 0.0 && s.v < 0.0 {
            self.best = self
                .best
                .max(hermite_max(self.x0, self.v0, s.x, s.v, self.h));
        }
        (self.x0, self.v0, self.kinks) = (s.x, s.v, false);
        if self.sample < self.samples {
            self.sample += 1;
            return Ok(None);
        }
        self.out.max_x.push(self.best);
        self.out.sections.push((self.x0, self.v0));
        (self.best, self.sample) = (self.x0, 1);
        self.cycle += 1;
        Ok((self.cycle == self.cycles).then(|| std::mem::take(&mut self.out)))
    }
}

/// The largest value of the cubic Hermite interpolant of `x(0) = x0, x'(0) = v0, x(h) = x1,
/// x'(h) = v1` (with `v0 > 0 > v1`) on `[0, h]`.
fn hermite_max(x0: f64, v0: f64, x1: f64, v1: f64, h: f64) -> f64 {
    // p(s) = a s³ + b s² + c s + d on s ∈ [0, 1].
    let c = h * v0;
    let b = 3.0 * (x1 - x0) - h * (2.0 * v0 + v1);
    let a = 2.0 * (x0 - x1) + h * (v0 + v1);
    let p = |s: f64| ((a * s + b) * s + c) * s + x0;
    // p'(s) = 3a s² + 2b s + c goes from c > 0 at 0 to h·v1 < 0 at 1: one root in between;
    // bisection is exact enough and never fails.
    let dp = |s: f64| (3.0 * a * s + 2.0 * b) * s + c;
    let (mut lo, mut hi) = (0.0, 1.0);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if dp(mid) > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    p(0.5 * (lo + hi)).max(x0).max(x1)
}

/// The simulator after `periods` shaker periods from the paper's initial condition, standing
/// at the section instant `model.shaker.section(periods)` (plate phase 0).
pub fn settled(model: &Model, periods: u32) -> Result<Simulator, SimError> {
    let mut sim = model.simulator()?;
    sim.advance_instant(
        model.shaker.section(u64::from(periods)),
        &mut |_: &Event| {},
    )?;
    Ok(sim)
}

/// A run of [`steady_cycles`]: the paper's initial condition for `transient` shaker periods,
/// then `cycles` recorded with `samples` samples per cycle.
#[derive(Debug, Clone, Copy)]
pub struct SteadyCycles {
    /// The model.
    pub model: Model,
    /// Shaker periods skipped.
    pub transient: u32,
    /// Shaker periods recorded.
    pub cycles: u32,
    /// Samples per recorded period.
    pub samples: NonZeroU32,
}

impl RunSpec for SteadyCycles {
    type Lane = CycleRecorder;

    fn setting(&self) -> (Params, SolverOptions) {
        (self.model.params, self.model.opts)
    }

    fn begin(&self) -> Result<(CycleRecorder, Simulator), SimError> {
        let rec = CycleRecorder::new(
            self.model.shaker,
            u64::from(self.transient),
            self.cycles,
            self.samples,
            true,
        );
        Ok((rec, self.model.simulator()?))
    }
}

/// Runs the paper's initial condition for `transient` shaker periods, then records `cycles`
/// with `samples` samples per cycle (see [`record_cycles`]).
pub fn steady_cycles(
    model: &Model,
    transient: u32,
    cycles: u32,
    samples: NonZeroU32,
) -> Result<Cycles, SimError> {
    SteadyCycles {
        model: *model,
        transient,
        cycles,
        samples,
    }
    .alone()
}

/// [`steady_cycles`] at every model (on `threads` threads of `width` lanes,
/// [`crate::ensemble::run`]; the records are the same for every width), in the order of
/// `models`; reports [`Stage::Simulating`] progress. The first simulation error stops the run.
pub fn steady_cycles_over<E: From<SimError>>(
    models: &[Model],
    transient: u32,
    cycles: u32,
    samples: NonZeroU32,
    threads: Threads,
    width: Width,
    progress: &mut OnProgress<'_, E>,
) -> Result<Vec<Cycles>, E> {
    let total = models.len();
    let mut out: Vec<Option<Cycles>> = vec![None; total];
    let mut finished = 0;
    ensemble::run(
        models,
        threads,
        width,
        |&model| {
            Ok(Single::new(SteadyCycles {
                model,
                transient,
                cycles,
                samples,
            }))
        },
        |i, c| {
            out[i] = Some(c?);
            finished += 1;
            progress(Progress {
                stage: Stage::Simulating,
                done: finished,
                total,
            })
        },
    )?;
    Ok(out.into_iter().flatten().collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::period::distinct;
    use bistable_core::{Params, SolverOptions};

    #[test]
    fn hermite_max_is_exact_for_a_cubic() {
        // x(t) = 1 − (t − 0.3)²·(1 + t) on [0, 1]: maximum 1 at t = 0.3.
        let x = |t: f64| 1.0 - (t - 0.3) * (t - 0.3) * (1.0 + t);
        let v = |t: f64| -2.0 * (t - 0.3) * (1.0 + t) - (t - 0.3) * (t - 0.3);
        let m = hermite_max(x(0.0), v(0.0), x(1.0), v(1.0), 1.0);
        assert!((m - 1.0).abs() < 1e-14, "{m}");
    }

    #[test]
    fn max_per_cycle_of_a_period_one_response_repeats() {
        let model = Model::new(
            Params::new(0.02, 0.85).unwrap(),
            Sinusoid::new(1.75, 0.07).unwrap(),
            SolverOptions::default(),
        );
        let n = |k| NonZeroU32::new(k).unwrap();
        let c = steady_cycles(&model, 600, 6, n(128)).unwrap();
        assert_eq!(c.max_x.len(), 6);
        assert_eq!(c.sections.len(), 7);
        assert_eq!(distinct(&c.max_x, 1e-9), 1, "{:?}", c.max_x);
        // One impact per cycle, at the same phase.
        assert_eq!(c.impacts.len(), 6);
        assert_eq!(
            distinct(&c.impacts.iter().map(|i| i.1).collect::<Vec<_>>(), 1e-9),
            1
        );
        // The refined maximum beats the plain samples by a little, never by much.
        let coarse = steady_cycles(&model, 600, 1, n(16)).unwrap().max_x[0];
        assert!(c.max_x[0] >= coarse - 1e-9 && c.max_x[0] - coarse < 1e-3);
        assert!(
            (coarse - c.max_x[0]).abs() < 1e-6,
            "{coarse} vs {}",
            c.max_x[0]
        );
    }
}
