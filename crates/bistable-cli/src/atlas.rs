//! `bistable atlas`: the fold and period-doubling points located on the orbit branches at one
//! V, each continued in (Ω, V) as a two-parameter curve (`bistable_analysis::twoparam`).

use std::path::{Path, PathBuf};

use clap::Args;
use plotters::prelude::*;
use serde::Serialize;

use bistable_analysis::bifurcations::{locate, Branch, Kind};
use bistable_analysis::codim2::{self, Codim2Point};
use bistable_analysis::continuation::{continue_orbits, Method};
use bistable_analysis::twoparam::{trace_all, CurveOptions, CurvePoint};

use crate::atlas_points;

use crate::classify::{Record, RecordCsv, CSV_COLUMNS};
use crate::common::{lanes, threads, ModelArgs};
use crate::error::CliError;
use crate::output::{print_json, print_text, sibling, CsvFile, Field};
use crate::plot::{self, Chart, DrawResult, Mark, FONT};
use crate::progress::StageBars;
use crate::ranges::{Pair, Range};

/// The columns of the curve CSV (`--out`, read back by `--curves`).
const COLUMNS: &str = "curve,kind,period,omega,velocity,x0,v0,multiplier_1_re,multiplier_1_im,\
                       multiplier_2_re,multiplier_2_im,impacts";

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
that turns in V meets --velocity twice) starts no second curve.

Codimension-two points on the curves are located and reported: fold_flip (the
other multiplier passes −1 on a fold curve, +1 on a period-doubling curve; none
in this model, where 0 < det M < 1), cusp (on a fold curve the fold's normal-form
coefficient vanishes: two folds meet and the curve turns back in (Ω, V)),
resonant_grazing (a curve ends inside the bounds because the impacts per period
change) and crossing (two curves meet in (Ω, V)), each to 1e-10 along the curve
where it converges.

--plot draws the curves (with those of --curves files from earlier runs) in the
(Ω, V) plane as thin lines, one colour per kind, each labelled (P-n → P-2n,
fold P-n), this run's codimension-two points as markers, with the thresholds of Eq. 16–18 (as 'bistable thresholds'), over
the cells of a 'bistable map' CSV when --map is given (its grid sets the axes;
else the curves do). With --map the summary also reports the check of issue
22: of the pairs of horizontally or vertically adjacent map cells with periods
1 and 2, the fraction whose joining segment a P-1 → P-2 curve crosses (over the
whole map, and over the pairs within the Ω × V box those curves span).";

/// Shown after the options by `bistable atlas --help`.
pub const AFTER_HELP: &str = "\
CSV (--out): one row per curve point,
  curve,kind,period,omega,velocity,x0,v0,multiplier_1_re,multiplier_1_im,
  multiplier_2_re,multiplier_2_im,impacts
(curve: its number in the summary; kind: fold or period_doubling; x0, v0: the
fixed point at plate phase 0; points ordered by the curve, low V end first).
<stem>_points.csv beside it: one row per codimension-two point,
  kind,omega,velocity,curve,index,other_curve,other_index,period,x0,v0,
  multiplier_1_re,multiplier_1_im,multiplier_2_re,multiplier_2_im,impacts,
  impacts_beyond,error
(kind: fold_flip, cusp, resonant_grazing or crossing; between points index and
index + 1 of curve (resonant grazing: beyond its end point index); crossing:
other_curve and other_index, empty otherwise; the orbit of curve there;
impacts_beyond: past a resonant grazing; error: bound along the curve).
The summary (--json) lists per curve its start (the point located at
--velocity), points, and the Ω and V it spans; \"points\": the CSV's rows as
objects (multipliers as [{re, im, abs}], other_curve/other_index null when
empty); with --map, \"map_check\": pairs, crossed, fraction, omega_span,
velocity_span, pairs_in_span, crossed_in_span, fraction_in_span.

Exit codes: 0 success; 2 invalid options; 1 a simulation failed or a file could
not be written.

