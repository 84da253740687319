//! `bistable map`: the response-class map of the paper's Fig. 9 over an `Ω × V` grid, computed
//! in parallel, written row by row to a resumable CSV file and drawn as a PNG.

use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};
use std::time::Instant as WallClock;

use clap::{ArgGroup, Args};
use plotters::prelude::*;
use serde::Serialize;

use bistable_analysis::period;
use bistable_analysis::sweep::classify_points_with;
use bistable_analysis::Model;
use bistable_core::ClassifyOptions;

use crate::classify::{ClassifyArgs, Record, RecordCsv, CSV_COLUMNS};
use crate::common::ModelArgs;
use crate::error::CliError;
use crate::grid::{self, grid_help, GridArgs, GridFile, GridRun, GridSummary, Rows};
use crate::output::{print_json, print_text};
use crate::plot::{self, header, Area, DrawResult, Mark, FONT};
use crate::ranges::Range;

/// Lyapunov periods of an aperiodic point in a map unless `--lyapunov-periods` says otherwise.
const MAP_LYAPUNOV_PERIODS: u32 = 300;

/// The CSV file of `map`.
const FILE: GridFile<Record> = GridFile {
    columns: &CSV_COLUMNS,
    kind: "map",
    axes: ["Ω", "V"],
    point: |r| (r.omega, r.velocity),
    rows: Rows::One,
};

/// Long description shown by `bistable map --help`.
pub const LONG_ABOUT: &str = "\
Classify every point of an Ω × V grid (the paper's Fig. 9) in parallel, as
'bistable classify' does for one point, and write one CSV row per point and a
PNG of the map.

Each point starts from the paper's initial condition and runs until its class is
decided, at most --max-periods natural periods (20,000). To keep a large map
fast, the largest Lyapunov exponent of an aperiodic point (which decides
'chaotic') is averaged over 300 shaker periods instead of classify's 2000; set
--lyapunov-periods to change it. Every point gets classify's sensitivity test
(--repeats 0 turns it off).

Resuming: rows are appended and flushed as points complete (in an interleaved
order that covers the whole grid early), so an interrupted run loses only the
points in progress. Run the same command again and the points already in
--out (same Ω and V to the last bit) are skipped; rows written with another ζ or
e are refused (the other options are not recorded in the file: resume with the
same ones). While a run appends to FILE.csv it holds FILE.csv.lock (its process
id); a second run on the same file is refused. The plot always shows every grid
point found in the file.";

/// Shown after the options by `bistable map --help`.
pub const AFTER_HELP: &str = "\
CSV (--out): header and one row per point, in completion order:
  omega,velocity,zeta,restitution,class,period,chaotic,lyapunov,snap_throughs,
  final_well,at_rest_in_second_well,impacts_per_period,sticking,
  periods_simulated,stopped_early,wall_time_s,sensitive,runs,majority_fraction,
  outcomes,sensitivity_trigger,efoldings,efoldings_threshold,at_rest
  (the keys of 'bistable classify'; empty period, lyapunov,
  impacts_per_period, efoldings, efoldings_threshold mean null; outcomes, a
  list of objects in the JSON, is text here: class:period:well=fraction
  joined by ';', period P-n, chaotic or aperiodic, well - for continuous
  interwell, fraction to 3 decimals).

PNG (--plot): the paper's colour logic. Hue by the number of snap-throughs over
the whole run: blue none, green one, orange several; shade by steady-state
period, dark P-1 to light P-6+ (periods 7..16). Black: chaotic (aperiodic, λ >
1e-3); grey: aperiodic but not chaotic; purple: converged to rest at the second
equilibrium x = 1. Pink hatch: sensitive points (the outcome depends on
rounding, see 'bistable classify --help'), coloured by their most frequent
outcome; their share is in the legend and the summary. Lines: the thresholds of Eq. 16–18, single impact
V = 1/(4(1+e)), interwell V = (1−e)/(2(1+e)), quasi-static V = Ω/2.

Prints a summary (points, wall time, points per second, share of points that
ran the full --max-periods); JSON with --json.

Exit codes: 0 success; 2 invalid options or a --out file that does not fit;
1 a file could not be written, or some points failed (listed on stderr; the
others are saved).

