//! Response classes of the paper's map (Sec. 3.4, Fig. 9), decided as early as possible.
//!
//! The run starts from the paper's initial condition and is sampled once per shaker period (the
//! stroboscopic section at plate phase 0). It stops as soon as the class is decided:
//! - **periodic**: for the smallest `p ≤ max_period`, the section points `p` periods apart agree
//!   to `period_tol` for `max(3p, 8)` consecutive sections;
//! - **at rest in well 2**: in well 2 with energy below the barrier and a lowest turning point
//!   above the plate's highest position, so that no impact or snap-through can happen again;
//! - otherwise the run goes on to `max_natural_periods` and is **aperiodic**; its largest
//!   Lyapunov exponent then tells whether it is chaotic.
//!
//! The class comes from the snap-throughs: none (intrawell), only before the steady state
//! (transient interwell), or on the steady-state orbit (continuous interwell).

use std::collections::VecDeque;

use crate::events::{ContactMode, Event, Well};
use crate::lane_run::{drive, LaneRun};
use crate::params::{check, ParamError, Params, SolverOptions};
use crate::potential::{self, BARRIER_ENERGY};
use crate::shaker::Sinusoid;
use crate::simulator::{SimError, Simulator};
use crate::time::Instant;

/// Response class (model.md Sec. 4).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ResponseClass {
    /// Never crosses `x = ½`.
    Intrawell,
    /// Crosses only during the transient.
    TransientInterwell,
    /// The steady-state orbit itself crosses `x = ½`.
    ContinuousInterwell,
}

impl ResponseClass {
    /// `intrawell`, `transient_interwell` or `continuous_interwell`.
    pub fn name(self) -> &'static str {
        match self {
            ResponseClass::Intrawell => "intrawell",
            ResponseClass::TransientInterwell => "transient_interwell",
            ResponseClass::ContinuousInterwell => "continuous_interwell",
        }
    }
}

/// Settings of a classification run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClassifyOptions {
    /// Longest run, in natural periods (the paper: 20,000).
    pub max_natural_periods: f64,
    /// Always run the full length (the class is then decided on the final sections).
    pub full_length: bool,
    /// Largest steady-state period looked for (shaker periods).
    pub max_period: u32,
    /// Agreement of section points `p` periods apart, relative to `max(1, |state|)`.
    pub period_tol: f64,
    /// Shaker periods used for the Lyapunov exponent of an aperiodic response.
    pub lyapunov_periods: u32,
}

impl Default for ClassifyOptions {
    fn default() -> Self {
        Self {
            max_natural_periods: 20_000.0,
            full_length: false,
            max_period: 16,
            period_tol: 1e-8,
            lyapunov_periods: 2_000,
        }
    }
}

impl ClassifyOptions {
    /// Checks the settings, in the order of the fields: `max_periods` (the natural periods,
    /// in `[1, 1e8]`), `max_period` (`[1, 64]`), `period_tol` (`(0, 1e-3]`) and
    /// `lyapunov_periods` (`>= 1`); the error names the first bad one.
    pub fn check(&self) -> Result<Self, ParamError> {
        let p = self.max_natural_periods;
        check(
            "max_periods",
            p,
            (1.0..=1e8).contains(&p),
            "must be in [1, 1e8]",
        )?;
        let m = self.max_period;
        check(
            "max_period",
            f64::from(m),
            (1..=64).contains(&m),
            "must be in [1, 64]",
        )?;
        let t = self.period_tol;
        check(
            "period_tol",
            t,
            t > 0.0 && t <= 1e-3,
            "must be in (0, 1e-3]",
        )?;
        let l = self.lyapunov_periods;
        check("lyapunov_periods", f64::from(l), l >= 1, "must be >= 1")?;
        Ok(*self)
    }
}

