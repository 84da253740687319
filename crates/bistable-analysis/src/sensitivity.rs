//! Final-state sensitivity of a classification: whether the response class that a
//! double-precision run reports is determined by the model or by rounding.
//!
//! A run whose transient amplifies an infinitesimal perturbation by more than `e^N` before its
//! class is decided (`N` = [`SensitivityOptions::efoldings`], measured with the variational
//! equations, see [`bistable_core::Classification::transient_efoldings`]) cannot be trusted to
//! land on the same attractor once rounding errors of relative size `1e-16` have grown to
//! `1e-16·e^N`: beyond about `ln(1e16) ≈ 37` e-foldings they are of order one, and a basin
//! boundary may be much closer than that. Such a run (and one decided later than the
//! [`SensitivityOptions::horizon`] over which the growth is tracked) is repeated
//! [`SensitivityOptions::repeats`] times: twice from the paper's initial condition with a
//! coarser tolerance, otherwise from starts displaced by [`SensitivityOptions::perturbation`].
//! A run still aperiodic at the end is repeated too, but only for
//! [`SensitivityOptions::repeat_periods`]: nearby starts that end elsewhere leave the chaotic
//! set early, in the transient from the initial condition; and its chaos verdict, which depends
//! on the stretch of the attractor the Lyapunov window happens to average over (a window that
//! meets sticking gives "not chaotic"), is repeated on [`SensitivityOptions::windows`] further
//! windows, the last stretches of the run itself (no further integration). The point is
//! *sensitive* when the runs do not all reach the same outcome (class, period, chaos, final
//! well); the reported classification is that of the most frequent outcome. Runs decided with
//! less growth stay a single run. A chaotic attractor reached and kept by every run is a
//! determinate outcome (`chaotic`), not a sensitive one.

use bistable_core::{
    Classification, ClassifyOptions, ParamError, ResponseClass, SimError, SolverOptions, Tracking,
    Well,
};

use crate::ensemble::{run_alone, Run, Task};
use crate::period;
use crate::Model;

/// Settings of the sensitivity test.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensitivityOptions {
    /// Perturbed repeats of a suspect run (0: no test, every point is a single run).
    pub repeats: u32,
    /// Transient growth (natural log of the amplification) from which a decided run is suspect.
    pub efoldings: f64,
    /// Displacement of the repeats' initial state `(x0, x0')` from `(0, 0)`.
    pub perturbation: f64,
    /// Stretch of the run, in natural periods, over which the transient growth is tracked; a
    /// run decided later is repeated too.
    pub horizon: f64,
    /// Length of the repeats of an aperiodic run, in natural periods (a repeat still aperiodic
    /// then counts as the run's own outcome).
    pub repeat_periods: f64,
    /// Further Lyapunov windows of an aperiodic run, each a verdict on `chaotic`: the last
    /// stretches of the run itself, as many as fit in it.
    pub windows: u32,
}

/// Default transient growth (e-foldings) from which a decided run is repeated; chosen on the
/// 60 × 40 map grid (see `docs/sensitivity.md`).
pub const DEFAULT_EFOLDINGS: f64 = 20.0;

impl Default for SensitivityOptions {
    fn default() -> Self {
        Self {
            repeats: 8,
            efoldings: DEFAULT_EFOLDINGS,
            perturbation: 1e-12,
            horizon: 1000.0,
            repeat_periods: 200.0,
            windows: 8,
        }
    }
}

impl SensitivityOptions {
    /// No test: every point is a single run.
    pub fn off() -> Self {
        Self {
            repeats: 0,
            ..Self::default()
        }
    }

