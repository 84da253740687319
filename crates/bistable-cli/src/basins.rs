//! `bistable basins`: basins of attraction over a grid of initial states `(x0, x0')` at one
//! plate phase for one shaker point `(Ω, V)`, computed in parallel, written row by row to a
//! resumable CSV file, drawn as a PNG, with the attractors and the uncertainty exponent.

use std::path::PathBuf;
use std::time::Instant as WallClock;

use clap::{ArgGroup, Args};
use plotters::prelude::*;
use serde::Serialize;

use bistable_analysis::basins::{
    classify_starts, identify, plate_at, uncertainty, uncertainty_epsilons, uncertainty_exponent,
    uncertainty_samples, Attractor, Cell, DecidedBy, Decision, Uncertain,
};
use bistable_analysis::recurrence::{Known, RecurrenceOptions};
use bistable_analysis::sensitivity::Outcome;
use bistable_analysis::Model;
use bistable_core::{ClassifyOptions, ResponseClass, Well};

use crate::common::CommonArgs;
use crate::decision::DecisionArgs;
use crate::error::CliError;
use crate::grid::{self, grid_help, GridArgs, GridFile, GridRun, GridSummary, Rows};
use crate::output::{print_json, print_text, Field};
use crate::plot::{self, header, Area, DrawResult, FONT};
use crate::progress::Progress;
use crate::ranges::Range;

/// Long description shown by `bistable basins --help`.
pub const LONG_ABOUT: &str = "\
Basins of attraction at one shaker point (Ω, V): every start (x0, x0') of a grid, at
τ = 0 with the plate at phase --phase (cycles), is classified as 'bistable
classify' does (until the period repeats or the mass rests in well 2, at most
--max-periods natural periods; aperiodic starts are chaotic when λ > 1e-3 over
--lyapunov-periods shaker periods). Starts that reach the same attractor are
grouped; attractors are numbered by basin size and named by class, period,
final well and, when periodic, the section point (x, x') at plate phase 0 of
their cycle with the smallest x (coexisting orbits of one period and class,
e.g. low- and high-energy P-1 in well 1, differ there).

Decision by recurrence (the default; --full-decision turns it off): a start stops as soon
as --recurrence-hits (2) consecutive section points (plate phase 0) lie within
the capture radius of the cycle points of a periodic attractor already found
here, or --aperiodic-hits (500) consecutive section points lie in the cells
(side 0.01) of an aperiodic (chaotic) attractor already found here without
closing in on a cycle (a periodic orbit can lie among those cells). Each
attractor is found and classified once by the full decision. The capture region
of each cycle point is an ellipse shaped by the cycle's monodromy matrix there
(its eigenvector basis, in which the linearised map shrinks every displacement
by the multipliers' modulus; smaller semi-axis = the radius); its radius is half
the largest of 0.1, 0.05, ..., 1e-4 (units Δx, ω0·Δx) whose ring of 16 probe
starts, and every smaller ring, all reach the attractor without crossing the
barrier (probed only when the starts still to decide are at least twice the
probes). The JSON lists each cycle point's radius and ellipse axes. The starts
are taken in rounds (256, then doubling) with the attractors of the rounds
before, so the cells do not depend on --threads or --lanes. Rest in well 2 is
decided as in full. See docs/sensitivity.md.

Uncertainty exponent (Grebogi, McDonald, Ott & Yorke 1983): a start is
ε-uncertain when x0 ± ε reaches another attractor. The fraction f(ε) of
uncertain starts among --uncertainty-samples grid cells is measured at ε = the
x0 step times 1, 1/4, 1/16, 1/64, 1/256; α is the least-squares slope of ln f
against ln ε, and 2 − α the dimension of the basin boundary (α near 1: smooth
boundaries; small α: fractal, the attractor of a start near the boundary is
practically unpredictable).

Starts below the plate (x0 < z at that phase) are refused (exit 2, naming
--x-range). Resuming: rows are appended and flushed as cells complete, in an
interleaved order; the same command again skips the cells already in --out
(rows with another Ω, V, phase, ζ or e are refused). The uncertainty samples
are recomputed on every run.";

/// Shown after the options by `bistable basins --help`.
pub const AFTER_HELP: &str = "\
CSV (--out): x0,v0,omega,velocity,phase,zeta,restitution,class,period,chaotic,
  final_well,anchor_x,anchor_v,at_rest_in_second_well,periods_simulated,
  decided_by (class of the start's own run; period and anchor empty when
  aperiodic, anchor empty at rest; final_well empty for continuous interwell;
  decided_by 'full' or 'recurrence', whose anchor is the attractor's).

PNG (--plot): cells coloured by attractor; the legend lists the attractors with
their basin fractions and the uncertainty exponent.

Prints a summary (attractors, fractions, f(ε), α); JSON with --json.

Exit codes: 0 success; 2 invalid options or a --out file that does not fit;
1 a file could not be written or some starts failed (the others are saved).

Examples:
  bistable basins --omega 1.45 --velocity 0.05 --x-range 0:1.2:200 \\
      --v-range -0.6:0.6:200 --out out/basins.csv --plot out/basins.png";

/// Options of `bistable basins`.
#[derive(Debug, Clone, Args)]
#[command(group(ArgGroup::new("output").required(true).multiple(true).args(["out", "plot"])))]
#[command(mut_args(grid_help(
    "Append one row per start to FILE.csv, skipping starts already in it",
    "Draw the basins to FILE.png"
)))]
pub struct BasinsArgs {
    #[command(flatten)]
    pub common: CommonArgs,

