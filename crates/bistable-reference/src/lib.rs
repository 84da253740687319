//! # bistable-reference
//!
//! An independent, deliberately simple high-precision solver of the bistable impact oscillator
//! (model: `shared/spec/model.md`), used as ground truth for the fast double-precision simulator.
//!
//! Nondimensional model (all times `τ`):
//! - free flight while `x > z`: `x'' + 2ζx' + x - 3x² + 2x³ = 0`;
//! - plate `z = (V/Ω) sin Ωτ`, `ż = V cos Ωτ`;
//! - impact when `x = z` with `x' < ż`: `x'₊ = -e x'₋ + (1+e) ż`;
//! - start `τ = 0`, `x = x' = 0` (impact number 0 happens at `τ = 0`), or any state above the
//!   plate with [`simulate_from`];
//! - chatter/sticking per [`RefChatter`]; while stuck `x = z` until the contact force
//!   `N = z̈ + 2ζż + z - 3z² + 2z³` turns negative.
//!
//! ## Method
//! Taylor series integration in arbitrary-precision binary floating point (`dashu-float`,
//! `bits` bits, round to nearest). The state integrated is the gap `u = x - z` and its rate
//! `u' = x' - ż`; the plate's series is exact (`sin`/`cos` evaluated at each step start, correctly
//! rounded). On every step the gap polynomial's sign changes are isolated with Bernstein
//! coefficients and bisection (so an excursion below the plate inside a step cannot be missed)
//! and refined by safeguarded Newton iteration to working precision. After an impact the exactly
//! zero gap is divided out (`u(s)/s`) instead of searching next to `s = 0`. See the crate README.
//!
//! Trust comes from running two precisions (e.g. 128 and 160 bits, which also use different
//! Taylor orders and step sizes) and checking that they agree.
//!
//! ```
//! use bistable_reference::*;
//! let p = RefParams { zeta: 0.02, restitution: 0.85, omega: 1.75, velocity: 0.07 };
//! let o = RefOptions { t_end: 10.0, ..RefOptions::default() };
//! let ev = simulate(&p, &o).unwrap();
//! assert_eq!(ev[0].kind, RefEventKind::Impact);
//! assert_eq!(ev[0].t, 0.0);
//! ```

mod poly;
mod real;
mod sim;
mod taylor;

pub use real::Real;

/// Model parameters. The exact binary values of these `f64`s are the parameters (they are
/// converted to the working precision without rounding).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RefParams {
    /// Damping ratio `ζ >= 0`.
    pub zeta: f64,
    /// Coefficient of restitution `e` in `[0, 1]`.
    pub restitution: f64,
    /// Shaker frequency ratio `Ω > 0`.
    pub omega: f64,
    /// Shaker velocity amplitude `V > 0`.
    pub velocity: f64,
}

impl Default for RefParams {
    /// The paper's baseline: `ζ = 0.02`, `e = 0.85`, `Ω = 1.75`, `V = 0.07`.
    fn default() -> Self {
        RefParams {
            zeta: 0.02,
            restitution: 0.85,
            omega: 1.75,
            velocity: 0.07,
        }
    }
}

/// How a chatter sequence (impacts accumulating in finite time) is ended and sticking begins.
///
/// Common to both rules: after an impact with exactly zero rebound velocity (`e = 0`), the mass
/// sticks at once if `N >= 0` and separates (free flight) if `N < 0`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RefChatter {
    /// Budd & Dux (1994) accumulation-time prediction. After an impact at `τₙ` with relative
    /// rebound velocity `w₊ > 0` and contact force `N(τₙ) > 0`, the chatter sequence would end at
    /// `τₙ + Δ`, `Δ = 2w₊/(N(τₙ)(1-e))`. If `Δ <= delta`, sticking starts at `τₙ + Δ` (the
    /// remaining infinitely many impacts are skipped). Never applies for `e = 1`.
    Accumulation {
        /// Threshold on the predicted remaining chatter time (e.g. `1e-20`).
        delta: f64,
    },
    /// The paper's rule: if two consecutive impacts are less than `gap` apart and `N(τₙ) >= 0`,
    /// sticking starts at the second impact `τₙ`.
    FixedGap {
        /// Minimum time between impacts (the paper: `1e-9`).
        gap: f64,
    },
}

impl Default for RefChatter {
    /// `Accumulation { delta: 1e-20 }`.
    fn default() -> Self {
        RefChatter::Accumulation { delta: 1e-20 }
    }
}

/// Run options.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RefOptions {
    /// Working precision in bits (mantissa), `64..=1024`. 128 bits ≈ 38 decimal digits.
    pub bits: usize,
    /// Chatter rule.
    pub chatter: RefChatter,
    /// End time `τ` (events with `t <= t_end` are reported).
    pub t_end: f64,
    /// Stop after this many events (all kinds together).
    pub max_events: usize,
}

