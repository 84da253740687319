//! `bistable orbit`: a periodic orbit by shooting, with its Floquet multipliers and stability;
//! or (with `--continue-omega`) branches of orbits continued in Ω for several V (Fig. 11a).

use std::path::PathBuf;

use clap::Args;
use plotters::prelude::*;
use serde::Serialize;

use bistable_analysis::bifurcations::{locate, BifurcationPoint, Branch};
use bistable_analysis::continuation::{continue_orbits, Curves, Method};
use bistable_analysis::cycles::settled;
use bistable_analysis::orbit::{shoot, summarise};
use bistable_analysis::Model;

use crate::bifurcations::{self, Multiplier};
use crate::branches;
use crate::common::{lanes, threads, ModelArgs};
use crate::error::CliError;
use crate::output::{print_json, print_text, sibling, CsvFile, Field};
use crate::plot::{self, header, Area, DrawResult, Mark};
use crate::progress::StageBars;
use crate::ranges::{Pair, Range};

/// Long description shown by `bistable orbit --help`.
pub const LONG_ABOUT: &str = "\
Find a periodic orbit by shooting: Newton's method on the map over --period
shaker periods, from plate phase 0 to plate phase 0, with the monodromy matrix M
from the variational equations (saltation matrices at impacts, M = 0 once the
mass sticks). The Floquet multipliers are the eigenvalues of M; the orbit is
stable when all have modulus < 1. Without sticking, det M must equal
e^(2·impacts)·exp(−2ζ·pT) with T = 2π/Ω (a consistency check, reported).

The initial guess is the section point (x, x') at plate phase 0 after --settle
shaker periods of a simulation from the paper's initial condition (for a stable
orbit that is its attractor, and the JSON reports how far the fixed point is
from it), or --guess X,V.

With --continue-omega A:B:N: natural continuation in Ω for each --velocity
(several allowed, comma separated), like the paper's Fig. 11a. At every Ω a
simulation (--settle shaker periods) seeds the orbit of period --period (or, if
the attractor has a multiple of that period, the orbit it doubled from); each
orbit found is continued from point to point in both directions, so unstable
parts are followed past period doublings. Folds end such a branch (natural
continuation cannot turn around); with --arclength the branches are followed
through folds by pseudo-arclength continuation (unknowns x, x', Ω; tangent from
[M − I | ∂P/∂Ω]), which shows the unstable middle branch of a hysteresis loop,
and through grazing points: a step that changes the impacts per period
approaches the grazing point from both sides and goes on along the new side.
--plot draws the largest displacement of the orbits against Ω: stable thick and
solid, unstable thin and dashed.

Bifurcation points: between consecutive orbits of every branch, a change of
sticking is located by bisection, a change of the impacts per period (grazing)
by driving the grazing flight's minimum gap (or the new impact's speed) to zero
at fixed Ω (Ω to 1e-10; bisection where that fails), and a sign
change of det(M − I) (fold), det(M + I) (period doubling) or det M − 1 with a
complex pair (Neimark–Sacker) by regula falsi along the branch, re-solving the
orbit by shooting at each trial (Ω to 1e-12 where the test function is smooth).
They are listed in the summary, drawn as markers (one legend entry per kind) and
written to <stem>_bifurcations.csv beside --out.";

/// Shown after the options by `bistable orbit --help`.
pub const AFTER_HELP: &str = concat!(
    "\
JSON (one orbit): omega, velocity, period, x0, v0 (fixed point at plate phase 0),
multipliers [{re, im, abs}], max_abs_multiplier, stable, floquet_exponent
(ln|λ|max/(pT), per unit of τ), impacts, sticks, snap_throughs, max_x,
cycle_max (largest x in each cycle), iterations, residual, monodromy,
det_monodromy, det_identity, det_relative_error (null when the orbit sticks),
guess, guess_source, distance_to_guess.

CSV (--out, with --continue-omega): one row per orbit, as the _orbits.csv of
'bistable bifurcation'; with --arclength one row per point of each trace:
  velocity,trace,index,omega,x0,v0,max_x,stable,multiplier_1_re,
  multiplier_1_im,multiplier_2_re,multiplier_2_im,abs_multiplier,impacts
The JSON summary gives per V the orbits, the stable ones, the Ω covered, and
with --arclength the traces and their folds (turning points in Ω).

",
    crate::bifurcations::help!(),
    "

Exit codes: 0 success; 2 invalid options; 1 Newton failed, a simulation failed
or a file could not be written.

Examples:
  bistable orbit --omega 1.75 --velocity 0.07
  bistable orbit --omega 2.2 --velocity 0.07 --period 2 --json
  bistable orbit --omega 2.2 --velocity 0.07 --guess 0.05,0.1
  bistable orbit --continue-omega 0.6:3.0:121 --velocity 0.03,0.05,0.07 \\
      --arclength --plot out/orbits.png --out out/orbits.csv
  bistable orbit --continue-omega 2.05:2.25:41 --velocity 0.07 --period 2 \\
      --out out/p2.csv    # and out/p2_bifurcations.csv: the P-2 → P-4 doubling"
);