Examples:
  bistable atlas --continue-omega 2.05:2.25:41 --velocity 0.07 \\
      --velocity-bounds 0.05,0.09 --out out/pd_curve.csv
  bistable atlas --continue-omega 1.2:1.6:41 --velocity 0.05 --arclength \\
      --velocity-bounds 0.03,0.07 --out out/fold_curve.csv
  bistable atlas --continue-omega 1.2:1.6:41 --velocity 0.05 --arclength \\
      --velocity-bounds 0.03,0.07 --curves out/pd_curve.csv \\
      --map out/map60.csv --plot out/atlas.png";

/// Options of `bistable atlas`.
#[derive(Debug, Clone, Args)]
pub struct AtlasArgs {
    /// The Ω grid A:B:N the branches are continued over at --velocity; the curves stay
    /// within A..B.
    #[arg(long, value_name = "A:B:N", allow_hyphen_values = true)]
    pub continue_omega: Range,

    /// V of the branches the points are located on, in [0, 1e6].
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

    /// Write the curves to FILE.csv and their codimension-two points to FILE_points.csv.
    #[arg(long, value_name = "FILE.csv")]
    pub out: Option<PathBuf>,

    /// Draw the curves in the (Ω, V) plane with the thresholds of Eq. 16–18 to FILE.png
    /// (over --map when given).
    #[arg(long, value_name = "FILE.png")]
    pub plot: Option<PathBuf>,

    /// A `bistable map` CSV: its cells are drawn under the curves on --plot (its grid sets the
    /// axes), and the summary reports how the P-1 → P-2 curves separate its P-1 and P-2 cells.
    #[arg(long, value_name = "MAP.csv")]
    pub map: Option<PathBuf>,

    /// The curves of an earlier `atlas --out` to draw and check with this run's (repeatable).
    #[arg(long, value_name = "FILE.csv")]
    pub curves: Vec<PathBuf>,

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
    points: Vec<atlas_points::PointReport>,
    #[serde(skip_serializing_if = "Option::is_none")]
    map_check: Option<MapCheck>,
    files: Vec<PathBuf>,
}

/// How the P-1 → P-2 curves separate the P-1 and P-2 cells of a map.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
struct MapCheck {
    /// Horizontally or vertically adjacent cell pairs with periods 1 and 2.
    pairs: usize,
    /// Those whose joining segment a curve crosses.
    crossed: usize,
    /// `crossed / pairs` (NaN without pairs).
    fraction: f64,
    /// The Ω the curves span.
    omega_span: (f64, f64),
    /// The V the curves span.
    velocity_span: (f64, f64),
    /// The pairs whose segment's midpoint lies in `omega_span × velocity_span`.
    pairs_in_span: usize,
    /// Those crossed.
    crossed_in_span: usize,
    /// `crossed_in_span / pairs_in_span`.
    fraction_in_span: f64,
}

/// A curve as drawn: its kind, the period of the orbits, its (Ω, V) points.
#[derive(Debug, Clone, PartialEq)]
struct Line {
    kind: Kind,
    period: u32,
    points: Vec<(f64, f64)>,
}

