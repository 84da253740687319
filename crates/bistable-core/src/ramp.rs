//! Set-point changes of the sinusoidal shaker that keep the plate centred: a smooth amplitude
//! ramp at the new frequency, built from quintic [`PolyPiece`]s, that continues the plate's
//! position and velocity and ends on the sinusoid `z = c + (V/Ω) sin(·)` about a fixed centre
//! `c` (nondimensional, as everything in the core).
//!
//! From the plate's position and velocity `(z0, ż0)` at the switch instant `τs` (whatever moved
//! it: a sinusoid, external pieces, an unfinished ramp), the ramp is
//! `z(τ) = c + Im[P(s) e^{iΩs}]`, `s = τ − τs`, with the complex amplitude
//! `P(s) = P0 + (P1 − P0) w(s/T)`: `P0 = ż0/Ω + i (z0 − c)` matches position and velocity at
//! `τs`, `P1 = (V/Ω) P0/|P0|` is the target amplitude with the same phase, and
//! `w(u) = 10u³ − 15u⁴ + 6u⁵` (zero first and second derivatives at both ends). `P` only
//! scales `P0`, so the phase `Ω s + arg P0` runs on at the new frequency while the amplitude
//! goes from `|P0|` to `V/Ω` and the mean position from wherever it was to `c`. After `T` the
//! plate is the target [`Sinusoid`] with position, velocity and acceleration continuous.
//!
//! The plate follows quintic Hermite pieces through `(z, ż, z̈)` of the ramp at
//! [`SetpointRamp::PIECES_PER_PERIOD`] knots per period of the new frequency (they differ
//! from the closed form by about 1e-9 of the amplitude, and are the plate motion: the
//! simulation, the ROS node and their references all use the same pieces). Unlike
//! [`PlateMotion::continued_by_sinusoid`] (position continuous, velocity jumps, centre moves),
//! any sequence of set-points leaves the plate centred on `c`.

use crate::events::{Event, Impact};
use crate::params::{check, ParamError};
use crate::shaker::{PlateMotion, PolyPiece, Sinusoid};
use crate::simulator::{SimError, Simulator};
use crate::time::Instant;

/// A set-point change in progress: the ramp from the plate's motion at [`SetpointRamp::start`]
/// to [`SetpointRamp::target`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SetpointRamp {
    start: Instant,
    /// Ramp length `T`.
    duration: f64,
    /// Number of pieces.
    pieces: u32,
    omega: f64,
    centre: f64,
    /// `P0`, `P1` as (real, imaginary).
    p0: (f64, f64),
    p1: (f64, f64),
    target: Sinusoid,
}

impl SetpointRamp {
    /// Quintic pieces per period `2π/Ω` of the new frequency.
    pub const PIECES_PER_PERIOD: u32 = 32;
    /// Longest ramp accepted [periods of the new frequency].
    pub const MAX_CYCLES: f64 = 1000.0;

    /// The ramp from `from` at `at` to the sinusoid of frequency `omega` (> 0) and velocity
    /// amplitude `velocity` (>= 0) centred on `centre`, over `cycles` periods of the new
    /// frequency (> 0, at most [`Self::MAX_CYCLES`]).
    pub fn new(
        from: &PlateMotion,
        at: Instant,
        centre: f64,
        omega: f64,
        velocity: f64,
        cycles: f64,
    ) -> Result<Self, ParamError> {
        let fresh = Sinusoid::new(omega, velocity)?;
        check("centre", centre, true, "must be finite")?;
        check(
            "ramp_cycles",
            cycles,
            cycles > 0.0 && cycles <= Self::MAX_CYCLES,
            "must be > 0 and at most 1000",
        )?;
        let (z0, zd0, _) = from.motion(at);
        let p0 = (zd0 / omega, z0 - centre);
        check("plate_position", p0.1, true, "must be finite")?;
        check("plate_velocity", p0.0, true, "must be finite")?;
        let phase = p0.1.atan2(p0.0);
        let amplitude = velocity / omega;
        let p1 = (amplitude * phase.cos(), amplitude * phase.sin());
        let duration = cycles * fresh.period();
        check("ramp_duration", duration, duration > 0.0, "must be finite")?;
        Ok(Self {
            start: at,
            duration,
            pieces: (cycles * f64::from(Self::PIECES_PER_PERIOD)).ceil() as u32,
            omega,
            centre,
            p0,
            p1,
            target: fresh.with_origin(at, phase, centre)?,
        })
    }

