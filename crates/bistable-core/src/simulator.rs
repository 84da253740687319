//! The event-driven simulator: Taylor steps in free flight and while stuck, every event located
//! as a polynomial root, and dense output between events.
//!
//! Each step is computed from the state at its start and ends at the first event in it (impact,
//! release, snap-through) or at the step size the tolerance allows. Requests for the state at a
//! time inside a step evaluate that step's polynomial: asking for output never restarts the
//! integration, so the trajectory does not depend on when it is observed.

use std::cell::Cell;
use std::fmt;
use std::ops::ControlFlow;
use std::sync::atomic::{AtomicU64, Ordering};

use crate::chatter;
use crate::checkpoint::{Checkpoint, KeptFlight, PlateRecord};
use crate::events::{ContactMode, Event, Impact, StickCause, Well};
use crate::lanes::{F64x16, Lane};
use crate::law::{self, Contact};
use crate::params::{check, ParamError, Params, SolverOptions};
use crate::potential::{self, BARRIER};
use crate::roots::{first_root, first_root_from};
use crate::sampled::{PieceMemo, Sample, SampleHistory};
#[cfg(doc)]
use crate::shaker::Sinusoid;
use crate::shaker::{PlateEval, PlateMotion, PolyPiece};
use crate::taylor::{self, eval, eval_d, FlightSeries, VariationSeries, BUF};
use crate::time::{self, Instant};

/// Why a run could not go on. The simulator stays usable at its last consistent state.
#[derive(Debug, Clone, PartialEq)]
pub enum SimError {
    /// The requested time is before the current one.
    BackwardTime {
        /// Current time.
        now: f64,
        /// Requested time.
        requested: f64,
    },
    /// The plate motion is not defined that far (an external piece ends earlier).
    BeyondPlate {
        /// Last instant with a defined plate motion.
        horizon: f64,
        /// Requested time.
        requested: f64,
    },
    /// A new plate motion would move the plate by a jump.
    PlateJump {
        /// Instant of the switch.
        t: f64,
        /// Plate position before.
        from: f64,
        /// Plate position after.
        to: f64,
    },
    /// The Zeno guard stopped an unending chatter sequence while the plate pulls away.
    Zeno {
        /// Instant.
        t: f64,
        /// Impacts in the sequence.
        impacts: u32,
    },
    /// The solution left the range of doubles (parameters far outside the model's scope).
    NonFinite {
        /// Instant of the step that overflowed.
        t: f64,
    },
    /// The check installed by [`crate::interrupt::with_check`] asked to stop (e.g. Ctrl-C).
    Interrupted {
        /// Instant where the simulator stopped.
        t: f64,
    },
    /// A rejected parameter or initial state.
    Param(ParamError),
}

impl fmt::Display for SimError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SimError::BackwardTime { now, requested } => {
                write!(f, "cannot go back in time from t={now} to t={requested}")
            }
            SimError::BeyondPlate { horizon, requested } => write!(
                f,
                "plate motion is defined up to t={horizon}, cannot advance to t={requested}"
            ),
            SimError::PlateJump { t, from, to } => write!(
                f,
                "new plate motion jumps at t={t} from z={from} to z={to}; plate position must be continuous"
            ),
            SimError::Zeno { t, impacts } => write!(
                f,
                "chatter did not end after {impacts} impacts at t={t} (Zeno guard) and the contact force is negative"
            ),
            SimError::NonFinite { t } => {
                write!(f, "solution is no longer finite at t={t}; parameters out of scope")
            }
            SimError::Interrupted { t } => write!(f, "interrupted at t={t}"),
            SimError::Param(e) => e.fmt(f),
        }
    }
}

impl std::error::Error for SimError {}

impl From<ParamError> for SimError {
    fn from(e: ParamError) -> Self {
        SimError::Param(e)
    }
}

/// Mass and plate at one instant. Lengths in `Δx`, velocities in `ω0 Δx`, energies in `k0 Δx²`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct State {
    /// Time.
    pub t: f64,
    /// Mass position.
    pub x: f64,
    /// Mass velocity.
    pub v: f64,
    /// Plate position.
    pub z: f64,
    /// Plate velocity.
    pub zdot: f64,
    /// Free flight or riding on the plate.
    pub mode: ContactMode,
    /// Well the mass is in.
    pub well: Well,
}

impl State {
    /// `v²/2`.
    pub fn kinetic_energy(&self) -> f64 {
        potential::kinetic(self.v)
    }

    /// `U(x)`.
    pub fn potential_energy(&self) -> f64 {
        potential::energy(self.x)
    }

    /// Gap `x − z ≥ 0`.
    pub fn gap(&self) -> f64 {
        self.x - self.z
    }
}

/// Counters of the work done.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Stats {
    /// Taylor steps taken (free and stuck).
    pub steps: u64,
    /// Impacts.
    pub impacts: u64,
    /// Sticking intervals begun.
    pub sticks: u64,
    /// Barrier crossings.
    pub snap_throughs: u64,
}

/// Receives events (and, for audits, every step) while the simulator advances.
pub trait Observer {
    /// Called for each event in time order; `Break` stops the advance at that event.
    fn event(&mut self, _event: &Event) -> ControlFlow<()> {
        ControlFlow::Continue(())
    }

    /// Called once for each step when it is computed.
    fn step(&mut self, _step: &StepView<'_>) {}
}

impl<F: FnMut(&Event)> Observer for F {
    fn event(&mut self, event: &Event) -> ControlFlow<()> {
        self(event);
        ControlFlow::Continue(())
    }
}

/// A computed step, for audits: the mass position as a polynomial over `[t0, t0 + len]`.
pub struct StepView<'a> {
    start: Instant,
    len: f64,
    riding: bool,
    x: &'a [f64],
    plate: &'a PlateMotion,
}

