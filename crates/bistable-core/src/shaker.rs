//! Prescribed plate motion `z(τ)`: the shaker's sinusoid, or a polynomial piece given from outside.
//!
//! The integrator needs the plate's normalised Taylor coefficients `z_k = z^(k)(τ)/k!` at the start
//! of each step; both kinds provide them exactly (up to rounding).

use std::ops::RangeInclusive;

use crate::lanes::Lane;
use crate::params::{check, ParamError};
use crate::taylor::BUF;
use crate::time::Instant;

/// Highest polynomial degree accepted for an external plate piece.
pub const MAX_POLY_DEGREE: usize = 5;

/// Shaker frequency ratios `Ω` a [`Sinusoid`] accepts, `[1e-6, 1e6]` (the FMU's `Omega`). Above
/// it the free flight's error grows with `Ω` (against a DOP853 run at `rtol = 1e-14`, after 0.5
/// time units: 3e-12 in `v` at `Ω = 1e6`, 1e-10 at 1e8, 1e-4 at 1e10), and a run's work grows as
/// `Ω` times its length (130,000 steps for 0.5 time units at 1e6).
pub const OMEGA_RANGE: RangeInclusive<f64> = 1e-6..=1e6;

/// Largest shaker velocity amplitude `V` a [`Sinusoid`] accepts (the FMU's `V`).
pub const MAX_VELOCITY: f64 = 1e6;

/// Sinusoidal shaker: `ż = V cos(Ω(τ−τs) + φs)`, `z = zs + (V/Ω) sin(Ω(τ−τs) + φs)`.
///
/// The default origin (`τs = 0`, `φs = 0`, `zs = 0`) is the paper's shaker: `z = (V/Ω) sin(Ωτ)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sinusoid {
    omega: f64,
    velocity: f64,
    origin: Instant,
    phase0: f64,
    offset: f64,
}

impl Sinusoid {
    /// Frequency ratio `Ω` in [`OMEGA_RANGE`] and velocity amplitude `V` in
    /// `[0, `[`MAX_VELOCITY`]`]` (both nondimensional).
    pub fn new(omega: f64, velocity: f64) -> Result<Self, ParamError> {
        Ok(Self {
            omega: check(
                "omega",
                omega,
                OMEGA_RANGE.contains(&omega),
                "must be in [1e-6, 1e6]",
            )?,
            velocity: check(
                "velocity",
                velocity,
                (0.0..=MAX_VELOCITY).contains(&velocity),
                "must be in [0, 1e6]",
            )?,
            origin: Instant::new(0.0),
            phase0: 0.0,
            offset: 0.0,
        })
    }

    /// The same sinusoid with phase `phase0` (radians) at instant `origin` and mean position
    /// `offset`. Used to switch shaker settings without a jump in plate position.
    pub fn with_origin(
        mut self,
        origin: Instant,
        phase0: f64,
        offset: f64,
    ) -> Result<Self, ParamError> {
        check("origin", origin.to_f64(), true, "must be finite")?;
        self.phase0 = check("phase0", phase0, true, "must be finite")?;
        self.offset = check("offset", offset, true, "must be finite")?;
        self.origin = origin;
        Ok(self)
    }

    /// `Ω`.
    pub fn omega(&self) -> f64 {
        self.omega
    }

    /// `V`.
    pub fn velocity(&self) -> f64 {
        self.velocity
    }

    /// `(origin, phase0, offset)` as given to [`Sinusoid::with_origin`].
    pub fn origin(&self) -> (Instant, f64, f64) {
        (self.origin, self.phase0, self.offset)
    }

    /// The instant of the `k`-th plate phase zero after the origin, `τs + (2πk − φs)/Ω`, in
    /// two-double precision (stroboscopic Poincaré sections without drift at long times).
    pub fn section(&self, k: u64) -> Instant {
        use crate::time::{two_prod, two_sum, TWO_PI};
        let kf = k as f64;
        // a = 2πk − φs as a double-double.
        let (p, pe) = two_prod(kf, TWO_PI.0);
        let pe = pe + kf * TWO_PI.1;
        let (a, e2) = two_sum(p, -self.phase0);
        let al = pe + e2;
        // q = a/Ω, with the remainder of the first quotient folded into the second.
        let q1 = a / self.omega;
        let (m, me) = two_prod(q1, self.omega);
        let q2 = ((a - m) - me + al) / self.omega;
        self.origin + q1 + q2
    }