    /// Checks the settings in the order of the fields: `repeats` (`<= 64`), `efoldings`
    /// (`(0, 700]`), `perturbation` (`(0, 1e-3]`), `horizon` and `repeat_periods` (`[1, 1e8]`),
    /// `windows` (`<= 1024`); the error names the setting as the adapters do
    /// (`lyapunov_windows` for `windows`).
    pub fn check(&self) -> Result<Self, ParamError> {
        let r = self.repeats;
        check("repeats", f64::from(r), r <= 64, "must be in [0, 64]")?;
        let n = self.efoldings;
        check("efoldings", n, n > 0.0 && n <= 700.0, "must be in (0, 700]")?;
        let d = self.perturbation;
        check(
            "perturbation",
            d,
            d > 0.0 && d <= 1e-3,
            "must be in (0, 1e-3]",
        )?;
        for (name, p) in [
            ("horizon", self.horizon),
            ("repeat_periods", self.repeat_periods),
        ] {
            check(name, p, (1.0..=1e8).contains(&p), "must be in [1, 1e8]")?;
        }
        let w = self.windows;
        check(
            "lyapunov_windows",
            f64::from(w),
            w <= 1024,
            "must be in [0, 1024]",
        )?;
        Ok(*self)
    }
}

fn check(name: &'static str, value: f64, ok: bool, rule: &'static str) -> Result<(), ParamError> {
    if value.is_finite() && ok {
        Ok(())
    } else {
        Err(ParamError { name, value, rule })
    }
}

/// What a run ends on: the part of a classification that the sensitivity test compares.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Outcome {
    /// Response class.
    pub class: ResponseClass,
    /// Steady-state period (`None`: aperiodic).
    pub period: Option<u32>,
    /// Aperiodic with a positive largest Lyapunov exponent.
    pub chaotic: bool,
    /// Final well; `None` for a continuous interwell response (it visits both).
    pub final_well: Option<Well>,
}

impl Outcome {
    /// The outcome of a classification.
    pub fn of(c: &Classification) -> Self {
        Self {
            class: c.class,
            period: c.period,
            chaotic: c.chaotic,
            final_well: (c.class != ResponseClass::ContinuousInterwell).then_some(c.final_well),
        }
    }

    /// `class:period:well`, period `P-n`, `chaotic` or `aperiodic`, well `1`, `2` or `-`
    /// (e.g. `transient_interwell:P-1:2`).
    pub fn key(&self) -> String {
        let period = period::label(self.period, self.chaotic);
        let well = self
            .final_well
            .map_or("-".to_string(), |w| w.number().to_string());
        format!("{}:{period}:{well}", self.class.name())
    }
}

/// Why a point was repeated.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Trigger {
    /// Decided with little transient growth: a single run.
    None,
    /// Decided after a transient growth of at least [`SensitivityOptions::efoldings`].
    Growth,
    /// Still aperiodic at the end of the run.
    Aperiodic,
    /// Decided after more than [`SensitivityOptions::horizon`] natural periods (the growth is
    /// tracked over that stretch only).
    Late,
}

impl Trigger {
    /// `none`, `growth`, `aperiodic` or `late`.
    pub fn name(self) -> &'static str {
        match self {
            Trigger::None => "none",
            Trigger::Growth => "growth",
            Trigger::Aperiodic => "aperiodic",
            Trigger::Late => "late",
        }
    }
}

/// The result of the sensitivity test at one point.
#[derive(Debug, Clone, PartialEq)]
pub struct Sensitivity {
    /// Why the point was repeated (or not).
    pub trigger: Trigger,
    /// The runs did not all reach the same outcome.
    pub sensitive: bool,
    /// Each distinct outcome with the number of runs that reached it, most frequent first
    /// (ties: in the order the runs were made, the paper's initial condition first).
    pub outcomes: Vec<(Outcome, u32)>,
    /// Verdicts counted: 1, or for a repeated point 1 + repeats, and for an aperiodic one also
    /// the base run's further Lyapunov windows (each a verdict on `chaotic`).
    pub runs: u32,
    /// Transient growth of the run from the paper's initial condition (capped at the
    /// threshold; `None` without the test).
    pub efoldings: Option<f64>,
    /// The threshold ([`SensitivityOptions::efoldings`]; `None` without the test).
    pub threshold: Option<f64>,
}

impl Sensitivity {
    /// Share of the runs that reached the reported (most frequent) outcome.
    pub fn majority_fraction(&self) -> f64 {
        self.outcomes
            .first()
            .map_or(1.0, |o| f64::from(o.1) / f64::from(self.runs.max(1)))
    }