    /// Plate phase at the start τ = 0, in cycles [0, 1).
    #[arg(
        long,
        value_name = "CYCLES",
        default_value_t = 0.0,
        allow_negative_numbers = true
    )]
    pub phase: f64,

    /// Start positions x0 A:B:N (not below the plate at --phase).
    #[arg(
        long,
        value_name = "A:B:N",
        default_value = "0:1.2:100",
        allow_hyphen_values = true
    )]
    pub x_range: Range,

    /// Start velocities x0' A:B:N.
    #[arg(
        long,
        value_name = "A:B:N",
        default_value = "-0.6:0.6:100",
        allow_hyphen_values = true
    )]
    pub v_range: Range,

    /// Longest run of a start, in natural periods τ/2π.
    #[arg(long, value_name = "N", default_value_t = 2_000.0)]
    pub max_periods: f64,

    /// Shaker periods averaged for the Lyapunov exponent of an aperiodic start.
    #[arg(long, value_name = "N", default_value_t = 300)]
    pub lyapunov_periods: u32,

    /// Grid cells sampled for the uncertainty exponent (0: skip it).
    #[arg(long, value_name = "N", default_value_t = 400)]
    pub uncertainty_samples: usize,

    #[command(flatten)]
    pub decision: DecisionArgs,

    #[command(flatten)]
    pub grid: GridArgs,
}

/// CSV header of `basins`.
pub const COLUMNS: [&str; 16] = [
    "x0",
    "v0",
    "omega",
    "velocity",
    "phase",
    "zeta",
    "restitution",
    "class",
    "period",
    "chaotic",
    "final_well",
    "anchor_x",
    "anchor_v",
    "at_rest_in_second_well",
    "periods_simulated",
    "decided_by",
];

/// The CSV file of `basins`.
const FILE: GridFile<Cell> = GridFile {
    columns: &COLUMNS,
    kind: "basins",
    axes: ["x0", "x0'"],
    point: |c| (c.x0, c.v0),
    rows: Rows::One,
};

#[derive(Debug, Serialize)]
struct AttractorJson {
    number: usize,
    label: String,
    across_barrier: bool,
    at_rest_in_second_well: bool,
    period: Option<u32>,
    chaotic: bool,
    final_well: Option<u8>,
    anchor: Option<[f64; 2]>,
    cells: usize,
    fraction: f64,
}