    /// Shaker period `2π/Ω`.
    pub fn period(&self) -> f64 {
        std::f64::consts::TAU / self.omega
    }

    /// Phase angle `Ω(τ−τs) + φs` reduced to `[−π, π)`.
    pub fn angle(&self, t: Instant) -> f64 {
        t.angle(self.origin, self.omega, self.phase0)
    }

    /// Phase in cycles, in `[0, 1)` (the paper's `φ/2π`, Eq. 12).
    pub fn phase_cycles(&self, t: Instant) -> f64 {
        cycles(self.angle(t))
    }

    fn series(&self, t: Instant, out: &mut [f64]) {
        self.magnitudes(out);
        let (s, c) = self.angle(t).sin_cos();
        scale_by_phase(s, c, self.offset, out);
    }

    /// Magnitudes `(V/Ω) Ω^k/k!` of the series coefficients: the part that does not depend on
    /// time.
    fn magnitudes(&self, out: &mut [f64]) {
        let mut a = self.velocity / self.omega;
        for (k, o) in out.iter_mut().enumerate() {
            if k > 0 {
                a *= self.omega / k as f64;
            }
            *o = a;
        }
    }
}

/// A sinusoid's series from its magnitudes in `out`, the sine `s` and cosine `c` of its phase
/// angle and its `offset`, for one sinusoid (`f64`) or one per lane of a batch ([`Lane`]; the
/// same operations in each lane).
#[inline(always)]
pub(crate) fn scale_by_phase<T: Lane>(s: T, c: T, offset: T, out: &mut [T]) {
    // d^k/dτ^k sin(θ) = sin(θ + kπ/2): the cycle sin, cos, −sin, −cos.
    let cycle = [s, c, -s, -c];
    let (quads, rest) = out.as_chunks_mut::<4>();
    for q in quads {
        for (o, f) in q.iter_mut().zip(cycle) {
            *o *= f;
        }
    }
    for (o, f) in rest.iter_mut().zip(cycle) {
        *o *= f;
    }
    out[0] += offset;
}

/// A phase angle in `[−π, π)` in cycles, in `[0, 1)`.
fn cycles(angle: f64) -> f64 {
    let c = angle / std::f64::consts::TAU;
    let c = if c < 0.0 { c + 1.0 } else { c };
    if c >= 1.0 {
        0.0
    } else {
        c
    }
}

/// Plate motion given as a polynomial in `τ − start`, valid on `[start, end]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PolyPiece {
    start: Instant,
    end: Instant,
    coeffs: [f64; MAX_POLY_DEGREE + 1],
}

impl PolyPiece {
    /// `z(τ) = Σ c_k (τ − start)^k` for `τ ∈ [start, end]`, degree ≤ [`MAX_POLY_DEGREE`],
    /// all coefficients finite, `end > start`.
    pub fn new(start: Instant, end: Instant, coeffs: &[f64]) -> Result<Self, ParamError> {
        check(
            "plate_coefficients",
            coeffs.len() as f64,
            coeffs.len() <= MAX_POLY_DEGREE + 1,
            "at most 6 coefficients (degree 5)",
        )?;
        let mut c = [0.0; MAX_POLY_DEGREE + 1];
        for (dst, &src) in c.iter_mut().zip(coeffs) {
            *dst = check("plate_coefficient", src, true, "must be finite")?;
        }
        let len = end.since(start);
        check(
            "plate_piece_length",
            len,
            len > 0.0,
            "end must be after start",
        )?;
        Ok(Self {
            start,
            end,
            coeffs: c,
        })
    }

    /// [`PolyPiece::new`] of all [`MAX_POLY_DEGREE`]` + 1` coefficients for an `end` after
    /// `start` (the caller's check): `None` when a coefficient is not finite.
    #[inline(always)]
    pub(crate) fn of_finite(
        start: Instant,
        end: Instant,
        coeffs: [f64; MAX_POLY_DEGREE + 1],
    ) -> Option<Self> {
        debug_assert!(end.since(start) > 0.0);
        let finite = coeffs.iter().fold(true, |all, c| all & c.is_finite());
        finite.then_some(Self { start, end, coeffs })
    }

    /// A cubic through `(z0, zd0)` at `start` and `(z1, zd1)` at `end` (Hermite interpolation).
    pub fn hermite(
        start: Instant,
        end: Instant,
        (z0, zd0): (f64, f64),
        (z1, zd1): (f64, f64),
    ) -> Result<Self, ParamError> {
        let h = end.since(start);
        check("plate_piece_length", h, h > 0.0, "end must be after start")?;
        let d = (z1 - z0) / h;
        let c2 = (3.0 * d - 2.0 * zd0 - zd1) / h;
        let c3 = (zd0 + zd1 - 2.0 * d) / (h * h);
        Self::new(start, end, &[z0, zd0, c2, c3])
    }

