//! Bifurcation points located on orbit branches (`bistable_analysis::bifurcations`) as CSV
//! rows, JSON objects and markers over a branch chart (`orbit --continue-omega`,
//! `bifurcation`).

use std::path::{Path, PathBuf};

use plotters::prelude::*;
use serde::Serialize;

use bistable_analysis::bifurcations::{BifurcationPoint, Kind};

use crate::error::CliError;
use crate::output::{CsvFile, Field};
use crate::plot::{draw_point, Chart, DrawResult, Mark};

/// Header of the `<stem>_bifurcations.csv` files.
pub const CSV_HEADER: &str = "kind,omega,velocity,period,x0,v0,max_x,multiplier_1_re,\
multiplier_1_im,multiplier_2_re,multiplier_2_im,omega_error,branch,index,impacts_before,\
impacts_after,sticks_before,sticks_after";

/// What `--help` says about the bifurcation points (the CSV columns and the kinds), a string
/// literal for `concat!`.
macro_rules! help {
    () => {
        "\
<stem>_bifurcations.csv beside --out (and \"bifurcations\" in --json, one object
per point with the same keys, multipliers as [{re, im, abs}]): one row per
bifurcation point located on a branch,
  kind,omega,velocity,period,x0,v0,max_x,multiplier_1_re,multiplier_1_im,
  multiplier_2_re,multiplier_2_im,omega_error,branch,index,impacts_before,
  impacts_after,sticks_before,sticks_after
kind: fold (a Floquet multiplier through +1), period_doubling (through −1),
neimark_sacker (a complex pair through the unit circle), grazing (the impacts
per period change), sticking (the orbit starts or stops sticking). Smooth kinds
are located by regula falsi on det(M − I), det(M + I) or det M − 1 along the
branch (re-solving the orbit by shooting at each trial), sticking by bisection,
grazing by secant steps at fixed Ω on the minimum gap of the flight that comes
to touch (side with fewer impacts) or the lowest impact speed (other side),
bisection on the impact count where both fail; omega_error bounds the error of
omega (at most 1e-12 for smooth kinds and 1e-10 for grazing and sticking when
converged; more where the iteration stalled). Impact counts of orbits that
stick on both sides are not compared (the chatter before sticking is truncated).
x0, v0, max_x and the multipliers are those of the orbit at the point (grazing:
the solved orbit nearest it, normally on the side with fewer impacts; sticking:
on the side of orbit index); the point lies between orbits index and
index + 1 of branch (a trace of the --arclength CSV, or a polyline of the
natural continuation); impacts_before/after and sticks_before/after are those
of the orbits on either side. Natural continuation stops at a fold, so folds
show only with --arclength."
    };
}
pub(crate) use help;

/// Marker colour and legend text of each kind.
fn style(kind: Kind) -> (RGBColor, &'static str) {
    match kind {
        Kind::Fold => (RGBColor(120, 30, 150), "fold (multiplier +1)"),
        Kind::PeriodDoubling => (RGBColor(235, 120, 0), "period doubling (multiplier −1)"),
        Kind::NeimarkSacker => (RGBColor(0, 150, 150), "Neimark–Sacker (|λ| = 1, complex)"),
        Kind::Grazing => (RGBColor(20, 20, 20), "grazing (impacts per period change)"),
        Kind::Sticking => (RGBColor(150, 90, 40), "sticking starts or stops"),
    }
}

fn mark(kind: Kind) -> Mark {
    let (c, _) = style(kind);
    match kind {
        Kind::Fold => Mark::Square(c),
        Kind::PeriodDoubling => Mark::Triangle(c),
        Kind::NeimarkSacker => Mark::Cross(c),
        Kind::Grazing => Mark::Ring(c, 6, 2),
        Kind::Sticking => Mark::Dot(c, 6),
    }
}

/// One legend entry per kind among `points`.
pub fn legend(points: &[BifurcationPoint]) -> Vec<(Mark, String)> {
    Kind::ALL
        .into_iter()
        .filter(|k| points.iter().any(|p| p.kind == *k))
        .map(|k| (mark(k), style(k).1.to_string()))
        .collect()
}