#[derive(Debug, Serialize)]
struct KnownJson {
    label: String,
    cycle: Vec<[f64; 2]>,
    capture_radii: Vec<f64>,
    capture_axes: Vec<[[f64; 2]; 2]>,
    found_by: [f64; 2],
}

#[derive(Debug, Serialize)]
struct KnownAperiodicJson {
    label: String,
    cells: usize,
    centroid: [f64; 2],
    found_by: [f64; 2],
}

#[derive(Debug, Serialize)]
struct RecurrenceJson {
    hits: u32,
    aperiodic_hits: u32,
    first_round: usize,
    probe_directions: u32,
    /// Starts computed in this run that were decided by recurrence.
    decided_by_recurrence: usize,
    known_attractors: Vec<KnownJson>,
    known_aperiodic: Vec<KnownAperiodicJson>,
}

#[derive(Debug, Serialize)]
struct UncertainJson {
    epsilon: f64,
    samples: usize,
    uncertain: usize,
    fraction: f64,
}

#[derive(Debug, Serialize)]
struct Summary {
    omega: f64,
    velocity: f64,
    phase: f64,
    zeta: f64,
    restitution: f64,
    x_range: String,
    v_range: String,
    plate_x: f64,
    #[serde(flatten)]
    grid: GridSummary,
    decision: &'static str,
    recurrence: Option<RecurrenceJson>,
    attractors: Vec<AttractorJson>,
    uncertainty: Vec<UncertainJson>,
    uncertainty_exponent: Option<f64>,
    boundary_dimension: Option<f64>,
    out: Option<PathBuf>,
    plot: Option<PathBuf>,
}

fn label(a: &Attractor) -> String {
    let mut s = a.steady.label();
    if let Some(x) = a.anchor {
        s.push_str(&format!(" (x = {:.4}, x' = {:.4})", x[0], x[1]));
    }
    s
}