impl StepView<'_> {
    /// Start of the step.
    pub fn t0(&self) -> f64 {
        self.start.to_f64()
    }

    /// Length of the step (time units).
    pub fn len(&self) -> f64 {
        self.len
    }

    /// Whether the step has zero length (an event at its start).
    pub fn is_empty(&self) -> bool {
        self.len == 0.0
    }

    /// Whether the mass rides on the plate during the step.
    pub fn riding(&self) -> bool {
        self.riding
    }

    /// Gap `x − z` at `t0 + s`, with the plate evaluated directly (not from the step's series).
    pub fn gap_at(&self, s: f64) -> f64 {
        let t = self.start + s;
        let z = self.plate.motion(t).0;
        if self.riding {
            0.0
        } else {
            eval(self.x, s) - z
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum StepEnd {
    /// Nothing happens at the end; the next step continues the motion.
    Plain,
    /// The gap closes.
    Impact,
    /// `x = ½`.
    Barrier,
    /// The contact force turns negative (`at_root`: at a root of `N`, so the gap's curvature
    /// `−N/2` vanishes there too); otherwise `N` is already negative at the step's start, which
    /// only a change of plate motion while the mass rides can cause.
    Release { at_root: bool },
    /// A chatter sequence accumulates (or the mass is pushed with no relative velocity).
    Stick(StickCause),
}

/// What a batch needs from a lane to compute its next free step ([`Simulator::lane_start`]).
#[derive(Debug, Clone, Copy)]
pub(crate) struct LaneStart {
    /// Gap and gap rate at the step's start.
    pub u0: f64,
    pub w0: f64,
    /// Sine and cosine of the plate's phase angle there.
    pub sin: f64,
    pub cos: f64,
    /// The sinusoid's mean position.
    pub offset: f64,
    /// The step starts on the plate (`u0 = 0`, `w0 > 0`, the gap's root there divided out).
    pub leaving: bool,
    /// In well 2 (the barrier is below).
    pub above: bool,
    /// The step starts on the barrier.
    pub on_barrier: bool,
    /// Start of the variational series, when they are integrated.
    pub phi: Option<[[f64; 2]; 2]>,
}

/// A batch kernel's verdict on one lane's free step ([`Simulator::take_lane_step`]).
#[derive(Clone, Copy)]
pub(crate) struct LaneEnd {
    /// Every coefficient of `x` is finite.
    pub finite: bool,
    /// Step size (before any event).
    pub h: f64,
    /// The gap certified root-free over `h`.
    pub clear: bool,
    /// The barrier certified out of reach over `h`.
    pub far: bool,
    /// Gap and gap rate at `h`.
    pub end_gap: (f64, f64),
}

#[derive(Clone)]
struct Step {
    len: f64,
    end: StepEnd,
    /// The mass rides on the plate (sticking, or the tail of a chatter sequence).
    riding: bool,
    /// Series of `x` and of the gap over the step (of the plate, while riding).
    series: FlightSeries,
    /// Gap and gap rate at the end of a free step, when a batch computed them with the step
    /// (the values `finish_step` would compute).
    end_gap: Option<(f64, f64)>,
    /// How far from the step's start the series of `x` holds (its step size before a plate
    /// piece's end limited it); zero for a step on the plate.
    reach: f64,
    /// The plate changed since the step was computed (later pieces continue it, see
    /// [`Simulator::keep_flight`]): `series.u` is stale, only `series.x` holds.
    kept: bool,
    /// Bounds over the whole reach, for continuing the step across plate pieces.
    guard: Option<Guard>,
    /// Which computation `series` holds: a number no other series of the process gets
    /// ([`next_stamp`]; 0 before the first), so that equal stamps mean equal series.
    stamp: u64,
}

/// A fresh [`Step::stamp`]. Each thread takes blocks of [`STAMP_BLOCK`] stamps from the
/// process's counter and hands them out one by one: unique in the process, without a shared
/// write per step (threads stepping side by side would contend for the counter's cache line).
fn next_stamp() -> u64 {
    static STAMPS: AtomicU64 = AtomicU64::new(1);
    thread_local! {
        /// The thread's next stamp and the end of its block.
        static BLOCK: Cell<(u64, u64)> = const { Cell::new((0, 0)) };
    }
    BLOCK.with(|b| {
        let (mut next, mut end) = b.get();
        if next == end {
            next = STAMPS.fetch_add(STAMP_BLOCK, Ordering::Relaxed);
            end = next + STAMP_BLOCK;
        }
        b.set((next + 1, end));
        next
    })
}

/// Stamps a thread takes from the process's counter at once ([`next_stamp`]).
const STAMP_BLOCK: u64 = 1 << 16;

/// What a free step's series allows to conclude cheaply over its whole reach, for continuing
/// it under a new plate piece ([`Simulator::continue_plate`]).
#[derive(Clone, Copy)]
struct Guard {
    /// The series stays moderate (`Σ|x_k| reach^k` and the bound below finite and below
    /// `1e100`) and the barrier out of reach ([`barrier_far`]) over the whole reach.
    usable: bool,
    /// `Σ k(k−1)|x_k| reach^(k−2) ≥ |x''|` over the reach.
    accel: f64,
    /// `Σ|x_k| reach^k ≥ |x|` over the reach (also for the rounding margin).
    size: f64,
    /// `Σ k|x_k| reach^(k−1) ≥ |x'|` over the reach.
    speed: f64,
    /// `(s, x(s), x'(s))` at the last point where the series was evaluated for a bound.
    anchor: Option<(f64, f64, f64)>,
}

impl Guard {
    /// The bounds of the series `x` over `[0, reach]`.
    fn of(x: &[f64], reach: f64, well: Well, on_barrier: bool) -> Self {
        let (mut size, mut hk) = (x[0].abs(), 1.0);
        for &xk in &x[1..] {
            hk *= reach;
            size += xk.abs() * hk;
        }
        let (mut speed, mut hk) = (0.0, 1.0);
        for (k, &xk) in x.iter().enumerate().skip(1) {
            speed += k as f64 * xk.abs() * hk;
            hk *= reach;
        }
        let (mut accel, mut hk) = (0.0, 1.0);
        for (k, &xk) in x.iter().enumerate().skip(2) {
            accel += (k * (k - 1)) as f64 * xk.abs() * hk;
            hk *= reach;
        }
        let far = barrier_far(!on_barrier, sign(well), x, reach);
        Self {
            usable: far && size < 1e100 && speed < 1e100 && accel < 1e100,
            accel,
            size,
            speed,
            anchor: None,
        }
    }
}

/// Where an advance stands after [`Simulator::resume`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Progress {
    /// The next step has to be computed ([`Simulator::compute_step`], or a batch's kernel).
    NeedStep,
    /// The advance is over: the target was reached (`true`) or the observer stopped it.
    Stopped(bool),
}

/// What [`Simulator::mass_at`] depends on for instants in free flight inside the current step
/// ([`Simulator::step_key`]). The default key is that of no step.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct StepKey {
    /// [`Step::stamp`] (0: no series).
    stamp: u64,
    /// The bits of the step's start and length.
    t0: u64,
    t0_lo: u64,
    len: u64,
    /// Bit 0: the step is live and in flight; bit 1: in well 2.
    flags: u64,
}

/// Instants [`Simulator::flights_at`] evaluates at once.
pub const FLIGHT_LANES: usize = 16;

/// The mass at [`FLIGHT_LANES`] instants ([`Simulator::flights_at`]).
#[derive(Debug, Clone, Copy, Default)]
pub struct Flights {
    /// Position at each instant where `flying`.
    pub x: [f64; FLIGHT_LANES],
    /// Velocity at each instant where `flying`.
    pub v: [f64; FLIGHT_LANES],
    /// The instant is in free flight inside the step, after its start.
    pub flying: [bool; FLIGHT_LANES],
}

/// The event-driven simulator (see the module documentation).
#[derive(Clone)]
pub struct Simulator {
    params: Params,
    opts: SolverOptions,
    /// The plate motion, with the work that repeats in evaluating it done once.
    plate: PlateEval,
    order: usize,
    /// `opts.tol().ln()`.
    ln_tol: f64,
    /// Start of the current step and the state there.
    t0: Instant,
    mode: ContactMode,
    u0: f64,
    w0: f64,
    /// Leading coefficients of the event function (gap in free flight, contact force while
    /// stuck) known to vanish exactly at `t0`: they are set to zero and divided out.
    pinned: usize,
    on_barrier: bool,
    well: Well,
    /// The current step, valid while `live`.
    step: Step,
    live: bool,
    /// Observation time, `t0 ≤ now ≤ t0 + step.len`.
    now: Instant,
    last_impact: Option<Impact>,
    last_impact_t: Option<Instant>,
    short_flights: u32,
    /// Consecutive empty steps in the current advance (a guard against a standstill).
    empty_steps: u32,
    stats: Stats,
    /// Variational state, when enabled: `Φ(t0)` and, for the current free step, the series of
    /// its two columns' `δx`.
    var: Option<Variational>,
    /// Free flights go on across plate pieces (see [`Simulator::keep_flight`]).
    keep_flight: bool,
}

/// The variational matrix `Φ = ∂(x, x')(t)/∂(x, x')(t_e)` from the instant `t_e` it was enabled.
#[derive(Clone)]
struct Variational {
    phi: [[f64; 2]; 2],
    cols: VariationSeries,
    /// Set `phi = I` at the start of the next step (see `Simulator::reseed_variational`).
    reseed: bool,
}

impl Variational {
    /// `Φ` at the start of the next free step: `I` when a reseed is pending.
    fn step_start(&self) -> [[f64; 2]; 2] {
        if self.reseed {
            IDENTITY
        } else {
            self.phi
        }
    }

    /// Takes a pending reseed once the free step from it goes on: `Φ = I` at its start.
    fn take_reseed(&mut self) {
        if self.reseed {
            self.phi = IDENTITY;
            self.reseed = false;
        }
    }
}

/// `Φ = I`: the variational solution where it starts.
const IDENTITY: [[f64; 2]; 2] = [[1.0, 0.0], [0.0, 1.0]];

/// Flights shorter than this count towards the Zeno guard (time units).
const SHORT_FLIGHT: f64 = 1e-6;

impl Simulator {
    /// The paper's initial condition: mass at rest at `x = 0`, `τ = 0`. With the paper's shaker the
    /// plate meets it moving up, so impact 0 happens at `τ = 0`.
    pub fn new(params: Params, plate: PlateMotion, opts: SolverOptions) -> Result<Self, SimError> {
        Self::with_state(params, plate, opts, 0.0, 0.0, 0.0)
    }

