//! Options shared by every subcommand, and the validated model and thread count built from
//! them.

use clap::{Args, ValueEnum};
use serde::Serialize;

use bistable_analysis::{Model, Threads};
use bistable_core::{ChatterRule, Params, Sinusoid, SolverOptions, Width};

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
    /// Shaker frequency ratio Ω = Ω̂/ω0, in [1e-6, 1e6].
    #[arg(long, value_name = "OMEGA", allow_negative_numbers = true)]
    pub omega: f64,

    /// Shaker velocity amplitude V = V̂/(ω0·Δx), in [0, 1e6]; the plate moves as z = (V/Ω)·sin(Ωτ).
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

    /// The validated model at `--omega`, `--velocity`; the error names the offending option and
    /// its range.
    pub fn model(&self) -> Result<Model, CliError> {
        self.model.model(self.omega, self.velocity)
    }
}

impl ModelArgs {
    /// Validates `--omega`, `--velocity` and the model options, in the order they are
    /// documented, so the first bad one is reported.
    pub fn model(&self, omega: f64, velocity: f64) -> Result<Model, CliError> {
        let shaker = Sinusoid::new(omega, velocity)?;
        let params = Params::new(self.zeta, self.restitution)?;
        let opts = SolverOptions::new(self.tol, self.chatter.rule())?;
        Ok(Model::new(params, shaker, opts))
    }
}

/// The number of worker threads: `requested` (validated, the error names `option`) or all
/// cores.
pub fn threads(requested: Option<usize>, option: &str) -> Result<Threads, CliError> {
    match requested {
        Some(n) => Threads::new(n).ok_or_else(|| CliError::invalid_text(option, n, "must be >= 1")),
        None => Ok(Threads::all()),
    }
}

/// The lane width: `requested` lanes per thread (1, 4 or 8; the error names `option`) or
/// [`Width::preferred`].
pub fn lanes(requested: Option<usize>, option: &str) -> Result<Width, CliError> {
    match requested {
        Some(n) => Width::from_lanes(n)
            .ok_or_else(|| CliError::invalid_text(option, n, "must be 1, 4 or 8")),
        None => Ok(Width::preferred()),
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