/// The outcome of a classification run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Classification {
    /// Response class.
    pub class: ResponseClass,
    /// Steady-state period in shaker periods (`None`: aperiodic). At rest counts as period 1.
    pub period: Option<u32>,
    /// Aperiodic with a positive largest Lyapunov exponent.
    pub chaotic: bool,
    /// Largest Lyapunov exponent (per unit of `τ`) of an aperiodic response.
    pub lyapunov: Option<f64>,
    /// Barrier crossings over the whole run.
    pub snap_throughs: u64,
    /// Well at the last section (for a continuous interwell orbit: where the run stopped).
    pub final_well: Well,
    /// Converged to rest at the second equilibrium `x = 1`.
    pub at_rest_in_second_well: bool,
    /// Impacts per steady-state period (`None`: aperiodic).
    pub impacts_per_period: Option<u64>,
    /// Whether the steady state includes sticking.
    pub sticking: bool,
    /// Natural periods simulated (`τ/2π`).
    pub periods_simulated: f64,
    /// Whether the run stopped before `max_natural_periods`.
    pub stopped_early: bool,
    /// Transient growth: the natural log of the largest amplification of an infinitesimal
    /// perturbation over any stretch of the run before its class was decided (from the
    /// variational equations, renormalised once per shaker period; sticking forgets the past and
    /// starts a new stretch). Tracking stops once the growth reaches the cap given to
    /// [`classify_from`], so values at the cap mean "at least", or after the number of periods
    /// given there. `None` when not tracked.
    pub transient_efoldings: Option<f64>,
    /// For an aperiodic response with further Lyapunov windows asked of [`classify_from`]: how
    /// many of them found `λ > 1e-3` (chaotic), and how many there were. `None` otherwise.
    pub chaos_votes: Option<(u32, u32)>,
    /// For a periodic response: the stroboscopic section point `(x, x')` (plate phase 0) of the
    /// steady-state cycle with the smallest `x`, a label of the orbit that does not depend on
    /// where along the cycle the run stopped (two coexisting orbits of the same period differ
    /// here). `None` when aperiodic.
    pub cycle_anchor: Option<[f64; 2]>,
}

/// Per-section record.
#[derive(Clone, Copy)]
struct Section {
    y: [f64; 2],
    impacts: u64,
    snaps: u64,
    sticks: u64,
}

/// Classifies the response at `(Ω, V)` from the paper's initial condition.
pub fn classify(
    params: Params,
    plate: Sinusoid,
    opts: SolverOptions,
    co: ClassifyOptions,
) -> Result<Classification, SimError> {
    classify_from(params, plate, opts, co, (0.0, 0.0), Tracking::default())
}

/// What [`classify_from`] measures besides the classification.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Tracking {
    /// Track the transient growth until it reaches this many e-foldings
    /// ([`Classification::transient_efoldings`]).
    pub efoldings_cap: Option<f64>,
    /// ... and for at most this many shaker periods (`0`: no limit); the growth then is that
    /// of this first stretch of the run.
    pub track_periods: u64,
    /// For an aperiodic response, this many further Lyapunov windows of `lyapunov_periods`
    /// besides the one after the run that decides `chaotic` ([`Classification::chaos_votes`]):
    /// the last stretches of the run itself, as many as fit in its last quarter (on the
    /// attractor, past the transient), measured alongside it, so they cost no further
    /// integration.
    pub extra_windows: u32,
    /// Skip the Lyapunov exponent of an aperiodic response (`lyapunov` is then `None` and
    /// `chaotic` false): for runs that only ask whether a period is reached.
    pub no_lyapunov: bool,
}

/// Classifies the response from the state `(x0, x0')` at `τ = 0` (the plate's phase and mean
/// position there are the sinusoid's origin; `x0` must not be below the plate), measuring what
/// `track` asks for; tracking does not change the trajectory or the classification.
pub fn classify_from(
    params: Params,
    plate: Sinusoid,
    opts: SolverOptions,
    co: ClassifyOptions,
    start: (f64, f64),
    track: Tracking,
) -> Result<Classification, SimError> {
    let (mut run, mut sim) = ClassifyRun::start(params, plate, opts, co, start, track)?;
    drive(&mut run, &mut sim)
}

/// A classification run ([`classify_from`]) taken one stretch at a time, so that a caller can
/// drive its simulator itself (as one lane of a [`crate::Batch`]): advance the simulator to
/// [`ClassifyRun::target`], passing every event to [`ClassifyRun::event`], then call
/// [`ClassifyRun::reached`], until it returns the classification. Driven this way the run does
/// exactly what [`classify_from`] does.
pub struct ClassifyRun {
    plate: Sinusoid,
    co: ClassifyOptions,
    track: Tracking,
    period_len: f64,
    max_sections: u64,
    growth: Option<Growth>,
    votes: Votes,
    keep: usize,
    hist: VecDeque<Section>,
    sticks: u64,
    /// Sections reached so far.
    k: u64,
    stage: Stage,
}

/// Where a [`ClassifyRun`] is.
enum Stage {
    /// At the stroboscopic sections, until the class is decided or the run ends.
    Sections,
    /// Decided; measuring the Lyapunov exponent of an aperiodic run (`Some`), or over.
    After(Box<Decided>, Option<LyapunovRun>),
}