/// Options of `bistable orbit`.
#[derive(Debug, Clone, Args)]
pub struct OrbitArgs {
    /// Shaker frequency ratio Ω, in [1e-6, 1e6]; not with --continue-omega.
    #[arg(
        long,
        value_name = "OMEGA",
        allow_negative_numbers = true,
        required_unless_present = "continue_omega",
        conflicts_with = "continue_omega"
    )]
    pub omega: Option<f64>,

    /// Shaker velocity amplitude V, in [0, 1e6]; with --continue-omega several, comma separated.
    #[arg(
        long,
        value_name = "V",
        allow_negative_numbers = true,
        value_delimiter = ',',
        required = true
    )]
    pub velocity: Vec<f64>,

    /// Period of the orbit in shaker periods (1..=64).
    #[arg(long, value_name = "P", default_value_t = 1)]
    pub period: u32,

    /// Initial guess x,x' at plate phase 0 instead of the simulated section point.
    #[arg(
        long,
        value_name = "X,V",
        allow_hyphen_values = true,
        conflicts_with = "continue_omega"
    )]
    pub guess: Option<Pair>,

    /// Shaker periods simulated from the paper's initial condition for the guess.
    #[arg(long, value_name = "N", default_value_t = 2000)]
    pub settle: u32,

    /// Continue the orbits over Ω = A:B:N for each --velocity.
    #[arg(
        long,
        value_name = "A:B:N",
        allow_hyphen_values = true,
        help_heading = "Continuation"
    )]
    pub continue_omega: Option<Range>,

    /// Draw the continued branches to FILE.png.
    #[arg(
        long,
        value_name = "FILE.png",
        requires = "continue_omega",
        help_heading = "Continuation"
    )]
    pub plot: Option<PathBuf>,

    /// Write the continued orbits to FILE.csv and the bifurcation points located on them to
    /// <stem>_bifurcations.csv beside it.
    #[arg(
        long,
        value_name = "FILE.csv",
        requires = "continue_omega",
        help_heading = "Continuation"
    )]
    pub out: Option<PathBuf>,

    /// Follow the branches through folds by pseudo-arclength continuation (unknowns x, x', Ω;
    /// ∂P/∂Ω by central differences) instead of natural continuation; the step along the
    /// branch is at most the spacing of --continue-omega.
    #[arg(long, requires = "continue_omega", help_heading = "Continuation")]
    pub arclength: bool,

    /// Worker threads for --continue-omega [default: all cores].
    #[arg(long, value_name = "N", help_heading = "Continuation")]
    pub threads: Option<usize>,

    /// Seeding runs each thread advances together in SIMD lanes for --continue-omega: 1 (one
    /// at a time), 4 (AVX2) or 8 (AVX-512) [default: 4]. The results are the same for every
    /// width.
    #[arg(long, value_name = "N", help_heading = "Continuation")]
    pub lanes: Option<usize>,

    #[command(flatten)]
    pub model: ModelArgs,
}

#[derive(Debug, Serialize)]
struct OrbitReport {
    omega: f64,
    velocity: f64,
    period: u32,
    x0: f64,
    v0: f64,
    multipliers: Vec<Multiplier>,
    max_abs_multiplier: f64,
    stable: bool,
    floquet_exponent: f64,
    impacts: u64,
    sticks: bool,
    snap_throughs: u64,
    max_x: f64,
    cycle_max: Vec<f64>,
    iterations: u32,
    residual: f64,
    monodromy: [[f64; 2]; 2],
    det_monodromy: f64,
    det_identity: f64,
    det_relative_error: Option<f64>,
    guess: (f64, f64),
    guess_source: String,
    distance_to_guess: f64,
}