/// Runs `bistable basins`.
pub fn run(args: &BasinsArgs) -> Result<(), CliError> {
    let model = args.common.model()?;
    let phase = args.phase;
    if !(phase.is_finite() && (0.0..1.0).contains(&phase)) {
        return Err(CliError::invalid(
            "--phase",
            phase,
            "must be in [0, 1) (cycles)",
        ));
    }
    let (plate_x, _) = plate_at(&model, phase)?;
    let xs = args
        .x_range
        .check("--x-range", f64::is_finite, "must be finite")?;
    let vs = args
        .v_range
        .check("--v-range", f64::is_finite, "must be finite")?;
    let (xlo, _) = xs.bounds();
    if xlo < plate_x {
        return Err(CliError::invalid_text(
            "--x-range",
            xs,
            format!(
                "starts below the plate: at phase {phase} the plate is at z = {plate_x:.6}, so \
                 x0 must be >= {plate_x:.6}"
            ),
        ));
    }
    grid::check_size(xs, vs, "--x-range")?;
    let co = ClassifyOptions {
        max_natural_periods: args.max_periods,
        lyapunov_periods: args.lyapunov_periods,
        ..ClassifyOptions::default()
    }
    .check()?;
    let (threads, width) = args.grid.parallel()?;
    let decision = args
        .decision
        .decision(RecurrenceOptions::default().first_round)?;

    let mut run = GridRun::open(&FILE, args.grid.out.as_deref(), (xs, vs), |text, row| {
        parse_row(text, &model, phase).map_err(|e| format!("has a bad row {row}: {e}"))
    })?;

    let start = WallClock::now();
    let mut known = Known::default();
    let mut captured = 0usize;
    let done = run.compute(
        format!("basins: {} starts", run.todo.len()),
        |c, cell| c.row(&row(cell, &model, phase)),
        |todo, done| {
            known = classify_starts(&model, phase, co, decision, todo, threads, width, |i, r| {
                if r.as_ref()
                    .is_ok_and(|c| c.decided_by == DecidedBy::Recurrence)
                {
                    captured += 1;
                }
                done(i, r.map_err(CliError::from))
            })?;
            Ok(())
        },
    )?;

    // Attractors over the grid's cells, in grid order.
    let cells: Vec<Cell> = (0..xs.n * vs.n)
        .filter_map(|k| run.get((xs.value(k % xs.n), vs.value(k / xs.n))).copied())
        .collect();
    let (attractors, index) = identify(&cells);

    // Uncertainty fraction on a spread sample of cells.
    let samples = uncertainty_samples(&cells, &index, args.uncertainty_samples);
    let epsilons = uncertainty_epsilons(xs.start, xs.end, xs.n);
    let unc: Vec<Uncertain> = if samples.is_empty() {
        Vec::new()
    } else {
        let mut bar = Progress::new(1.0, "uncertainty exponent".to_string());
        let r = uncertainty(
            &model,
            phase,
            co,
            &attractors,
            &samples,
            &epsilons,
            plate_x,
            threads,
            width,
            |n, total| {
                bar.set(n as f64 / total as f64);
                Ok::<(), CliError>(())
            },
        )??;
        bar.finish();
        r
    };
    let alpha = uncertainty_exponent(&unc);
    let wall = start.elapsed().as_secs_f64();

    let total = cells.len().max(1) as f64;
    let summary = Summary {
        omega: model.omega(),
        velocity: model.velocity(),
        phase,
        zeta: model.params.zeta(),
        restitution: model.restitution(),
        x_range: xs.to_string(),
        v_range: vs.to_string(),
        plate_x,
        grid: run.summary(&done, (threads, width), wall),
        decision: match decision {
            Decision::Full => "full",
            Decision::Recurrence(_) => "recurrence",
        },
        recurrence: match decision {
            Decision::Full => None,
            Decision::Recurrence(ro) => Some(RecurrenceJson {
                hits: ro.hits,
                aperiodic_hits: ro.aperiodic_hits,
                first_round: ro.first_round,
                probe_directions: ro.directions,
                decided_by_recurrence: captured,
                known_attractors: known
                    .periodic
                    .iter()
                    .map(|k| KnownJson {
                        label: format!(
                            "{} (x = {:.4}, x' = {:.4})",
                            k.steady.label(),
                            k.anchor[0],
                            k.anchor[1]
                        ),
                        cycle: k.cycle.clone(),
                        capture_radii: k.radii.clone(),
                        capture_axes: k.shapes.iter().map(|e| e.axes).collect(),
                        found_by: [k.found_by.0, k.found_by.1],
                    })
                    .collect(),
                known_aperiodic: known
                    .aperiodic
                    .iter()
                    .map(|k| KnownAperiodicJson {
                        label: k.steady.label(),
                        cells: k.cells.len(),
                        centroid: k.centroid,
                        found_by: [k.found_by.0, k.found_by.1],
                    })
                    .collect(),
            }),
        },
        attractors: attractors
            .iter()
            .enumerate()
            .map(|(i, a)| AttractorJson {
                number: i + 1,
                label: label(a),
                across_barrier: a.steady.across,
                at_rest_in_second_well: a.steady.at_rest,
                period: a.steady.period,
                chaotic: a.steady.chaotic,
                final_well: a.steady.well.map(|w| w.number()),
                anchor: a.anchor,
                cells: a.cells,
                fraction: a.cells as f64 / total,
            })
            .collect(),
        uncertainty: unc
            .iter()
            .map(|u| UncertainJson {
                epsilon: u.epsilon,
                samples: u.samples,
                uncertain: u.uncertain,
                fraction: u.fraction(),
            })
            .collect(),
        uncertainty_exponent: alpha,
        boundary_dimension: alpha.map(|a| 2.0 - a),
        out: args.grid.out.clone(),
        plot: args.grid.plot.clone(),
    };
    if let Some(path) = &args.grid.plot {
        plot::png(path, (1500, 1000), |root| {
            draw(root, &summary, xs, vs, &cells, &index, &attractors)
        })?;
    }
    if args.common.json() {
        print_json(&summary)?;
    } else {
        print_text(&human(&summary))?;
    }
    run.check(&done, "starts")
}

