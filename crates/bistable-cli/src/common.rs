//! Options shared by every subcommand, and the validated model built from them.

use clap::{Args, ValueEnum};
use serde::Serialize;

use bistable_core::{ChatterRule, Params, Simulator, Sinusoid, SolverOptions};

use crate::error::CliError;

/// How chatter (impacts accumulating in finite time) is turned into sticking.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Chatter {
    /// Predict the accumulation point of the chatter sequence (Budd & Dux 1994) and jump to it
    /// once it is less than 1e-7 time units away (the core's default rule).
    Accumulation,
    /// The paper's rule: sticking starts when two impacts are less than 1e-9 time units apart
    /// and the contact force is non-negative.
    Paper,
}

impl Chatter {
    fn rule(self) -> ChatterRule {
        match self {
            Chatter::Accumulation => SolverOptions::default().chatter(),
            Chatter::Paper => ChatterRule::paper(),
        }
    }
}

/// Damping, restitution, solver and output options shared by every subcommand (flatten into
/// each subcommand's args; [`CommonArgs`] adds the shaker's `--omega` and `--velocity`).
#[derive(Debug, Clone, Args)]
#[command(next_help_heading = "Model and solver options")]
pub struct ModelArgs {
    /// Damping ratio ζ (>= 0).
    #[arg(
        long,
        value_name = "ZETA",
        default_value_t = 0.02,
        allow_negative_numbers = true
    )]
    pub zeta: f64,

    /// Coefficient of restitution e, in [0, 1].
    #[arg(
        long,
        value_name = "E",
        default_value_t = 0.85,
        allow_negative_numbers = true
    )]
    pub restitution: f64,

    /// Local error tolerance of the Taylor integrator, in [1e-18, 1e-3].
    #[arg(
        long,
        value_name = "TOL",
        default_value = "1e-16",
        allow_negative_numbers = true
    )]
    pub tol: f64,

    /// Chatter rule: `accumulation` (predicted accumulation point, default) or `paper` (the
    /// paper's fixed 1e-9 gap between impacts).
    #[arg(long, value_enum, value_name = "RULE", default_value_t = Chatter::Accumulation)]
    pub chatter: Chatter,

    /// Print the result as one JSON object on stdout instead of a human-readable summary.
    #[arg(long)]
    pub json: bool,
}

/// The shaker point `(Ω, V)` and the [`ModelArgs`]: the options of subcommands that work at one
/// point of the parameter plane.
#[derive(Debug, Clone, Args)]
#[command(next_help_heading = "Model and solver options")]
pub struct CommonArgs {
    /// Shaker frequency ratio Ω = Ω̂/ω0 (> 0).
    #[arg(long, value_name = "OMEGA", allow_negative_numbers = true)]
    pub omega: f64,

    /// Shaker velocity amplitude V = V̂/(ω0·Δx) (>= 0); the plate moves as z = (V/Ω)·sin(Ωτ).
    #[arg(long, value_name = "V", allow_negative_numbers = true)]
    pub velocity: f64,

    #[command(flatten)]
    pub model: ModelArgs,
}

impl CommonArgs {
    /// Whether to print JSON.
    pub fn json(&self) -> bool {
        self.model.json
    }
}

/// A validated model: parameters, shaker and solver options.
#[derive(Debug, Clone, Copy)]
pub struct Model {
    /// `ζ` and `e`.
    pub params: Params,
    /// The plate's sinusoid.
    pub shaker: Sinusoid,
    /// Tolerance and chatter rule.
    pub opts: SolverOptions,
    /// The chatter rule as chosen on the command line.
    pub chatter: Chatter,
}

impl Model {
    /// Validates the common options; the error names the offending option and its range.
    pub fn from_args(args: &CommonArgs) -> Result<Self, CliError> {
        Self::new(&args.model, args.omega, args.velocity)
    }

    /// Validates `--omega`, `--velocity` and the model options, in the order they are
    /// documented, so the first bad one is reported.
    pub fn new(args: &ModelArgs, omega: f64, velocity: f64) -> Result<Self, CliError> {
        let shaker = Sinusoid::new(omega, velocity)?;
        let params = Params::new(args.zeta, args.restitution)?;
        let opts = SolverOptions::new(args.tol, args.chatter.rule())?;
        Ok(Self {
            params,
            shaker,
            opts,
            chatter: args.chatter,
        })
    }

    /// The same model at another shaker point `(Ω, V)`.
    pub fn at(&self, omega: f64, velocity: f64) -> Result<Self, CliError> {
        Ok(Self {
            shaker: Sinusoid::new(omega, velocity)?,
            ..*self
        })
    }

    /// A simulator at the paper's initial condition (mass at rest at x = 0, τ = 0).
    pub fn simulator(&self) -> Result<Simulator, CliError> {
        Ok(Simulator::new(self.params, self.shaker.into(), self.opts)?)
    }

    /// `Ω`.
    pub fn omega(&self) -> f64 {
        self.shaker.omega()
    }

    /// `V`.
    pub fn velocity(&self) -> f64 {
        self.shaker.velocity()
    }

    /// `e`.
    pub fn restitution(&self) -> f64 {
        self.params.restitution()
    }

    /// Shaker period `2π/Ω` (time units).
    pub fn shaker_period(&self) -> f64 {
        self.shaker.period()
    }

    /// `ΔK0 = ½((1+e)V)²` (Eq. 11), the energy gain of the first impact.
    pub fn delta_k0(&self) -> f64 {
        let w = (1.0 + self.restitution()) * self.velocity();
        0.5 * w * w
    }

    /// Short description for plot titles: `Ω = 1.75, V = 0.07, ζ = 0.02, e = 0.85`.
    pub fn label(&self) -> String {
        format!(
            "Ω = {}, V = {}, ζ = {}, e = {}",
            self.omega(),
            self.velocity(),
            self.params.zeta(),
            self.restitution()
        )
    }
}

/// Checks a time-like option: finite and > 0.
pub fn positive(option: &str, value: f64) -> Result<f64, CliError> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(CliError::invalid(option, value, "must be finite and > 0"))
    }
}
