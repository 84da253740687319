//! `bistable_impact_node`: the bistable impact oscillator as a ROS 2 node (see `ros/README.md`).

mod node;

use std::process::ExitCode;

use bistable_impact_node::args::{self, DiscoveryRange, Parsed};
use bistable_impact_node::params::{Change, Settings, SPECS};

fn main() -> ExitCode {
    let argv: Vec<String> = std::env::args().skip(1).collect();
    let domain = std::env::var("ROS_DOMAIN_ID").ok();
    let read = |f: &str| std::fs::read_to_string(f).map_err(|e| e.to_string());
    match args::parse(&argv, domain.as_deref(), read) {
        Ok(Parsed::Help) => {
            print_help();
            ExitCode::SUCCESS
        }
        Ok(Parsed::Run(cfg)) => match environment()
            .map_err(|e| (e, ExitCode::from(2)))
            .and_then(|range| node::run::run(*cfg, range).map_err(|e| (e, ExitCode::FAILURE)))
        {
            Ok(()) => ExitCode::SUCCESS,
            Err((e, code)) => {
                eprintln!("[FATAL] [bistable_impact]: {e}");
                code
            }
        },
        Err(e) => {
            eprintln!("bistable_impact_node: {e}");
            ExitCode::from(2)
        }
    }
}

/// What the environment settles before the node starts (a refusal is exit status 2): the
/// simulator's SIMD path (`BISTABLE_SIMD`) and the discovery range.
fn environment() -> Result<DiscoveryRange, String> {
    bistable_core::simd::check().map_err(|e| e.to_string())?;
    args::discovery_range(
        std::env::var("ROS_AUTOMATIC_DISCOVERY_RANGE")
            .ok()
            .as_deref(),
        std::env::var("ROS_LOCALHOST_ONLY").ok().as_deref(),
    )
}

/// `--help`: the usage, then every parameter with its unit, kind and default.
fn print_help() {
    println!("{}", args::USAGE);
    let d = Settings::default();
    let width = SPECS.iter().map(|s| s.name.len()).max().unwrap_or(0);
    for s in SPECS {
        let kind = match s.change {
            Change::Runtime => "runtime",
            Change::StartUp => "start-up",
        };
        let v = d.get(s.name).map(|v| format!("{v:?}")).unwrap_or_default();
        println!("  {:<width$} {} ({kind}; default {v})", s.name, s.doc);
    }
}