/// Runs `bistable orbit`.
pub fn run(args: &OrbitArgs) -> Result<(), CliError> {
    if !(1..=64).contains(&args.period) {
        return Err(CliError::invalid_text(
            "--period",
            args.period,
            "must be in [1, 64]",
        ));
    }
    match (args.omega, args.continue_omega) {
        (Some(w), None) => single(args, w),
        (None, Some(r)) => continuation(args, r),
        // clap makes exactly one of them present.
        _ => Err(CliError::invalid_text(
            "--omega",
            "",
            "give --omega or --continue-omega",
        )),
    }
}

fn single(args: &OrbitArgs, omega: f64) -> Result<(), CliError> {
    let [velocity] = args.velocity[..] else {
        return Err(CliError::invalid_text(
            "--velocity",
            args.velocity
                .iter()
                .map(|v| v.to_string())
                .collect::<Vec<_>>()
                .join(","),
            "takes one value without --continue-omega",
        ));
    };
    let model = args.model.model(omega, velocity)?;
    let (guess, source) = match args.guess {
        Some(Pair(x, v)) => ((x, v), "--guess".to_string()),
        None => {
            let st = settled(&model, args.settle)?.state();
            (
                (st.x, st.v),
                format!(
                    "section point after {} shaker periods from the paper's initial condition",
                    args.settle
                ),
            )
        }
    };
    let orbit = shoot(&model, args.period, guess).map_err(|e| {
        CliError::Failed(format!(
            "no {}-periodic orbit found from ({}, {}): {e}",
            args.period, guess.0, guess.1
        ))
    })?;
    let s = summarise(&model, orbit, guess)?;
    let report = OrbitReport {
        omega,
        velocity,
        period: orbit.periods,
        x0: orbit.x0,
        v0: orbit.v0,
        multipliers: orbit.multipliers.iter().map(Multiplier::from).collect(),
        max_abs_multiplier: s.max_abs_multiplier,
        stable: orbit.stable,
        floquet_exponent: s.floquet_exponent,
        impacts: orbit.impacts,
        sticks: orbit.sticks,
        snap_throughs: orbit.snap_throughs,
        max_x: orbit.max_x,
        cycle_max: s.cycle_max,
        iterations: orbit.iterations,
        residual: orbit.residual,
        monodromy: orbit.monodromy,
        det_monodromy: s.det_monodromy,
        det_identity: orbit.det_identity,
        det_relative_error: s.det_relative_error,
        guess,
        guess_source: source,
        distance_to_guess: s.distance_to_guess,
    };
    if args.model.json {
        print_json(&report)
    } else {
        print_text(&human(&report))
    }
}

fn human(r: &OrbitReport) -> String {
    let mults: Vec<String> = r
        .multipliers
        .iter()
        .map(|m| {
            if m.im == 0.0 {
                format!("{:.6}", m.re)
            } else {
                format!(
                    "{:.6} {} {:.6}i",
                    m.re,
                    if m.im < 0.0 { '−' } else { '+' },
                    m.im.abs()
                )
            }
        })
        .collect();
    format!(
        "period-{} orbit at Ω = {}, V = {}: {}\n\
         fixed point at plate phase 0: x = {:.12}, x' = {:.12} ({} Newton iterations, \
         residual {:.1e})\n\
         Floquet multipliers: {} (largest |λ| = {:.6})\n\
         impacts per orbit: {}{}, snap-throughs: {}, max x = {:.6}\n\
         det M = {:.9e}, e^(2·impacts)·exp(−2ζpT) = {:.9e}{}\n\
         guess ({:.6}, {:.6}): {}; distance to the fixed point {:.2e}\n",
        r.period,
        r.omega,
        r.velocity,
        if r.stable { "stable" } else { "unstable" },
        r.x0,
        r.v0,
        r.iterations,
        r.residual,
        mults.join(", "),
        r.max_abs_multiplier,
        r.impacts,
        if r.sticks { " (sticks: M = 0)" } else { "" },
        r.snap_throughs,
        r.max_x,
        r.det_monodromy,
        r.det_identity,
        r.det_relative_error
            .map_or(String::new(), |e| format!(" (relative difference {e:.1e})")),
        r.guess.0,
        r.guess.1,
        r.guess_source,
        r.distance_to_guess
    )
}

#[derive(Debug, Serialize)]
struct BranchSummary {
    velocity: f64,
    orbits: usize,
    stable: usize,
    omega_min: Option<f64>,
    omega_max: Option<f64>,
    /// With --arclength: separate traces, and turning points in Ω (folds) along them.
    traces: Option<usize>,
    folds: Option<usize>,
}

