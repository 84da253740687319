//! `bistable energy-map`: the energy change of an impact (Eq. 13–15) over impact phase and
//! pre-impact velocity, with the neutral and grazing lines, optionally with the impacts of a
//! simulation on top.

use std::path::PathBuf;

use clap::Args;
use plotters::prelude::*;

use bistable_analysis::energy::{self, grazing, neutral, EnergyMap, ImpactPoint};

use crate::common::{positive, ModelArgs};
use crate::error::CliError;
use crate::output::print_text;
use crate::plot::{self, header, Area, DrawResult, Mark};

const TAU: f64 = std::f64::consts::TAU;

/// Long description shown by `bistable energy-map --help`.
pub const LONG_ABOUT: &str = "\
Draw the kinetic energy change of an impact, normalised by that of the first
impact (Eq. 10, 11, 13),

  ΔK/ΔK0 = ((1+e)·cos φ − e·u)² − u²) / (1+e)²,   u = x'₋/V,

over the impact phase φ/2π ∈ [0, 1) and the pre-impact velocity u = x'₋/V
(the mass velocity just before the impact, in units of the shaker velocity
amplitude V). Red: the impact adds energy; blue: it takes energy away; the
colour scale is asinh-compressed (see the colour bar).

Lines: the neutral line ΔK = 0, u = −(1+e)/(1−e)·cos φ, and the grazing line
u = cos φ (zero relative velocity, also ΔK = 0): an impact adds energy iff it
lies between them (Eq. 14). Above the grazing line the mass moves up faster
than the plate and cannot be hit (Eq. 15): that region is hatched grey.

With --overlay, the impacts of a simulation at (--omega, --velocity) from the
paper's initial condition over --periods natural periods are drawn on top,
coloured from early (yellow) to late (dark violet).";

/// Shown after the options by `bistable energy-map --help`.
pub const AFTER_HELP: &str = "\
Examples:
  bistable energy-map --plot out/energy_map.png
  bistable energy-map --restitution 0.7 --plot out/energy_map_e07.png
  bistable energy-map --overlay --omega 2.45 --velocity 0.07 --periods 300 \\
      --plot out/energy_map_chaos.png";

/// Options of `bistable energy-map`.
#[derive(Debug, Clone, Args)]
pub struct EnergyMapArgs {
    /// Write the figure to FILE.png.
    #[arg(long, value_name = "FILE.png", required = true)]
    pub plot: PathBuf,

    /// Range of u = x'₋/V shown, LO:HI [default: up to 1.5, down to below the neutral line
    /// at φ = 0, or with --overlay to below the lowest overlaid impact].
    #[arg(long, value_name = "LO:HI", allow_hyphen_values = true)]
    pub u_range: Option<String>,

    /// Draw the impacts of a simulation at --omega, --velocity on top.
    #[arg(long, requires_all = ["omega", "velocity"])]
    pub overlay: bool,

    /// Shaker frequency ratio Ω of the overlaid simulation, in [1e-6, 1e6].
    #[arg(
        long,
        value_name = "OMEGA",
        allow_negative_numbers = true,
        requires = "overlay"
    )]
    pub omega: Option<f64>,

    /// Shaker velocity amplitude V of the overlaid simulation, in (0, 1e6].
    #[arg(
        long,
        value_name = "V",
        allow_negative_numbers = true,
        requires = "overlay"
    )]
    pub velocity: Option<f64>,

    /// Natural periods simulated for --overlay.
    #[arg(long, value_name = "N", default_value_t = 200.0, requires = "overlay")]
    pub periods: f64,

    #[command(flatten)]
    pub model: ModelArgs,
}

fn parse_span(text: &str) -> Result<(f64, f64), CliError> {
    let bad = || CliError::invalid_text("--u-range", text, "expected LO:HI with LO < HI");
    let (a, b) = text.split_once(':').ok_or_else(bad)?;
    let (lo, hi): (f64, f64) = (
        a.trim().parse().map_err(|_| bad())?,
        b.trim().parse().map_err(|_| bad())?,
    );
    if lo.is_finite() && hi.is_finite() && lo < hi {
        Ok((lo, hi))
    } else {
        Err(bad())
    }
}

/// Runs `bistable energy-map`.
pub fn run(args: &EnergyMapArgs) -> Result<(), CliError> {
    let e = energy::check_restitution(args.model.restitution)?;
    let span = args.u_range.as_deref().map(parse_span).transpose()?;
    let mut impacts: Vec<ImpactPoint> = Vec::new();
    let mut overlay_label = None;
    if args.overlay {
        let (w, v) = (
            args.omega.unwrap_or(f64::NAN),
            args.velocity.unwrap_or(f64::NAN),
        );
        let model = args.model.model(w, v)?;
        if model.velocity() <= 0.0 {
            return Err(CliError::invalid(
                "--velocity",
                v,
                "must be > 0 for --overlay",
            ));
        }
        let t_end = positive("--periods", args.periods)? * TAU;
        impacts = energy::impacts(&model, t_end)?;
        overlay_label = Some(format!(
            "{} impacts of the run at Ω = {w}, V = {v} over {} natural periods",
            impacts.len(),
            args.periods
        ));
    }
    // Default: the whole neutral line, or the overlaid impacts with a margin.
    let (lo, hi) = span.unwrap_or_else(|| energy::default_u_range(e, &impacts));
    plot::png(&args.plot, (1400, 1000), |root| {
        draw(root, e, (lo, hi), &impacts, overlay_label.as_deref())
    })?;
    print_text(&format!("wrote {}\n", args.plot.display()))
}