fn row<'a>(c: &Cell, m: &Model, phase: f64) -> [Field<'a>; 16] {
    let o = &c.outcome;
    [
        Field::F(c.x0),
        Field::F(c.v0),
        Field::F(m.omega()),
        Field::F(m.velocity()),
        Field::F(phase),
        Field::F(m.params.zeta()),
        Field::F(m.restitution()),
        Field::S(o.class.name()),
        o.period.map_or(Field::Empty, |p| Field::I(u64::from(p))),
        Field::flag(o.chaotic),
        o.final_well
            .map_or(Field::Empty, |w| Field::I(u64::from(w.number()))),
        c.anchor.map_or(Field::Empty, |a| Field::F(a[0])),
        c.anchor.map_or(Field::Empty, |a| Field::F(a[1])),
        Field::flag(c.at_rest),
        Field::F(c.periods_simulated),
        Field::S(c.decided_by.name()),
    ]
}

fn parse_row(text: &str, model: &Model, phase: f64) -> Result<Cell, String> {
    let f: Vec<&str> = text.split(',').collect();
    if f.len() != COLUMNS.len() {
        return Err(format!("{} fields, expected {}", f.len(), COLUMNS.len()));
    }
    let num = |i: usize| -> Result<f64, String> {
        f[i].parse::<f64>()
            .map_err(|_| format!("bad {} '{}'", COLUMNS[i], f[i]))
    };
    let opt = |i: usize| -> Result<Option<f64>, String> {
        if f[i].is_empty() {
            Ok(None)
        } else {
            num(i).map(Some)
        }
    };
    let here = [
        model.omega(),
        model.velocity(),
        phase,
        model.params.zeta(),
        model.restitution(),
    ];
    for (k, want) in here.iter().enumerate() {
        if num(2 + k)? != *want {
            return Err(format!(
                "it holds {} = {}, this run has {want}; use another file",
                COLUMNS[2 + k],
                f[2 + k]
            ));
        }
    }
    let class = match f[7] {
        "intrawell" => ResponseClass::Intrawell,
        "transient_interwell" => ResponseClass::TransientInterwell,
        "continuous_interwell" => ResponseClass::ContinuousInterwell,
        other => return Err(format!("bad class '{other}'")),
    };
    let well = match f[10] {
        "" => None,
        "1" => Some(Well::One),
        "2" => Some(Well::Two),
        other => return Err(format!("bad final_well '{other}'")),
    };
    let anchor = match (opt(11)?, opt(12)?) {
        (Some(a), Some(b)) => Some([a, b]),
        _ => None,
    };
    Ok(Cell {
        x0: num(0)?,
        v0: num(1)?,
        outcome: Outcome {
            class,
            period: opt(8)?.map(|p| p as u32),
            chaotic: f[9] == "true",
            final_well: well,
        },
        anchor,
        at_rest: f[13] == "true",
        periods_simulated: num(14)?,
        decided_by: match f[15] {
            "full" => DecidedBy::Full,
            "recurrence" => DecidedBy::Recurrence,
            other => return Err(format!("bad decided_by '{other}'")),
        },
    })
}