/// What the section stage found.
struct Decided {
    class: ResponseClass,
    period: Option<u32>,
    at_rest: bool,
    snap_throughs: u64,
    impacts_per_period: Option<u64>,
    sticking: bool,
    cycle_anchor: Option<[f64; 2]>,
    transient_efoldings: Option<f64>,
}

impl ClassifyRun {
    /// The run and its simulator, at the start (`start` as in [`classify_from`]).
    pub fn start(
        params: Params,
        plate: Sinusoid,
        opts: SolverOptions,
        co: ClassifyOptions,
        start: (f64, f64),
        track: Tracking,
    ) -> Result<(Self, Simulator), SimError> {
        let period_len = plate.period();
        let max_sections = (co.max_natural_periods * std::f64::consts::TAU / period_len)
            .ceil()
            .max(1.0) as u64;
        let mut sim = Simulator::with_state(params, plate.into(), opts, 0.0, start.0, start.1)?;
        let growth = track.efoldings_cap.map(Growth::new);
        let votes = Votes::new(
            track.extra_windows,
            co.lyapunov_periods,
            max_sections,
            !track.no_lyapunov,
        );
        if growth.is_some() {
            sim.start_variational();
        }
        let keep = (4 * co.max_period + 8) as usize;
        let run = Self {
            plate,
            co,
            track,
            period_len,
            max_sections,
            growth,
            votes,
            keep,
            hist: VecDeque::with_capacity(keep + 1),
            sticks: 0,
            k: 1,
            stage: Stage::Sections,
        };
        Ok((run, sim))
    }

    /// Whether the run is still at its stroboscopic sections (the class not yet decided): the
    /// next [`ClassifyRun::target`] is then the next section, at plate phase 0.
    pub fn at_sections(&self) -> bool {
        matches!(self.stage, Stage::Sections)
    }

    /// The instant to advance the simulator to next.
    pub fn target(&self) -> Instant {
        match &self.stage {
            Stage::Sections => self.plate.section(self.k),
            Stage::After(_, Some(l)) => l.target(),
            Stage::After(_, None) => self.plate.section(self.k),
        }
    }

    /// Takes an event of the simulator's advance.
    pub fn event(&mut self, e: &Event) {
        self.sticks += u64::from(matches!(e, Event::StickStart { .. }));
    }

    /// Takes the simulator at [`ClassifyRun::target`]: the classification when the run is
    /// over, `None` when it goes on to the next target.
    pub fn reached(&mut self, sim: &mut Simulator) -> Result<Option<Classification>, SimError> {
        if let Stage::After(_, l) = &mut self.stage {
            let lyapunov = match l {
                Some(l) => match l.reached(sim) {
                    None => return Ok(None),
                    Some(lyapunov) => lyapunov,
                },
                None => None,
            };
            return Ok(Some(self.result(sim, lyapunov)));
        }
        let co = self.co;
        let k = self.k;
        // Only the mass is recorded: `mass` skips the plate's sine and cosine.
        let (x, v, mode, well) = sim.mass();
        let stats = sim.stats();
        self.hist.push_back(Section {
            y: [x, v],
            impacts: stats.impacts,
            snaps: stats.snap_throughs,
            sticks: self.sticks,
        });
        if self.hist.len() > self.keep {
            self.hist.pop_front();
        }
        if self.growth.as_ref().is_some_and(|g| g.live) || self.votes.measuring(k) {
            let l = sim.renormalize_variational();
            if l.is_none() {
                // Stuck (Φ = 0): a new stretch starts with the next free flight.
                sim.reseed_variational();
            }
            if let Some(g) = self.growth.as_mut() {
                g.section(l);
                if self.track.track_periods > 0 && k >= self.track.track_periods {
                    g.live = false;
                }
            }
            self.votes.section(k, l);
        }
        if self.votes.from == Some(k + 1) {
            // The next section warms up the windows' measurement: from its first step on,
            // without restarting the integration (the ongoing step carries no variation).
            sim.track_variational();
        } else if !self.growth.as_ref().is_some_and(|g| g.live) && !self.votes.measuring(k + 1) {
            sim.disable_variational();
        }
        let rest = at_rest_in_well_two(x, v, mode, well, self.plate);
        let found = if rest {
            Some((1, true))
        } else {
            find_period(&self.hist, co).map(|p| (p, false))
        };
        if (found.is_some() && !co.full_length) || k >= self.max_sections {
            return Ok(self.decide(sim, found));
        }
        self.k += 1;
        Ok(None)
    }