    /// Instant from which the piece is valid.
    pub fn start(&self) -> Instant {
        self.start
    }

    /// Instant up to which the piece is valid.
    pub fn end(&self) -> Instant {
        self.end
    }

    /// Coefficients `c_k` of `(τ − start)^k`, `k = 0..=5`.
    pub fn coeffs(&self) -> [f64; MAX_POLY_DEGREE + 1] {
        self.coeffs
    }

    /// Upper bounds of `|z|`, `|z'|` and `|z''|` over the piece (`Σ k!/(k−j)! |c_k| h^(k−j)`
    /// for the `j`-th derivative, `h` the piece's length); infinite when they overflow.
    pub fn bounds(&self) -> [f64; 3] {
        let h = self.end.since(self.start).abs();
        let mut out = [0.0; 3];
        for (j, o) in out.iter_mut().enumerate() {
            let mut hk = 1.0;
            for (k, &c) in self.coeffs.iter().enumerate().skip(j) {
                let falling = (k + 1 - j..=k).product::<usize>() as f64;
                *o += falling * c.abs() * hk;
                hk *= h;
            }
        }
        out
    }

    /// Position and velocity at `t`: the first two entries of [`PolyPiece::series`], the
    /// same numbers.
    #[inline(always)]
    pub(crate) fn position_velocity(&self, t: Instant) -> (f64, f64) {
        let s = t.since(self.start);
        let mut c = self.coeffs;
        let n = c.len();
        for k in 0..2 {
            for j in (k..n - 1).rev() {
                c[j] += s * c[j + 1];
            }
        }
        (c[0], c[1])
    }

    fn series(&self, t: Instant, out: &mut [f64]) {
        // Taylor shift of the polynomial to s = t − start.
        let s = t.since(self.start);
        out.iter_mut().for_each(|o| *o = 0.0);
        let mut c = self.coeffs;
        let n = c.len();
        for (k, o) in out.iter_mut().enumerate().take(n) {
            // After pass k, c[k] holds the k-th coefficient at s (synthetic division).
            for j in (k..n - 1).rev() {
                c[j] += s * c[j + 1];
            }
            *o = c[k];
        }
    }
}

/// What the plate does.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PlateMotion {
    /// The shaker's sinusoid, valid forever.
    Sinusoid(Sinusoid),
    /// An external piece, valid up to its end.
    Poly(PolyPiece),
}

impl PlateMotion {
    /// Normalised Taylor coefficients `z_k = z^(k)(t)/k!` for `k < out.len()`.
    pub fn series(&self, t: Instant, out: &mut [f64]) {
        match self {
            PlateMotion::Sinusoid(s) => s.series(t, out),
            PlateMotion::Poly(p) => p.series(t, out),
        }
    }

    /// A sinusoid with frequency `omega` and velocity amplitude `velocity` that takes over from
    /// this motion at `at` without a jump in plate position: it keeps the current shaker phase
    /// (phase 0 after an external piece) and absorbs any position difference into its mean
    /// position. Velocity may jump (a new set-point is a new velocity amplitude).
    pub fn continued_by_sinusoid(
        &self,
        at: Instant,
        omega: f64,
        velocity: f64,
    ) -> Result<Sinusoid, ParamError> {
        let fresh = Sinusoid::new(omega, velocity)?;
        let phase = match self {
            PlateMotion::Sinusoid(s) => s.angle(at),
            PlateMotion::Poly(_) => 0.0,
        };
        let z_now = self.motion(at).0;
        let offset = z_now - velocity / omega * phase.sin();
        fresh.with_origin(at, phase, offset)
    }

    /// Position, velocity and acceleration `(z, ż, z̈)` at `t`.
    pub fn motion(&self, t: Instant) -> (f64, f64, f64) {
        let mut c = [0.0; 3];
        self.series(t, &mut c);
        (c[0], c[1], 2.0 * c[2])
    }

    /// Last instant at which the motion is defined (`None`: forever).
    pub fn horizon(&self) -> Option<Instant> {
        match self {
            PlateMotion::Sinusoid(_) => None,
            PlateMotion::Poly(p) => Some(p.end),
        }
    }