#[derive(Debug, Serialize)]
struct ContinuationSummary {
    period: u32,
    method: &'static str,
    omega_range: String,
    branches: Vec<BranchSummary>,
    /// The bifurcation points located on the branches, for every V in order.
    bifurcations: Vec<bifurcations::PointReport>,
    files: Vec<PathBuf>,
}

/// Header of the CSV of `--arclength` traces.
const ARC_HEADER: &str = "velocity,trace,index,omega,x0,v0,max_x,stable,multiplier_1_re,\
multiplier_1_im,multiplier_2_re,multiplier_2_im,abs_multiplier,impacts";

fn continuation(args: &OrbitArgs, range: Range) -> Result<(), CliError> {
    let range = range.omegas("--continue-omega")?;
    let threads = threads(args.threads, "--threads")?;
    let width = lanes(args.lanes, "--lanes")?;
    let omegas = range.values();
    let p = args.period;
    let method = if args.arclength {
        Method::Arclength
    } else {
        Method::Natural
    };
    let mut all: Vec<(f64, Curves)> = Vec::new();
    let mut found: Vec<BifurcationPoint> = Vec::new();
    for &v in &args.velocity {
        let models = omegas
            .iter()
            .map(|&w| args.model.model(w, v))
            .collect::<Result<Vec<_>, _>>()?;
        let mut bars = StageBars::new(format!(" at V = {v}"));
        let curves = continue_orbits(&models, p, args.settle, method, threads, width, &mut |r| {
            bars.report(r)
        })?;
        let on = Branch::from_curves(&models, p, &curves);
        found.extend(locate(&on, threads, &mut |r| bars.report(r))?);
        all.push((v, curves));
    }
    let mut files = Vec::new();
    if let Some(path) = &args.out {
        files.push(write_continuation_csv(path, &all)?);
        files.push(bifurcations::write_csv(
            &sibling(path, "_bifurcations.csv"),
            &found,
        )?);
    }
    if let Some(path) = &args.plot {
        let model = args.model.model(range.start, args.velocity[0])?;
        plot::png(path, (1400, 950), |root| {
            draw(root, &model, p, args.arclength, &omegas, &all, &found)
        })?;
        files.push(path.clone());
    }
    let summary = ContinuationSummary {
        period: p,
        method: if args.arclength {
            "pseudo-arclength"
        } else {
            "natural"
        },
        omega_range: range.to_string(),
        branches: all
            .iter()
            .map(|(v, c)| branch_summary(*v, c, &omegas))
            .collect(),
        bifurcations: bifurcations::reports(&found),
        files,
    };
    if args.model.json {
        return print_json(&summary);
    }
    let mut text = format!(
        "period-{p} orbits continued over Ω = {} ({} continuation):\n",
        summary.omega_range, summary.method
    );
    for b in &summary.branches {
        text.push_str(&format!(
            "  V = {}: {} orbits ({} stable), Ω from {} to {}{}\n",
            b.velocity,
            b.orbits,
            b.stable,
            b.omega_min.map_or("-".into(), |w| format!("{w:.4}")),
            b.omega_max.map_or("-".into(), |w| format!("{w:.4}")),
            match (b.traces, b.folds) {
                (Some(t), Some(f)) => format!(", {t} traces, {f} folds"),
                _ => String::new(),
            }
        ));
    }
    if !found.is_empty() {
        text.push_str("bifurcation points:\n");
        text.push_str(&bifurcations::human(&found));
    }
    for f in &summary.files {
        text.push_str(&format!("wrote {}\n", f.display()));
    }
    print_text(&text)
}

fn branch_summary(v: f64, c: &Curves, omegas: &[f64]) -> BranchSummary {
    let s = c.summary(omegas);
    BranchSummary {
        velocity: v,
        orbits: s.orbits,
        stable: s.stable,
        omega_min: s.omega_min,
        omega_max: s.omega_max,
        traces: s.traces,
        folds: s.folds,
    }
}

