//! `bistable bifurcation`: Fig. 6/8 style diagrams. For each value of the control parameter
//! (Ω at fixed V, or V at fixed Ω) the response from the paper's initial condition is run past
//! a transient, then the largest displacement of every shaker cycle and the phases of the
//! impacts are recorded; the periodic-orbit branches found by shooting are drawn over them.

use std::path::{Path, PathBuf};

use clap::{ArgGroup, Args, ValueEnum};
use plotters::prelude::*;
use serde::Serialize;

use bistable_analysis::bifurcations::{locate, BifurcationPoint, Branch};
use bistable_analysis::branches::Branches;
use bistable_analysis::cycles::Cycles;
use bistable_analysis::diagram::{self, Bifurcation, BifurcationOptions};
use bistable_analysis::Model;

use crate::bifurcations;
use crate::branches;
use crate::common::{lanes, threads, ModelArgs};
use crate::error::CliError;
use crate::grid::{grid_help, GridArgs};
use crate::output::{print_json, print_text, sibling, CsvFile, Field};
use crate::plot::{self, header, Area, DrawResult, Mark};
use crate::progress::StageBars;
use crate::ranges::Range;

/// Long description shown by `bistable bifurcation --help`.
pub const LONG_ABOUT: &str = "\
Bifurcation diagram against Ω (at fixed --velocity) or V (at fixed --omega), as
in the paper's Fig. 6 and 8. For each parameter value (in parallel) the response
starts from the paper's initial condition, runs --transient shaker periods, and
then --record shaker periods are recorded:

  max x     the largest displacement in each shaker cycle, from --samples
            dense-output samples per cycle (at the same plate phases in every
            cycle, so periodic responses repeat exactly) refined by cubic
            Hermite interpolation of (x, x') around each turning point;
  phases    the shaker phase (cycles, [0, 1)) of every impact.

Periodic-orbit branches (unless --no-branches): for each period in
--branch-periods, orbits are found by shooting (Newton on the p-period map with
the monodromy matrix from the variational equations) seeded from the simulated
attractor (its own period, and the orbits it doubled from), then continued from
point to point in both directions. Stable orbits (all Floquet multipliers inside
the unit circle) are drawn thick and solid, unstable ones thin and dashed, each
period in its own colour over the max-x panel.

With --param omega, the bifurcation points on the branches (fold, period
doubling, Neimark–Sacker, grazing, sticking) are located between consecutive
orbits and drawn as markers (see below; natural continuation stops at folds,
use 'bistable orbit --continue-omega --arclength' to pass them). With --param
velocity no points are located (the locator follows branches in Ω).

Prints a summary per point (detected period, number of distinct max-x values,
impacts per cycle) and the bifurcation points; JSON with --json.";

/// Shown after the options by `bistable bifurcation --help`.
pub const AFTER_HELP: &str = concat!(
    "\
CSV (--out FILE.csv): omega,velocity,kind,cycle,value with kind max_x (value:
largest x in that recorded cycle) or impact_phase (value: phase in cycles of an
impact in that cycle); cycle counts from 0 at the end of the transient.
<stem>_orbits.csv next to it: one row per periodic orbit,
  omega,velocity,period,stable,x0,v0,max_x,cycle_max,multiplier_1_re,
  multiplier_1_im,multiplier_2_re,multiplier_2_im,abs_multiplier,impacts,
  snap_throughs,sticks
(x0, v0: the fixed point at plate phase 0; cycle_max: the largest x of each of
its cycles, ';'-separated).
",
    crate::bifurcations::help!(),
    "

Exit codes: 0 success; 2 invalid options; 1 a file could not be written or a
simulation failed.

Examples:
  bistable bifurcation --param omega --range 2.0:2.7:141 --velocity 0.07 \\
      --out out/bif.csv --plot out/bif.png
  bistable bifurcation --param velocity --range 0.01:0.2:200 --omega 0.85 \\
      --plot out/bif_v.png"
);