    /// Ends the section stage with `decided` (`(period, at rest)`): the classification, or
    /// `None` when the Lyapunov stage follows.
    fn decide(
        &mut self,
        sim: &mut Simulator,
        decided: Option<(u32, bool)>,
    ) -> Option<Classification> {
        let hist = &self.hist;
        let stats = sim.stats();
        let (period, at_rest) = match decided {
            Some((p, r)) => (Some(p), r),
            None => (None, false),
        };
        // Steady-state window: the confirmation window of the period, or the last sections kept.
        let window = period.map_or(hist.len(), |p| confirm_len(p) as usize + p as usize);
        let window = window.min(hist.len());
        let first = hist[hist.len() - window];
        let last = hist[hist.len() - 1];
        let steady_snaps = last.snaps - first.snaps;
        let class = if steady_snaps > 0 && !at_rest {
            ResponseClass::ContinuousInterwell
        } else if stats.snap_throughs > 0 {
            ResponseClass::TransientInterwell
        } else {
            ResponseClass::Intrawell
        };
        let per_window = |f: fn(&Section) -> u64| {
            period.map(|p| {
                let back = hist[hist.len() - 1 - p as usize];
                f(&last) - f(&back)
            })
        };
        let impacts_per_period = if at_rest {
            Some(0)
        } else {
            per_window(|s| s.impacts)
        };
        let sticking = !at_rest && per_window(|s| s.sticks).is_some_and(|n| n > 0);
        let cycle_anchor = period.map(|p| {
            hist.iter()
                .rev()
                .take(p as usize)
                .map(|s| s.y)
                .fold([f64::INFINITY, 0.0], |a, y| if y[0] < a[0] { y } else { a })
        });
        let transient_efoldings = self.growth.as_ref().map(|g| g.max.min(g.cap));
        sim.disable_variational();
        let decided = Box::new(Decided {
            class,
            period,
            at_rest,
            snap_throughs: stats.snap_throughs,
            impacts_per_period,
            sticking,
            cycle_anchor,
            transient_efoldings,
        });
        let measure = period.is_none() && !self.track.no_lyapunov;
        let run =
            measure.then(|| LyapunovRun::start(sim, self.period_len, self.co.lyapunov_periods));
        let instant = match &run {
            None => Some(None),
            Some(l) if l.periods == 0 => Some(l.value(sim)),
            Some(_) => None,
        };
        self.stage = Stage::After(decided, run);
        instant.map(|lyapunov| self.result(sim, lyapunov))
    }

    /// The classification, with the Lyapunov exponent measured after the sections (if any).
    fn result(&self, sim: &Simulator, lyapunov: Option<f64>) -> Classification {
        let Stage::After(d, _) = &self.stage else {
            unreachable!("the result follows the section stage");
        };
        let chaos_votes = if d.period.is_none() {
            self.votes.result(self.period_len)
        } else {
            None
        };
        Classification {
            class: d.class,
            period: d.period,
            chaotic: d.period.is_none() && lyapunov.is_some_and(|l| l > CHAOS),
            lyapunov,
            snap_throughs: d.snap_throughs,
            final_well: sim.state().well,
            at_rest_in_second_well: d.at_rest,
            impacts_per_period: d.impacts_per_period,
            sticking: d.sticking,
            periods_simulated: self.k as f64 * self.period_len / std::f64::consts::TAU,
            stopped_early: self.k < self.max_sections,
            transient_efoldings: d.transient_efoldings,
            chaos_votes,
            cycle_anchor: d.cycle_anchor,
        }
    }
}

/// Largest Lyapunov exponent (per unit of `τ`) above which an aperiodic response is chaotic.
const CHAOS: f64 = 1e-3;

impl LaneRun for ClassifyRun {
    type Result = Classification;

    fn target(&self) -> Instant {
        ClassifyRun::target(self)
    }

    fn event(&mut self, e: &Event) {
        ClassifyRun::event(self, e);
    }

    fn reached(&mut self, sim: &mut Simulator) -> Result<Option<Classification>, SimError> {
        ClassifyRun::reached(self, sim)
    }
}

/// Largest growth of the variational solution over any stretch of sections (the largest
/// rise of its accumulated log-norm), until it reaches `cap`.
struct Growth {
    cap: f64,
    acc: f64,
    low: f64,
    max: f64,
    live: bool,
}

