//! The plate: what moves it ([`ShakerMode`]), the clock range of a sinusoid, and the pieces
//! built from the inputs in external mode (input derivatives, or sampled inputs rebuilt as
//! [`Reconstruction`] says; the Hermite reconstruction itself is `bistable_core::sampled`).

use bistable_core::sampled::{taylor_piece, TaylorPieceError};
use bistable_core::{Instant, PolyPiece};

use super::outputs::fly_limit;
use super::si::{describe_param, Scale};
use crate::md::var;
use crate::num::Num;

/// Highest plate derivative that an external piece carries (degree of `PolyPiece`).
pub const MAX_PLATE_ORDER: usize = bistable_core::shaker::MAX_POLY_DEGREE;

/// Largest span `Ω·|τ − τ_origin|` (shaker radians; time units when `Ω < 1`) from the origin
/// of a sinusoid: the core keeps the shaker phase accurate below 2^52 (`Instant::angle`), and a
/// step costs time in proportion to the periods it spans, so a request beyond this (e.g.
/// `h = 1e20` s) could never finish.
pub(crate) const MAX_CLOCK_SPAN: f64 = 4_503_599_627_370_496.0;

/// Whether a sinusoid of frequency `omega` with origin `origin` is within the clock range at
/// `now` (and the origin not after it).
pub(crate) fn origin_in_range(omega: f64, origin: Instant, now: Instant) -> bool {
    origin <= now && omega.max(1.0) * now.since(origin) < MAX_CLOCK_SPAN
}

/// What moves the plate (`shaker_mode`, an Enumeration in the model description).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ShakerMode {
    /// `ż = V cos(Ωτ)` from the parameters.
    Internal = 1,
    /// From the inputs `z_in`, `zdot_in` and their derivatives.
    External = 2,
}

impl ShakerMode {
    /// From the variable's value (range-checked at the boundary).
    pub fn of(value: f64) -> Option<Self> {
        match value {
            1.0 => Some(Self::Internal),
            2.0 => Some(Self::External),
            _ => None,
        }
    }
}

/// How the plate is rebuilt from sampled inputs in external mode (`plate_reconstruction`, an
/// Enumeration in the model description). Input derivatives, when given for a step, take
/// precedence over both.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reconstruction {
    /// `z_in + zdot_in·s`, the position mismatch blended out over the step (first order: the
    /// plate velocity is a staircase and its acceleration is wrong by `O(1)`).
    Taylor = 1,
    /// Quintic Hermite extrapolation through the last three samples (`bistable_core::sampled`).
    Hermite = 2,
}

impl Reconstruction {
    /// From the variable's value (range-checked at the boundary).
    pub fn of(value: f64) -> Option<Self> {
        match value {
            1.0 => Some(Self::Taylor),
            2.0 => Some(Self::Hermite),
            _ => None,
        }
    }
}

/// Plate derivatives for the next step (SI, order 0..=5); `None`: not given (zero above order 1).
pub type PlateInputs = [Option<f64>; MAX_PLATE_ORDER + 1];

/// The plate derivatives from the inputs: `z_in`, `zdot_in`, then the higher ones given with
/// `fmi2SetRealInputDerivatives` (`derivatives`, orders 2..=5).
pub(crate) fn plate_inputs(values: &[f64], derivatives: &PlateInputs) -> PlateInputs {
    let mut p = *derivatives;
    p[0] = Some(values[var::z_in]);
    p[1] = Some(values[var::zdot_in]);
    p
}

/// Whether `plate_reconstruction` rebuilds sampled inputs by the Hermite scheme. The core keeps
/// a free flight across the plate pieces of an external-mode step (`Simulator::keep_flight`)
/// only for such pieces, in steps without input derivatives; pieces from input derivatives or
/// the first-order scheme restart the integration at each piece as before (the first-order
/// scheme's plate acceleration is wrong by O(1), which makes its trajectory depend on every
/// rounding: it is kept as it behaved).
pub(crate) fn is_hermite(values: &[f64]) -> bool {
    Reconstruction::of(values[var::plate_reconstruction]) == Some(Reconstruction::Hermite)
}

