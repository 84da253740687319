//! `bistable`: command-line front end of the bistable impact oscillator.
//!
//! Layout (so that more subcommands can be added as their own modules):
//! - `main.rs`: the clap top level, one enum variant per subcommand, error reporting and exit codes;
//! - `common.rs`: the options every subcommand shares ([`common::CommonArgs`], flattened into each
//!   subcommand's arguments) and the validated model built from them;
//! - `error.rs`: [`error::CliError`] and its exit codes;
//! - `output.rs`: number formatting, CSV writers, JSON printing;
//! - `progress.rs`: a progress bar on stderr for long runs;
//! - `plot.rs`: PNG figures;
//! - `simulate.rs`: `bistable simulate`.
//!
//! To add a subcommand: write `foo.rs` with a `#[derive(clap::Args)] pub struct FooArgs` that has
//! `#[command(flatten)] pub common: CommonArgs` and a `pub fn run(args: &FooArgs) ->
//! Result<(), CliError>`, then add a variant to [`Command`] and a line to [`main`].

mod common;
mod error;
mod output;
mod plot;
mod progress;
mod simulate;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

const AFTER_HELP: &str = "\
Units: everything is nondimensional as in the paper (doi 10.1007/s11071-022-07793-w): time τ = ω0·t \
(one linear natural period is 2π), lengths in units of the well distance Δx (wells at x = 0 and \
x = 1, barrier at x = 1/2), velocities in units of ω0·Δx, energies in units of k0·Δx². Phases are \
in shaker cycles, in [0, 1).

Exit codes: 0 success; 2 invalid or missing options or option values; 1 a file could not be \
written or the simulation failed.";

/// Simulate and analyse a bistable oscillator driven only by impacts with a sinusoidally vibrating
/// shaker plate.
#[derive(Debug, Parser)]
#[command(name = "bistable", version, after_help = AFTER_HELP, propagate_version = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Simulate from the paper's initial condition; write impacts, sticking intervals,
    /// snap-throughs, a sampled trace and plots.
    #[command(
        long_about = simulate::LONG_ABOUT,
        after_help = simulate::AFTER_SHORT_HELP,
        after_long_help = simulate::AFTER_LONG_HELP
    )]
    Simulate(simulate::SimulateArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match &cli.command {
        Command::Simulate(args) => simulate::run(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(e.exit_code())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    #[test]
    fn clap_definition_is_consistent() {
        Cli::command().debug_assert();
    }
}