/// Draws each point at `(Ω, max_x)` with its kind's marker.
pub fn draw(chart: &mut Chart<'_, '_>, points: &[BifurcationPoint]) -> DrawResult {
    for p in points.iter().filter(|p| p.max_x.is_finite()) {
        draw_point(chart, (p.omega, p.max_x), mark(p.kind))?;
    }
    Ok(())
}

/// A Floquet multiplier in JSON.
#[derive(Debug, Serialize)]
pub struct Multiplier {
    pub re: f64,
    pub im: f64,
    pub abs: f64,
}

impl From<&(f64, f64)> for Multiplier {
    /// The multiplier `re + i·im`.
    fn from(&(re, im): &(f64, f64)) -> Self {
        Self {
            re,
            im,
            abs: re.hypot(im),
        }
    }
}

/// A bifurcation point in JSON (the CSV's columns, multipliers as a list).
#[derive(Debug, Serialize)]
pub struct PointReport {
    kind: &'static str,
    omega: f64,
    velocity: f64,
    period: u32,
    x0: f64,
    v0: f64,
    max_x: Option<f64>,
    multipliers: Vec<Multiplier>,
    omega_error: f64,
    branch: usize,
    index: usize,
    impacts_before: u64,
    impacts_after: u64,
    sticks_before: bool,
    sticks_after: bool,
}

/// The JSON objects of `points`.
pub fn reports(points: &[BifurcationPoint]) -> Vec<PointReport> {
    points
        .iter()
        .map(|p| PointReport {
            kind: p.kind.name(),
            omega: p.omega,
            velocity: p.velocity,
            period: p.period,
            x0: p.x0,
            v0: p.v0,
            max_x: Some(p.max_x).filter(|x| x.is_finite()),
            multipliers: p.multipliers.iter().map(Multiplier::from).collect(),
            omega_error: p.omega_error,
            branch: p.branch,
            index: p.index,
            impacts_before: p.impacts_before,
            impacts_after: p.impacts_after,
            sticks_before: p.sticks_before,
            sticks_after: p.sticks_after,
        })
        .collect()
}

/// Writes `points` to `path` (header only when there are none).
pub fn write_csv(path: &Path, points: &[BifurcationPoint]) -> Result<PathBuf, CliError> {
    let mut csv = CsvFile::create(path, CSV_HEADER)?;
    for p in points {
        let m = p.multipliers;
        csv.row(&[
            Field::S(p.kind.name()),
            Field::F(p.omega),
            Field::F(p.velocity),
            Field::I(u64::from(p.period)),
            Field::F(p.x0),
            Field::F(p.v0),
            if p.max_x.is_finite() {
                Field::F(p.max_x)
            } else {
                Field::Empty
            },
            Field::F(m[0].0),
            Field::F(m[0].1),
            Field::F(m[1].0),
            Field::F(m[1].1),
            Field::F(p.omega_error),
            Field::I(p.branch as u64),
            Field::I(p.index as u64),
            Field::I(p.impacts_before),
            Field::I(p.impacts_after),
            Field::flag(p.sticks_before),
            Field::flag(p.sticks_after),
        ])?;
    }
    csv.finish()
}

/// One line per point for the text summary.
pub fn human(points: &[BifurcationPoint]) -> String {
    points
        .iter()
        .map(|p| {
            let m = p.multipliers;
            let mult = |(re, im): (f64, f64)| {
                if im == 0.0 {
                    format!("{re:.6}")
                } else {
                    format!("{re:.6}{im:+.6}i")
                }
            };
            let side = if p.impacts_before != p.impacts_after || p.sticks_before != p.sticks_after {
                format!(
                    ", impacts {}{} → {}{}",
                    p.impacts_before,
                    if p.sticks_before { " + sticking" } else { "" },
                    p.impacts_after,
                    if p.sticks_after { " + sticking" } else { "" }
                )
            } else {
                String::new()
            };
            format!(
                "  {} of P-{} at Ω = {:.12} (± {:.0e}), V = {}: multipliers {}, {}{}\n",
                p.kind.name(),
                p.period,
                p.omega,
                p.omega_error,
                p.velocity,
                mult(m[0]),
                mult(m[1]),
                side
            )
        })
        .collect()
}
