//! `bistable`: command-line front end of the bistable impact oscillator.
//!
//! The numerics live in `bistable-core` (model, integrator) and `bistable-analysis` (sweeps,
//! shooting, continuation, bifurcation data, energy maps, spectra); this crate holds argument
//! handling, files, JSON, progress bars and plots.
//!
//! Layout (so that more subcommands can be added as their own modules):
//! - `main.rs`: the clap top level, one enum variant per subcommand, error reporting and exit codes;
//! - `common.rs`: the options every subcommand shares ([`common::CommonArgs`], flattened into each
//!   subcommand's arguments), the validated model and the thread count built from them;
//! - `error.rs`: [`error::CliError`] and its exit codes;
//! - `output.rs`: number formatting, CSV writers (and the resumable ones' lock), JSON printing;
//! - `grid.rs`: the resumable grid driver of `map` and `basins` (skip the points in `--out`,
//!   compute the others with a progress bar, append their rows as they complete);
//! - `progress.rs`: progress bars on stderr for long runs;
//! - `plot/`: PNG figures: `plot/mod.rs` the helpers every figure uses, `plot/simulate.rs`
//!   `simulate`'s figures (the other commands draw theirs in their own modules);
//! - `ranges.rs`: `A:B:N` parameter ranges;
//! - `simulate.rs`: `bistable simulate`;
//! - `classify.rs`: `bistable classify` (and the classification record `map` writes);
//! - `map.rs`: `bistable map`;
//! - `basins.rs`: `bistable basins`;
//! - `branches.rs`: periodic-orbit branches as CSV rows and curves on a chart;
//! - `bifurcations.rs`: bifurcation points located on the branches as CSV rows, JSON and
//!   markers;
//! - `diagram.rs`: `bistable bifurcation` (the diagram of Fig. 6/8);
//! - `orbit.rs`: `bistable orbit`;
//! - `atlas.rs`: `bistable atlas`;
//! - `thresholds.rs`: `bistable thresholds`;
//! - `energy_map.rs`: `bistable energy-map`;
//! - `spectrum.rs`: `bistable spectrum`.
//!
//! To add a subcommand: write `foo.rs` with a `#[derive(clap::Args)] pub struct FooArgs` that has
//! `#[command(flatten)] pub common: CommonArgs` and a `pub fn run(args: &FooArgs) ->
//! Result<(), CliError>`, then add a variant to [`Command`] and a line to [`main`].

// The arguments' doc comments are their --help texts, where <stem> and <FILE> name placeholders,
// not HTML tags.
#![allow(rustdoc::invalid_html_tags)]

mod atlas;
mod atlas_points;
mod basins;
mod bifurcations;
mod branches;
mod classify;
mod coexistence;
mod common;
mod decision;
mod diagram;
mod energy_map;
mod error;
mod grid;
mod map;
mod orbit;
mod output;
mod plot;
mod progress;
mod ranges;
mod simulate;
mod spectrum;
mod thresholds;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

const AFTER_HELP: &str = "\
Units: everything is nondimensional as in the paper (doi 10.1007/s11071-022-07793-w): time τ = ω0·t \
(one linear natural period is 2π), lengths in units of the well distance Δx (wells at x = 0 and \
x = 1, barrier at x = 1/2), velocities in units of ω0·Δx, energies in units of k0·Δx². Phases are \
in shaker cycles, in [0, 1).

Environment: BISTABLE_SIMD=auto|portable|avx2|avx512 forces the SIMD code path (default auto: \
the widest the CPU has; the results are the same on every path, only the speed differs).