Examples:
  bistable map --omega-range 0.2:3.5:60 --velocity-range 0.005:0.2:40 \\
      --out out/map.csv --plot out/map.png
  bistable map --restitution 0.7 --out out/map_e07.csv --plot out/map_e07.png";

/// Options of `bistable map`.
#[derive(Debug, Clone, Args)]
#[command(group(ArgGroup::new("output").required(true).multiple(true).args(["out", "plot"])))]
#[command(mut_args(grid_help(
    "Append one row per point to FILE.csv, skipping points already in it (see below)",
    "Draw the map to FILE.png"
)))]
pub struct MapArgs {
    /// Ω values A:B:N (N evenly spaced values from A to B, ends included; Ω > 0).
    #[arg(
        long,
        value_name = "A:B:N",
        default_value = "0.2:3.5:300",
        allow_hyphen_values = true
    )]
    pub omega_range: Range,

    /// V values A:B:N (V >= 0; the paper's map is V ∈ (0, 0.2]).
    #[arg(
        long,
        value_name = "A:B:N",
        default_value = "0.001:0.2:200",
        allow_hyphen_values = true
    )]
    pub velocity_range: Range,

    #[command(flatten)]
    pub grid: GridArgs,

    #[command(flatten)]
    pub classify: ClassifyArgs,

    #[command(flatten)]
    pub model: ModelArgs,
}

/// What `map` prints at the end.
#[derive(Debug, Serialize)]
struct Summary {
    omega_range: String,
    velocity_range: String,
    restitution: f64,
    zeta: f64,
    #[serde(flatten)]
    grid: GridSummary,
    points_per_second: f64,
    /// Sum of the points' own wall times (≈ CPU time).
    point_time_s: f64,
    /// Share of the grid's points that ran the full `--max-periods`.
    full_length_share: f64,
    /// Points flagged sensitive (their outcome depends on rounding).
    sensitive: usize,
    /// Share of the grid's points flagged sensitive.
    sensitive_share: f64,
    /// Points repeated by the sensitivity test (suspect ones).
    repeated: usize,
    /// Points per category, by label (in label order, so the JSON is the same every run).
    counts: BTreeMap<String, usize>,
    out: Option<PathBuf>,
    plot: Option<PathBuf>,
}

/// Runs `bistable map`.
pub fn run(args: &MapArgs) -> Result<(), CliError> {
    let omegas = args.omega_range.omegas("--omega-range")?;
    let vs = args.velocity_range.velocities("--velocity-range")?;
    grid::check_size(omegas, vs, "--omega-range")?;
    let model = args.model.model(omegas.start, vs.start)?;
    let co = args.classify.options(MAP_LYAPUNOV_PERIODS)?;
    let so = args.classify.sensitivity()?;
    let (threads, width) = args.grid.parallel()?;

    let mut run = GridRun::open(
        &FILE,
        args.grid.out.as_deref(),
        (omegas, vs),
        |text, row| {
            let cells: Vec<&str> = text.split(',').collect();
            let r = Record::from_csv(&cells).map_err(|e| format!("has a bad row {row}: {e}"))?;
            if r.restitution != model.restitution() || r.zeta != model.params.zeta() {
                return Err(format!(
                    "holds points with ζ = {}, e = {}, but this run has ζ = {}, e = {}; use \
                     another file",
                    r.zeta,
                    r.restitution,
                    model.params.zeta(),
                    model.restitution()
                ));
            }
            Ok(r)
        },
    )?;

    let start = WallClock::now();
    let done = run.compute(
        format!("classifying {} points", run.todo.len()),
        |c, r| c.row(&r.fields()),
        |todo, done| {
            classify_points_with(&model, todo, co, so, threads, width, |i, r| {
                done(i, r.map(|p| Record::new(&p)).map_err(CliError::from))
            })
        },
    )?;
    let wall = start.elapsed().as_secs_f64();

    let records: Vec<&Record> = run.grid.iter().filter_map(|&p| run.get(p)).collect();
    if let Some(path) = &args.grid.plot {
        draw(path, &model, omegas, vs, &records, &done.failed, co)?;
    }
    let mut counts: BTreeMap<String, usize> = BTreeMap::new();
    for r in &records {
        *counts.entry(category(r).label()).or_default() += 1;
    }
    let summary = Summary {
        omega_range: omegas.to_string(),
        velocity_range: vs.to_string(),
        restitution: model.restitution(),
        zeta: model.params.zeta(),
        grid: run.summary(&done, (threads, width), wall),
        points_per_second: if wall > 0.0 {
            done.computed as f64 / wall
        } else {
            0.0
        },
        point_time_s: records.iter().map(|r| r.wall_time_s).sum(),
        full_length_share: if records.is_empty() {
            0.0
        } else {
            records.iter().filter(|r| !r.stopped_early).count() as f64 / records.len() as f64
        },
        sensitive: records.iter().filter(|r| r.sensitive).count(),
        sensitive_share: if records.is_empty() {
            0.0
        } else {
            records.iter().filter(|r| r.sensitive).count() as f64 / records.len() as f64
        },
        repeated: records.iter().filter(|r| r.runs > 1).count(),
        counts,
        out: args.grid.out.clone(),
        plot: args.grid.plot.clone(),
    };
    if args.model.json {
        print_json(&summary)?;
    } else {
        print_text(&human(&summary))?;
    }
    run.check(&done, "points")
}