/// Runs `bistable atlas`.
pub fn run(args: &AtlasArgs) -> Result<(), CliError> {
    let range = args.continue_omega.omegas("--continue-omega")?;
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
    let mut lines = Vec::new();
    for path in &args.curves {
        lines.extend(read_curves(path)?);
    }
    let map = args.map.as_deref().map(read_map).transpose()?;
    let threads = threads(args.threads, "--threads")?;
    let width = lanes(args.lanes, "--lanes")?;
    let omegas = range.values();
    let models = omegas
        .iter()
        .map(|&w| args.model.model(w, args.velocity))
        .collect::<Result<Vec<_>, _>>()?;
    let (e, zeta) = (models[0].restitution(), models[0].params.zeta());
    if let Some((path, records)) = &map {
        if let Some(r) = records
            .iter()
            .find(|r| r.restitution != e || r.zeta != zeta)
        {
            return Err(CliError::invalid_text(
                "--map",
                path.display(),
                format!(
                    "holds points with ζ = {}, e = {}, but this run has ζ = {zeta}, e = {e}",
                    r.zeta, r.restitution
                ),
            ));
        }
    }
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
    let on = Branch::from_curves(&models, p, &curves);
    let starts = locate(&on, threads, &mut |r| bars.report(r))?;
    let (lo, hi) = range.bounds();
    let o = CurveOptions {
        omega_bounds: (lo, hi),
        velocity_bounds: (v_lo, v_hi),
        ds_max: args.ds,
        max_points: args.max_points,
    };
    let all = trace_all(&models[0], starts, o).map_err(|(kind, omega, e)| {
        CliError::Failed(format!(
            "cannot continue the {} at Ω = {omega}: {e}",
            kind.name()
        ))
    })?;
    let points = codim2::points(&models[0], &all, o);
    let mut files = Vec::new();
    if let Some(path) = &args.out {
        let mut csv = CsvFile::create(path, COLUMNS)?;
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
        files.push(atlas_points::write_csv(
            &sibling(path, "_points.csv"),
            &all,
            &points,
        )?);
    }
    lines.splice(
        0..0,
        all.iter().map(|(s, c)| Line {
            kind: s.kind,
            period: s.period,
            points: c.iter().map(|q| (q.omega, q.velocity)).collect(),
        }),
    );
    let map_check = map.as_ref().map(|(_, records)| {
        let cells: Vec<(f64, f64, Option<u32>)> = records
            .iter()
            .map(|r| (r.omega, r.velocity, r.period))
            .collect();
        separation(&cells, &lines)
    });
    if let Some(path) = &args.plot {
        let sources = std::iter::once(format!("from V = {}", args.velocity))
            .chain(args.curves.iter().map(|p| p.display().to_string()))
            .collect::<Vec<_>>()
            .join(", ");
        let title = format!("Bifurcation curves — ζ = {zeta}, e = {e}");
        match &map {
            Some((file, records)) => {
                let subtitle = format!(
                    "curves {sources}; map {}; thresholds of Eq. 16–18",
                    file.display()
                );
                let refs: Vec<&Record> = records.iter().collect();
                let mut legend = line_legend(&lines);
                legend.extend(atlas_points::legend(&points));
                plot::png(path, crate::map::MAP_SIZE, |root| {
                    crate::map::draw_map(
                        root,
                        (&title, &subtitle),
                        e,
                        grid_of(records),
                        (&refs, &[]),
                        (&legend, |chart| draw_lines(chart, &lines, &points)),
                    )
                })?;
            }
            None => {
                let subtitle = format!("curves {sources}; thresholds of Eq. 16–18");
                draw_alone(
                    path,
                    (&title, &subtitle),
                    e,
                    (&lines, &points),
                    (o.omega_bounds, o.velocity_bounds),
                )?;
            }
        }
        files.push(path.clone());
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
        points: atlas_points::reports(&all, &points),
        map_check,
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
    text.push_str(&format!(
        "codimension-two points on the curves: {}\n",
        points.len()
    ));
    text.push_str(&atlas_points::human(&points));
    if let Some(c) = &summary.map_check {
        text.push_str(&format!(
            "P-1/P-2 neighbour pairs of the map crossed by a P-1 → P-2 curve: {} of {} \
             ({:.1}%); within the curves' span Ω {:.4}..{:.4}, V {:.4}..{:.4}: {} of {} \
             ({:.1}%)\n",
            c.crossed,
            c.pairs,
            100.0 * c.fraction,
            c.omega_span.0,
            c.omega_span.1,
            c.velocity_span.0,
            c.velocity_span.1,
            c.crossed_in_span,
            c.pairs_in_span,
            100.0 * c.fraction_in_span
        ));
    }
    for f in &summary.files {
        text.push_str(&format!("wrote {}\n", f.display()));
    }
    print_text(&text)
}

/// The curves of an `atlas --out` file (`--curves`), in the file's order.
fn read_curves(path: &Path) -> Result<Vec<Line>, CliError> {
    let bad = |rule: String| CliError::invalid_text("--curves", path.display(), rule);
    let text = std::fs::read_to_string(path).map_err(|e| bad(format!("cannot be read: {e}")))?;
    let mut rows = text.lines();
    if rows.next().map(str::trim_end) != Some(COLUMNS) {
        return Err(bad(format!(
            "is not an atlas file (its header is not {COLUMNS})"
        )));
    }
    let mut out: Vec<(u64, Line)> = Vec::new();
    for (k, row) in rows.enumerate().filter(|(_, r)| !r.trim().is_empty()) {
        let cells: Vec<&str> = row.trim_end().split(',').collect();
        let parsed = (|| -> Option<(u64, Kind, u32, f64, f64)> {
            if cells.len() != COLUMNS.split(',').count() {
                return None;
            }
            let kind = [Kind::Fold, Kind::PeriodDoubling]
                .into_iter()
                .find(|k| k.name() == cells[1])?;
            let (w, v): (f64, f64) = (cells[3].parse().ok()?, cells[4].parse().ok()?);
            (w.is_finite() && v.is_finite()).then_some(())?;
            Some((cells[0].parse().ok()?, kind, cells[2].parse().ok()?, w, v))
        })();
        let (curve, kind, period, w, v) =
            parsed.ok_or_else(|| bad(format!("has a bad row {}", k + 2)))?;
        match out.last_mut() {
            Some((c, l)) if *c == curve && l.kind == kind && l.period == period => {
                l.points.push((w, v))
            }
            _ => out.push((
                curve,
                Line {
                    kind,
                    period,
                    points: vec![(w, v)],
                },
            )),
        }
    }
    Ok(out.into_iter().map(|(_, l)| l).collect())
}

/// The records of a `bistable map` CSV (`--map`), with its path.
fn read_map(path: &Path) -> Result<(PathBuf, Vec<Record>), CliError> {
    let bad = |rule: String| CliError::invalid_text("--map", path.display(), rule);
    let text = std::fs::read_to_string(path).map_err(|e| bad(format!("cannot be read: {e}")))?;
    let mut rows = text.lines();
    if rows.next().map(str::trim_end) != Some(CSV_COLUMNS.join(",").as_str()) {
        return Err(bad(
            "is not a map file (its header is not that of 'bistable map --out')".into(),
        ));
    }
    let records = rows
        .enumerate()
        .filter(|(_, r)| !r.trim().is_empty())
        .map(|(k, r)| {
            let cells: Vec<&str> = r.trim_end().split(',').collect();
            Record::from_csv(&cells).map_err(|e| bad(format!("has a bad row {}: {e}", k + 2)))
        })
        .collect::<Result<Vec<_>, _>>()?;
    if records.is_empty() {
        return Err(bad("holds no points".into()));
    }
    Ok((path.to_path_buf(), records))
}

/// The distinct values of `key` over `records`, ascending.
fn axis<T>(records: &[T], key: impl Fn(&T) -> f64) -> Vec<f64> {
    let mut v: Vec<f64> = records.iter().map(key).collect();
    v.sort_by(f64::total_cmp);
    v.dedup();
    v
}

/// The Ω × V grid of a map's records.
fn grid_of(records: &[Record]) -> (Range, Range) {
    let range = |v: Vec<f64>| Range {
        start: v[0],
        end: v[v.len() - 1],
        n: v.len(),
    };
    (
        range(axis(records, |r| r.omega)),
        range(axis(records, |r| r.velocity)),
    )
}

/// Whether the segments `a`–`b` and `c`–`d` meet.
fn crosses(a: (f64, f64), b: (f64, f64), c: (f64, f64), d: (f64, f64)) -> bool {
    let side = |p: (f64, f64), q: (f64, f64), r: (f64, f64)| {
        (q.0 - p.0) * (r.1 - p.1) - (q.1 - p.1) * (r.0 - p.0)
    };
    side(c, d, a) * side(c, d, b) <= 0.0 && side(a, b, c) * side(a, b, d) <= 0.0
}

/// How the P-1 → P-2 curves of `lines` separate the P-1 and P-2 cells of a map given as
/// `(Ω, V, period)` per cell.
fn separation(cells: &[(f64, f64, Option<u32>)], lines: &[Line]) -> MapCheck {
    let pd: Vec<&[(f64, f64)]> = lines
        .iter()
        .filter(|l| l.kind == Kind::PeriodDoubling && l.period == 1)
        .map(|l| l.points.as_slice())
        .collect();
    let (ws, vs) = (axis(cells, |c| c.0), axis(cells, |c| c.1));
    let index = |v: &[f64], x: f64| v.binary_search_by(|p| p.total_cmp(&x)).ok();
    let mut grid = std::collections::HashMap::new();
    for &(w, v, period) in cells {
        if let (Some(i), Some(j), Some(p @ (1 | 2))) = (index(&ws, w), index(&vs, v), period) {
            grid.insert((i, j), (p, (w, v)));
        }
    }
    let span = |key: fn(&(f64, f64)) -> f64| {
        pd.iter()
            .flat_map(|l| l.iter().map(key))
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                (a.min(v), b.max(v))
            })
    };
    let (sw, sv) = (span(|q| q.0), span(|q| q.1));
    let (mut pairs, mut crossed, mut pairs_in, mut crossed_in) = (0, 0, 0, 0);
    for (&(i, j), &(p, a)) in &grid {
        for n in [(i + 1, j), (i, j + 1)] {
            let Some(&(q, b)) = grid.get(&n) else {
                continue;
            };
            if p == q {
                continue;
            }
            let hit = pd
                .iter()
                .any(|l| l.windows(2).any(|s| crosses(a, b, s[0], s[1])));
            let mid = (0.5 * (a.0 + b.0), 0.5 * (a.1 + b.1));
            let inside = (sw.0..=sw.1).contains(&mid.0) && (sv.0..=sv.1).contains(&mid.1);
            pairs += 1;
            crossed += usize::from(hit);
            pairs_in += usize::from(inside);
            crossed_in += usize::from(inside && hit);
        }
    }
    let ratio = |k: usize, n: usize| {
        if n == 0 {
            f64::NAN
        } else {
            k as f64 / n as f64
        }
    };
    MapCheck {
        pairs,
        crossed,
        fraction: ratio(crossed, pairs),
        omega_span: sw,
        velocity_span: sv,
        pairs_in_span: pairs_in,
        crossed_in_span: crossed_in,
        fraction_in_span: ratio(crossed_in, pairs_in),
    }
}