    /// Mass at `x0` with velocity `v0` at time `t0`; `x0` must not be below the plate.
    pub fn with_state(
        params: Params,
        plate: PlateMotion,
        opts: SolverOptions,
        t0: f64,
        x0: f64,
        v0: f64,
    ) -> Result<Self, SimError> {
        check("t0", t0, true, "must be finite")?;
        check("x0", x0, true, "must be finite")?;
        check("v0", v0, true, "must be finite")?;
        let start = Instant::new(t0);
        if let Some(h) = plate.horizon() {
            if h < start {
                return Err(SimError::BeyondPlate {
                    horizon: h.to_f64(),
                    requested: t0,
                });
            }
        }
        let (z, zd, _) = plate.motion(start);
        let u0 = x0 - z;
        check(
            "x0",
            x0,
            u0 >= 0.0,
            "must not be below the plate (x0 >= z(t0))",
        )?;
        Ok(Self::fresh(
            params,
            opts,
            plate,
            start,
            u0,
            v0 - zd,
            Well::of(x0),
            x0 == BARRIER,
        ))
    }

    /// A simulator at the start of a step at `t0` with gap `u0` and gap rate `w0`.
    #[allow(clippy::too_many_arguments)]
    fn fresh(
        params: Params,
        opts: SolverOptions,
        plate: PlateMotion,
        t0: Instant,
        u0: f64,
        w0: f64,
        well: Well,
        on_barrier: bool,
    ) -> Self {
        Self {
            params,
            opts,
            plate: PlateEval::new(plate),
            order: opts.order(),
            ln_tol: opts.tol().ln(),
            t0,
            mode: ContactMode::Free,
            u0,
            w0,
            pinned: usize::from(u0 == 0.0),
            on_barrier,
            well,
            step: Step {
                len: 0.0,
                end: StepEnd::Plain,
                riding: false,
                series: FlightSeries::default(),
                end_gap: None,
                reach: 0.0,
                kept: false,
                guard: None,
                stamp: 0,
            },
            live: false,
            now: t0,
            last_impact: None,
            last_impact_t: None,
            short_flights: 0,
            empty_steps: 0,
            stats: Stats::default(),
            var: None,
            keep_flight: false,
        }
    }

    /// With `on`, a free flight goes on across the pieces of a piecewise plate: a step that a
    /// piece's end cut short stays the current step at that end, and [`Simulator::set_plate`]
    /// with the next piece keeps its series (the mass's flight does not depend on the plate)
    /// when a bound shows that the gap stays open over the new piece; only a piece that may
    /// hold an event restarts the integration. Without it (the default) every piece restarts
    /// it. The trajectories of the two differ by rounding. Not part of a [`Checkpoint`]: set it
    /// again on a simulator rebuilt from one.
    pub fn keep_flight(&mut self, on: bool) {
        self.keep_flight = on;
    }

    /// Model parameters.
    pub fn params(&self) -> &Params {
        &self.params
    }

    /// Solver options.
    pub fn options(&self) -> &SolverOptions {
        &self.opts
    }

    /// Current plate motion.
    pub fn plate(&self) -> &PlateMotion {
        self.plate.law()
    }

    /// Taylor order in use.
    pub fn order(&self) -> usize {
        self.order
    }

    /// Current time.
    pub fn time(&self) -> f64 {
        self.now.to_f64()
    }

    /// Current time in full (two-double) precision.
    pub fn instant(&self) -> Instant {
        self.now
    }

    /// Work counters.
    pub fn stats(&self) -> Stats {
        self.stats
    }

    /// The last impact so far.
    pub fn last_impact(&self) -> Option<Impact> {
        self.last_impact
    }

    /// State at the current time.
    pub fn state(&self) -> State {
        let (z, zdot, _) = self.plate.law().motion(self.now);
        let (x, v, mode) = self.mass_with(|| (z, zdot));
        State {
            t: self.now.to_f64(),
            x,
            v,
            z,
            zdot,
            mode,
            well: self.well,
        }
    }

    /// The mass now: position, velocity, contact mode and well, the same values as in
    /// [`Simulator::state`], without evaluating the plate's motion when the mass is in flight
    /// inside a step (its position and velocity then come from the step's series alone).
    pub fn mass(&self) -> (f64, f64, ContactMode, Well) {
        let (x, v, mode) = self.mass_with(|| {
            let (z, zdot, _) = self.plate.law().motion(self.now);
            (z, zdot)
        });
        (x, v, mode, self.well)
    }

    /// Whether `t` lies inside the current step, not before the current time: an advance to
    /// `t` would only move the current time there (no step to compute, no event).
    pub fn inside_step(&self, t: Instant) -> bool {
        self.live && self.step.len > 0.0 && self.now <= t && self.t0 + self.step.len > t
    }

    /// The mass at `t` if `t` is [inside the current step](Simulator::inside_step): the values
    /// [`Simulator::mass`] gives after an advance to `t`, without advancing.
    pub fn mass_at(&self, t: Instant) -> Option<(f64, f64, ContactMode, Well)> {
        if !self.inside_step(t) {
            return None;
        }
        let s = t.since(self.t0);
        if self.step.riding {
            let (z, zdot, _) = self.plate.law().motion(t);
            Some((z, zdot, ContactMode::Sticking, self.well))
        } else if s > 0.0 {
            let (x, v) = eval_d(&self.step.series.x[..=self.order + 1], s);
            Some((x, v, ContactMode::Free, self.well))
        } else {
            let (z, zdot, _) = self.plate.law().motion(t);
            Some((self.u0 + z, self.w0 + zdot, ContactMode::Free, self.well))
        }
    }

    /// The potential well the mass is in now.
    pub fn well(&self) -> Well {
        self.well
    }

    /// What [`Simulator::mass_at`] depends on for an instant in free flight inside the current
    /// step: at two moments with equal keys, `mass_at` of such an instant gives the same values
    /// (a cache of them stays valid while the key does).
    pub fn step_key(&self) -> StepKey {
        let flying = self.live && !self.step.riding;
        StepKey {
            stamp: self.step.stamp,
            t0: self.t0.parts().0.to_bits(),
            t0_lo: self.t0.parts().1.to_bits(),
            len: self.step.len.to_bits(),
            flags: u64::from(flying) | u64::from(self.well == Well::Two) << 1,
        }
    }

    /// [`Simulator::mass_at`] at [`FLIGHT_LANES`] instants `Instant::new(taus[i])` at once, into
    /// `out`, for those in free flight inside the current step after its start: where
    /// `out.flying[i]`, `out.x[i]` and `out.v[i]` are the position and velocity of that
    /// `mass_at` bit for bit (its mode is free flight, its well [`Simulator::well`]; the step's
    /// series is evaluated in SIMD lanes, each lane with the IEEE operations of the scalar
    /// evaluation, see [`crate::lanes`]). For the other instants ask `mass_at`.
    pub fn flights_at(&self, taus: &[f64; FLIGHT_LANES], out: &mut Flights) {
        #[cfg(target_arch = "x86_64")]
        if crate::simd::avx512f() {
            // SAFETY: the CPU has the feature (the SIMD path allows only features it has).
            return unsafe { self.flights_at_avx512(taus, out) };
        }
        self.flights_in_lanes(taus, out)
    }

    /// [`Simulator::flights_at`] compiled for AVX-512 registers (the same operations).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f")]
    fn flights_at_avx512(&self, taus: &[f64; FLIGHT_LANES], out: &mut Flights) {
        self.flights_in_lanes(taus, out)
    }

    /// The body of [`Simulator::flights_at`], inlined into each of its compilations.
    #[inline(always)]
    fn flights_in_lanes(&self, taus: &[f64; FLIGHT_LANES], out: &mut Flights) {
        out.flying = [false; FLIGHT_LANES];
        if !self.live || self.step.riding || self.step.len <= 0.0 {
            return;
        }
        // `inside_step` and `t.since(t0) > 0` in lanes, with the step's end computed once.
        let (hi, lo) = (F64x16(*taus), F64x16::splat(0.0));
        let at = |t: Instant| (F64x16::splat(t.parts().0), F64x16::splat(t.parts().1));
        let ((t0_hi, t0_lo), (now_hi, now_lo)) = (at(self.t0), at(self.now));
        let (end_hi, end_lo) = at(self.t0 + self.step.len);
        let zero = F64x16::splat(0.0);
        let s = time::since(hi, lo, t0_hi, t0_lo);
        let before_now = time::since(now_hi, now_lo, hi, lo);
        let not_before_now = F64x16::or(before_now.lt(zero), before_now.equal(zero));
        let before_end = time::since(end_hi, end_lo, hi, lo).gt(zero);
        let flying = F64x16::and(F64x16::and(not_before_now, before_end), s.gt(zero));
        if flying.contains(&true) {
            let (x, v) = eval_d(&self.step.series.x[..=self.order + 1], s);
            (out.x, out.v, out.flying) = (x.0, v.0, flying);
        }
    }