impl Growth {
    fn new(cap: f64) -> Self {
        Self {
            cap,
            acc: 0.0,
            low: 0.0,
            max: 0.0,
            live: true,
        }
    }

    /// Takes the log-growth of one section (`None`: stuck, the past is forgotten and a new
    /// stretch starts with the next free flight).
    fn section(&mut self, growth: Option<f64>) {
        if !self.live {
            return;
        }
        match growth {
            Some(l) => {
                self.acc += l;
                self.low = self.low.min(self.acc);
                self.max = self.max.max(self.acc - self.low);
            }
            None => {
                self.acc = 0.0;
                self.low = 0.0;
            }
        }
        if self.max >= self.cap {
            self.live = false;
        }
    }
}

/// Chaos verdicts of the last windows of a run (sections `from + 1 ..= run`, `len` each; the
/// variation is started during section `from`, which only warms it up).
struct Votes {
    /// Section after which the windows start (`None`: no windows; otherwise at least 2).
    from: Option<u64>,
    len: u64,
    /// Per window: log-growth, and whether it met sticking.
    windows: Vec<(f64, bool)>,
}

impl Votes {
    /// `wanted` windows of `len` sections at the end of a run of `run` sections, as many as fit
    /// in its last quarter and after its first two sections (none when `measure` is false).
    fn new(wanted: u32, len: u32, run: u64, measure: bool) -> Self {
        let len = u64::from(len.max(1));
        let n = if measure {
            u64::from(wanted).min((run / 4).min(run.saturating_sub(2)) / len)
        } else {
            0
        };
        Self {
            from: (n > 0).then(|| run - n * len),
            len,
            windows: vec![(0.0, false); n as usize],
        }
    }

    /// Whether the variation is measured over section `k` (a window's or the warm-up).
    fn measuring(&self, k: u64) -> bool {
        self.from == Some(k) || self.counting(k)
    }

    /// Whether section `k` belongs to a window.
    fn counting(&self, k: u64) -> bool {
        self.from
            .is_some_and(|f| k > f && k <= f + self.len * self.windows.len() as u64)
    }

    fn section(&mut self, k: u64, growth: Option<f64>) {
        if let (true, Some(f)) = (self.counting(k), self.from) {
            let w = &mut self.windows[((k - f - 1) / self.len) as usize];
            match growth {
                Some(l) => w.0 += l,
                None => w.1 = true,
            }
        }
    }

    /// Chaotic windows (no sticking, `λ > 1e-3`) and windows, if any were measured.
    fn result(&self, period_len: f64) -> Option<(u32, u32)> {
        (!self.windows.is_empty()).then(|| {
            let span = self.len as f64 * period_len;
            let chaotic = self
                .windows
                .iter()
                .filter(|w| !w.1 && w.0 / span > CHAOS)
                .count();
            (chaotic as u32, self.windows.len() as u32)
        })
    }
}

fn confirm_len(p: u32) -> u32 {
    (3 * p).max(8)
}

/// Largest component difference of section points `lag` apart, relative to `max(1, |state|)`.
fn lag_distance(hist: &VecDeque<Section>, i: usize, lag: usize) -> f64 {
    let (a, b) = (hist[i].y, hist[i - lag].y);
    let scale = a[0].abs().max(a[1].abs()).max(1.0);
    (a[0] - b[0]).abs().max((a[1] - b[1]).abs()) / scale
}

/// Smallest `p` whose last `confirm_len(p)` sections repeat with period `p` and keep converging
/// (or have converged to rounding), unless a proper divisor `d` of `p` is still converging (its
/// `d`-lag differences shrink over the window): an orbit of period `d` approached through a
/// multiplier near −1 meets the `2d` test first.
fn find_period(hist: &VecDeque<Section>, co: ClassifyOptions) -> Option<u32> {
    let n = hist.len();
    let p = (1..=co.max_period).find(|&p| {
        let need = (confirm_len(p) + p) as usize;
        n >= need
            && (n - confirm_len(p) as usize..n)
                .all(|i| lag_distance(hist, i, p as usize) <= co.period_tol)
    })?;
    // Compare the same point of the p-cycle a confirmation window apart: on a periodic orbit
    // these lag distances are equal to rounding; any clear decrease means still converging.
    let back = (p * confirm_len(p).div_ceil(p)) as usize;
    if n < back + 2 * p as usize {
        return None;
    }
    let earlier = n - 1 - back;
    let shrinking = |d: u32| {
        lag_distance(hist, n - 1, d as usize)
            < (1.0 - 1e-9) * lag_distance(hist, earlier, d as usize)
    };
    // A periodic orbit is approached geometrically (or already reached to rounding); a constant
    // small drift is a torus near a resonance, not a period.
    let settled = lag_distance(hist, n - 1, p as usize) <= SETTLED || shrinking(p);
    let divisor_converging = (1..p).filter(|d| p % d == 0).any(shrinking);
    (settled && !divisor_converging).then_some(p)
}

