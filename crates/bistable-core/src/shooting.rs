//! Periodic orbits by shooting on the stroboscopic map, with Floquet stability.
//!
//! The map `P` takes the state `(x, x')` at plate phase 0 to the state `p` shaker periods later.
//! Newton's method solves `P(y) = y` with the Jacobian `M − I`, where the monodromy matrix `M` comes
//! from the variational equations integrated along the orbit (saltation matrices at impacts). The
//! Floquet multipliers are the eigenvalues of `M`; for an orbit with `n` impacts and no sticking,
//! `det M = e^(2n)·exp(−2ζ·pT)` (model.md Sec. 4), which is reported as a consistency check.

use std::fmt;

use crate::events::Event;
use crate::params::{check, ParamError, Params, SolverOptions};
use crate::shaker::Sinusoid;
use crate::simulator::{SimError, Simulator};

/// Newton settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShootOptions {
    /// Iteration limit.
    pub max_iterations: u32,
    /// Convergence: `|P(y) − y| ≤ tol·max(1, |y|)`.
    pub tol: f64,
    /// Samples per shaker period used to find the largest displacement on the orbit.
    pub samples_per_period: u32,
}

impl Default for ShootOptions {
    fn default() -> Self {
        Self {
            max_iterations: 40,
            tol: 1e-11,
            samples_per_period: 256,
        }
    }
}

/// A periodic orbit of the stroboscopic map.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PeriodicOrbit {
    /// `Ω`.
    pub omega: f64,
    /// `V`.
    pub velocity: f64,
    /// Period in shaker periods.
    pub periods: u32,
    /// Position at plate phase 0.
    pub x0: f64,
    /// Velocity at plate phase 0.
    pub v0: f64,
    /// Monodromy matrix, row-major over `(x, x')`.
    pub monodromy: [[f64; 2]; 2],
    /// Floquet multipliers as `(re, im)`, largest modulus first.
    pub multipliers: [(f64, f64); 2],
    /// All multipliers strictly inside the unit circle.
    pub stable: bool,
    /// Impacts per orbit.
    pub impacts: u64,
    /// Whether the mass sticks on the orbit (then `M = 0`).
    pub sticks: bool,
    /// Barrier crossings per orbit (> 0: the orbit itself is interwell).
    pub snap_throughs: u64,
    /// Largest displacement on the orbit (sampled).
    pub max_x: f64,
    /// Newton iterations used.
    pub iterations: u32,
    /// Final `|P(y) − y|`.
    pub residual: f64,
    /// `e^(2·impacts)·exp(−2ζ·pT)`, which `det M` must equal when the orbit does not stick.
    pub det_identity: f64,
}

/// Why shooting failed.
#[derive(Debug, Clone, PartialEq)]
pub enum ShootError {
    /// A simulation failed.
    Sim(SimError),
    /// Newton did not converge.
    NoConvergence {
        /// Iterations done.
        iterations: u32,
        /// Residual reached.
        residual: f64,
    },
    /// `M − I` is singular (a multiplier at 1: a fold).
    Singular,
}

impl fmt::Display for ShootError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ShootError::Sim(e) => e.fmt(f),
            ShootError::NoConvergence {
                iterations,
                residual,
            } => write!(
                f,
                "Newton did not converge in {iterations} iterations (residual {residual:e})"
            ),
            ShootError::Singular => write!(f, "M − I is singular (a Floquet multiplier at 1)"),
        }
    }
}

impl std::error::Error for ShootError {}

impl From<SimError> for ShootError {
    fn from(e: SimError) -> Self {
        ShootError::Sim(e)
    }
}

impl From<ParamError> for ShootError {
    fn from(e: ParamError) -> Self {
        ShootError::Sim(SimError::Param(e))
    }
}

/// One application of the `p`-period map from `(x0, v0)` at phase 0, with its Jacobian.
struct MapResult {
    y: [f64; 2],
    m: [[f64; 2]; 2],
    impacts: u64,
    sticks: bool,
    snaps: u64,
}

fn period_map(
    params: Params,
    plate: Sinusoid,
    opts: SolverOptions,
    periods: u32,
    y0: [f64; 2],
    samples: u32,
    max_x: Option<&mut f64>,
) -> Result<MapResult, SimError> {
    // Below the plate (which is at 0 at phase 0) is not a state: start on it instead.
    let x0 = y0[0].max(0.0);
    let mut sim = Simulator::with_state(params, plate.into(), opts, 0.0, x0, y0[1])?;
    sim.enable_variational();
    let t_end = f64::from(periods) * plate.period();
    let mut sticks = false;
    let mut on_event = |e: &Event| sticks |= matches!(e, Event::StickStart { .. });
    match max_x {
        Some(mx) => {
            let n = samples * periods;
            for k in 1..=n {
                sim.advance_to(t_end * f64::from(k) / f64::from(n), &mut on_event)?;
                *mx = mx.max(sim.state().x);
            }
        }
        None => sim.advance_to(t_end, &mut on_event)?,
    }
    let st = sim.state();
    let stats = sim.stats();
    Ok(MapResult {
        y: [st.x, st.v],
        m: sim.variational().unwrap_or([[0.0; 2]; 2]),
        impacts: stats.impacts,
        sticks,
        snaps: stats.snap_throughs,
    })
}