fn human(s: &Summary) -> String {
    let mut t = format!(
        "basins at Ω = {}, V = {}, phase {} (ζ = {}, e = {}): x0 {} × x0' {}, {}; {:.1} s \
         on {} threads\n",
        s.omega,
        s.velocity,
        s.phase,
        s.zeta,
        s.restitution,
        s.x_range,
        s.v_range,
        s.grid.counts("starts", "resumed"),
        s.grid.wall_time_s,
        s.grid.threads
    );
    if let Some(r) = &s.recurrence {
        t.push_str(&format!(
            "  decided by recurrence: {} of {} starts computed ({} known periodic and {} \
             aperiodic attractors)\n",
            r.decided_by_recurrence,
            s.grid.computed,
            r.known_attractors.len(),
            r.known_aperiodic.len()
        ));
    }
    for a in s.attractors.iter().take(20) {
        t.push_str(&format!(
            "  #{:<2} {:>6.2}%  {}\n",
            a.number,
            100.0 * a.fraction,
            a.label
        ));
    }
    if s.attractors.len() > 20 {
        t.push_str(&format!(
            "  … {} more (see --json)\n",
            s.attractors.len() - 20
        ));
    }
    for u in &s.uncertainty {
        t.push_str(&format!(
            "  ε = {:.3e}: {} of {} starts uncertain ({:.3})\n",
            u.epsilon, u.uncertain, u.samples, u.fraction
        ));
    }
    if let Some(a) = s.uncertainty_exponent {
        t.push_str(&format!(
            "uncertainty exponent α = {a:.3} (boundary dimension {:.3})\n",
            2.0 - a
        ));
    }
    t
}

fn draw(
    root: &Area<'_>,
    s: &Summary,
    xs: Range,
    vs: Range,
    cells: &[Cell],
    index: &[usize],
    attractors: &[Attractor],
) -> DrawResult {
    let area = header(
        root,
        &format!(
            "Basins of attraction — Ω = {}, V = {}, plate phase {} cycles",
            s.omega, s.velocity, s.phase
        ),
        &format!(
            "ζ = {}, e = {}; {} × {} starts (x0, x0') at τ = 0; {}",
            s.zeta,
            s.restitution,
            xs.n,
            vs.n,
            match s.uncertainty_exponent {
                Some(a) => format!("uncertainty exponent α = {a:.3}"),
                None => "uncertainty exponent: not measured".into(),
            }
        ),
        &[],
    )?;
    plot::grid_figure(
        &area,
        420,
        (xs, vs),
        (
            "start position x0 (units of Δx)",
            "start velocity x0' (units of ω0·Δx)",
        ),
        |chart, right, [(_, hx), (_, hv)]| {
            chart.draw_series(
                cells
                    .iter()
                    .zip(index)
                    .map(|(c, &i)| plot::cell((c.x0, c.v0), (hx, hv), plot::category_colour(i))),
            )?;
            // Legend: attractors with their basin fractions.
            let text = |size| (FONT, size).into_font().color(&BLACK);
            let mut y = 40;
            right.draw(&Text::new(
                "Attractors (basin share)",
                (12, y),
                plot::left(text(20)),
            ))?;
            y += 36;
            for (i, a) in s.attractors.iter().enumerate().take(24) {
                plot::swatch(
                    right,
                    y,
                    plot::category_colour(i),
                    format!("#{} {:.1}%", a.number, 100.0 * a.fraction),
                    (a.label.clone(), 12, RGBColor(70, 70, 70)),
                )?;
                y += 46;
            }
            if attractors.len() > 24 {
                right.draw(&Text::new(
                    format!("… {} more", attractors.len() - 24),
                    (14, y),
                    plot::left(text(14)),
                ))?;
                y += 30;
            }
            if !s.uncertainty.is_empty() {
                y += 10;
                right.draw(&Text::new(
                    "ε-uncertain fraction f(ε)",
                    (12, y),
                    plot::left(text(16)),
                ))?;
                y += 24;
                for u in &s.uncertainty {
                    right.draw(&Text::new(
                        format!("ε = {:.2e}: {:.3}", u.epsilon, u.fraction),
                        (14, y),
                        plot::left(text(13)),
                    ))?;
                    y += 20;
                }
            }
            Ok(())
        },
    )
}
