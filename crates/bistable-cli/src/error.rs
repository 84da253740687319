//! Errors of the command-line program and their exit codes.

use std::fmt;
use std::num::NonZeroU32;
use std::path::{Path, PathBuf};

use bistable_core::{ParamError, SimError};

/// Everything that can make a subcommand fail. Each variant prints as one line.
#[derive(Debug)]
pub enum CliError {
    /// An option value outside its allowed range (exit code 2, like clap's own usage errors).
    InvalidValue {
        /// The option as typed, e.g. `--restitution`.
        option: String,
        /// The rejected value, as given.
        value: String,
        /// The allowed range, e.g. "must be finite and in [0, 1]".
        rule: String,
    },
    /// A file could not be created or written (exit code 1).
    Io {
        /// What was being done, e.g. "cannot write".
        action: &'static str,
        /// The file.
        path: PathBuf,
        /// The system's reason.
        source: std::io::Error,
    },
    /// A plot could not be drawn (exit code 1).
    Plot {
        /// The file.
        path: PathBuf,
        /// The reason.
        message: String,
    },
    /// The simulator stopped with an error (exit code 1).
    Sim(SimError),
    /// Part of the work failed (exit code 1); the message says what.
    Failed(String),
}

impl CliError {
    /// An option value outside its range.
    pub fn invalid(option: &str, value: f64, rule: impl Into<String>) -> Self {
        Self::invalid_text(option, crate::output::num(value), rule)
    }

    /// An option value outside its range, with the value as text.
    pub fn invalid_text(option: &str, value: impl fmt::Display, rule: impl Into<String>) -> Self {
        CliError::InvalidValue {
            option: option.to_string(),
            value: value.to_string(),
            rule: rule.into(),
        }
    }

    /// `Ok` when the count given for `option` is at least `min`, else the error naming both.
    pub fn at_least<T: PartialOrd + fmt::Display>(
        option: &str,
        value: T,
        min: T,
    ) -> Result<(), Self> {
        if value >= min {
            Ok(())
        } else {
            Err(Self::invalid_text(
                option,
                value,
                format!("must be >= {min}"),
            ))
        }
    }

    /// The count given for `option` when it is at least `min` (>= 1), else the error naming
    /// both.
    pub fn count(option: &str, value: u32, min: u32) -> Result<NonZeroU32, Self> {
        NonZeroU32::new(value)
            .filter(|v| v.get() >= min)
            .ok_or_else(|| Self::invalid_text(option, value, format!("must be >= {min}")))
    }

    /// An I/O error on `path`.
    pub fn io(action: &'static str, path: &Path, source: std::io::Error) -> Self {
        CliError::Io {
            action,
            path: path.to_path_buf(),
            source,
        }
    }

    /// Process exit code: 2 for bad option values, 1 for everything else.
    pub fn exit_code(&self) -> u8 {
        match self {
            CliError::InvalidValue { .. } => 2,
            _ => 1,
        }
    }
}

impl fmt::Display for CliError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CliError::InvalidValue {
                option,
                value,
                rule,
            } => write!(f, "invalid value '{value}' for '{option}': {rule}"),
            CliError::Io {
                action,
                path,
                source,
            } => write!(f, "{action} '{}': {source}", path.display()),
            CliError::Plot { path, message } => {
                write!(f, "cannot draw '{}': {message}", path.display())
            }
            CliError::Sim(e) => write!(f, "simulation failed: {e}"),
            CliError::Failed(message) => f.write_str(message),
        }
    }
}

impl std::error::Error for CliError {}

impl From<SimError> for CliError {
    fn from(e: SimError) -> Self {
        match e {
            SimError::Param(p) => p.into(),
            other => CliError::Sim(other),
        }
    }
}

impl From<ParamError> for CliError {
    /// Maps the core's parameter names to the options that set them.
    fn from(e: ParamError) -> Self {
        let option = match e.name {
            "omega" => "--omega",
            "velocity" => "--velocity",
            "zeta" => "--zeta",
            "restitution" => "--restitution",
            "tol" => "--tol",
            "max_periods" => "--max-periods",
            "max_period" => "--max-period",
            "period_tol" => "--period-tol",
            "lyapunov_periods" => "--lyapunov-periods",
            "repeats" => "--repeats",
            "efoldings" => "--efoldings",
            "perturbation" => "--perturbation",
            "horizon" => "--horizon",
            "repeat_periods" => "--repeat-periods",
            "lyapunov_windows" => "--lyapunov-windows",
            "recurrence_hits" => "--recurrence-hits",
            "aperiodic_hits" => "--aperiodic-hits",
            other => return CliError::invalid(other, e.value, e.rule),
        };
        CliError::invalid(option, e.value, e.rule)
    }
}