    /// Impact phase in cycles for a periodic shaker, `None` otherwise.
    pub fn phase_cycles(&self, t: Instant) -> Option<f64> {
        match self {
            PlateMotion::Sinusoid(s) => Some(s.phase_cycles(t)),
            PlateMotion::Poly(_) => None,
        }
    }
}

/// [`PlateMotion::series`], [`PlateMotion::motion`] and [`PlateMotion::phase_cycles`] (the same
/// values) with the work that repeats done once: a sinusoid's coefficient magnitudes, and its
/// phase angle with sine and cosine at the last instant asked (an impact and the step from it).
#[derive(Clone)]
pub(crate) struct PlateEval {
    plate: PlateMotion,
    mags: [f64; BUF],
    /// `(hi, lo)` bits of the instant, angle, sine, cosine.
    last: Option<((u64, u64), f64, f64, f64)>,
}

impl PlateEval {
    /// Evaluation of `plate`, nothing cached yet but the magnitudes.
    pub(crate) fn new(plate: PlateMotion) -> Self {
        let mut mags = [0.0; BUF];
        if let PlateMotion::Sinusoid(s) = &plate {
            s.magnitudes(&mut mags);
        }
        Self {
            plate,
            mags,
            last: None,
        }
    }

    /// Makes this the evaluation of the piece `p` (the same as `PlateEval::new(p.into())`,
    /// without rebuilding the magnitudes when they are already a piece's zeros).
    pub(crate) fn set_piece(&mut self, p: PolyPiece) {
        if !matches!(self.plate, PlateMotion::Poly(_)) {
            self.mags = [0.0; BUF];
        }
        self.plate = PlateMotion::Poly(p);
        self.last = None;
    }

    /// The plate motion evaluated.
    pub(crate) fn law(&self) -> &PlateMotion {
        &self.plate
    }

    /// Angle, sine and cosine of the sinusoid's phase at `t`.
    fn trig(&mut self, s: &Sinusoid, t: Instant) -> (f64, f64, f64) {
        let (hi, lo) = t.parts();
        let key = (hi.to_bits(), lo.to_bits());
        match self.last {
            Some((k, a, sn, cs)) if k == key => (a, sn, cs),
            _ => {
                let a = s.angle(t);
                let (sn, cs) = a.sin_cos();
                self.last = Some((key, a, sn, cs));
                (a, sn, cs)
            }
        }
    }

    /// Sine and cosine of the sinusoid `s`'s phase angle at `t` (as [`PlateEval::series`]
    /// takes them; `s` is the motion evaluated).
    pub(crate) fn sin_cos(&mut self, s: &Sinusoid, t: Instant) -> (f64, f64) {
        let (_, sn, cs) = self.trig(s, t);
        (sn, cs)
    }

    /// A sinusoid's coefficient magnitudes `(V/Ω) Ω^k/k!` (zero for a polynomial piece).
    pub(crate) fn magnitudes(&self) -> &[f64; BUF] {
        &self.mags
    }

    /// [`PlateMotion::series`]; `out` is at most `BUF` long.
    pub(crate) fn series(&mut self, t: Instant, out: &mut [f64]) {
        match self.plate {
            PlateMotion::Sinusoid(s) => {
                let (_, sn, cs) = self.trig(&s, t);
                out.copy_from_slice(&self.mags[..out.len()]);
                scale_by_phase(sn, cs, s.offset, out);
            }
            PlateMotion::Poly(p) => p.series(t, out),
        }
    }

    /// [`PlateMotion::motion`].
    pub(crate) fn motion(&mut self, t: Instant) -> (f64, f64, f64) {
        let mut c = [0.0; 3];
        self.series(t, &mut c);
        (c[0], c[1], 2.0 * c[2])
    }

    /// [`PlateMotion::phase_cycles`].
    pub(crate) fn phase_cycles(&mut self, t: Instant) -> Option<f64> {
        match self.plate {
            PlateMotion::Sinusoid(s) => Some(cycles(self.trig(&s, t).0)),
            PlateMotion::Poly(_) => None,
        }
    }
}

impl From<Sinusoid> for PlateMotion {
    fn from(s: Sinusoid) -> Self {
        PlateMotion::Sinusoid(s)
    }
}