/// Lag distance at which a section sequence counts as repeating to rounding.
const SETTLED: f64 = 1e-12;

/// In well 2, unable to cross the barrier or to reach the plate ever again (energy only decays
/// without impacts): the mass at `x` with velocity `v`, in contact `mode`, in `well`.
fn at_rest_in_well_two(x: f64, v: f64, mode: ContactMode, well: Well, plate: Sinusoid) -> bool {
    if well != Well::Two || mode != ContactMode::Free {
        return false;
    }
    let energy = potential::kinetic(v) + potential::energy(x);
    if energy >= BARRIER_ENERGY {
        return false;
    }
    let (_, _, offset) = plate.origin();
    let plate_top = offset + plate.velocity() / plate.omega();
    // Lowest turning point in well 2: U(x_min) = energy with ½ < x_min ≤ 1 (bisection). `lo`
    // only rises and `hi` only falls, so the answer is known once the bracket has left
    // `plate_top` (the same answer as after all the iterations).
    let (mut lo, mut hi) = (0.5, 1.0);
    for _ in 0..60 {
        if lo > plate_top || hi <= plate_top {
            break;
        }
        let mid = 0.5 * (lo + hi);
        if potential::energy(mid) > energy {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo > plate_top
}

/// Largest Lyapunov exponent (per unit of `τ`) of the response at `(Ω, V)` from the paper's
/// initial condition: `transient` shaker periods are skipped, then `periods` are averaged.
/// `None` when the variation vanishes (the steady state sticks, which forgets the initial state).
pub fn largest_lyapunov(
    params: Params,
    plate: Sinusoid,
    opts: SolverOptions,
    transient: u32,
    periods: u32,
) -> Result<Option<f64>, SimError> {
    let mut sim = Simulator::new(params, plate.into(), opts)?;
    sim.advance_to(f64::from(transient) * plate.period(), &mut |_: &Event| {})?;
    lyapunov_exponent(&mut sim, plate.period(), periods)
}

/// Largest Lyapunov exponent over `periods` shaker periods from the current state, per unit
/// of `τ`; `None` when the variation vanishes (sticking forgets the initial state).
fn lyapunov_exponent(
    sim: &mut Simulator,
    period_len: f64,
    periods: u32,
) -> Result<Option<f64>, SimError> {
    let mut run = LyapunovRun::start(sim, period_len, periods);
    if periods == 0 {
        return Ok(run.value(sim));
    }
    loop {
        sim.advance_instant(run.target(), &mut |_: &Event| {})?;
        if let Some(l) = run.reached(sim) {
            return Ok(l);
        }
    }
}

/// The measurement of [`lyapunov_exponent`], one shaker period at a time.
struct LyapunovRun {
    t0: f64,
    period_len: f64,
    periods: u32,
    /// Periods reached so far.
    k: u32,
    sum: f64,
}

impl LyapunovRun {
    /// Starts the variational equations on `sim` now.
    fn start(sim: &mut Simulator, period_len: f64, periods: u32) -> Self {
        sim.enable_variational();
        Self {
            t0: sim.time(),
            period_len,
            periods,
            k: 1,
            sum: 0.0,
        }
    }

    fn target(&self) -> Instant {
        Instant::new(self.t0 + f64::from(self.k) * self.period_len)
    }

    /// Takes `sim` at the target: the exponent when the measurement is over.
    fn reached(&mut self, sim: &mut Simulator) -> Option<Option<f64>> {
        match sim.renormalize_variational() {
            Some(l) => self.sum += l,
            None => return Some(None),
        }
        if self.k >= self.periods {
            return Some(self.value(sim));
        }
        self.k += 1;
        None
    }

    /// The exponent measured so far, at `sim`'s time.
    fn value(&self, sim: &Simulator) -> Option<f64> {
        Some(self.sum / (sim.time() - self.t0))
    }
}