    /// Position, velocity and mode of the mass now; `plate` gives the plate's position and
    /// velocity now, asked only when they are needed.
    fn mass_with(&self, plate: impl FnOnce() -> (f64, f64)) -> (f64, f64, ContactMode) {
        let s = self.now.since(self.t0);
        let riding = if self.live {
            self.step.riding
        } else {
            self.mode == ContactMode::Sticking
        };
        if riding {
            let (z, zdot) = plate();
            (z, zdot, ContactMode::Sticking)
        } else if self.live && s > 0.0 {
            let (x, v) = eval_d(&self.step.series.x[..=self.order + 1], s);
            (x, v, ContactMode::Free)
        } else {
            let (z, zdot) = plate();
            (self.u0 + z, self.w0 + zdot, ContactMode::Free)
        }
    }

    /// Advances to `t`, reporting events to `on_event` (a closure `FnMut(&Event)` will do).
    /// Events at exactly `t` are included.
    pub fn advance_to(&mut self, t: f64, on_event: &mut impl Observer) -> Result<(), SimError> {
        self.advance(t, on_event).map(|_| ())
    }

    /// Advances to `t` or until the observer answers `Break` to an event; returns whether `t`
    /// was reached (`true`) or the observer stopped the run at the current time (`false`).
    pub fn advance(&mut self, t: f64, obs: &mut impl Observer) -> Result<bool, SimError> {
        check("t", t, true, "must be finite")?;
        self.advance_instant(Instant::new(t), obs)
    }

    /// [`Simulator::advance`] to an instant given in full two-double precision (e.g. an exact
    /// stroboscopic section, [`Sinusoid::section`]).
    pub fn advance_instant(
        &mut self,
        target: Instant,
        obs: &mut impl Observer,
    ) -> Result<bool, SimError> {
        self.begin_advance(target)?;
        loop {
            match self.resume(target, obs)? {
                Progress::Stopped(reached) => return Ok(reached),
                Progress::NeedStep => {
                    self.interruption()?;
                    self.compute_step()?;
                    self.step_ready(obs);
                }
            }
        }
    }

    /// Checks that the simulator can advance to `target` (not back in time, not past the plate
    /// motion's horizon) and starts the advance's standstill guard.
    pub(crate) fn begin_advance(&mut self, target: Instant) -> Result<(), SimError> {
        let t = target.to_f64();
        check("t", t, true, "must be finite")?;
        if target < self.now {
            return Err(SimError::BackwardTime {
                now: self.time(),
                requested: t,
            });
        }
        if let Some(h) = self.plate.law().horizon() {
            if h < target {
                return Err(SimError::BeyondPlate {
                    horizon: h.to_f64(),
                    requested: t,
                });
            }
        }
        self.empty_steps = 0;
        Ok(())
    }

    /// Goes on with an advance to `target` (begun by [`Simulator::begin_advance`]) through the
    /// steps already computed, until the next one has to be computed or the advance is over.
    pub(crate) fn resume(
        &mut self,
        target: Instant,
        obs: &mut impl Observer,
    ) -> Result<Progress, SimError> {
        loop {
            if !self.live {
                return Ok(Progress::NeedStep);
            }
            let (len, end) = (self.step.len, self.step.end);
            if len == 0.0 && end == StepEnd::Plain {
                // Only at the end of an external plate piece.
                self.now = target;
                return Ok(Progress::Stopped(true));
            }
            let step_end = self.t0 + len;
            if step_end > target || self.cut_at_horizon() {
                self.now = target;
                return Ok(Progress::Stopped(true));
            }
            self.empty_steps = if len == 0.0 { self.empty_steps + 1 } else { 0 };
            if self.empty_steps > 8 {
                return Err(SimError::NonFinite { t: self.time() });
            }
            let flow = self.finish_step(obs)?;
            self.now = self.t0;
            if flow.is_break() {
                return Ok(Progress::Stopped(false));
            }
        }
    }

    /// [`SimError::Interrupted`] when the check installed by [`crate::interrupt::with_check`]
    /// asks to stop (asked every [`crate::interrupt::CHECK_EVERY`] calls); called before each
    /// step is computed, so the state stays consistent.
    pub(crate) fn interruption(&self) -> Result<(), SimError> {
        if crate::interrupt::stop_requested() {
            return Err(SimError::Interrupted { t: self.time() });
        }
        Ok(())
    }

    /// Marks the step just computed as the current one, counts it and shows it to `obs`.
    pub(crate) fn step_ready(&mut self, obs: &mut impl Observer) {
        self.live = true;
        self.stats.steps += 1;
        obs.step(&StepView {
            start: self.t0,
            len: self.step.len,
            riding: self.step.riding,
            x: &self.step.series.x[..=self.order + 1],
            plate: self.plate.law(),
        });
    }

    /// Switches the plate motion at the current time. The new motion must continue the plate
    /// position (within `1e-12` relative); the integration restarts here. Its velocity may jump:
    /// a mass in flight keeps its velocity (an impact follows at once if the plate now moves
    /// into it); a mass riding the plate stays on it and moves with the new velocity while the
    /// contact force is non-negative, and is released at once if the new motion pulls away.
    pub fn set_plate(&mut self, plate: PlateMotion) -> Result<(), SimError> {
        if let PlateMotion::Poly(piece) = &plate {
            if self.continue_flight(piece, false, f64::INFINITY) {
                return Ok(());
            }
        }
        let now = self.now;
        if let Some(h) = plate.horizon() {
            if h < now {
                return Err(SimError::BeyondPlate {
                    horizon: h.to_f64(),
                    requested: now.to_f64(),
                });
            }
        }
        let st = self.state();
        let (z, zd, _) = plate.motion(now);
        if (z - st.z).abs() > 1e-12 * st.z.abs().max(1.0) || !z.is_finite() {
            return Err(SimError::PlateJump {
                t: now.to_f64(),
                from: st.z,
                to: z,
            });
        }
        self.plate = PlateEval::new(plate);
        self.restart_at_now(&st, z, zd);
        Ok(())
    }

    /// Takes `piece` as the plate and moves to its end, if flights are kept across pieces
    /// ([`Simulator::keep_flight`]) and the current free flight covers the whole piece without
    /// an event: the state is then the one [`Simulator::set_plate`] and an advance to the
    /// piece's end give. Otherwise returns `false` and changes nothing.
    ///
    /// `limit` bounds what the stretch may reach: the bounds used for `|x|`, `|x'|`, `|x''|`
    /// over the step and for `|z|`, `|ż|`, `|z̈|` over the piece must not exceed it (a host that
    /// skips its checks of the state after such a stretch chooses it so that they hold).
    pub fn fly_over(&mut self, piece: &PolyPiece, limit: f64) -> bool {
        if !self.continue_flight(piece, true, limit) {
            return false;
        }
        self.now = piece.end();
        true
    }

    /// The current step is a free flight that the plate piece's end cut short (its series goes
    /// on past it) and flights are kept across pieces: an advance stops there without ending
    /// the step (no advance goes past the piece's end). Not a step of length zero (a
    /// checkpoint does not keep one: it is computed again when needed).
    fn cut_at_horizon(&self) -> bool {
        self.keep_flight
            && !self.step.riding
            && self.step.end == StepEnd::Plain
            && self.step.len > 0.0
            && self.step.len < self.step.reach
            && self.plate.law().horizon().is_some()
    }

    /// Continues the current free step under `piece`, which starts now, at the end of the
    /// piece that cut the step short: the series of `x` is kept and the step goes on to the
    /// new piece's end (or its reach, `whole`: only if it reaches the piece's end), if the gap
    /// `x − z` is shown to stay open over that stretch by bounds (the last evaluation of the
    /// series and `|x''|` over the step for the mass, the piece's coefficients for the plate)
    /// and the barrier is out of reach over the whole step (a bound that fails from the last
    /// evaluation is tried again from one now, which becomes the last). Returns whether it
    /// did; otherwise only the last evaluation may change. The outcome depends on the step,
    /// the piece and the last evaluation, which a checkpoint of a kept step records, so a
    /// simulator rebuilt from one decides the same way.
    fn continue_flight(&mut self, piece: &PolyPiece, whole: bool, limit: f64) -> bool {
        let Some(stretch) = self.flight_stretch(piece.end(), whole) else {
            return false;
        };
        if piece.start() != self.now {
            return false;
        }
        let c = piece.coeffs();
        let z_old = self.plate.law().motion(self.now).0;
        let continuous = (c[0] - z_old).abs() <= 1e-12 * z_old.abs().max(1.0);
        continuous && self.continue_with(piece, stretch, limit)
    }