fn write_continuation_csv(
    path: &std::path::Path,
    all: &[(f64, Curves)],
) -> Result<PathBuf, CliError> {
    let arc = all.iter().any(|(_, c)| matches!(c, Curves::Arclength(_)));
    let mut csv = CsvFile::create(
        path,
        if arc {
            ARC_HEADER
        } else {
            branches::CSV_HEADER
        },
    )?;
    for (v, c) in all {
        match c {
            Curves::Natural(b) => branches::write_csv(&mut csv, std::slice::from_ref(b))?,
            Curves::Arclength(traces) => {
                for (k, t) in traces.iter().enumerate() {
                    for (i, a) in t.iter().enumerate() {
                        let m = a.multipliers;
                        csv.row(&[
                            Field::F(*v),
                            Field::I(k as u64),
                            Field::I(i as u64),
                            Field::F(a.omega),
                            Field::F(a.x0),
                            Field::F(a.v0),
                            Field::F(a.max_x),
                            Field::flag(a.stable),
                            Field::F(m[0].0),
                            Field::F(m[0].1),
                            Field::F(m[1].0),
                            Field::F(m[1].1),
                            Field::F(m[0].0.hypot(m[0].1)),
                            Field::I(a.impacts),
                        ])?;
                    }
                }
            }
        }
    }
    csv.finish()
}

/// Distinct colours for the velocity series.
const SERIES: [RGBColor; 8] = [
    RGBColor(31, 87, 165),
    RGBColor(215, 40, 40),
    RGBColor(30, 150, 60),
    RGBColor(230, 140, 0),
    RGBColor(140, 60, 180),
    RGBColor(0, 160, 170),
    RGBColor(120, 80, 40),
    RGBColor(230, 60, 160),
];

/// The barrier line x = 1/2.
const BARRIER: RGBColor = RGBColor(90, 90, 90);

/// The largest displacements of the orbits drawn (those of arclength traces within `Ω` range).
fn orbit_maxima(all: &[(f64, Curves)], (x0, x1): (f64, f64)) -> impl Iterator<Item = f64> + '_ {
    all.iter().flat_map(move |(_, c)| -> Vec<f64> {
        match c {
            Curves::Natural(b) => b
                .slots
                .iter()
                .flatten()
                .flat_map(|o| o.cycle_max.iter().copied())
                .collect(),
            Curves::Arclength(t) => t
                .iter()
                .flatten()
                .filter(|p| p.omega >= x0 && p.omega <= x1)
                .map(|p| p.max_x)
                .collect(),
        }
    })
}

fn draw(
    root: &Area<'_>,
    model: &Model,
    period: u32,
    arc: bool,
    omegas: &[f64],
    all: &[(f64, Curves)],
    found: &[BifurcationPoint],
) -> DrawResult {
    let mut legend: Vec<(Mark, String)> = all
        .iter()
        .enumerate()
        .map(|(k, (v, _))| (Mark::Line(SERIES[k % SERIES.len()], 3), format!("V = {v}")))
        .collect();
    legend.push((Mark::Line(RGBColor(60, 60, 60), 3), "stable".to_string()));
    legend.push((Mark::Dashed(RGBColor(60, 60, 60)), "unstable".to_string()));
    let (x0, x1) = plot::range(omegas.iter().copied(), 0.01);
    let (y0, y1) = plot::range(orbit_maxima(all, (x0, x1)).chain([0.0]), 0.05);
    let barrier = y0 < 0.5 && y1 > 0.5;
    if barrier {
        legend.push((Mark::Dashed(BARRIER), "barrier x = ½".to_string()));
    }
    legend.extend(bifurcations::legend(found));
    let area = header(
        root,
        &format!(
            "Period-{period} orbits against Ω — ζ = {}, e = {}",
            model.params.zeta(),
            model.restitution()
        ),
        &format!(
            "largest displacement of each orbit found by shooting from simulated attractors, {}",
            if arc {
                "followed through folds by pseudo-arclength continuation"
            } else {
                "continued in Ω point by point (natural continuation)"
            }
        ),
        &legend,
    )?;
    let mut chart = plot::chart(
        &area,
        (x0, x1),
        (y0, y1),
        "shaker frequency ratio Ω (units of ω0)",
        "max displacement x_max of the orbit (units of Δx)",
        None,
    )?;
    if barrier {
        plot::hline(&mut chart, 0.5, BARRIER)?;
    }
    for (k, (_, c)) in all.iter().enumerate() {
        let colour = SERIES[k % SERIES.len()];
        match c {
            Curves::Natural(b) => branches::draw(&mut chart, b, omegas, colour)?,
            Curves::Arclength(traces) => {
                for t in traces {
                    let pts: Vec<(f64, f64, bool)> =
                        t.iter().map(|p| (p.omega, p.max_x, p.stable)).collect();
                    branches::draw_curve(&mut chart, &pts, colour)?;
                }
            }
        }
    }
    bifurcations::draw(&mut chart, found)
}