impl Default for RefOptions {
    /// 128 bits, `Accumulation { delta: 1e-20 }`, `t_end = 100`, `max_events = 1_000_000`.
    fn default() -> Self {
        RefOptions {
            bits: 128,
            chatter: RefChatter::default(),
            t_end: 100.0,
            max_events: 1_000_000,
        }
    }
}

/// Kind of a reported event.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum RefEventKind {
    /// Mass hits the plate (`x = z`, `x' < ż`).
    Impact,
    /// Mass starts moving with the plate.
    StickStart,
    /// Mass leaves the plate (contact force crosses zero downwards).
    StickEnd,
    /// Crossing of the barrier `x = 1/2`.
    SnapThrough,
}

impl RefEventKind {
    /// Lower-case name used in the CSV output.
    pub fn name(self) -> &'static str {
        match self {
            RefEventKind::Impact => "impact",
            RefEventKind::StickStart => "stick_start",
            RefEventKind::StickEnd => "stick_end",
            RefEventKind::SnapThrough => "snap_through",
        }
    }
}

/// One event. The `f64` fields are the high-precision values rounded to the nearest `f64`.
#[derive(Clone, Debug, PartialEq)]
pub struct RefEvent {
    /// What happened.
    pub kind: RefEventKind,
    /// For impacts: the impact number (0 is the impact at `τ = 0`). For the other kinds: a
    /// running count of events of that kind, from 0.
    pub index: usize,
    /// Time `τ`.
    pub t: f64,
    /// The time in full working precision, as a decimal string (`bits·log10 2` significant digits).
    pub t_str: String,
    /// Plate phase `frac(Ωτ/2π)` in cycles, in `[0, 1)`.
    pub phase: f64,
    /// Mass position (`= z` for impacts and sticking events, `= 1/2` for snap-throughs).
    pub x: f64,
    /// Mass velocity just before the event (`x'₋` for an impact).
    pub v_before: f64,
    /// Mass velocity just after the event (`x'₊` for an impact; equal to `v_before` otherwise).
    pub v_after: f64,
    /// The well the mass is in after the event: 1 (`x < 1/2`) or 2 (`x > 1/2`). For a
    /// snap-through, the well it enters.
    pub to_well: u8,
}

/// A state sample in full precision.
#[derive(Clone, Debug)]
pub struct RefSample {
    /// Requested time.
    pub t: f64,
    /// Position `x`.
    pub x: Real,
    /// Velocity `x'`.
    pub v: Real,
    /// Whether the mass is stuck to the plate at `t`.
    pub stuck: bool,
}

/// Errors (invalid input or a numerical breakdown); the solver never panics on bad input.
#[derive(Clone, Debug, PartialEq)]
pub enum RefError {
    /// A parameter or option is out of its domain.
    InvalidInput(String),
    /// The integration could not proceed (should not happen for valid input).
    Numerical(String),
}

impl std::fmt::Display for RefError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RefError::InvalidInput(m) => write!(f, "invalid input: {m}"),
            RefError::Numerical(m) => write!(f, "numerical failure: {m}"),
        }
    }
}

impl std::error::Error for RefError {}

fn check(ok: bool, msg: impl FnOnce() -> String) -> Result<(), RefError> {
    if ok {
        Ok(())
    } else {
        Err(RefError::InvalidInput(msg()))
    }
}

/// Validate parameters and options.
fn validate(p: &RefParams, o: &RefOptions) -> Result<(), RefError> {
    check(
        p.zeta.is_finite() && p.zeta >= 0.0 && p.zeta <= 100.0,
        || format!("zeta must be in [0, 100], got {}", p.zeta),
    )?;
    check(
        p.restitution.is_finite() && (0.0..=1.0).contains(&p.restitution),
        || format!("restitution must be in [0, 1], got {}", p.restitution),
    )?;
    check(
        p.omega.is_finite() && p.omega >= 1e-6 && p.omega <= 1e6,
        || format!("omega must be in [1e-6, 1e6], got {}", p.omega),
    )?;
    check(
        p.velocity.is_finite() && p.velocity >= 1e-12 && p.velocity <= 1e3,
        || format!("velocity must be in [1e-12, 1e3], got {}", p.velocity),
    )?;
    check((64..=1024).contains(&o.bits), || {
        format!("bits must be in 64..=1024, got {}", o.bits)
    })?;
    check(
        o.t_end.is_finite() && o.t_end >= 0.0 && o.t_end <= 1e7,
        || format!("t_end must be in [0, 1e7], got {}", o.t_end),
    )?;
    check(o.max_events >= 1, || "max_events must be at least 1".into())?;
    match o.chatter {
        RefChatter::Accumulation { delta } => check(delta.is_finite() && delta >= 0.0, || {
            format!("accumulation delta must be finite and >= 0, got {delta}")
        }),
        RefChatter::FixedGap { gap } => check(gap.is_finite() && gap >= 0.0, || {
            format!("chatter gap must be finite and >= 0, got {gap}")
        }),
    }
}