/// The control parameter.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Param {
    /// Ω, at fixed --velocity.
    Omega,
    /// V, at fixed --omega.
    Velocity,
}

/// Options of `bistable bifurcation`.
#[derive(Debug, Clone, Args)]
#[command(group(ArgGroup::new("output").required(true).multiple(true).args(["out", "plot", "json"])))]
#[command(mut_args(grid_help(
    "Write the recorded maxima and impact phases to FILE.csv and the orbits to <stem>_orbits.csv \
     next to it",
    "Draw the diagram to FILE.png"
)))]
pub struct BifurcationArgs {
    /// Control parameter.
    #[arg(long, value_enum, value_name = "PARAM")]
    pub param: Param,

    /// Values of the control parameter, A:B:N (N evenly spaced values, ends included).
    #[arg(long, value_name = "A:B:N", allow_hyphen_values = true)]
    pub range: Range,

    /// Fixed Ω when --param velocity, in [1e-6, 1e6].
    #[arg(long, value_name = "OMEGA", allow_negative_numbers = true)]
    pub omega: Option<f64>,

    /// Fixed V when --param omega, in [0, 1e6].
    #[arg(long, value_name = "V", allow_negative_numbers = true)]
    pub velocity: Option<f64>,

    /// Shaker periods skipped as transient at each point.
    #[arg(long, value_name = "N", default_value_t = 500)]
    pub transient: u32,

    /// Shaker periods recorded after the transient (>= 1).
    #[arg(long, value_name = "N", default_value_t = 100)]
    pub record: u32,

    /// Dense-output samples per shaker period for the maximum of x (>= 8).
    #[arg(long, value_name = "N", default_value_t = 128)]
    pub samples: u32,

    /// Periods (shaker periods) of the orbit branches to find, comma separated.
    #[arg(
        long,
        value_name = "P,P,..",
        value_delimiter = ',',
        default_value = "1,2,4,8"
    )]
    pub branch_periods: Vec<u32>,

    /// Do not look for periodic orbits.
    #[arg(long)]
    pub no_branches: bool,

    #[command(flatten)]
    pub grid: GridArgs,

    #[command(flatten)]
    pub model: ModelArgs,
}

/// The summary of one point.
#[derive(Debug, Serialize)]
struct PointSummary {
    omega: f64,
    velocity: f64,
    /// Period of the recorded response in shaker periods (null: none up to 16).
    period: Option<usize>,
    /// Distinct values of max x over the recorded cycles (to 1e-6).
    distinct_max_x: usize,
    impacts_per_cycle: f64,
}

#[derive(Debug, Serialize)]
struct OrbitCount {
    period: u32,
    orbits: usize,
    stable: usize,
    links: usize,
}

#[derive(Debug, Serialize)]
struct Summary {
    param: Param,
    range: String,
    transient: u32,
    record: u32,
    /// Trajectories per thread in SIMD lanes.
    lanes: usize,
    points: Vec<PointSummary>,
    branches: Vec<OrbitCount>,
    /// The bifurcation points located on the branches (`--param omega` only).
    bifurcations: Vec<bifurcations::PointReport>,
    wall_time_s: f64,
    files: Vec<PathBuf>,
}

