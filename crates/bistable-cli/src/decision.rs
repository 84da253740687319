//! How the starts of `basins` and `coexistence` are decided: by recurrence onto the attractors
//! already found at the point (the default) or each in full.

use clap::Args;

use bistable_analysis::basins::Decision;
use bistable_analysis::recurrence::RecurrenceOptions;

use crate::error::CliError;

/// The decision options, flattened into a command's options.
#[derive(Debug, Clone, Args)]
pub struct DecisionArgs {
    /// Decide every start in full (no recurrence onto known attractors).
    #[arg(long)]
    pub full_decision: bool,

    /// Consecutive section points within the capture radius of a known periodic attractor
    /// that decide a start by recurrence.
    #[arg(long, value_name = "N", default_value_t = RecurrenceOptions::default().hits)]
    pub recurrence_hits: u32,

    /// Consecutive section points in the cells of a known aperiodic (chaotic) attractor that
    /// decide a start by recurrence, unless they close in on a cycle.
    #[arg(long, value_name = "N", default_value_t = RecurrenceOptions::default().aperiodic_hits)]
    pub aperiodic_hits: u32,
}

impl DecisionArgs {
    /// The checked decision, with a first round of `first_round` starts.
    pub fn decision(&self, first_round: usize) -> Result<Decision, CliError> {
        if self.full_decision {
            return Ok(Decision::Full);
        }
        Ok(Decision::Recurrence(
            RecurrenceOptions {
                hits: self.recurrence_hits,
                aperiodic_hits: self.aperiodic_hits,
                first_round,
                ..RecurrenceOptions::default()
            }
            .check()?,
        ))
    }
}