    /// Takes as the plate the piece that `history` builds over `[now, end]` once `sample` (at
    /// the current time) is added, from the plate's position and velocity now
    /// ([`SampleHistory::piece_with`], with `memo`), and moves to `end`, as
    /// [`Simulator::fly_over`] does with that piece; the sample is then added to `history`.
    /// Otherwise (also when the sample or the piece is refused) returns `false` and changes
    /// nothing but `memo`. The piece starts where the plate is by construction, so no
    /// continuity check is needed.
    pub fn fly_over_sampled(
        &mut self,
        history: &mut SampleHistory,
        sample: Sample,
        end: Instant,
        memo: &mut PieceMemo,
        limit: f64,
    ) -> bool {
        let now = self.now;
        let Some(stretch) = self.flight_stretch(end, true).filter(|_| sample.t == now) else {
            return false;
        };
        let PlateMotion::Poly(old) = self.plate.law() else {
            return false;
        };
        let Ok(prepared) = history.prepare(sample) else {
            return false;
        };
        let Ok(piece) = history.piece_after(&prepared, end, old.position_velocity(now), memo)
        else {
            return false;
        };
        if !self.continue_with(&piece, stretch, limit) {
            return false;
        }
        history.commit(prepared);
        self.now = end;
        true
    }

    /// Where the current free step may go on under a plate piece that starts now and ends at
    /// `end` (see [`Simulator::continue_flight`]): `(sa, len)`, the step's offsets of now and
    /// of the stretch's end; `None` when it may not.
    #[inline(always)]
    fn flight_stretch(&self, end: Instant, whole: bool) -> Option<(f64, f64)> {
        if !self.live
            || self.mode != ContactMode::Free
            || self.var.is_some()
            || !self.cut_at_horizon()
        {
            return None;
        }
        let now = self.now;
        if self.plate.law().horizon() != Some(now) {
            return None;
        }
        let t0 = self.t0;
        let reach = self.step.reach;
        let sa = now.since(t0);
        let room = end.since(t0);
        let len = room.min(reach);
        // NaN fails every comparison: nothing is continued then.
        let fits = len > sa && (room < reach || !whole);
        fits.then_some((sa, len))
    }

    /// The rest of [`Simulator::continue_flight`]: the bounds over the stretch `(sa, len)` for
    /// `piece`, which continues the plate now, and the switch to it.
    #[inline(always)]
    fn continue_with(&mut self, piece: &PolyPiece, (sa, len): (f64, f64), limit: f64) -> bool {
        let c = piece.coeffs();
        let reach = self.step.reach;
        let (well, on_barrier) = (self.well, self.on_barrier);
        let step = &mut self.step;
        let x = &step.series.x[..=self.order + 1];
        let guard = step
            .guard
            .get_or_insert_with(|| Guard::of(x, reach, well, on_barrier));
        // The plate over the stretch, σ = s − sa ∈ [0, hw]: z ≤ c0 + c1 σ + q σ².
        let hw = len - sa;
        let (mut q, mut hk) = (0.0, 1.0);
        for &ck in &c[2..] {
            q += ck.abs() * hk;
            hk *= hw;
        }
        let plate = c[0].abs() + c[1].abs() * hw + q * hw * hw;
        let plate_rate = c[1].abs() + 5.0 * q * hw;
        let bounded = [
            guard.size,
            guard.speed,
            guard.accel,
            plate,
            plate_rate,
            20.0 * q,
        ]
        .iter()
        .fold(true, |all, &b| all & (b <= limit));
        if !(guard.usable && bounded) {
            return false;
        }
        let margin = 1e-10 * (1.0 + guard.size + c[0].abs());
        // The mass from the last evaluation at s_ref ≤ sa: x ≥ x_ref + v_ref (s − s_ref) −
        // accel (s − s_ref)²/2, the linear part smallest at an end of the stretch.
        let from_anchor = match guard.anchor {
            Some((s_ref, xa, va)) => {
                let (d1, d2) = (sa - s_ref, len - s_ref);
                let low = xa + (va * d1).min(va * d2) - 0.5 * guard.accel * d2 * d2;
                let high = c[0] + (c[1] * hw).max(0.0) + q * hw * hw;
                d1 >= 0.0 && low - high > margin
            }
            None => false,
        };
        if !from_anchor {
            // From the mass now: gap ≥ (x − c0) + min(0, (v − c1) hw) − (accel/2 + q) hw².
            let (xa, va) = eval_d(x, sa);
            guard.anchor = Some((sa, xa, va));
            let low = (xa - c[0]) + ((va - c[1]) * hw).min(0.0) - (0.5 * guard.accel + q) * hw * hw;
            let open = low > margin;
            if !open {
                return false;
            }
        }
        self.plate.set_piece(*piece);
        self.step.len = len;
        self.step.end = StepEnd::Plain;
        self.step.kept = true;
        true
    }

    /// Makes the current time the start of a fresh step, with the plate at `(z, zd)` now.
    fn restart_at_now(&mut self, st: &State, z: f64, zd: f64) {
        if let Some(phi) = self.variational() {
            if let Some(v) = self.var.as_mut() {
                v.phi = phi;
            }
        }
        // Still at the instant of a barrier crossing (the run stopped at the snap-through): the
        // new step starts on the barrier too, so that root is not found again.
        self.on_barrier &= self.t0 == self.now;
        self.t0 = self.now;
        if st.mode == ContactMode::Free {
            self.u0 = (st.x - z).max(0.0);
            self.w0 = st.v - zd;
            self.pinned = usize::from(self.u0 == 0.0);
        } else if self.mode == ContactMode::Free {
            // In the accumulated tail of a chatter sequence: on the plate, no relative velocity.
            self.u0 = 0.0;
            self.w0 = 0.0;
            self.pinned = 2;
        } else {
            self.pinned = 0;
        }
        self.live = false;
    }

    /// Starts integrating the variational equations along the trajectory from now on, with
    /// `Φ = I` now (through impacts by the saltation matrix of `model.md` Sec. 4; `Φ = 0` once
    /// the mass sticks, since sticking forgets the initial state).
    pub fn enable_variational(&mut self) {
        let st = self.state();
        self.var = Some(Variational {
            phi: IDENTITY,
            cols: VariationSeries::default(),
            reseed: false,
        });
        self.restart_at_now(&st, st.z, st.zdot);
        if let Some(v) = self.var.as_mut() {
            v.phi = IDENTITY;
        }
    }

    /// Like [`Simulator::enable_variational`], but without restarting the step when no step has
    /// been taken from the current instant yet (a fresh simulator), so that the trajectory is
    /// exactly the one without variational equations.
    pub fn start_variational(&mut self) {
        if !self.live && self.now == self.t0 {
            self.var = Some(Variational {
                phi: IDENTITY,
                cols: VariationSeries::default(),
                reseed: false,
            });
        } else {
            self.enable_variational();
        }
    }

    /// Starts the variational solution from `Φ = I` at the start of the next free-flight step,
    /// without restarting the integration (the trajectory is not affected); until then
    /// [`Simulator::renormalize_variational`] gives `None`. Does nothing if it is running.
    pub fn track_variational(&mut self) {
        if self.var.is_none() {
            self.var = Some(Variational {
                phi: [[0.0; 2]; 2],
                cols: VariationSeries::default(),
                reseed: true,
            });
        }
    }

    /// Restarts the variational solution from `Φ = I` at the start of the next free-flight
    /// step, without restarting the integration (the trajectory is not affected): for a
    /// variation that sticking has set to zero.
    pub fn reseed_variational(&mut self) {
        if let Some(v) = self.var.as_mut() {
            v.reseed = true;
        }
    }

    /// Stops integrating the variational equations (the trajectory is not affected).
    pub fn disable_variational(&mut self) {
        self.var = None;
    }