/// Runs `bistable bifurcation`.
pub fn run(args: &BifurcationArgs) -> Result<(), CliError> {
    let start = std::time::Instant::now();
    let (models, range) = grid(args)?;
    CliError::at_least("--record", args.record, 1)?;
    let samples = CliError::count("--samples", args.samples, 8)?;
    if let Some(&p) = args
        .branch_periods
        .iter()
        .find(|&&p| !(1..=64).contains(&p))
    {
        return Err(CliError::invalid_text(
            "--branch-periods",
            p,
            "periods must be in [1, 64]",
        ));
    }
    let threads = threads(args.grid.threads, "--threads")?;
    let width = lanes(args.grid.lanes, "--lanes")?;
    let options = BifurcationOptions {
        transient: args.transient,
        record: args.record,
        samples,
        branch_periods: if args.no_branches {
            Vec::new()
        } else {
            args.branch_periods.clone()
        },
        width,
    };
    let mut bars = StageBars::new("");
    let data = diagram::compute(&models, &options, threads, &mut |p| bars.report(p))?;
    let summaries = data.point_summaries(&models, args.record);
    let Bifurcation {
        points, branches, ..
    } = data;
    let found: Vec<BifurcationPoint> = match args.param {
        Param::Omega => {
            let on: Vec<Branch> = branches
                .iter()
                .flat_map(|b| Branch::from_natural(&models, b))
                .collect();
            locate(&on, threads, &mut |p| bars.report(p))?
        }
        Param::Velocity => Vec::new(),
    };

    let mut files = Vec::new();
    if let Some(path) = &args.grid.out {
        files.extend(write_csv(path, &models, &points, &branches)?);
        if args.param == Param::Omega {
            files.push(bifurcations::write_csv(
                &sibling(path, "_bifurcations.csv"),
                &found,
            )?);
        }
    }
    let xs: Vec<f64> = range.values();
    if let Some(path) = &args.grid.plot {
        plot::png(path, (1500, 1250), |root| {
            draw(root, args, &models, &xs, &points, &branches, &found)
        })?;
        files.push(path.clone());
    }
    let summary = Summary {
        param: args.param,
        range: range.to_string(),
        transient: args.transient,
        record: args.record,
        lanes: width.lanes(),
        points: summaries
            .into_iter()
            .map(|p| PointSummary {
                omega: p.omega,
                velocity: p.velocity,
                period: p.period,
                distinct_max_x: p.distinct_max_x,
                impacts_per_cycle: p.impacts_per_cycle,
            })
            .collect(),
        branches: branches
            .iter()
            .map(|b| OrbitCount {
                period: b.period,
                orbits: b.len(),
                stable: b.stable(),
                links: b.links.len(),
            })
            .collect(),
        bifurcations: bifurcations::reports(&found),
        wall_time_s: start.elapsed().as_secs_f64(),
        files,
    };
    if args.model.json {
        print_json(&summary)
    } else {
        print_text(&human(&summary, &found))
    }
}