/// Colour scale: `asinh(r/0.5)`, divided by that of the largest magnitude shown.
fn compress(r: f64) -> f64 {
    (r / 0.5).asinh()
}

fn diverging(t: f64) -> RGBColor {
    // t in [−1, 1]: blue … white … red.
    let t = t.clamp(-1.0, 1.0);
    if t >= 0.0 {
        plot::mix(WHITE, RGBColor(178, 24, 43), t)
    } else {
        plot::mix(WHITE, RGBColor(33, 102, 172), -t)
    }
}

const NEUTRAL: RGBColor = RGBColor(0, 0, 0);
const GRAZING: RGBColor = RGBColor(0, 140, 60);
/// The overlaid impacts: dark dots with a white rim, visible on red, white and blue.
const IMPACT: RGBColor = RGBColor(25, 25, 25);

fn draw(
    root: &Area<'_>,
    e: f64,
    (lo, hi): (f64, f64),
    impacts: &[ImpactPoint],
    overlay: Option<&str>,
) -> DrawResult {
    let mut legend = vec![
        (
            Mark::Line(NEUTRAL, 2),
            "neutral ΔK = 0: x'₋/V = −(1+e)/(1−e)·cos φ".to_string(),
        ),
        (
            Mark::Line(GRAZING, 3),
            "grazing x'₋/V = cos φ (also ΔK = 0)".to_string(),
        ),
        (
            Mark::Band(RGBColor(120, 120, 120)),
            "no contact possible".to_string(),
        ),
    ];
    if let Some(label) = overlay {
        legend.push((Mark::Dot(IMPACT, 4), label.to_string()));
    }
    let area = header(
        root,
        &format!("Energy change per impact ΔK/ΔK0 — e = {e}"),
        "ΔK/ΔK0 = (((1+e)cos φ − e·u)² − u²)/(1+e)², u = x'₋/V (Eq. 13–15); red adds energy, \
         blue removes it",
        &legend,
    )?;
    let (w, _) = area.dim_in_pixel();
    let (left, right) = area.split_horizontally(w - 150);
    let mut chart = plot::chart(
        &left,
        (0.0, 1.0),
        (lo, hi),
        "impact phase φ/2π (cycles)",
        "pre-impact velocity x'₋/V",
        None,
    )?;
    let map = EnergyMap::new(e, (lo, hi), 360, 300);
    let (nx, ny) = map.size();
    let vmax = map.max_abs();
    let scale = compress(vmax);
    let (dx, dy) = (1.0 / nx as f64, (hi - lo) / ny as f64);
    let mut cells = Vec::with_capacity(nx * ny);
    for i in 0..nx {
        for j in 0..ny {
            let colour = match map.value(i, j) {
                Some(r) => diverging(compress(r) / scale),
                None => {
                    let stripe = ((i + j) / 3) % 2 == 0;
                    if stripe {
                        RGBColor(150, 150, 150)
                    } else {
                        RGBColor(205, 205, 205)
                    }
                }
            };
            let x0 = i as f64 * dx;
            let y0 = lo + j as f64 * dy;
            cells.push(Rectangle::new(
                [(x0, y0), (x0 + dx, y0 + dy)],
                colour.filled(),
            ));
        }
    }
    chart.draw_series(cells)?;
    // The lines where contact is possible (u <= cos φ) and inside the chart, as pieces.
    let pieces = |f: &dyn Fn(f64) -> f64| -> Vec<Vec<(f64, f64)>> {
        let mut out: Vec<Vec<(f64, f64)>> = vec![Vec::new()];
        for k in 0..=1440 {
            let ph = f64::from(k) / 1440.0;
            let u = f(TAU * ph);
            if u >= lo && u <= hi && u <= grazing(TAU * ph) + 1e-12 {
                out.last_mut().expect("one piece").push((ph, u));
            } else if out.last().is_some_and(|p| !p.is_empty()) {
                out.push(Vec::new());
            }
        }
        out
    };
    for piece in pieces(&|phi| neutral(e, phi)) {
        plot::thick_line(&mut chart, &piece, NEUTRAL, 2)?;
    }
    for piece in pieces(&grazing) {
        plot::thick_line(&mut chart, &piece, GRAZING, 3)?;
    }
    let r = if impacts.len() > 3000 { 2 } else { 3 };
    let shown = || impacts.iter().filter(|i| i.u >= lo && i.u <= hi);
    chart.draw_series(shown().map(|i| Circle::new((i.phase, i.u), r + 1, WHITE.filled())))?;
    chart.draw_series(shown().map(|i| Circle::new((i.phase, i.u), r, IMPACT.filled())))?;
    colour_bar(&right, vmax, scale)
}

/// The colour bar of ΔK/ΔK0: ticks at round values, on the asinh scale of the colours.
fn colour_bar(area: &Area<'_>, vmax: f64, scale: f64) -> DrawResult {
    let ticks: Vec<(f64, String)> = [
        -100.0, -50.0, -20.0, -10.0, -5.0, -2.0, -1.0, -0.5, 0.0, 0.5, 1.0, 2.0, 5.0, 10.0, 20.0,
        50.0,
    ]
    .into_iter()
    .filter(|v: &f64| *v == 0.0 || v.abs() <= vmax)
    .map(|v| (0.5 * (compress(v) / scale + 1.0), plot::tick(&v)))
    .collect();
    plot::colour_bar(
        area,
        |s| diverging(2.0 * s - 1.0),
        &ticks,
        &["ΔK/ΔK0"],
        &[
            "asinh scale:",
            "asinh(2·ΔK/ΔK0),",
            "linear within ±0.5,",
            "logarithmic beyond",
        ],
    )
}