    /// Starts a ramp on `sim` at its current time from its current plate motion (see
    /// [`Self::new`]); the plate then follows the ramp's first piece. Drive it with
    /// [`Self::follow`].
    pub fn start(
        sim: &mut Simulator,
        centre: f64,
        omega: f64,
        velocity: f64,
        cycles: f64,
    ) -> Result<Self, SimError> {
        let ramp = Self::new(sim.plate(), sim.instant(), centre, omega, velocity, cycles)?;
        sim.set_plate(ramp.plate_at(sim.instant())?)?;
        Ok(ramp)
    }

    /// When `sim` has reached the end of its plate piece, gives it the ramp's motion from
    /// there (the next piece, or the target sinusoid after the last one). Returns whether the
    /// ramp still runs (the plate is a piece of it): advance `sim` to its plate's horizon and
    /// call this again.
    pub fn follow(&self, sim: &mut Simulator) -> Result<bool, SimError> {
        let now = sim.instant();
        if sim.plate().horizon().is_some_and(|h| h <= now) {
            sim.set_plate(self.plate_at(now)?)?;
        }
        Ok(matches!(sim.plate(), PlateMotion::Poly(_)))
    }

    /// Runs `sim` (on this ramp since [`Self::start`]) to the end of the ramp, following its
    /// pieces, and returns the events; impacts on the pieces carry the ramp's phase.
    pub fn events_through(&self, sim: &mut Simulator) -> Result<Vec<Event>, SimError> {
        let mut events = Vec::new();
        while self.follow(sim)? {
            let Some(end) = sim.plate().horizon() else {
                break;
            };
            for mut e in sim.events_until(end.to_f64())? {
                if let Event::Impact(i) = &mut e {
                    i.phase = self.impact_phase(i);
                }
                events.push(e);
            }
        }
        Ok(events)
    }

    /// The instant the ramp started.
    pub fn start_instant(&self) -> Instant {
        self.start
    }

    /// The instant from which the plate is the target sinusoid.
    pub fn end(&self) -> Instant {
        Instant::new(self.knot(self.pieces))
    }

    /// The sinusoid the ramp ends on (defined from the start instant on: its phase is the
    /// ramp's phase throughout).
    pub fn target(&self) -> Sinusoid {
        self.target
    }

    /// Shaker phase in cycles, `[0, 1)`, at `t` (the ramp runs at the target's phase).
    pub fn phase_cycles(&self, t: Instant) -> f64 {
        self.target.phase_cycles(t)
    }

    /// The shaker phase \[cycles\] of an impact: the core's (the plate was a sinusoid) or, for
    /// an impact on the ramp's pieces (the core gives none), the ramp's.
    pub fn impact_phase(&self, i: &Impact) -> Option<f64> {
        let on_ramp = i.t >= self.start.to_f64() && i.t <= self.knot(self.pieces);
        i.phase
            .or_else(|| on_ramp.then(|| self.phase_cycles(Instant::new(i.t))))
    }

    /// Knot `k` as a plain double, so that a simulation advanced to a piece's end (a double)
    /// stands exactly on the next piece's start.
    fn knot(&self, k: u32) -> f64 {
        if k == 0 {
            self.start.to_f64()
        } else {
            self.start.to_f64() + self.duration * f64::from(k) / f64::from(self.pieces)
        }
    }

    fn knot_instant(&self, k: u32) -> Instant {
        if k == 0 {
            self.start
        } else {
            Instant::new(self.knot(k))
        }
    }

    /// The plate motion from `t` on: the ramp piece whose interval contains `t` (ending after
    /// it), or the target sinusoid from the end of the ramp on.
    pub fn plate_at(&self, t: Instant) -> Result<PlateMotion, ParamError> {
        if t >= self.end() {
            return Ok(self.target.into());
        }
        let guess = (t.since(self.start) / self.duration * f64::from(self.pieces)).floor();
        // In 0..pieces (t is before the end); then the piece that ends after t.
        let mut k = guess.clamp(0.0, f64::from(self.pieces - 1)) as u32;
        while k + 1 < self.pieces && self.knot_instant(k + 1) <= t {
            k += 1;
        }
        while k > 0 && self.knot_instant(k) > t {
            k -= 1;
        }
        let (a, b) = (self.knot_instant(k), self.knot_instant(k + 1));
        Ok(quintic(a, b, self.motion(a), self.motion(b))?.into())
    }