    /// `Φ(now)`, row-major over `(x, x')`, if enabled.
    pub fn variational(&self) -> Option<[[f64; 2]; 2]> {
        let v = self.var.as_ref()?;
        let s = self.now.since(self.t0);
        if !self.live || s == 0.0 || self.step.riding {
            return Some(if self.live && self.step.riding && s > 0.0 {
                [[0.0; 2]; 2]
            } else {
                v.phi
            });
        }
        let q = self.order + 1;
        Some(v.cols.phi_at(q, s))
    }

    /// Divides `Φ` by its largest entry (in magnitude) and returns the natural log of that
    /// factor, for Lyapunov exponents; `None` if not enabled or `Φ = 0`.
    pub fn renormalize_variational(&mut self) -> Option<f64> {
        let phi = self.variational()?;
        let norm = phi.iter().flatten().fold(0.0_f64, |m, v| m.max(v.abs()));
        if norm == 0.0 || !norm.is_finite() {
            return None;
        }
        let v = self.var.as_mut()?;
        let r = 1.0 / norm;
        v.phi.iter_mut().flatten().for_each(|c| *c *= r);
        v.cols.scale(r);
        Some(norm.ln())
    }

    /// Switches to a sinusoidal shaker with frequency `omega` and velocity amplitude `velocity`
    /// at the current time, continuing the plate position and phase (see
    /// [`PlateMotion::continued_by_sinusoid`]).
    pub fn set_sinusoid(&mut self, omega: f64, velocity: f64) -> Result<(), SimError> {
        let s = self
            .plate
            .law()
            .continued_by_sinusoid(self.now, omega, velocity)?;
        self.set_plate(s.into())
    }

    /// A complete copy of the state (see [`Checkpoint`]).
    pub fn checkpoint(&self) -> Checkpoint {
        let tail = match self.step.end {
            StepEnd::Stick(cause) if self.live && self.step.riding => Some((self.step.len, cause)),
            _ => None,
        };
        Checkpoint {
            zeta: self.params.zeta(),
            restitution: self.params.restitution(),
            tol: self.opts.tol(),
            order: self.order,
            chatter: self.opts.chatter(),
            max_chatter_impacts: self.opts.max_chatter_impacts(),
            plate: PlateRecord::of(self.plate.law()),
            t0: self.t0.parts(),
            mode: self.mode,
            u0: self.u0,
            w0: self.w0,
            pinned: self.pinned as u8,
            on_barrier: self.on_barrier,
            well: self.well,
            now: self.now.parts(),
            last_impact: self.last_impact,
            last_impact_t: self.last_impact_t.map(Instant::parts),
            short_flights: self.short_flights,
            stats: self.stats,
            tail,
            kept: (self.live && self.step.kept).then(|| KeptFlight {
                x0: self.step.series.x[0],
                v0: self.step.series.x[1],
                reach: self.step.reach,
                anchor: self.step.guard.and_then(|g| g.anchor),
            }),
        }
    }

    /// Rebuilds a simulator from a checkpoint, checking every value; it continues exactly as
    /// the simulator the checkpoint was taken from.
    pub fn from_checkpoint(c: &Checkpoint) -> Result<Self, SimError> {
        let (params, opts, plate) = c.config()?;
        let (t0, now, last_impact_t) = c.instants()?;
        if let Some(h) = plate.horizon() {
            if h < now {
                return Err(SimError::BeyondPlate {
                    horizon: h.to_f64(),
                    requested: now.to_f64(),
                });
            }
        }
        let mut sim = Self::fresh(params, opts, plate, t0, c.u0, c.w0, c.well, c.on_barrier);
        sim.now = now;
        sim.mode = c.mode;
        sim.pinned = usize::from(c.pinned);
        sim.last_impact = c.last_impact;
        sim.last_impact_t = last_impact_t;
        sim.short_flights = c.short_flights;
        sim.stats = c.stats;
        sim.live = false;
        if let Some(k) = c.kept {
            sim.restore_kept(&k)?;
        } else if let Some((len, cause)) = c.tail {
            sim.step.len = len;
            sim.step.end = StepEnd::Stick(cause);
            sim.step.riding = true;
            sim.live = true;
        } else if now > t0 {
            // The original was inside the step from `t0` (only a computed step moves `now` past
            // its start): recompute it (the same inputs give the same series) so that `state()`
            // is the dense output at `now`, without counting it or showing it to observers again.
            sim.compute_step()?;
            sim.live = true;
        }
        Ok(sim)
    }

    /// Rebuilds a free step that later plate pieces continued ([`Simulator::keep_flight`]): its
    /// series from the mass's position and velocity at its start (the same coefficients: the
    /// series of `x` does not depend on the plate), up to the current piece's end or its reach.
    fn restore_kept(&mut self, k: &KeptFlight) -> Result<(), SimError> {
        let bad = |name, value, rule| SimError::Param(ParamError { name, value, rule });
        let PlateMotion::Poly(piece) = *self.plate.law() else {
            return Err(bad("kept", 0.0, "a kept flight needs a plate piece"));
        };
        if self.mode != ContactMode::Free || self.var.is_some() {
            return Err(bad("kept", 0.0, "a kept flight is a free flight"));
        }
        if !(k.x0.is_finite() && k.v0.is_finite() && k.reach > 0.0 && k.reach <= taylor::MAX_STEP) {
            return Err(bad("kept", k.reach, "must be finite, with reach in (0, 8]"));
        }
        let (start, room) = (piece.start().since(self.t0), piece.end().since(self.t0));
        let len = room.min(k.reach);
        let anchored = k
            .anchor
            .is_none_or(|(s, x, v)| s >= 0.0 && s <= start && x.is_finite() && v.is_finite());
        if !(start > 0.0 && len > start && self.now.since(self.t0) <= room && anchored) {
            return Err(bad(
                "kept",
                start,
                "the plate piece must start inside the kept flight and hold the current time",
            ));
        }
        let p = self.order;
        let zero = [0.0; BUF];
        self.step.stamp = next_stamp();
        taylor::flight(
            self.params.zeta(),
            k.x0,
            k.v0,
            &zero,
            p,
            &mut self.step.series,
            None,
        );
        if !self.step.series.x[..=p + 1].iter().all(|c| c.is_finite()) {
            return Err(SimError::NonFinite {
                t: self.t0.to_f64(),
            });
        }
        let step = &mut self.step;
        step.len = len;
        step.end = StepEnd::Plain;
        step.riding = false;
        step.end_gap = None;
        step.reach = k.reach;
        step.kept = true;
        step.guard = k.anchor.map(|a| Guard {
            anchor: Some(a),
            ..Guard::of(
                &step.series.x[..=p + 1],
                k.reach,
                self.well,
                self.on_barrier,
            )
        });
        self.live = true;
        Ok(())
    }

    /// Advances to `t` and returns the events on the way.
    pub fn events_until(&mut self, t: f64) -> Result<Vec<Event>, SimError> {
        let mut out = Vec::new();
        self.advance_to(t, &mut |e: &Event| out.push(*e))?;
        Ok(out)
    }