fn human(s: &Summary) -> String {
    let mut counts: Vec<_> = s.counts.iter().collect();
    counts.sort_by(|a, b| b.1.cmp(a.1).then(a.0.cmp(b.0)));
    let mut text = format!(
        "map Ω {} × V {} (ζ = {}, e = {}): {}\n\
         wall time {:.1} s on {} threads: {:.1} points/s; {:.1}% of the points ran the full \
         length\n\
         sensitive (the outcome depends on rounding): {} points ({:.2}%); {} points repeated\n",
        s.omega_range,
        s.velocity_range,
        s.zeta,
        s.restitution,
        s.grid.counts("points", "resumed from the file"),
        s.grid.wall_time_s,
        s.grid.threads,
        s.points_per_second,
        100.0 * s.full_length_share,
        s.sensitive,
        100.0 * s.sensitive_share,
        s.repeated
    );
    for (label, n) in counts {
        text.push_str(&format!("  {n:>7}  {label}\n"));
    }
    for (what, p) in [("csv", &s.out), ("plot", &s.plot)] {
        if let Some(p) = p {
            text.push_str(&format!("{what}: {}\n", p.display()));
        }
    }
    text
}

// ---------------------------------------------------------------------------------------------
// Colours (the paper's logic) and the figure.

/// Snap-throughs over the whole run: none, one, several.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
enum Snaps {
    None,
    One,
    Several,
}

/// What a map cell shows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
enum Category {
    /// Period 1..=6, or 7 for P-6+.
    Periodic(Snaps, u32),
    Chaotic,
    Aperiodic,
    AtRestInWellTwo,
    Failed,
}

impl Category {
    fn label(self) -> String {
        match self {
            Category::Periodic(s, p) => format!(
                "{} snap-through{}, {}",
                match s {
                    Snaps::None => "no",
                    Snaps::One => "one",
                    Snaps::Several => "several",
                },
                if s == Snaps::One { "" } else { "s" },
                period_label(p)
            ),
            Category::Chaotic => period::label(None, true),
            Category::Aperiodic => format!("{}, not chaotic", period::label(None, false)),
            Category::AtRestInWellTwo => "at rest in well 2".into(),
            Category::Failed => "failed".into(),
        }
    }

    fn colour(self) -> RGBColor {
        match self {
            Category::Periodic(s, p) => {
                let (dark, light) = match s {
                    Snaps::None => (RGBColor(8, 48, 107), RGBColor(198, 219, 239)),
                    Snaps::One => (RGBColor(0, 80, 30), RGBColor(199, 233, 192)),
                    Snaps::Several => (RGBColor(140, 40, 4), RGBColor(253, 212, 158)),
                };
                plot::mix(dark, light, f64::from(p.clamp(1, 7) - 1) / 6.0)
            }
            Category::Chaotic => RGBColor(15, 15, 15),
            Category::Aperiodic => RGBColor(140, 140, 140),
            Category::AtRestInWellTwo => RGBColor(150, 70, 200),
            Category::Failed => RGBColor(255, 0, 255),
        }
    }
}