/// Simulate from `τ = 0` (x = x' = 0) to `o.t_end` and return all events in time order
/// (at most `o.max_events`).
pub fn simulate(p: &RefParams, o: &RefOptions) -> Result<Vec<RefEvent>, RefError> {
    validate(p, o)?;
    let mut run = sim::Run::new(p, o, &RefStart::PAPER, &[], o.max_events)?;
    run.run(o.t_end)?;
    Ok(run.events)
}

/// A start in free flight: time `t0` and the mass's position `x0` and velocity `v0`, taken
/// exactly. `x0` must not be below the plate at `t0` (in working precision); a start on the
/// plate moving towards it is an impact at `t0`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RefStart {
    /// Start time `τ0 ∈ [0, 1e7]`.
    pub t0: f64,
    /// Position.
    pub x0: f64,
    /// Velocity.
    pub v0: f64,
}

impl RefStart {
    /// The paper's start: `τ = 0`, `x = x' = 0`, on the plate as it moves up at `V`.
    pub const PAPER: RefStart = RefStart {
        t0: 0.0,
        x0: 0.0,
        v0: 0.0,
    };
}

/// Simulate from `start` to `o.t_end` (`>= start.t0`) and return all events in time order
/// (at most `o.max_events`); impacts are numbered from 0.
pub fn simulate_from(
    p: &RefParams,
    o: &RefOptions,
    start: &RefStart,
) -> Result<Vec<RefEvent>, RefError> {
    validate(p, o)?;
    check(
        start.t0.is_finite() && (0.0..=o.t_end).contains(&start.t0),
        || format!("start t0 must be in [0, t_end], got {}", start.t0),
    )?;
    check(
        start.x0.is_finite()
            && start.v0.is_finite()
            && start.x0.abs() <= 1e6
            && start.v0.abs() <= 1e6,
        || {
            format!(
                "start x0, v0 must be finite and at most 1e6 in size, got {}, {}",
                start.x0, start.v0
            )
        },
    )?;
    let mut run = sim::Run::new(p, o, start, &[], o.max_events)?;
    run.run(o.t_end)?;
    Ok(run.events)
}

/// Full-precision state samples at the given times (any order; each must be in `[0, 1e7]`).
/// Uses `o.bits` and `o.chatter`; ignores `o.t_end` (integrates to the largest time) and
/// `o.max_events`. A sample exactly at an impact time gets the post-impact velocity.
pub fn sample_hp(p: &RefParams, o: &RefOptions, times: &[f64]) -> Result<Vec<RefSample>, RefError> {
    validate(p, o)?;
    for &t in times {
        check(t.is_finite() && (0.0..=1e7).contains(&t), || {
            format!("sample time must be in [0, 1e7], got {t}")
        })?;
    }
    let t_last = times.iter().cloned().fold(0.0, f64::max);
    let mut run = sim::Run::new(p, o, &RefStart::PAPER, times, usize::MAX)?;
    run.run(t_last)?;
    run.finish_samples()
}

/// State `(t, x, x')` at the given times, rounded to `f64` (see [`sample_hp`]).
pub fn sample(
    p: &RefParams,
    o: &RefOptions,
    times: &[f64],
) -> Result<Vec<(f64, f64, f64)>, RefError> {
    Ok(sample_hp(p, o, times)?
        .into_iter()
        .map(|s| (s.t, real::to_f64(&s.x), real::to_f64(&s.v)))
        .collect())
}

/// Parse a decimal string (e.g. [`RefEvent::t_str`]) into a [`Real`] with `bits` bits.
pub fn parse_real(s: &str, bits: usize) -> Result<Real, RefError> {
    use std::str::FromStr;
    let d = dashu_float::DBig::from_str(s)
        .map_err(|e| RefError::InvalidInput(format!("cannot parse {s:?}: {e:?}")))?;
    Ok(d.with_base_and_precision::<2>(bits)
        .value()
        .with_rounding::<dashu_float::round::mode::HalfEven>())
}

/// Convert a [`Real`] to the nearest `f64`.
pub fn real_to_f64(x: &Real) -> f64 {
    real::to_f64(x)
}