    /// `(z, ż, z̈)` of the closed-form ramp at `t` (clamped to the ramp's interval).
    pub fn motion(&self, t: Instant) -> (f64, f64, f64) {
        let s = t.since(self.start).clamp(0.0, self.duration);
        let u = s / self.duration;
        let t1 = self.duration;
        let w = u * u * u * (10.0 + u * (-15.0 + 6.0 * u));
        let dw = 30.0 * u * u * (1.0 - u) * (1.0 - u) / t1;
        let ddw = 60.0 * u * (1.0 - u) * (1.0 - 2.0 * u) / (t1 * t1);
        let d = (self.p1.0 - self.p0.0, self.p1.1 - self.p0.1);
        let p = (self.p0.0 + d.0 * w, self.p0.1 + d.1 * w);
        let om = self.omega;
        let (sin, cos) = (om * s).sin_cos();
        // Im[X e^{iΩs}] for X = (re, im).
        let im = |x: (f64, f64)| x.0 * sin + x.1 * cos;
        // P, P' + iΩP, P'' + 2iΩP' − Ω²P.
        let z = im(p);
        let zd = im((d.0 * dw - om * p.1, d.1 * dw + om * p.0));
        let zdd = im((
            d.0 * ddw - 2.0 * om * d.1 * dw - om * om * p.0,
            d.1 * ddw + 2.0 * om * d.0 * dw - om * om * p.1,
        ));
        (self.centre + z, zd, zdd)
    }
}

/// The quintic through `(z, ż, z̈)` at `a` and at `b`.
fn quintic(
    a: Instant,
    b: Instant,
    (z0, v0, acc0): (f64, f64, f64),
    (z1, v1, acc1): (f64, f64, f64),
) -> Result<PolyPiece, ParamError> {
    let h = b.since(a);
    check("plate_piece_length", h, h > 0.0, "end must be after start")?;
    let c2 = acc0 / 2.0;
    let d0 = z1 - (z0 + h * (v0 + h * c2));
    let d1 = (v1 - (v0 + 2.0 * c2 * h)) * h;
    let d2 = (acc1 - acc0) * h * h;
    let c3 = (10.0 * d0 - 4.0 * d1 + 0.5 * d2) / (h * h * h);
    let c4 = (-15.0 * d0 + 7.0 * d1 - d2) / (h * h * h * h);
    let c5 = (6.0 * d0 - 3.0 * d1 + 0.5 * d2) / (h * h * h * h * h);
    PolyPiece::new(a, b, &[z0, v0, c2, c3, c4, c5])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quintic_matches_both_ends() {
        let (a, b) = (Instant::new(1.0), Instant::new(1.7));
        let p = PlateMotion::from(quintic(a, b, (0.3, -0.2, 0.5), (-0.1, 0.4, -1.5)).unwrap());
        let (ea, eb) = (p.motion(a), p.motion(b));
        for (got, want) in [
            (ea.0, 0.3),
            (ea.1, -0.2),
            (ea.2, 0.5),
            (eb.0, -0.1),
            (eb.1, 0.4),
            (eb.2, -1.5),
        ] {
            assert!((got - want).abs() < 1e-13, "{got} vs {want}");
        }
    }

    #[test]
    fn ramp_derivatives_match_finite_differences() {
        let from = PlateMotion::from(Sinusoid::new(1.75, 0.07).unwrap());
        let r = SetpointRamp::new(&from, Instant::new(3.1), 0.0, 2.5, 0.12, 2.0).unwrap();
        let e = 1e-5;
        for k in 1..40 {
            let t = Instant::new(3.1 + 0.06 * f64::from(k));
            let (zm, vm, _) = r.motion(t + -e);
            let (_, v, a) = r.motion(t);
            let (zp, vp, _) = r.motion(t + e);
            assert!(((zp - zm) / (2.0 * e) - v).abs() < 1e-9, "velocity at {k}");
            assert!(
                ((vp - vm) / (2.0 * e) - a).abs() < 1e-8,
                "acceleration at {k}"
            );
        }
        assert!(SetpointRamp::new(&from, Instant::new(0.0), 0.0, 0.0, 0.1, 2.0).is_err());
        assert!(SetpointRamp::new(&from, Instant::new(0.0), 0.0, 1.0, 0.1, 0.0).is_err());
        assert!(SetpointRamp::new(&from, Instant::new(0.0), f64::NAN, 1.0, 0.1, 1.0).is_err());
    }
}