    /// Computes the step from `t0` into `self.step`: its series, length and end event.
    pub(crate) fn compute_step(&mut self) -> Result<(), SimError> {
        let p = self.order;
        let mut z = [0.0; BUF];
        self.plate.series(self.t0, &mut z[..p + 3]);
        let room = self
            .plate
            .law()
            .horizon()
            .map_or(f64::INFINITY, |h| h.since(self.t0).max(0.0));
        let nonfinite = SimError::NonFinite {
            t: self.t0.to_f64(),
        };
        let tol = self.opts.tol();
        let ln_tol = self.ln_tol;
        let zeta = self.params.zeta();
        let step = &mut self.step;
        step.len = 0.0;
        step.end_gap = None;
        step.reach = 0.0;
        step.kept = false;
        step.guard = None;
        step.stamp = next_stamp();
        match self.mode {
            ContactMode::Free => {
                step.riding = false;
                let s = &mut step.series;
                // With the variational equations, their series is computed in the same pass
                // (from Φ = I if a reseed is pending; the reseed is taken only if the step
                // goes on).
                let var = self.var.as_mut().map(|v| {
                    v.cols.start(v.step_start());
                    &mut v.cols
                });
                taylor::flight(zeta, self.u0, self.w0, &z, p, s, var);
                if !s.x[..=p + 1].iter().all(|c| c.is_finite()) {
                    return Err(nonfinite);
                }
                // Coefficients known to vanish are skipped (taken as exactly zero).
                let gap = &s.u[..=p + 1];
                let Some(m) = gap
                    .iter()
                    .skip(self.pinned)
                    .position(|&c| c != 0.0)
                    .map(|m| m + self.pinned)
                else {
                    // The mass rests exactly on a plate that exerts no force: stuck.
                    step.end = StepEnd::Stick(StickCause::Plastic);
                    return Ok(());
                };
                if gap[m] < 0.0 {
                    step.end = match m {
                        0 => return Err(nonfinite),
                        // Approaching the plate while touching it: impact now.
                        1 => StepEnd::Impact,
                        // Touching with no relative velocity and pushed: stuck.
                        _ => StepEnd::Stick(StickCause::Plastic),
                    };
                    return Ok(());
                }
                if let Some(v) = self.var.as_mut() {
                    v.take_reseed();
                }
                let reach = taylor::step_size(&[&s.x[..=p], &s.u[..=p]], p, tol, ln_tol);
                let h = reach.min(room);
                if h.is_nan() || h < 0.0 {
                    return Err(nonfinite);
                }
                // Checked for the whole step first, alongside the root search: far from the
                // barrier over `h`, so over any shorter step too.
                let far = barrier_far(!self.on_barrier, sign(self.well), &s.x[..=p + 1], h);
                self.end_free_step(m, h, false, far, None);
                self.step.reach = reach;
            }
            ContactMode::Sticking => {
                step.riding = true;
                let mut n = taylor::contact_force(zeta, &z, p);
                if !n[..=p].iter().all(|c| c.is_finite()) {
                    return Err(nonfinite);
                }
                n[..self.pinned].iter_mut().for_each(|c| *c = 0.0);
                let n = &n[..=p];
                step.series.x[..BUF].copy_from_slice(&z);
                let m = n.iter().position(|&c| c != 0.0);
                if m.is_some_and(|m| n[m] < 0.0) {
                    step.end = StepEnd::Release {
                        at_root: m != Some(0),
                    };
                    return Ok(());
                }
                let h = taylor::step_size(&[&z[..=p], n], p, tol, ln_tol).min(room);
                if h.is_nan() || h < 0.0 {
                    return Err(nonfinite);
                }
                let far = barrier_far(!self.on_barrier, sign(self.well), &z[..=p], h);
                step.len = h;
                step.end = StepEnd::Plain;
                if let Some(r) = m.and_then(|m| first_root(&n[m..], h)) {
                    step.len = r;
                    step.end = StepEnd::Release { at_root: true };
                }
                if !far {
                    if let Some(r) = barrier_root(self.well, self.on_barrier, &z[..=p], step.len) {
                        step.len = r;
                        step.end = StepEnd::Barrier;
                    }
                }
            }
        }
        Ok(())
    }

    /// Ends the free step of length up to `h` whose series is in `self.step`, at the first root
    /// of the gap (from its coefficient `m`, the first that does not vanish) or of `x − ½` in
    /// it. `clear`: the gap is known to have no root over `h`; `far`: the barrier is known to
    /// be out of reach over `h`; `bernstein`: the gap's Bernstein coefficients over `h`, when
    /// known (the root search then starts from them).
    fn end_free_step(
        &mut self,
        m: usize,
        h: f64,
        clear: bool,
        far: bool,
        bernstein: Option<&[f64]>,
    ) {
        let p = self.order;
        let step = &mut self.step;
        let s = &step.series;
        step.len = h;
        step.end = StepEnd::Plain;
        if !clear {
            let gap = &s.u[m..=p + 1];
            let root = match bernstein {
                Some(b) => first_root_from(gap, h, b),
                None => first_root(gap, h),
            };
            if let Some(r) = root {
                step.len = r;
                step.end = StepEnd::Impact;
            }
        }
        if !far {
            if let Some(r) = barrier_root(self.well, self.on_barrier, &s.x[..=p + 1], step.len) {
                step.len = r;
                step.end = StepEnd::Barrier;
            }
        }
    }

    /// The start of the next step, if it is a free flight under a sinusoidal plate that starts
    /// away from the plate or leaves it (the gap pinned at zero, moving away), the cases a
    /// batch computes in its lanes.
    pub(crate) fn lane_start(&mut self) -> Option<LaneStart> {
        let PlateMotion::Sinusoid(s) = *self.plate.law() else {
            return None;
        };
        let leaving = match self.pinned {
            0 if self.u0 > 0.0 => false,
            1 if self.u0 == 0.0 && self.w0 > 0.0 => true,
            _ => return None,
        };
        if self.mode != ContactMode::Free {
            return None;
        }
        let (sin, cos) = self.plate.sin_cos(&s, self.t0);
        Some(LaneStart {
            u0: self.u0,
            w0: self.w0,
            sin,
            cos,
            offset: s.origin().2,
            leaving,
            above: self.well == Well::Two,
            on_barrier: self.on_barrier,
            phi: self.var.as_ref().map(Variational::step_start),
        })
    }

    /// The plate's coefficient magnitudes for a batch's kernel, keyed by the sinusoid's
    /// `(Ω, V)` bits (`u64::MAX` for a polynomial piece).
    pub(crate) fn plate_magnitudes(&self) -> ([u64; 2], &[f64; BUF]) {
        let key = match self.plate.law() {
            PlateMotion::Sinusoid(s) => [s.omega().to_bits(), s.velocity().to_bits()],
            PlateMotion::Poly(_) => [u64::MAX; 2],
        };
        (key, self.plate.magnitudes())
    }

    /// Takes a free step that a batch computed from [`Simulator::lane_start`]: `fill` writes the
    /// series of `x`, of the gap and (with variational equations) of their columns, and, when
    /// asked (a root search follows), the Bernstein coefficients of the gap over the step;
    /// `out` is the kernel's verdict. The step is the one [`Simulator::compute_step`] would compute
    /// from the same start: a lane whose step the kernel left open (non-finite, no valid step
    /// size) is computed here by `compute_step` itself.
    pub(crate) fn take_lane_step(
        &mut self,
        leaving: bool,
        out: LaneEnd,
        fill: impl FnOnce(&mut FlightSeries, Option<&mut VariationSeries>, Option<&mut [f64; BUF]>),
    ) -> Result<(), SimError> {
        if !out.finite || out.h.is_nan() || out.h < 0.0 {
            return self.compute_step();
        }
        let step = &mut self.step;
        step.len = 0.0;
        step.end_gap = None;
        step.riding = false;
        step.kept = false;
        step.guard = None;
        step.stamp = next_stamp();
        // The kernel's Bernstein coefficients are those of the whole gap, so not of the gap
        // divided by `s` when the step leaves the plate.
        let mut bernstein = (!out.clear && !leaving).then_some([0.0; BUF]);
        fill(
            &mut step.series,
            self.var.as_mut().map(|v| &mut v.cols),
            bernstein.as_mut(),
        );
        if let Some(v) = self.var.as_mut() {
            v.take_reseed();
        }
        let bernstein = bernstein.as_ref().map(|b| &b[..=self.order + 1]);
        self.end_free_step(usize::from(leaving), out.h, out.clear, out.far, bernstein);
        self.step.reach = out.h;
        if out.clear && out.far {
            self.step.end_gap = Some(out.end_gap);
        }
        Ok(())
    }

