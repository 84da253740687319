//! The model at one shaker point: parameters, plate sinusoid and solver options, each validated
//! by its own core type, so every `Model` is a valid one.

use bistable_core::{ParamError, Params, SimError, Simulator, Sinusoid, SolverOptions};

/// The oscillator at one shaker point `(Ω, V)`.
#[derive(Debug, Clone, Copy)]
pub struct Model {
    /// Damping ratio `ζ` and restitution `e`.
    pub params: Params,
    /// The plate's sinusoid `z = (V/Ω)·sin(Ωτ)`.
    pub shaker: Sinusoid,
    /// Integrator tolerance and chatter rule.
    pub opts: SolverOptions,
}

impl Model {
    /// The model with these parts.
    pub fn new(params: Params, shaker: Sinusoid, opts: SolverOptions) -> Self {
        Self {
            params,
            shaker,
            opts,
        }
    }

    /// The same model at another shaker point `(Ω, V)` (`Ω > 0`, `V >= 0`).
    pub fn at(&self, omega: f64, velocity: f64) -> Result<Self, ParamError> {
        Ok(Self {
            shaker: Sinusoid::new(omega, velocity)?,
            ..*self
        })
    }

    /// A simulator at the paper's initial condition (mass at rest at `x = 0`, `τ = 0`).
    pub fn simulator(&self) -> Result<Simulator, SimError> {
        Simulator::new(self.params, self.shaker.into(), self.opts)
    }

    /// A simulator started at `τ = 0` (plate phase 0) from `(x, x')`.
    pub fn simulator_from(&self, x: f64, v: f64) -> Result<Simulator, SimError> {
        Simulator::with_state(self.params, self.shaker.into(), self.opts, 0.0, x, v)
    }

    /// Shaker frequency ratio `Ω`.
    pub fn omega(&self) -> f64 {
        self.shaker.omega()
    }

    /// Shaker velocity amplitude `V` (units of `ω0·Δx`).
    pub fn velocity(&self) -> f64 {
        self.shaker.velocity()
    }

    /// Coefficient of restitution `e`.
    pub fn restitution(&self) -> f64 {
        self.params.restitution()
    }

    /// Shaker period `2π/Ω` (time units).
    pub fn shaker_period(&self) -> f64 {
        self.shaker.period()
    }

    /// `ΔK0 = ½((1+e)V)²` (Eq. 11), the kinetic energy gain of the first impact (units of
    /// `k0·Δx²`).
    pub fn delta_k0(&self) -> f64 {
        let w = (1.0 + self.restitution()) * self.velocity();
        0.5 * w * w
    }
}