/// The models along the range, with the fixed parameter checked.
fn grid(args: &BifurcationArgs) -> Result<(Vec<Model>, Range), CliError> {
    let (range, fixed, fixed_name) = match args.param {
        Param::Omega => (args.range.omegas("--range")?, args.velocity, "--velocity"),
        Param::Velocity => (args.range.velocities("--range")?, args.omega, "--omega"),
    };
    let fixed = fixed.ok_or_else(|| {
        CliError::invalid_text(
            fixed_name,
            "(missing)",
            format!(
                "is required with --param {}",
                match args.param {
                    Param::Omega => "omega",
                    Param::Velocity => "velocity",
                }
            ),
        )
    })?;
    let models = range
        .values()
        .into_iter()
        .map(|p| match args.param {
            Param::Omega => args.model.model(p, fixed),
            Param::Velocity => args.model.model(fixed, p),
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok((models, range))
}

fn write_csv(
    path: &Path,
    models: &[Model],
    points: &[Cycles],
    branches: &[Branches],
) -> Result<Vec<PathBuf>, CliError> {
    let mut csv = CsvFile::create(path, "omega,velocity,kind,cycle,value")?;
    for (m, c) in models.iter().zip(points) {
        let (w, v) = (Field::F(m.omega()), Field::F(m.velocity()));
        for (k, &x) in c.max_x.iter().enumerate() {
            csv.row(&[w, v, Field::S("max_x"), Field::I(k as u64), Field::F(x)])?;
        }
        for &(k, ph) in &c.impacts {
            csv.row(&[
                w,
                v,
                Field::S("impact_phase"),
                Field::I(u64::from(k)),
                Field::F(ph),
            ])?;
        }
    }
    let mut files = vec![csv.finish()?];
    if !branches.is_empty() {
        let mut orbits = CsvFile::create(&sibling(path, "_orbits.csv"), branches::CSV_HEADER)?;
        branches::write_csv(&mut orbits, branches)?;
        files.push(orbits.finish()?);
    }
    Ok(files)
}

fn human(s: &Summary, found: &[BifurcationPoint]) -> String {
    let mut text = format!(
        "bifurcation diagram over {} = {} ({} transient + {} recorded shaker periods per \
         point, {:.1} s)\n",
        match s.param {
            Param::Omega => "Ω",
            Param::Velocity => "V",
        },
        s.range,
        s.transient,
        s.record,
        s.wall_time_s
    );
    // Runs of equal period.
    let mut i = 0;
    while i < s.points.len() {
        let p = s.points[i].period;
        let j = (i..s.points.len())
            .find(|&j| s.points[j].period != p)
            .unwrap_or(s.points.len());
        let value = |k: usize| match s.param {
            Param::Omega => s.points[k].omega,
            Param::Velocity => s.points[k].velocity,
        };
        text.push_str(&format!(
            "  {:>9.5} .. {:<9.5}  {}\n",
            value(i),
            value(j - 1),
            match p {
                Some(p) => format!("period {p}"),
                None => "no period <= 16".to_string(),
            }
        ));
        i = j;
    }
    for b in &s.branches {
        text.push_str(&format!(
            "  P-{} orbits: {} ({} stable), {} continuation links\n",
            b.period, b.orbits, b.stable, b.links
        ));
    }
    if !found.is_empty() {
        text.push_str("  bifurcation points on the branches:\n");
        text.push_str(&bifurcations::human(found));
    }
    for f in &s.files {
        text.push_str(&format!("wrote {}\n", f.display()));
    }
    text
}

/// Colour of the branches of period `p`.
pub fn period_colour(p: u32) -> RGBColor {
    match p {
        1 => RGBColor(215, 40, 40),
        2 => RGBColor(30, 150, 60),
        4 => RGBColor(40, 90, 220),
        8 => RGBColor(230, 140, 0),
        _ => RGBColor(160, 50, 170),
    }
}

const DOTS: RGBColor = RGBColor(20, 20, 20);
/// Responses beyond the top of the axis (drawn at its edge).
const ABOVE: RGBColor = RGBColor(200, 30, 120);
/// The barrier line x = 1/2.
const BARRIER: RGBColor = RGBColor(90, 90, 90);

fn draw(
    root: &Area<'_>,
    args: &BifurcationArgs,
    models: &[Model],
    xs: &[f64],
    points: &[Cycles],
    branches: &[Branches],
    found: &[BifurcationPoint],
) -> DrawResult {
    let m0 = &models[0];
    let (pname, xdesc, fixed) = match args.param {
        Param::Omega => (
            "Ω",
            "shaker frequency ratio Ω (units of ω0)",
            format!("V = {}", m0.velocity()),
        ),
        Param::Velocity => (
            "V",
            "shaker velocity amplitude V (units of ω0·Δx)",
            format!("Ω = {}", m0.omega()),
        ),
    };
    let mut legend = vec![(Mark::Dot(DOTS, 3), "simulated response".to_string())];
    for b in branches.iter().filter(|b| !b.is_empty()) {
        legend.push((
            Mark::Line(period_colour(b.period), 3),
            format!("P-{} orbits, stable", b.period),
        ));
        legend.push((
            Mark::Dashed(period_colour(b.period)),
            format!("P-{} unstable", b.period),
        ));
    }
    // The top panel's range: the responses and orbit branches, without the few points far
    // above the rest (e.g. at rest in well 2, x = 1), drawn as markers at the top edge.
    let (x0, x1) = plot::range(xs.iter().copied(), 0.01);
    let orbit_max = branches
        .iter()
        .flat_map(|b| b.slots.iter().flatten())
        .flat_map(|o| o.cycle_max.iter().copied());
    let groups: Vec<Vec<f64>> = points.iter().map(|c| c.max_x.clone()).collect();
    let (lo, _) = plot::range(
        points
            .iter()
            .flat_map(|c| c.max_x.iter().copied())
            .chain(orbit_max.clone()),
        0.0,
    );
    let cut = plot::trimmed_top(&groups, lo);
    let (y0, mut y1) = plot::range(
        points
            .iter()
            .flat_map(|c| c.max_x.iter().copied())
            .chain(orbit_max)
            .filter(|&y| cut.is_none_or(|c| y <= c)),
        0.05,
    );
    let above: Vec<(f64, f64)> = match cut {
        Some(c) => {
            y1 = y1.max(c + 0.12 * (c - y0));
            xs.iter()
                .zip(points)
                .filter_map(|(&x, p)| {
                    let top = p.max_x.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                    (top > y1).then_some((x, top))
                })
                .collect()
        }
        None => Vec::new(),
    };
    if !above.is_empty() {
        let (lo_a, hi_a) = above
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |a, p| {
                (a.0.min(p.1), a.1.max(p.1))
            });
        let values = if hi_a - lo_a < 5e-3 {
            format!("{hi_a:.3}")
        } else {
            format!("{lo_a:.3} to {hi_a:.3}")
        };
        legend.push((
            Mark::Dot(ABOVE, 5),
            format!(
                "{} beyond the top of the axis (max x {values}), drawn at its edge",
                plot::plural(above.len() as u64, "point")
            ),
        ));
    }
    let barrier = y0 < 0.5 && y1 > 0.5;
    if barrier {
        legend.push((Mark::Dashed(BARRIER), "barrier x = ½".to_string()));
    }
    legend.extend(bifurcations::legend(found));
    let area = header(
        root,
        &format!(
            "Bifurcation diagram against {pname} — {fixed}, ζ = {}, e = {}",
            m0.params.zeta(),
            m0.restitution()
        ),
        &format!(
            "{} points; per point: {} shaker periods of transient from rest at x = 0, then {} \
             recorded; orbits by shooting",
            xs.len(),
            args.transient,
            args.record
        ),
        &legend,
    )?;
    let (_, h) = area.dim_in_pixel();
    let (upper, lower) = area.split_vertically(h * 58 / 100);
    let mut chart = plot::chart(
        &upper,
        (x0, x1),
        (y0, y1),
        xdesc,
        "max x per shaker cycle (units of Δx)",
        Some("largest displacement in each recorded shaker cycle"),
    )?;
    if barrier {
        plot::hline(&mut chart, 0.5, BARRIER)?;
    }
    let edge = y1 - 0.02 * (y1 - y0);
    chart.draw_series(
        above
            .iter()
            .map(|&(x, _)| Circle::new((x, edge), 5, ABOVE.filled())),
    )?;
    dots(
        &mut chart,
        xs.iter()
            .zip(points)
            .flat_map(|(&x, c)| c.max_x.iter().map(move |&y| (x, y)))
            .filter(|&(_, y)| y <= y1),
    )?;
    for b in branches {
        branches::draw(&mut chart, b, xs, period_colour(b.period))?;
    }
    bifurcations::draw(&mut chart, found)?;
    let mut chart = plot::chart(
        &lower,
        (x0, x1),
        (0.0, 1.0),
        xdesc,
        "impact phase φ/2π (cycles)",
        Some("phases of the impacts in the recorded cycles"),
    )?;
    dots(
        &mut chart,
        xs.iter()
            .zip(points)
            .flat_map(|(&x, c)| c.impacts.iter().map(move |&(_, ph)| (x, ph))),
    )?;
    Ok(())
}

fn dots(chart: &mut plot::Chart<'_, '_>, pts: impl Iterator<Item = (f64, f64)>) -> DrawResult {
    chart.draw_series(pts.map(|p| Circle::new(p, 1, DOTS.mix(0.8).filled())))?;
    Ok(())
}