Exit codes: 0 success; 2 invalid or missing options or option values, or a refused BISTABLE_SIMD \
(unknown value, or a path the CPU lacks); 1 a file could not be written or the simulation failed.";

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

    /// Classify the response at (Ω, V): intrawell, transient or continuous interwell, period,
    /// chaos, snap-throughs (JSON).
    #[command(long_about = classify::LONG_ABOUT, after_help = classify::AFTER_HELP)]
    Classify(classify::ClassifyCmdArgs),

    /// Response-class map over an Ω × V grid (Fig. 9): parallel, resumable CSV, PNG with the
    /// thresholds of Eq. 16–18.
    #[command(long_about = map::LONG_ABOUT, after_help = map::AFTER_HELP)]
    Map(map::MapArgs),

    /// Basins of attraction at one (Ω, V): the attractor every start of an (x0, x0') grid
    /// reaches, basin fractions, uncertainty exponent; CSV, PNG.
    #[command(long_about = basins::LONG_ABOUT, after_help = basins::AFTER_HELP)]
    Basins(basins::BasinsArgs),

    /// Which attractors coexist over an Ω × V grid (or along one parameter): basin fractions
    /// from a box of starts, decided by recurrence, matched into branches; CSV, PNG.
    #[command(long_about = coexistence::LONG_ABOUT, after_help = coexistence::AFTER_HELP)]
    Coexistence(coexistence::CoexistenceArgs),

    /// Bifurcation diagram (Fig. 6/8): max x per shaker cycle and impact phases against Ω or
    /// V, with periodic-orbit branches.
    #[command(long_about = diagram::LONG_ABOUT, after_help = diagram::AFTER_HELP)]
    Bifurcation(diagram::BifurcationArgs),

    /// Periodic orbit by shooting: fixed point, Floquet multipliers, stability; continuation
    /// in Ω (Fig. 11a).
    #[command(long_about = orbit::LONG_ABOUT, after_help = orbit::AFTER_HELP)]
    Orbit(orbit::OrbitArgs),

    /// Fold and period-doubling curves in (Ω, V), continued from the points located on the
    /// orbit branches at one V.
    #[command(long_about = atlas::LONG_ABOUT, after_help = atlas::AFTER_HELP)]
    Atlas(atlas::AtlasArgs),

    /// Energy change per impact ΔK/ΔK0 over impact phase and pre-impact velocity (Eq. 13–15),
    /// optionally with a simulation's impacts.
    #[command(long_about = energy_map::LONG_ABOUT, after_help = energy_map::AFTER_HELP)]
    EnergyMap(energy_map::EnergyMapArgs),

    /// Amplitude spectrum of the steady-state x(τ) (Hann window, FFT): lines for periodic,
    /// broadband for chaotic responses.
    #[command(long_about = spectrum::LONG_ABOUT, after_help = spectrum::AFTER_HELP)]
    Spectrum(spectrum::SpectrumArgs),

    /// The velocity thresholds of Eq. 16–18 (single impact, interwell, quasi-static).
    #[command(long_about = thresholds::LONG_ABOUT)]
    Thresholds(thresholds::ThresholdsArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    // A refused BISTABLE_SIMD (unknown value, or a path the CPU lacks) is a bad option.
    if let Err(e) = bistable_core::simd::check() {
        eprintln!("error: {e}");
        return ExitCode::from(2);
    }
    let result = match &cli.command {
        Command::Simulate(args) => simulate::run(args),
        Command::Classify(args) => classify::run(args),
        Command::Map(args) => map::run(args),
        Command::Basins(args) => basins::run(args),
        Command::Coexistence(args) => coexistence::run(args),
        Command::Bifurcation(args) => diagram::run(args),
        Command::Orbit(args) => orbit::run(args),
        Command::Atlas(args) => atlas::run(args),
        Command::Thresholds(args) => thresholds::run(args),
        Command::EnergyMap(args) => energy_map::run(args),
        Command::Spectrum(args) => spectrum::run(args),
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

    #[test]
    fn sensitivity_defaults_are_the_librarys() {
        use bistable_analysis::sensitivity::SensitivityOptions;
        let point = ["--omega", "1", "--velocity", "0.1"];
        let grid = [
            "--omega-range",
            "1:2:2",
            "--velocity-range",
            "0.1:0.2:2",
            "--out",
            "m.csv",
        ];
        for (sub, rest) in [("classify", &point[..]), ("map", &grid[..])] {
            let args = ["bistable", sub].into_iter().chain(rest.iter().copied());
            let so = match Cli::try_parse_from(args).unwrap().command {
                Command::Classify(a) => a.classify.sensitivity(),
                Command::Map(a) => a.classify.sensitivity(),
                _ => unreachable!(),
            };
            assert_eq!(so.unwrap(), SensitivityOptions::default(), "{sub}");
        }
    }
}
