//! `bistable thresholds`: the three velocity thresholds of the paper's Eq. 16–18.

use clap::Args;
use serde::Serialize;

use bistable_analysis::thresholds::{check_restitution, interwell, quasi_static, single_impact};

use crate::error::CliError;
use crate::output::{print_json, print_text};

/// Long description shown by `bistable thresholds --help`.
pub const LONG_ABOUT: &str = "\
The shaker velocity thresholds of the paper's Eq. 16–18 for a coefficient of
restitution e (nondimensional V = V̂/(ω0·Δx)):

  single impact   V = 1/(4(1+e))       the first impact alone, x' = (1+e)V,
                                       gives the barrier energy U(1/2) = 1/32
                                       (damping neglected): above it the mass
                                       escapes to well 2 at once
  interwell       V = (1−e)/(2(1+e))   below it only intrawell motion is
                                       possible
  quasi-static    V = Ω/2              the plate displacement amplitude V/Ω
                                       reaches the barrier x = 1/2

With --omega the quasi-static threshold is also given as a number.";

/// Options of `bistable thresholds`.
#[derive(Debug, Clone, Args)]
pub struct ThresholdsArgs {
    /// Coefficient of restitution e, in [0, 1).
    #[arg(
        long,
        value_name = "E",
        default_value_t = 0.85,
        allow_negative_numbers = true
    )]
    pub restitution: f64,

    /// Shaker frequency ratio Ω (> 0), to evaluate the quasi-static threshold V = Ω/2.
    #[arg(long, value_name = "OMEGA", allow_negative_numbers = true)]
    pub omega: Option<f64>,

    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
}

/// The thresholds for one `e`, as printed.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
struct Thresholds {
    /// `e`.
    restitution: f64,
    /// `V = 1/(4(1+e))` (Eq. 16).
    single_impact: f64,
    /// `V = (1−e)/(2(1+e))` (Eq. 17).
    interwell: f64,
    /// `Ω` if given.
    omega: Option<f64>,
    /// `V = Ω/2` (Eq. 18) at `omega`.
    quasi_static: Option<f64>,
}

impl Thresholds {
    /// The thresholds for restitution `e` (and the quasi-static one at `omega`).
    fn new(e: f64, omega: Option<f64>) -> Self {
        Self {
            restitution: e,
            single_impact: single_impact(e),
            interwell: interwell(e),
            omega,
            quasi_static: omega.map(quasi_static),
        }
    }
}

/// Runs `bistable thresholds`.
pub fn run(args: &ThresholdsArgs) -> Result<(), CliError> {
    let e = check_restitution(args.restitution)?;
    if let Some(w) = args.omega {
        if !(w.is_finite() && w > 0.0) {
            return Err(CliError::invalid("--omega", w, "must be finite and > 0"));
        }
    }
    let t = Thresholds::new(e, args.omega);
    if args.json {
        return print_json(&t);
    }
    let mut text = format!(
        "Thresholds of Eq. 16–18 for e = {e} (V in units of ω0·Δx):\n\
         single impact   V = 1/(4(1+e))     = {:.6}   (the first impact alone clears the \
         barrier)\n\
         interwell       V = (1−e)/(2(1+e)) = {:.6}   (below: intrawell motion only)\n",
        t.single_impact, t.interwell
    );
    match (t.omega, t.quasi_static) {
        (Some(w), Some(v)) => text.push_str(&format!(
            "quasi-static    V = Ω/2            = {v:.6}   at Ω = {w} (plate amplitude V/Ω \
             reaches x = 1/2)\n"
        )),
        _ => text.push_str(
            "quasi-static    V = Ω/2                       (plate amplitude V/Ω reaches x = \
             1/2; give --omega for a number)\n",
        ),
    }
    print_text(&text)
}
