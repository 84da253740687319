//! The codimension-two points of `bistable atlas` (`bistable_analysis::codim2`): CSV rows, JSON
//! objects, text lines and markers over the (Ω, V) plot.

use std::path::{Path, PathBuf};

use plotters::prelude::*;
use serde::Serialize;

use bistable_analysis::codim2::{Codim2Point, PointKind};
use bistable_analysis::twoparam::Atlas;

use crate::bifurcations::Multiplier;
use crate::error::CliError;
use crate::output::{CsvFile, Field};
use crate::plot::{draw_point, Chart, DrawResult, Mark};

/// Header of `<stem>_points.csv`.
pub const CSV_HEADER: &str = "kind,omega,velocity,curve,index,other_curve,other_index,period,\
                              x0,v0,multiplier_1_re,multiplier_1_im,multiplier_2_re,\
                              multiplier_2_im,impacts,impacts_beyond,error";

/// Marker colour and legend text of each kind.
fn style(kind: PointKind) -> (RGBColor, &'static str) {
    match kind {
        PointKind::FoldFlip => (RGBColor(200, 0, 200), "fold–flip (multipliers +1 and −1)"),
        PointKind::Cusp => (RGBColor(0, 0, 0), "cusp (two folds meet)"),
        PointKind::ResonantGrazing => (
            RGBColor(0, 70, 220),
            "resonant grazing (curve ends: impacts per period change)",
        ),
        PointKind::Crossing => (RGBColor(0, 130, 0), "crossing of two curves"),
    }
}

fn mark(kind: PointKind) -> Mark {
    let (c, _) = style(kind);
    match kind {
        PointKind::FoldFlip => Mark::Cross(c),
        PointKind::Cusp => Mark::Square(c),
        PointKind::ResonantGrazing => Mark::Ring(c, 6, 3),
        PointKind::Crossing => Mark::Dot(c, 5),
    }
}

/// One legend entry per kind among `points`.
pub fn legend(points: &[Codim2Point]) -> Vec<(Mark, String)> {
    PointKind::ALL
        .into_iter()
        .filter(|k| points.iter().any(|p| p.kind == *k))
        .map(|k| (mark(k), style(k).1.to_string()))
        .collect()
}

/// Draws each point at `(Ω, V)` with its kind's marker (on a white underlay).
pub fn draw(chart: &mut Chart<'_, '_>, points: &[Codim2Point]) -> DrawResult {
    for p in points {
        let at = (p.omega, p.velocity);
        chart.draw_series([Circle::new(at, 8, WHITE.mix(0.7).filled())])?;
        draw_point(chart, at, mark(p.kind))?;
    }
    Ok(())
}

/// A codimension-two point in JSON (the CSV's columns, multipliers as a list).
#[derive(Debug, Serialize)]
pub struct PointReport {
    kind: &'static str,
    omega: f64,
    velocity: f64,
    curve: usize,
    index: usize,
    other_curve: Option<usize>,
    other_index: Option<usize>,
    period: u32,
    x0: f64,
    v0: f64,
    multipliers: Vec<Multiplier>,
    impacts: u64,
    impacts_beyond: u64,
    error: f64,
}

/// The period of the orbits of `p`'s curve.
fn period(atlas: &Atlas, p: &Codim2Point) -> u32 {
    atlas[p.curve].0.period
}

/// The JSON objects of `points` (on the curves of `atlas`).
pub fn reports(atlas: &Atlas, points: &[Codim2Point]) -> Vec<PointReport> {
    points
        .iter()
        .map(|p| PointReport {
            kind: p.kind.name(),
            omega: p.omega,
            velocity: p.velocity,
            curve: p.curve,
            index: p.index,
            other_curve: p.other.map(|o| o.0),
            other_index: p.other.map(|o| o.1),
            period: period(atlas, p),
            x0: p.x0,
            v0: p.v0,
            multipliers: p.multipliers.iter().map(Multiplier::from).collect(),
            impacts: p.impacts,
            impacts_beyond: p.impacts_beyond,
            error: p.error,
        })
        .collect()
}

/// Writes `points` to `path` (header only when there are none).
pub fn write_csv(path: &Path, atlas: &Atlas, points: &[Codim2Point]) -> Result<PathBuf, CliError> {
    let mut csv = CsvFile::create(path, CSV_HEADER)?;
    for p in points {
        let m = p.multipliers;
        let other = |f: fn((usize, usize)) -> usize| {
            p.other.map_or(Field::Empty, |o| Field::I(f(o) as u64))
        };
        csv.row(&[
            Field::S(p.kind.name()),
            Field::F(p.omega),
            Field::F(p.velocity),
            Field::I(p.curve as u64),
            Field::I(p.index as u64),
            other(|o| o.0),
            other(|o| o.1),
            Field::I(u64::from(period(atlas, p))),
            Field::F(p.x0),
            Field::F(p.v0),
            Field::F(m[0].0),
            Field::F(m[0].1),
            Field::F(m[1].0),
            Field::F(m[1].1),
            Field::I(p.impacts),
            Field::I(p.impacts_beyond),
            Field::F(p.error),
        ])?;
    }
    csv.finish()
}

/// One line per point for the text summary.
pub fn human(points: &[Codim2Point]) -> String {
    points
        .iter()
        .map(|p| {
            let m = p.multipliers;
            let what = match (p.kind, p.other) {
                (PointKind::Crossing, Some((c, _))) => format!(" with curve {c}"),
                (PointKind::ResonantGrazing, _) => {
                    format!(", impacts {} → {}", p.impacts, p.impacts_beyond)
                }
                _ => String::new(),
            };
            format!(
                "  {} on curve {}{} at Ω = {:.10}, V = {:.10} (± {:.0e} along the curve): \
                 multipliers {:.6}, {:.6}\n",
                p.kind.name(),
                p.curve,
                what,
                p.omega,
                p.velocity,
                p.error,
                m[0].0,
                m[1].0
            )
        })
        .collect()
}