    /// `key=fraction` of every outcome joined by `;` (e.g.
    /// `transient_interwell:P-1:2=0.667;continuous_interwell:P-1:-=0.333`).
    pub fn fractions(&self) -> String {
        let n = f64::from(self.runs.max(1));
        self.outcomes
            .iter()
            .map(|(o, c)| format!("{}={:.3}", o.key(), f64::from(*c) / n))
            .collect::<Vec<_>>()
            .join(";")
    }
}

/// The starting state of a repeat, number `j` of `k` (`1..=k`) among those started from a
/// perturbed state: displaced by `delta` in the direction at angle `π(j − ½)/k` in the
/// `(x0', x0)` half-plane with `x0 > 0` (never below the plate).
pub fn perturbed_start(j: u32, k: u32, delta: f64) -> (f64, f64) {
    let a = std::f64::consts::PI * (f64::from(j) - 0.5) / f64::from(k.max(1));
    (delta * a.sin(), delta * a.cos())
}

/// How repeat `j` (`1..=k`) differs from the run it checks: the first two (when `k >= 4`) start
/// from the paper's initial condition with the tolerance 10 and 100 times coarser (another
/// Taylor order and step sequence: another rounding history of equal merit; finer when the
/// coarser one would leave the allowed range), the others from a start displaced by `delta`.
fn repeat_setup(
    j: u32,
    k: u32,
    delta: f64,
    opts: SolverOptions,
) -> Result<((f64, f64), SolverOptions), SimError> {
    let tol_repeats = if k >= 4 { 2 } else { 0 };
    if j <= tol_repeats {
        let factor = if j == 1 { 10.0 } else { 100.0 };
        let coarse = opts.tol() * factor;
        let tol = if coarse <= 1e-3 {
            coarse
        } else {
            opts.tol() / factor
        };
        let o = SolverOptions::new(tol, opts.chatter())?
            .with_max_chatter_impacts(opts.max_chatter_impacts())?;
        Ok(((0.0, 0.0), o))
    } else {
        let start = perturbed_start(j - tol_repeats, k - tol_repeats, delta);
        Ok((start, opts))
    }
}

/// Classifies `model`'s point from the paper's initial condition with the sensitivity test:
/// returns the reported classification (of the most frequent outcome) and the test's result.
pub fn classify_sensitive(
    model: &Model,
    co: ClassifyOptions,
    so: SensitivityOptions,
) -> Result<(Classification, Sensitivity), SimError> {
    run_alone(PointTest::new(model, co, so))
}

/// The sensitivity test at one point as a [`Task`]: the run from the paper's
/// initial condition, then (when it is suspect) its repeats, then the verdict
/// ([`classify_sensitive`] makes the runs one after the other; a sweep makes them in lanes).
pub struct PointTest {
    model: Model,
    co: ClassifyOptions,
    so: SensitivityOptions,
    /// The base run, once done.
    base: Option<Classification>,
    trigger: Trigger,
    /// The repeats, by number (`1..=repeats` at `j − 1`).
    repeats: Vec<Option<Classification>>,
}

impl PointTest {
    /// The test at `model`'s point.
    pub fn new(model: &Model, co: ClassifyOptions, so: SensitivityOptions) -> Self {
        Self {
            model: *model,
            co,
            so,
            base: None,
            trigger: Trigger::None,
            repeats: Vec::new(),
        }
    }

    /// A run of the point with these settings.
    fn run(
        &self,
        co: ClassifyOptions,
        opts: SolverOptions,
        start: (f64, f64),
        cap: Option<f64>,
        no_lyapunov: bool,
    ) -> Run {
        // The growth is tracked over the first `horizon` natural periods; a run decided later
        // than that is suspect by its length alone.
        let horizon_sections =
            (self.so.horizon * std::f64::consts::TAU / self.model.shaker_period()).ceil() as u64;
        Run {
            params: self.model.params,
            plate: self.model.shaker,
            opts,
            co,
            start,
            track: Tracking {
                efoldings_cap: cap,
                track_periods: horizon_sections,
                extra_windows: if cap.is_some() { self.so.windows } else { 0 },
                no_lyapunov,
            },
        }
    }

    fn cap(&self) -> Option<f64> {
        (self.so.repeats > 0).then_some(self.so.efoldings)
    }
}