const PD_COLOUR: RGBColor = RGBColor(230, 0, 0);
const FOLD_COLOUR: RGBColor = RGBColor(255, 140, 0);

fn colour(kind: Kind) -> RGBColor {
    if kind == Kind::Fold {
        FOLD_COLOUR
    } else {
        PD_COLOUR
    }
}

/// The legend entries of the kinds in `lines`.
fn line_legend(lines: &[Line]) -> Vec<(Mark, String)> {
    [
        (
            Kind::PeriodDoubling,
            "period doubling P-n → P-2n (det(M + I) = 0)",
        ),
        (Kind::Fold, "fold (det(M − I) = 0)"),
    ]
    .into_iter()
    .filter(|(k, _)| lines.iter().any(|l| l.kind == *k))
    .map(|(k, text)| (Mark::Line(colour(k), 2), text.to_string()))
    .collect()
}

/// The curves as thin lines on a white underlay, each labelled at its middle point, and the
/// codimension-two points on them.
fn draw_lines(chart: &mut Chart<'_, '_>, lines: &[Line], points: &[Codim2Point]) -> DrawResult {
    for l in lines {
        plot::thick_line(chart, &l.points, WHITE, 3)?;
        plot::thick_line(chart, &l.points, colour(l.kind), 2)?;
    }
    let area = chart.plotting_area().strip_coord_spec();
    let base = chart.plotting_area().get_base_pixel();
    let style = plot::left((FONT, 15).into_font().color(&BLACK));
    for l in lines {
        let Some(&mid) = l.points.get(l.points.len() / 2) else {
            continue;
        };
        let text = match l.kind {
            Kind::Fold => format!("fold P-{}", l.period),
            _ => format!("P-{} → P-{}", l.period, 2 * l.period),
        };
        let (x, y) = chart.backend_coord(&mid);
        let (x, y) = (x - base.0 + 8, y - base.1 - 12);
        let (tw, _) = area.estimate_text_size(&text, &style)?;
        area.draw(&Rectangle::new(
            [(x - 3, y - 10), (x + tw as i32 + 3, y + 10)],
            WHITE.mix(0.85).filled(),
        ))?;
        area.draw(&Text::new(text, (x, y), style.clone()))?;
    }
    atlas_points::draw(chart, points)
}