    /// Completes the current step: moves to its end and applies what happens there.
    fn finish_step(&mut self, obs: &mut impl Observer) -> Result<ControlFlow<()>, SimError> {
        if !self.live {
            return Ok(ControlFlow::Continue(()));
        }
        self.live = false;
        let step = &self.step;
        let p = self.order;
        let t1 = self.t0 + step.len;
        self.t0 = t1;
        self.on_barrier = false;
        if step.riding {
            self.pinned = 0;
            return Ok(match step.end {
                StepEnd::Release { at_root } => {
                    self.mode = ContactMode::Free;
                    self.u0 = 0.0;
                    self.w0 = 0.0;
                    // Gap, its rate and (at a root of N) its curvature vanish.
                    self.pinned = if at_root { 3 } else { 2 };
                    let (z, zd, _) = self.plate.motion(t1);
                    obs.event(&law::release(t1.to_f64(), z, zd))
                }
                StepEnd::Barrier => self.cross_barrier(t1, obs),
                StepEnd::Stick(cause) => self.stick(t1, cause, false, obs),
                StepEnd::Plain | StepEnd::Impact => ControlFlow::Continue(()),
            });
        }
        let (u1, w1) = if step.len == 0.0 {
            (self.u0, self.w0)
        } else {
            if let Some(v) = self.var.as_mut() {
                v.phi = v.cols.phi_at(p + 1, step.len);
            }
            step.end_gap.unwrap_or_else(|| {
                if step.kept {
                    // Continued under later plate pieces: the gap from `x` and the plate now.
                    let (x, v) = eval_d(&step.series.x[..=p + 1], step.len);
                    let (z, zd, _) = self.plate.law().motion(t1);
                    (x - z, v - zd)
                } else {
                    eval_d(&step.series.u[..=p + 1], step.len)
                }
            })
        };
        let end = step.end;
        if !(u1.is_finite() && w1.is_finite()) {
            return Err(SimError::NonFinite { t: t1.to_f64() });
        }
        let just_released = self.pinned >= 3;
        self.u0 = u1.max(0.0);
        self.w0 = w1;
        self.pinned = usize::from(self.u0 == 0.0);
        Ok(match end {
            StepEnd::Plain => ControlFlow::Continue(()),
            StepEnd::Barrier => self.cross_barrier(t1, obs),
            StepEnd::Impact => return self.impact(t1, w1.min(0.0), obs),
            StepEnd::Stick(cause) => self.stick(t1, cause, just_released, obs),
            StepEnd::Release { .. } => ControlFlow::Continue(()),
        })
    }

    fn cross_barrier(&mut self, t1: Instant, obs: &mut impl Observer) -> ControlFlow<()> {
        self.well = self.well.other();
        self.on_barrier = true;
        self.stats.snap_throughs += 1;
        let v = match self.mode {
            ContactMode::Free => self.w0 + self.plate.motion(t1).1,
            ContactMode::Sticking => self.plate.motion(t1).1,
        };
        obs.event(&law::snap_through(t1.to_f64(), v, self.well))
    }

    /// Puts the mass on the plate at `t1`. `pin_force`: the contact force is zero there (a
    /// release that only touched `N = 0`), so its root is not found again.
    fn stick(
        &mut self,
        t1: Instant,
        cause: StickCause,
        pin_force: bool,
        obs: &mut impl Observer,
    ) -> ControlFlow<()> {
        self.pinned = usize::from(pin_force);
        if let Some(v) = self.var.as_mut() {
            v.phi = [[0.0; 2]; 2];
        }
        self.mode = ContactMode::Sticking;
        self.stats.sticks += 1;
        self.short_flights = 0;
        obs.event(&law::stick_start(
            t1.to_f64(),
            self.plate.motion(t1).0,
            cause,
            self.stats.impacts,
        ))
    }

    /// Applies the impact law at `t1` with incoming relative velocity `w_minus ≤ 0`.
    fn impact(
        &mut self,
        t1: Instant,
        w_minus: f64,
        obs: &mut impl Observer,
    ) -> Result<ControlFlow<()>, SimError> {
        let e = self.params.restitution();
        let (z, zd, zdd) = self.plate.motion(t1);
        let (imp, w_plus) = law::impact_law(
            &self.params,
            &Contact {
                index: self.stats.impacts,
                t: t1.to_f64(),
                phase: self.plate.phase_cycles(t1),
                z,
                zdot: zd,
                w_minus,
                v_before: w_minus + zd,
            },
        );
        self.stats.impacts += 1;
        self.last_impact = Some(imp);
        let since = self.last_impact_t.map(|p| t1.since(p));
        self.last_impact_t = Some(t1);
        self.short_flights = match since {
            Some(d) if d < SHORT_FLIGHT => self.short_flights + 1,
            _ => 0,
        };
        self.u0 = 0.0;
        self.w0 = w_plus;
        self.pinned = if w_plus == 0.0 { 2 } else { 1 };
        let force = self.params.contact_force(z, zd, zdd);
        if let Some(v) = self.var.as_mut() {
            // Saltation matrix (model.md Sec. 4): S = [[−e, 0], [−(1+e)N/w₋, −e]].
            let s21 = if w_minus < 0.0 {
                -(1.0 + e) * force / w_minus
            } else {
                0.0
            };
            let [a, b] = v.phi;
            v.phi = [
                [-e * a[0], -e * a[1]],
                [s21 * a[0] - e * b[0], s21 * a[1] - e * b[1]],
            ];
        }
        let decision = chatter::decide(
            self.opts.chatter(),
            e,
            w_plus,
            force,
            since,
            self.short_flights >= self.opts.max_chatter_impacts(),
        );
        if obs.event(&Event::Impact(imp)).is_break() {
            // Stopped at the impact: the chatter decision is taken again at the next step.
            self.pending_decision(decision);
            return Ok(ControlFlow::Break(()));
        }
        self.pending_decision(decision);
        match decision {
            chatter::Decision::Zeno => Err(SimError::Zeno {
                t: t1.to_f64(),
                impacts: self.short_flights,
            }),
            _ => Ok(ControlFlow::Continue(())),
        }
    }

    /// Turns a chatter decision into the next step: a tail on the plate ending in sticking.
    fn pending_decision(&mut self, decision: chatter::Decision) {
        let (len, cause) = match decision {
            chatter::Decision::Fly | chatter::Decision::Zeno => return,
            chatter::Decision::StickAfter(len, cause) => (len, cause),
        };
        self.step.len = len;
        self.step.end = StepEnd::Stick(cause);
        self.step.riding = true;
        self.step.reach = 0.0;
        self.step.kept = false;
        self.live = true;
    }
}

/// `+1` in well 2, `−1` in well 1: the side of the barrier `x = ½` the mass is on.
fn sign(well: Well) -> f64 {
    if well == Well::Two {
        1.0
    } else {
        -1.0
    }
}

/// Whether the series `x` of the position stays clear of `x = ½` over `(0, h]` by the bound
/// `|x(s) − x(0)| ≤ Σ_{k≥1} |x_k| h^k`, which settles most steps: never where the step starts
/// on the barrier (`free` false), else where the bound keeps `x` on its side (`sign`, see
/// [`sign`]). The bound only grows with `h` (also as computed: rounding is monotone), so clear
/// over `h` means clear over any shorter step. For one trajectory (`f64`) or one per lane of a
/// batch ([`Lane`]).
#[inline(always)]
pub(crate) fn barrier_far<T: Lane>(free: T::Mask, sign: T, x: &[T], h: T) -> T::Mask {
    let (mut reach, mut hk) = (T::splat(0.0), T::splat(1.0));
    for &xk in &x[1..] {
        hk *= h;
        reach += xk.abs() * hk;
    }
    T::and(free, (sign * (x[0] - T::splat(BARRIER))).gt(reach))
}

/// First crossing of `x = ½` out of `well` within `(0, h]`, for the series `x` of the position
/// (`on_barrier`: the step starts on the barrier, so that root is divided out).
fn barrier_root(well: Well, on_barrier: bool, x: &[f64], h: f64) -> Option<f64> {
    let sign = sign(well);
    if barrier_far(!on_barrier, sign, x, h) {
        return None;
    }
    let mut g = [0.0; BUF];
    for (gk, &xk) in g.iter_mut().zip(x) {
        *gk = sign * xk;
    }
    g[0] = if on_barrier {
        0.0
    } else {
        sign * (x[0] - BARRIER)
    };
    let g = &g[..x.len()];
    let m = g.iter().position(|&c| c != 0.0)?;
    if g[m] < 0.0 {
        // Leaving the barrier back into the other well right away.
        return Some(0.0);
    }
    first_root(&g[m..], h)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashSet;

    #[test]
    fn stamps_are_unique_across_threads_and_blocks() {
        // Two threads, each past a block's end: no stamp twice, none 0 (the "no series" key).
        let n = STAMP_BLOCK as usize + 1_000;
        let drawn: Vec<Vec<u64>> = std::thread::scope(|s| {
            let handles: Vec<_> = (0..2)
                .map(|_| s.spawn(move || (0..n).map(|_| next_stamp()).collect::<Vec<_>>()))
                .collect();
            handles.into_iter().map(|h| h.join().unwrap()).collect()
        });
        let all: HashSet<u64> = drawn.iter().flatten().copied().collect();
        assert_eq!(all.len(), 2 * n);
        assert!(!all.contains(&0));
        // Within a thread, stamps rise (a block is handed out in order).
        assert!(drawn.iter().all(|d| d.windows(2).all(|w| w[0] < w[1])));
    }
}