impl Task for PointTest {
    type Run = Run;
    type Output = (Classification, Sensitivity);

    fn start(&mut self) -> Result<Vec<Run>, SimError> {
        Ok(vec![self.run(
            self.co,
            self.model.opts,
            (0.0, 0.0),
            self.cap(),
            false,
        )])
    }

    fn run_done(&mut self, i: usize, mut r: Classification) -> Result<Vec<Run>, SimError> {
        let (co, so) = (self.co, self.so);
        if i > 0 {
            let base = self.base.as_ref().expect("repeats follow the base run");
            if self.trigger == Trigger::Aperiodic && r.period.is_none() {
                r.chaotic = base.chaotic;
                r.lyapunov = base.lyapunov;
            }
            self.repeats[i - 1] = Some(r);
            return Ok(Vec::new());
        }
        let base = r;
        self.trigger = if so.repeats == 0 {
            Trigger::None
        } else if base.period.is_none() && !base.stopped_early {
            Trigger::Aperiodic
        } else if base.transient_efoldings.is_some_and(|g| g >= so.efoldings) {
            Trigger::Growth
        } else if !co.full_length && base.periods_simulated > so.horizon {
            Trigger::Late
        } else {
            Trigger::None
        };
        self.base = Some(base);
        if self.trigger == Trigger::None {
            return Ok(Vec::new());
        }
        // Repeats of an aperiodic run stop at `repeat_periods` (still aperiodic then: counted
        // as aperiodic, chaotic or not by their own Lyapunov exponent); those of a decided run
        // run as long as it may.
        let aperiodic = self.trigger == Trigger::Aperiodic;
        let co_r = if aperiodic {
            ClassifyOptions {
                max_natural_periods: so.repeat_periods.min(co.max_natural_periods),
                ..co
            }
        } else {
            co
        };
        let mut runs = Vec::with_capacity(so.repeats as usize);
        for j in 1..=so.repeats {
            let (start, opts) = repeat_setup(j, so.repeats, so.perturbation, self.model.opts)?;
            // A repeat of an aperiodic run only asks whether another attractor is reached; the
            // chaos verdict is tested on the base run's further Lyapunov windows.
            runs.push(self.run(co_r, opts, start, None, aperiodic));
        }
        self.repeats = vec![None; runs.len()];
        Ok(runs)
    }

    fn finish(self) -> (Classification, Sensitivity) {
        let threshold = self.cap();
        let base = self.base.expect("the base run is done");
        let mut runs = vec![base];
        runs.extend(self.repeats.into_iter().flatten());
        // Each run's outcome, then the base run's chaos verdicts on its further Lyapunov
        // windows (as the base outcome with `chaotic` set by the window).
        let mut votes: Vec<(Outcome, usize)> = runs
            .iter()
            .enumerate()
            .map(|(i, r)| (Outcome::of(r), i))
            .collect();
        if let Some((chaotic, n)) = base.chaos_votes {
            let o = Outcome::of(&base);
            for w in 0..n {
                votes.push((
                    Outcome {
                        chaotic: w < chaotic,
                        ..o
                    },
                    0,
                ));
            }
        }
        let mut outcomes: Vec<(Outcome, u32, usize)> = Vec::new();
        for (o, i) in votes.iter().copied() {
            match outcomes.iter_mut().find(|e| e.0 == o) {
                Some(e) => e.1 += 1,
                None => outcomes.push((o, 1, i)),
            }
        }
        let total = votes.len() as u32;
        // Most frequent first; ties in run order (stable sort).
        outcomes.sort_by_key(|e| std::cmp::Reverse(e.1));
        // The reported run: the first one with the most frequent outcome (a vote of a further
        // window of the base run reports the base run with that window's verdict).
        let mut reported = runs[outcomes[0].2];
        if Outcome::of(&reported) != outcomes[0].0 {
            reported.chaotic = outcomes[0].0.chaotic;
        }
        let sensitivity = Sensitivity {
            trigger: self.trigger,
            sensitive: outcomes.len() > 1,
            outcomes: outcomes.iter().map(|e| (e.0, e.1)).collect(),
            runs: total,
            efoldings: base.transient_efoldings,
            threshold,
        };
        (reported, sensitivity)
    }
}