/// `P-1` to `P-6`, and `P-6+` for the longer periods (7).
fn period_label(p: u32) -> String {
    if p >= 7 {
        format!("{}+", period::label(Some(6), false))
    } else {
        period::label(Some(p), false)
    }
}

fn category(r: &Record) -> Category {
    if r.at_rest_in_second_well {
        return Category::AtRestInWellTwo;
    }
    let snaps = match r.snap_throughs {
        0 => Snaps::None,
        1 => Snaps::One,
        _ => Snaps::Several,
    };
    match r.period {
        Some(p) => Category::Periodic(snaps, p.min(7)),
        None if r.chaotic => Category::Chaotic,
        None => Category::Aperiodic,
    }
}

fn draw(
    path: &Path,
    model: &Model,
    omegas: Range,
    vs: Range,
    records: &[&Record],
    failed: &[(f64, f64)],
    co: ClassifyOptions,
) -> Result<(), CliError> {
    let subtitle = format!(
        "{} × {} points ({} classified), from rest at x = 0, up to {} natural periods; \
         thresholds of Eq. 16–18",
        omegas.n,
        vs.n,
        records.len(),
        co.max_natural_periods
    );
    plot::png(path, MAP_SIZE, |root| {
        draw_map(
            root,
            (
                &format!(
                    "Response classes — ζ = {}, e = {}",
                    model.params.zeta(),
                    model.restitution()
                ),
                &subtitle,
            ),
            model.restitution(),
            (omegas, vs),
            (records, failed),
            (&[], |_| Ok(())),
        )
    })
}

/// Pixels of a map figure.
pub(crate) const MAP_SIZE: (u32, u32) = (1600, 1000);

/// A map figure in `root`: `(title, subtitle)`, the cells of `records` (and `failed` points)
/// on the grid `omegas × vs` in the class colours with the colour key beside them, the
/// thresholds of Eq. 16–18 for restitution `e`, and an `overlay`: its legend entries (after
/// the thresholds') and what it draws on the chart over the cells and thresholds.
pub(crate) fn draw_map(
    root: &Area<'_>,
    (title, subtitle): (&str, &str),
    e: f64,
    (omegas, vs): (Range, Range),
    (records, failed): (&[&Record], &[(f64, f64)]),
    (extra, overlay): (
        &[(Mark, String)],
        impl FnOnce(&mut plot::Chart<'_, '_>) -> DrawResult,
    ),
) -> DrawResult {
    let mut legend = plot::threshold_legend(e);
    legend.extend_from_slice(extra);
    let total = omegas.n * vs.n;
    let area = header(root, title, subtitle, &legend)?;
    plot::grid_figure(
        &area,
        330,
        (omegas, vs),
        (
            "shaker frequency ratio Ω (units of ω0)",
            "shaker velocity amplitude V (units of ω0·Δx)",
        ),
        |chart, right, [(_, hw), (_, hv)]| {
            let mut present: HashMap<Category, usize> = HashMap::new();
            let cells = records
                .iter()
                .map(|r| (r.omega, r.velocity, category(r)))
                .chain(failed.iter().map(|&(w, v)| (w, v, Category::Failed)));
            let mut rects = Vec::with_capacity(total);
            for (om, v, c) in cells {
                *present.entry(c).or_default() += 1;
                rects.push(plot::cell((om, v), (hw, hv), c.colour()));
            }
            chart.draw_series(rects)?;
            // Sensitive points: a hatch stroke across the cell.
            let sensitive: Vec<(f64, f64)> = records
                .iter()
                .filter(|r| r.sensitive)
                .map(|r| (r.omega, r.velocity))
                .collect();
            chart.draw_series(sensitive.iter().map(|&(om, v)| {
                PathElement::new(
                    vec![(om - hw, v - hv), (om + hw, v + hv)],
                    SENSITIVE.stroke_width(2),
                )
            }))?;
            plot::draw_thresholds(root, chart, e)?;
            overlay(chart)?;
            legend_panel(
                right,
                &present,
                records.len() + failed.len(),
                sensitive.len(),
            )
        },
    )
}