impl From<PolyPiece> for PlateMotion {
    fn from(p: PolyPiece) -> Self {
        PlateMotion::Poly(p)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sinusoid_series_matches_closed_form() {
        let s = Sinusoid::new(1.75, 0.07).unwrap();
        let t = 3.2_f64;
        let mut c = [0.0; 6];
        PlateMotion::from(s).series(Instant::new(t), &mut c);
        let a = 0.07 / 1.75;
        assert!((c[0] - a * (1.75 * t).sin()).abs() < 1e-16);
        assert!((c[1] - 0.07 * (1.75 * t).cos()).abs() < 1e-16);
        assert!((c[2] - (-0.07 * 1.75 * (1.75 * t).sin() / 2.0)).abs() < 1e-16);
        assert!(Sinusoid::new(0.0, 0.1).is_err());
        assert_eq!(Sinusoid::new(1.0, -0.1).unwrap_err().name, "velocity");
    }

    #[test]
    fn phase_stays_exact_at_long_times() {
        // frac(Ωτ/2π) for exactly representable Ω and τ, from 60-digit decimal arithmetic.
        for (omega, tau, expected) in [
            (2.0, 130_000.25, 0.364_781_364_333_247_6),
            (1.75, 125_663.5, 0.942_584_649_681_671_2),
        ] {
            let ph = Sinusoid::new(omega, 0.07)
                .unwrap()
                .phase_cycles(Instant::new(tau));
            let d = (ph - expected).abs();
            assert!(d.min(1.0 - d) < 1e-13, "Ω={omega}: {ph} vs {expected}");
        }
    }

    #[test]
    fn sections_are_at_phase_zero_without_drift() {
        let s = Sinusoid::new(1.75, 0.07).unwrap();
        for k in [1, 17, 36_000, 1_000_000] {
            let ph = s.phase_cycles(s.section(k));
            assert!(ph.min(1.0 - ph) < 1e-15, "k = {k}: {ph}");
        }
        let moved = s.with_origin(Instant::new(3.0), 1.0, 0.0).unwrap();
        let ph = moved.phase_cycles(moved.section(5));
        assert!(ph.min(1.0 - ph) < 1e-15);
        assert!(moved.section(0) < Instant::new(3.0));
    }

    #[test]
    fn continuation_keeps_position_and_phase() {
        let old = PlateMotion::from(Sinusoid::new(1.75, 0.07).unwrap());
        let at = Instant::new(12.345);
        let new = PlateMotion::from(old.continued_by_sinusoid(at, 2.5, 0.1).unwrap());
        assert!((new.motion(at).0 - old.motion(at).0).abs() < 1e-16);
        assert!((new.phase_cycles(at).unwrap() - old.phase_cycles(at).unwrap()).abs() < 1e-15);
        // After the switch it is a sinusoid of the new frequency and amplitude.
        let (z1, zd1, _) = new.motion(at + 0.3);
        let th = new.phase_cycles(at + 0.3).unwrap() * std::f64::consts::TAU;
        assert!((zd1 - 0.1 * th.cos()).abs() < 1e-15);
        assert!((z1 - new.motion(at).0 - 0.1 / 2.5 * (th.sin() - (th - 0.75).sin())).abs() < 1e-15);
        assert!(old.continued_by_sinusoid(at, -1.0, 0.1).is_err());
    }

    #[test]
    fn poly_shift_and_hermite() {
        let p =
            PolyPiece::new(Instant::new(1.0), Instant::new(2.0), &[1.0, 2.0, 3.0, 4.0]).unwrap();
        let mut c = [0.0; 5];
        PlateMotion::from(p).series(Instant::new(1.5), &mut c);
        // z(s) = 1 + 2s + 3s² + 4s³ at s = 0.5 and its derivatives / k!.
        assert!((c[0] - (1.0 + 1.0 + 0.75 + 0.5)).abs() < 1e-15);
        assert!((c[1] - (2.0 + 3.0 + 3.0)).abs() < 1e-15);
        assert!((c[2] - (3.0 + 6.0)).abs() < 1e-15);
        assert!((c[3] - 4.0).abs() < 1e-15);
        assert_eq!(c[4], 0.0);
        let h = PolyPiece::hermite(
            Instant::new(0.0),
            Instant::new(2.0),
            (1.0, -1.0),
            (3.0, 0.5),
        )
        .unwrap();
        let m = PlateMotion::from(h).motion(Instant::new(2.0));
        assert!((m.0 - 3.0).abs() < 1e-14 && (m.1 - 0.5).abs() < 1e-14);
        assert!(PolyPiece::new(Instant::new(1.0), Instant::new(1.0), &[0.0]).is_err());
        assert!(PolyPiece::new(Instant::new(0.0), Instant::new(1.0), &[f64::NAN]).is_err());
    }
}