/// The curves without a map: axes from the curves (`bounds`, the Ω and V bounds of the run,
/// when there are none), with the thresholds.
fn draw_alone(
    path: &Path,
    (title, subtitle): (&str, &str),
    e: f64,
    (lines, points): (&[Line], &[Codim2Point]),
    bounds: ((f64, f64), (f64, f64)),
) -> Result<(), CliError> {
    let pts = || lines.iter().flat_map(|l| l.points.iter().copied());
    let (x, y) = if pts().next().is_some() {
        (
            plot::range(pts().map(|p| p.0), 0.05),
            plot::range(pts().map(|p| p.1), 0.05),
        )
    } else {
        bounds
    };
    let mut legend = plot::threshold_legend(e);
    legend.extend(line_legend(lines));
    legend.extend(atlas_points::legend(points));
    plot::png(path, (1300, 900), |root| {
        let area = plot::header(root, title, subtitle, &legend)?;
        let mut chart = plot::chart(
            &area,
            x,
            y,
            "shaker frequency ratio Ω (units of ω0)",
            "shaker velocity amplitude V (units of ω0·Δx)",
            None,
        )?;
        plot::draw_thresholds(root, &chart, e)?;
        draw_lines(&mut chart, lines, points)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn separation_counts_the_p1_p2_pairs_a_period_doubling_curve_crosses() {
        // A 4 × 3 grid: P-1 left of Ω = 1.5, P-2 right of it, one aperiodic cell; the curve
        // runs up Ω = 1.5 between V = 0 and 1.5 (so the top row's pair is not crossed).
        let mut cells = Vec::new();
        for j in 0..3 {
            for i in 0..4 {
                let p = if (i, j) == (3, 0) {
                    None
                } else if i < 2 {
                    Some(1)
                } else {
                    Some(2)
                };
                cells.push((f64::from(i), f64::from(j), p));
            }
        }
        let line = |kind, period| Line {
            kind,
            period,
            points: vec![(1.5, 0.0), (1.5, 1.5)],
        };
        let c = separation(&cells, &[line(Kind::PeriodDoubling, 1)]);
        assert_eq!((c.pairs, c.crossed), (3, 2), "{c:?}");
        assert_eq!((c.pairs_in_span, c.crossed_in_span), (2, 2), "{c:?}");
        // A fold, or the doubling of P-2 orbits, is no P-1 → P-2 boundary.
        for l in [line(Kind::Fold, 1), line(Kind::PeriodDoubling, 2)] {
            let c = separation(&cells, &[l]);
            assert_eq!((c.pairs, c.crossed), (3, 0), "{c:?}");
        }
    }
}
