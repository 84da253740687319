//! `bistable atlas`: the fold and period-doubling points located on the orbit branches at one
//! V, each continued in (Ω, V) as a two-parameter curve (`bistable_analysis::twoparam`).

use std::path::PathBuf;

use clap::Args;
use serde::Serialize;

use bistable_analysis::bifurcations::{locate, BifurcationPoint, Branch, Kind};
use bistable_analysis::continuation::{continue_orbits, Curves, Method};
use bistable_analysis::twoparam::{continue_point, covers, CurveOptions, CurvePoint};

use crate::common::{lanes, threads, ModelArgs};
use crate::error::CliError;
use crate::output::{print_json, print_text, CsvFile, Field};
use crate::progress::StageBars;
use crate::ranges::{Pair, Range};

/// A located point this close (Euclidean in x, x', Ω, V) to a curve already traced is on it.
const ON_CURVE: f64 = 1e-4;

/// Long description shown by `bistable atlas --help`.
pub const LONG_ABOUT: &str = "\
Two-parameter bifurcation curves. The period-P orbits are continued over
--continue-omega at --velocity (as 'bistable orbit --continue-omega', natural or
with --arclength), the bifurcation points on them are located, and every fold
(a Floquet multiplier at +1) and period doubling (at −1) is continued in (Ω, V):
the shooting system P(x, x'; Ω, V) = (x, x') is extended by det(M − I) = 0 or
det(M + I) = 0 and followed by pseudo-arclength continuation in (x, x', Ω, V)
(Jacobian: M − I exactly, the rest by central differences). A curve ends where
Ω leaves the --continue-omega range, V leaves --velocity-bounds, the impacts per
period change (the condition is not smooth there), the step collapses, or after
--max-points points each way. A located point already on a traced curve (one
that turns in V meets --velocity twice) starts no second curve.";

/// Shown after the options by `bistable atlas --help`.
pub const AFTER_HELP: &str = "\
CSV (--out): one row per curve point,
  curve,kind,period,omega,velocity,x0,v0,multiplier_1_re,multiplier_1_im,
  multiplier_2_re,multiplier_2_im,impacts
(curve: its number in the summary; kind: fold or period_doubling; x0, v0: the
fixed point at plate phase 0; points ordered by the curve, low V end first).
The summary (--json) lists per curve its start (the point located at
--velocity), points, and the Ω and V it spans.

Exit codes: 0 success; 2 invalid options; 1 a simulation failed or a file could
not be written.

Examples:
  bistable atlas --continue-omega 2.05:2.25:41 --velocity 0.07 \\
      --velocity-bounds 0.05,0.09 --out out/pd_curve.csv
  bistable atlas --continue-omega 1.2:1.6:41 --velocity 0.05 --arclength \\
      --velocity-bounds 0.03,0.07 --out out/fold_curve.csv";

/// Options of `bistable atlas`.
#[derive(Debug, Clone, Args)]
pub struct AtlasArgs {
    /// The Ω grid A:B:N the branches are continued over at --velocity; the curves stay
    /// within A..B.
    #[arg(long, value_name = "A:B:N", allow_hyphen_values = true)]
    pub continue_omega: Range,

    /// V of the branches the points are located on (>= 0).
    #[arg(long, value_name = "V", allow_negative_numbers = true)]
    pub velocity: f64,

    /// The curves stay within V = LO..HI (0 <= LO < --velocity < HI).
    #[arg(long, value_name = "LO,HI", allow_hyphen_values = true)]
    pub velocity_bounds: Pair,

    /// Period of the orbits in shaker periods (1..=64).
    #[arg(long, value_name = "P", default_value_t = 1)]
    pub period: u32,

    /// Follow the branches at --velocity through folds (pseudo-arclength; needed for folds).
    #[arg(long)]
    pub arclength: bool,

    /// Largest step along a curve (Euclidean in x, x', Ω, V; > 0).
    #[arg(long, value_name = "DS", default_value_t = 0.005)]
    pub ds: f64,

    /// Most points of a curve each way from its start (>= 1).
    #[arg(long, value_name = "N", default_value_t = 200)]
    pub max_points: usize,

    /// Shaker periods simulated at every Ω for the seeds of the branches.
    #[arg(long, value_name = "N", default_value_t = 2000)]
    pub settle: u32,

    /// Write the curves to FILE.csv.
    #[arg(long, value_name = "FILE.csv")]
    pub out: Option<PathBuf>,

    /// Worker threads [default: all cores].
    #[arg(long, value_name = "N")]
    pub threads: Option<usize>,

    /// Seeding runs each thread advances together in SIMD lanes: 1, 4 or 8 [default: 4].
    #[arg(long, value_name = "N")]
    pub lanes: Option<usize>,

    #[command(flatten)]
    pub model: ModelArgs,
}

#[derive(Debug, Serialize)]
struct CurveSummary {
    curve: usize,
    kind: &'static str,
    period: u32,
    start_omega: f64,
    start_velocity: f64,
    points: usize,
    omega_min: f64,
    omega_max: f64,
    velocity_min: f64,
    velocity_max: f64,
}

#[derive(Debug, Serialize)]
struct Summary {
    velocity: f64,
    omega_range: String,
    period: u32,
    curves: Vec<CurveSummary>,
    files: Vec<PathBuf>,
}

/// Runs `bistable atlas`.
pub fn run(args: &AtlasArgs) -> Result<(), CliError> {
    let range = args
        .continue_omega
        .check("--continue-omega", |w| w > 0.0, "Ω must be > 0")?;
    if !(1..=64).contains(&args.period) {
        return Err(CliError::invalid_text(
            "--period",
            args.period,
            "must be in [1, 64]",
        ));
    }
    let Pair(v_lo, v_hi) = args.velocity_bounds;
    if !(v_lo >= 0.0 && v_lo < args.velocity && args.velocity < v_hi) {
        return Err(CliError::invalid_text(
            "--velocity-bounds",
            format!("{v_lo},{v_hi}"),
            "must satisfy 0 <= LO < --velocity < HI",
        ));
    }
    if !(args.ds.is_finite() && args.ds > 0.0) {
        return Err(CliError::invalid_text(
            "--ds",
            args.ds,
            "must be finite and > 0",
        ));
    }
    if args.max_points < 1 {
        return Err(CliError::invalid_text(
            "--max-points",
            args.max_points,
            "must be >= 1",
        ));
    }
    let threads = threads(args.threads, "--threads")?;
    let width = lanes(args.lanes, "--lanes")?;
    let omegas = range.values();
    let models = omegas
        .iter()
        .map(|&w| args.model.model(w, args.velocity))
        .collect::<Result<Vec<_>, _>>()?;
    let method = if args.arclength {
        Method::Arclength
    } else {
        Method::Natural
    };
    let mut bars = StageBars::new(format!(" at V = {}", args.velocity));
    let p = args.period;
    let curves = continue_orbits(&models, p, args.settle, method, threads, width, &mut |r| {
        bars.report(r)
    })?;
    let on = match &curves {
        Curves::Natural(b) => Branch::from_natural(&models, b),
        Curves::Arclength(t) => Branch::from_traces(&models[0], p, t),
    };
    let starts: Vec<BifurcationPoint> = locate(&on, threads, &mut |r| bars.report(r))?
        .into_iter()
        .filter(|b| matches!(b.kind, Kind::Fold | Kind::PeriodDoubling))
        .collect();
    let (lo, hi) = range.bounds();
    let o = CurveOptions {
        omega_bounds: (lo, hi),
        velocity_bounds: (v_lo, v_hi),
        ds_max: args.ds,
        max_points: args.max_points,
    };
    let mut all: Vec<(BifurcationPoint, Vec<CurvePoint>)> = Vec::new();
    for s in starts {
        // A curve that turns in V meets --velocity again: its second point is on it.
        if all
            .iter()
            .any(|(t, c)| t.kind == s.kind && t.period == s.period && covers(c, &s, ON_CURVE))
        {
            continue;
        }
        let c = continue_point(&models[0], &s, o).map_err(|e| {
            CliError::Failed(format!(
                "cannot continue the {} at Ω = {}: {e}",
                s.kind.name(),
                s.omega
            ))
        })?;
        all.push((s, c));
    }
    let mut files = Vec::new();
    if let Some(path) = &args.out {
        let mut csv = CsvFile::create(
            path,
            "curve,kind,period,omega,velocity,x0,v0,multiplier_1_re,multiplier_1_im,\
             multiplier_2_re,multiplier_2_im,impacts",
        )?;
        for (k, (s, c)) in all.iter().enumerate() {
            for q in c {
                let m = q.multipliers;
                csv.row(&[
                    Field::I(k as u64),
                    Field::S(s.kind.name()),
                    Field::I(u64::from(s.period)),
                    Field::F(q.omega),
                    Field::F(q.velocity),
                    Field::F(q.x0),
                    Field::F(q.v0),
                    Field::F(m[0].0),
                    Field::F(m[0].1),
                    Field::F(m[1].0),
                    Field::F(m[1].1),
                    Field::I(q.impacts),
                ])?;
            }
        }
        files.push(csv.finish()?);
    }
    let fold = |f: fn(f64, f64) -> f64, c: &[CurvePoint], key: fn(&CurvePoint) -> f64| {
        c.iter().map(key).reduce(f).unwrap_or(f64::NAN)
    };
    let summary = Summary {
        velocity: args.velocity,
        omega_range: range.to_string(),
        period: p,
        curves: all
            .iter()
            .enumerate()
            .map(|(k, (s, c))| CurveSummary {
                curve: k,
                kind: s.kind.name(),
                period: s.period,
                start_omega: s.omega,
                start_velocity: s.velocity,
                points: c.len(),
                omega_min: fold(f64::min, c, |q| q.omega),
                omega_max: fold(f64::max, c, |q| q.omega),
                velocity_min: fold(f64::min, c, |q| q.velocity),
                velocity_max: fold(f64::max, c, |q| q.velocity),
            })
            .collect(),
        files,
    };
    if args.model.json {
        return print_json(&summary);
    }
    let mut text = format!(
        "fold and period-doubling curves of P-{p} orbits from V = {} over Ω = {}:\n",
        args.velocity, summary.omega_range
    );
    for c in &summary.curves {
        text.push_str(&format!(
            "  curve {}: {} from Ω = {:.10}: {} points, Ω {:.6}..{:.6}, V {:.6}..{:.6}\n",
            c.curve,
            c.kind,
            c.start_omega,
            c.points,
            c.omega_min,
            c.omega_max,
            c.velocity_min,
            c.velocity_max
        ));
    }
    if summary.curves.is_empty() {
        text.push_str("  no fold or period doubling on the branches\n");
    }
    for f in &summary.files {
        text.push_str(&format!("wrote {}\n", f.display()));
    }
    print_text(&text)
}