/// Eigenvalues of a 2×2 matrix as `(re, im)`, largest modulus first.
pub fn eigenvalues(m: [[f64; 2]; 2]) -> [(f64, f64); 2] {
    let tr = m[0][0] + m[1][1];
    let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
    let disc = 0.25 * tr * tr - det;
    if disc >= 0.0 {
        let r = disc.sqrt();
        // Avoid cancellation: the larger root directly, the other from the product.
        let big = 0.5 * tr + r.copysign(tr);
        let small = if big != 0.0 { det / big } else { 0.0 };
        if big.abs() >= small.abs() {
            [(big, 0.0), (small, 0.0)]
        } else {
            [(small, 0.0), (big, 0.0)]
        }
    } else {
        let im = (-disc).sqrt();
        [(0.5 * tr, im), (0.5 * tr, -im)]
    }
}

/// Finds the `periods`-periodic orbit near `guess = (x, x')` at plate phase 0.
pub fn shoot(
    params: Params,
    plate: Sinusoid,
    opts: SolverOptions,
    periods: u32,
    guess: (f64, f64),
    so: ShootOptions,
) -> Result<PeriodicOrbit, ShootError> {
    check("periods", f64::from(periods), periods >= 1, "must be >= 1")?;
    check("guess_x", guess.0, true, "must be finite")?;
    check("guess_v", guess.1, true, "must be finite")?;
    let mut y = [guess.0.max(0.0), guess.1];
    let mut residual = f64::INFINITY;
    for it in 1..=so.max_iterations {
        let r = period_map(params, plate, opts, periods, y, 0, None)?;
        let g = [r.y[0] - y[0], r.y[1] - y[1]];
        residual = g[0].hypot(g[1]);
        let scale = y[0].hypot(y[1]).max(1.0);
        if residual <= so.tol * scale {
            return Ok(finish(params, plate, opts, periods, y, it, residual, so)?);
        }
        // Solve (M − I) δ = −g.
        let a = [[r.m[0][0] - 1.0, r.m[0][1]], [r.m[1][0], r.m[1][1] - 1.0]];
        let det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
        if det == 0.0 || !det.is_finite() {
            return Err(ShootError::Singular);
        }
        let dx = (-g[0] * a[1][1] + g[1] * a[0][1]) / det;
        let dv = (-g[1] * a[0][0] + g[0] * a[1][0]) / det;
        // Damped step: never more than 0.2 in position at once, never below the plate.
        let damp = (0.2 / dx.abs().max(1e-300)).min(1.0);
        y = [(y[0] + damp * dx).max(0.0), y[1] + damp * dv];
        if !(y[0].is_finite() && y[1].is_finite()) {
            break;
        }
    }
    Err(ShootError::NoConvergence {
        iterations: so.max_iterations,
        residual,
    })
}

#[allow(clippy::too_many_arguments)]
fn finish(
    params: Params,
    plate: Sinusoid,
    opts: SolverOptions,
    periods: u32,
    y: [f64; 2],
    iterations: u32,
    residual: f64,
    so: ShootOptions,
) -> Result<PeriodicOrbit, SimError> {
    let mut max_x = y[0];
    let r = period_map(
        params,
        plate,
        opts,
        periods,
        y,
        so.samples_per_period.max(1),
        Some(&mut max_x),
    )?;
    let multipliers = eigenvalues(r.m);
    let modulus = |(re, im): (f64, f64)| re.hypot(im);
    let t = f64::from(periods) * plate.period();
    Ok(PeriodicOrbit {
        omega: plate.omega(),
        velocity: plate.velocity(),
        periods,
        x0: y[0],
        v0: y[1],
        monodromy: r.m,
        multipliers,
        stable: modulus(multipliers[0]) < 1.0,
        impacts: r.impacts,
        sticks: r.sticks,
        snap_throughs: r.snaps,
        max_x,
        iterations,
        residual,
        det_identity: params.restitution().powi(2 * r.impacts as i32)
            * (-2.0 * params.zeta() * t).exp(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eigenvalues_of_known_matrices() {
        let e = eigenvalues([[2.0, 0.0], [0.0, 0.5]]);
        assert_eq!(e, [(2.0, 0.0), (0.5, 0.0)]);
        // Rotation by 90° scaled by 0.5: ±0.5i.
        let e = eigenvalues([[0.0, -0.5], [0.5, 0.0]]);
        assert_eq!(e, [(0.0, 0.5), (0.0, -0.5)]);
        let e = eigenvalues([[-3.0, 1.0], [0.0, 0.1]]);
        assert!((e[0].0 + 3.0).abs() < 1e-15 && (e[1].0 - 0.1).abs() < 1e-15);
    }
}