/// The hatch of sensitive points.
const SENSITIVE: RGBColor = RGBColor(255, 20, 147);

/// The colour key: a table of hue (snap-throughs) × shade (period), then the other categories
/// with their counts.
fn legend_panel(
    area: &Area<'_>,
    present: &HashMap<Category, usize>,
    n: usize,
    sensitive: usize,
) -> DrawResult {
    let text = |size| (FONT, size).into_font().color(&BLACK);
    let y0 = 40;
    area.draw(&Text::new("Colour key", (12, y0), plot::left(text(20))))?;
    let rows = [
        (Snaps::None, "no snap-through"),
        (Snaps::One, "one snap-through"),
        (Snaps::Several, "several"),
    ];
    let (col0, cw, rh) = (150, 24, 30);
    for p in 1..=7u32 {
        let x = col0 + (p as i32 - 1) * cw + cw / 2;
        let label = if p == 7 {
            "6+".to_string()
        } else {
            p.to_string()
        };
        area.draw(&Text::new(label, (x, y0 + 34), plot::centred(text(14))))?;
    }
    area.draw(&Text::new(
        "period P-",
        (col0 - 6, y0 + 34),
        text(14).pos(plotters::style::text_anchor::Pos::new(
            plotters::style::text_anchor::HPos::Right,
            plotters::style::text_anchor::VPos::Center,
        )),
    ))?;
    for (k, (s, name)) in rows.iter().enumerate() {
        let y = y0 + 62 + k as i32 * rh;
        area.draw(&Text::new(*name, (12, y), plot::left(text(15))))?;
        for p in 1..=7u32 {
            let c = Category::Periodic(*s, p);
            let x = col0 + (p as i32 - 1) * cw;
            area.draw(&Rectangle::new(
                [(x + 2, y - 11), (x + cw - 2, y + 11)],
                c.colour().filled(),
            ))?;
            if present.contains_key(&c) {
                area.draw(&Circle::new((x + cw / 2, y), 2, WHITE.mix(0.8).filled()))?;
            }
        }
    }
    let mut y = y0 + 62 + 3 * rh + 14;
    area.draw(&Text::new(
        "(dot: occurs in this map)",
        (12, y),
        plot::left(text(13).color(&RGBColor(90, 90, 90))),
    ))?;
    y += 36;
    let mut others = vec![
        Category::Chaotic,
        Category::Aperiodic,
        Category::AtRestInWellTwo,
    ];
    if present.contains_key(&Category::Failed) {
        others.push(Category::Failed);
    }
    for c in others {
        let count = present.get(&c).copied().unwrap_or(0);
        let label = match c {
            Category::AtRestInWellTwo => "converged to the second equilibrium".to_string(),
            _ => c.label(),
        };
        let note = format!(
            "{count} points ({:.1}%)",
            100.0 * count as f64 / n.max(1) as f64
        );
        plot::swatch(area, y, c.colour(), label, (note, 13, RGBColor(90, 90, 90)))?;
        y += 50;
    }
    // Sensitive points: the same hatch on a neutral cell.
    area.draw(&Rectangle::new(
        [(14, y - 11), (36, y + 11)],
        RGBColor(200, 200, 200).filled(),
    ))?;
    area.draw(&PathElement::new(
        vec![(14, y + 11), (36, y - 11)],
        SENSITIVE.stroke_width(2),
    ))?;
    area.draw(&Text::new(
        "sensitive: outcome decided by rounding",
        (46, y - 1),
        plot::left(text(15)),
    ))?;
    let note = RGBColor(90, 90, 90);
    area.draw(&Text::new(
        format!(
            "{sensitive} points ({:.1}%), in the colour",
            100.0 * sensitive as f64 / n.max(1) as f64
        ),
        (46, y + 17),
        plot::left(text(13).color(&note)),
    ))?;
    area.draw(&Text::new(
        "of their most frequent outcome",
        (46, y + 33),
        plot::left(text(13).color(&note)),
    ))?;
    Ok(())
}