/// The plate over `[start, end]` (τ) from the inputs (SI derivatives, `canInterpolateInputs`):
/// their nondimensional Taylor polynomial at the step start, blended from the plate position
/// `z_now` by [`taylor_piece`] (`None`: the plate starts at `z_in`, initialization).
pub(crate) fn plate_piece(
    scale: &Scale,
    start: Instant,
    end: f64,
    inputs: &PlateInputs,
    z_now: Option<f64>,
) -> Result<PolyPiece, String> {
    let mut c = [0.0; MAX_PLATE_ORDER + 1];
    for (k, (ck, d)) in c.iter_mut().zip(inputs).enumerate() {
        *ck = scale.plate_coefficient(k, d.unwrap_or(0.0));
    }
    taylor_piece(start, end, c, z_now).map_err(|e| match e {
        TaylorPieceError::Empty => format!(
            "the step must end after t = {} s",
            scale.time(start.to_f64())
        ),
        TaylorPieceError::NotFinite(k) => format!(
            "the plate polynomial from the inputs is not finite (coefficient of order {k}); inputs z_in, zdot_in and their derivatives must be finite and moderate"
        ),
        TaylorPieceError::Piece(e) => describe_param(&e),
    })
}

/// `piece` if its position, velocity and acceleration stay below what makes an output overflow
/// (`fly_limit`). The plate at the start time must: its outputs are read in initialization
/// mode, before any step could fail on them (a step's plate is checked by the step itself,
/// which ends with `fmi2Discard` where the state stops being finite).
pub(crate) fn moderate(piece: PolyPiece, scale: &Scale) -> Result<PolyPiece, String> {
    let limit = fly_limit(scale);
    if piece.bounds().iter().all(|&b| b <= limit) {
        return Ok(piece);
    }
    Err(format!(
        "the plate polynomial from the inputs at t = {} s is too large (its position, velocity or acceleration could exceed {} in units of delta_x and omega0); inputs z_in, zdot_in and their derivatives must be moderate",
        scale.time(piece.start().to_f64()),
        Num(limit)
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use bistable_core::PlateMotion;

    #[test]
    fn plate_blend_starts_at_the_plate_and_ends_on_the_inputs() {
        let scale = Scale {
            omega0: 2.0,
            dx: 0.5,
            mass: 1.0,
        };
        let inputs = [Some(0.1), Some(0.2), Some(-0.4), None, None, None];
        let start = Instant::new(1.0);
        let piece = plate_piece(&scale, start, 1.5, &inputs, Some(0.25)).unwrap();
        let p = PlateMotion::from(piece);
        // Starts where the plate was (nondimensional 0.25), with the input velocity.
        let (z0, zd0, _) = p.motion(start);
        assert!((z0 - 0.25).abs() < 1e-15);
        assert!((zd0 - 0.2 / (0.5 * 2.0)).abs() < 1e-15);
        // Ends on the inputs' Taylor polynomial: z = (0.1 + 0.2 s − 0.2 s²)/Δx, s = 0.25 s.
        let s = 0.25;
        let (z1, _, _) = p.motion(Instant::new(1.5));
        assert!(
            (z1 - (0.1 + 0.2 * s - 0.2 * s * s) / 0.5).abs() < 1e-14,
            "{z1}"
        );
        // Without a plate position (initialization) it starts on the inputs.
        let first = plate_piece(&scale, start, 1.5, &inputs, None).unwrap();
        assert!((PlateMotion::from(first).motion(start).0 - 0.2).abs() < 1e-15);
        assert!(plate_piece(&scale, start, 0.5, &inputs, None).is_err());
    }

    #[test]
    fn a_start_plate_that_would_overflow_the_outputs_is_refused() {
        let scale = Scale {
            omega0: 1.0,
            dx: 0.5,
            mass: 1.0,
        };
        let start = Instant::new(0.0);
        // A finite acceleration input of 1e300 m/s² (the fuzzer's): z'' = 2e300 in units of Δx.
        let huge = [Some(0.0), Some(0.0), Some(1e300), None, None, None];
        let e = moderate(
            plate_piece(&scale, start, 1.0, &huge, None).unwrap(),
            &scale,
        );
        assert!(e.unwrap_err().contains("too large"));
        // Moderate inputs pass, and the bounds hold over the piece.
        let fine = [Some(0.1), Some(0.2), Some(-0.4), Some(3.0), None, None];
        let piece = plate_piece(&scale, start, 1.0, &fine, None).unwrap();
        let piece = moderate(piece, &scale).unwrap();
        let [bz, bv, ba] = piece.bounds();
        let p = PlateMotion::from(piece);
        for k in 0..=100 {
            let (z, v, a) = p.motion(Instant::new(f64::from(k) / 100.0));
            assert!(
                z.abs() <= bz && v.abs() <= bv && a.abs() <= ba,
                "{k}: {z} {v} {a}"
            );
        }
    }
}
