//! The figures of `bistable simulate`: waveform, phase portrait with Poincaré section, energy
//! per impact.

use std::path::{Path, PathBuf};

use plotters::prelude::*;

use bistable_analysis::Model;
use bistable_core::State;

use super::{
    chart, colour_bar, ensure_font, header, hline, label, mix, plot_err, plural, png, range,
    thick_line, vline, Area, DrawResult, Mark,
};
use crate::error::CliError;

const TAU: f64 = std::f64::consts::TAU;

// Colours.
const MASS: RGBColor = RGBColor(31, 87, 165);
const MASS_LIGHT: RGBColor = RGBColor(160, 185, 220);
const PLATE: RGBColor = RGBColor(230, 120, 20);
const IMPACT: RGBColor = RGBColor(200, 20, 30);
const POINCARE_LIGHT: RGBColor = RGBColor(240, 150, 150);
const GUIDE: RGBColor = RGBColor(90, 90, 90);
const STICK: RGBColor = RGBColor(60, 170, 90);
const EARLY: RGBColor = RGBColor(245, 190, 40);
const MIDDLE: RGBColor = RGBColor(215, 50, 70);
const LATE: RGBColor = RGBColor(45, 20, 110);

/// One sample of the run, from the dense output.
#[derive(Debug, Clone, Copy)]
pub struct Sample {
    /// Time.
    pub t: f64,
    /// Mass position.
    pub x: f64,
    /// Mass velocity.
    pub v: f64,
    /// Plate position.
    pub z: f64,
}

impl Sample {
    /// The sample of a state.
    pub fn from_state(s: &State) -> Self {
        Self {
            t: s.t,
            x: s.x,
            v: s.v,
            z: s.z,
        }
    }
}

/// Everything the figures need.
pub struct PlotData {
    /// Parameters (for titles and `ΔK0`).
    pub model: Model,
    /// End of the run.
    pub t_end: f64,
    /// Start of the plotted part (0 unless the run is long).
    pub window_start: f64,
    /// Regular samples over `[window_start, t_end]`.
    pub samples: Vec<Sample>,
    /// Impacts in the window: `(t, x, v_before, v_after)`.
    pub impacts: Vec<(f64, f64, f64, f64)>,
    /// Sticking intervals that reach into the window: `(start, end)`, end `None` if still open.
    pub sticking: Vec<(f64, Option<f64>)>,
    /// `(x, v)` at `τ = k·2π/Ω` in the window.
    pub poincare: Vec<(f64, f64)>,
    /// The last impacts of the run: `(index, t, phase in cycles, ΔK/ΔK0)`.
    pub energy: Vec<(u64, f64, f64, f64)>,
    /// All impacts of the run.
    pub total_impacts: u64,
}

/// A figure: file name, size in pixels, drawing function.
type Figure = (
    &'static str,
    (u32, u32),
    fn(&Area<'_>, &PlotData) -> DrawResult,
);

/// Draws the three figures into `dir` and returns their paths.
pub fn draw_all(dir: &Path, data: &PlotData) -> Result<Vec<PathBuf>, CliError> {
    ensure_font().map_err(|e| plot_err(dir, e))?;
    let figures: [Figure; 3] = [
        ("waveform.png", (1500, 950), waveform),
        ("phase_portrait.png", (1050, 900), phase_portrait),
        ("energy_per_impact.png", (1050, 750), energy_per_impact),
    ];
    let mut out = Vec::new();
    for (name, size, draw) in figures {
        let path = dir.join(name);
        png(&path, size, |root| draw(root, data))?;
        out.push(path);
    }
    Ok(out)
}

/// The window, in words, for subtitles.
fn window_note(data: &PlotData) -> String {
    if data.window_start > 0.0 {
        format!(
            "last part of the run, τ/2π ∈ [{:.1}, {:.1}] (of {:.1} natural periods)",
            data.window_start / TAU,
            data.t_end / TAU,
            data.t_end / TAU
        )
    } else {
        format!("whole run, τ/2π ∈ [0, {:.2}]", data.t_end / TAU)
    }
}

/// The regular samples with the impacts merged in, in time order: at an impact the mass is at
/// `x` with velocity `v_before` and then `v_after` (a vertical jump in the phase plane).
fn merged(data: &PlotData) -> Vec<Sample> {
    let mut pts: Vec<(f64, u8, Sample)> = data.samples.iter().map(|s| (s.t, 2, *s)).collect();
    for &(t, x, vb, va) in &data.impacts {
        pts.push((t, 0, Sample { t, x, v: vb, z: x }));
        pts.push((t, 1, Sample { t, x, v: va, z: x }));
    }
    pts.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    pts.into_iter().map(|p| p.2).collect()
}

// ---------------------------------------------------------------------------------------------
// The figures.

fn waveform(root: &Area<'_>, data: &PlotData) -> DrawResult {
    let ts = data.model.shaker_period();
    let span = data.t_end - data.window_start;
    // A detail panel with the last few shaker periods, when the window is much longer.
    let detail_len = ((4.0 * ts).max(2.0 * TAU) / ts).ceil() * ts;
    let detail = detail_len < 0.6 * span;
    let pts = merged(data);
    let (ylo, yhi) = range(pts.iter().flat_map(|s| [s.x, s.z]), 0.06);
    let show_barrier = ylo < 0.5 && yhi > 0.45;
    let mut legend = vec![
        (Mark::Line(MASS, 2), "mass x(τ)".to_string()),
        (
            Mark::Line(PLATE, 2),
            "plate z(τ) = (V/Ω)·sin(Ωτ)".to_string(),
        ),
        (Mark::Ring(IMPACT, 4, 2), "impacts".to_string()),
    ];
    if !data.sticking.is_empty() {
        legend.push((Mark::Band(STICK), "sticking to the plate".to_string()));
    }
    if show_barrier {
        legend.push((Mark::Dashed(GUIDE), "barrier x = ½".to_string()));
    }
    let area = header(
        root,
        &format!("Waveform — {}", label(&data.model)),
        &format!(
            "{}; {} in view, {} in the run",
            window_note(data),
            plural(data.impacts.len() as u64, "impact"),
            data.total_impacts
        ),
        &legend,
    )?;
    if detail {
        let (_, h) = area.dim_in_pixel();
        let (upper, lower) = area.split_vertically(h * 55 / 100);
        waveform_panel(&upper, data, &pts, data.window_start, None)?;
        waveform_panel(
            &lower,
            data,
            &pts,
            data.t_end - detail_len,
            Some(format!(
                "detail: the last {:.0} shaker periods (2π/Ω = {:.4})",
                detail_len / ts,
                ts
            )),
        )?;
    } else {
        waveform_panel(&area, data, &pts, data.window_start, None)?;
    }
    Ok(())
}

fn waveform_panel(
    area: &Area<'_>,
    data: &PlotData,
    all: &[Sample],
    from: f64,
    caption: Option<String>,
) -> DrawResult {
    let first = all.partition_point(|s| s.t < from);
    let pts = &all[first.saturating_sub(1)..];
    let t0 = from / TAU;
    let t1 = (data.t_end / TAU).max(t0 + 1e-9);
    let (mut ylo, mut yhi) = range(pts.iter().flat_map(|s| [s.x, s.z]), 0.06);
    let show_barrier = ylo < 0.5 && yhi > 0.45;
    if show_barrier {
        ylo = ylo.min(0.45);
        yhi = yhi.max(0.55);
    }
    let mut chart = chart(
        area,
        (t0, t1),
        (ylo, yhi),
        "τ/2π (natural periods)",
        "x, z (units of Δx)",
        caption.as_deref(),
    )?;
    for &(a, b) in &data.sticking {
        let (a, b) = (a.max(from) / TAU, b.unwrap_or(data.t_end) / TAU);
        if b > a {
            chart.draw_series([Rectangle::new(
                [(a, ylo), (b, yhi)],
                STICK.mix(0.35).filled(),
            )])?;
        }
    }
    if show_barrier {
        hline(&mut chart, 0.5, GUIDE)?;
    }
    let z: Vec<(f64, f64)> = pts.iter().map(|s| (s.t / TAU, s.z)).collect();
    thick_line(&mut chart, &z, PLATE, 1)?;
    let x: Vec<(f64, f64)> = pts.iter().map(|s| (s.t / TAU, s.x)).collect();
    thick_line(&mut chart, &x, MASS, 2)?;
    let marks: Vec<(f64, f64)> = data
        .impacts
        .iter()
        .filter(|i| i.0 >= from)
        .map(|&(t, x, _, _)| (t / TAU, x))
        .collect();
    let r = if marks.len() > 2000 { 2 } else { 4 };
    chart.draw_series(
        marks
            .iter()
            .map(|&p| Circle::new(p, r, IMPACT.stroke_width(1))),
    )?;
    Ok(())
}

/// Start of the "late" part of the window, drawn in strong colours in the phase portrait: the
/// last quarter of the window, at least 5 shaker periods. `None` when that is most of it.
fn late_start(data: &PlotData) -> Option<f64> {
    let span = data.t_end - data.window_start;
    let len = (0.25 * span).max(5.0 * data.model.shaker_period());
    (len < 0.7 * span).then_some(data.t_end - len)
}

fn phase_portrait(root: &Area<'_>, data: &PlotData) -> DrawResult {
    let ts = data.model.shaker_period();
    let split = late_start(data);
    let pts = merged(data);
    let (xlo, xhi) = range(pts.iter().map(|s| s.x), 0.06);
    let (vlo, vhi) = range(pts.iter().map(|s| s.v), 0.06);
    let show_barrier = xlo < 0.5 && xhi > 0.5;
    let n_late = split.map_or(data.poincare.len(), |s| {
        data.poincare
            .iter()
            .zip(poincare_times(data))
            .filter(|(_, t)| *t >= s)
            .count()
    });
    let cut = data.poincare.len() - n_late;
    let mut legend = Vec::new();
    match split {
        Some(s) => {
            legend.push((
                Mark::Line(MASS_LIGHT, 2),
                format!("trajectory, τ/2π ≤ {:.1}", s / TAU),
            ));
            legend.push((
                Mark::Line(MASS, 2),
                format!("last {:.0} shaker periods", (data.t_end - s) / ts),
            ));
        }
        None => legend.push((Mark::Line(MASS, 2), "trajectory".to_string())),
    }
    if cut > 0 {
        legend.push((
            Mark::Dot(POINCARE_LIGHT, 3),
            "Poincaré points before".to_string(),
        ));
    }
    legend.push((
        Mark::Dot(IMPACT, 5),
        format!("Poincaré section: plate phase 0 ({n_late} points)"),
    ));
    if show_barrier {
        legend.push((Mark::Dashed(GUIDE), "barrier x = ½".to_string()));
    }
    let area = header(
        root,
        &format!("Phase portrait — {}", label(&data.model)),
        &format!(
            "{}; Poincaré section: the state at τ = k·2π/Ω",
            window_note(data)
        ),
        &legend,
    )?;
    let mut chart = chart(
        &area,
        (xlo, xhi),
        (vlo, vhi),
        "x (units of Δx)",
        "v = dx/dτ (units of ω0·Δx)",
        None,
    )?;
    if show_barrier {
        vline(&mut chart, 0.5, GUIDE)?;
    }
    match split {
        Some(s) => {
            let k = pts.partition_point(|p| p.t < s);
            let early: Vec<(f64, f64)> = pts[..(k + 1).min(pts.len())]
                .iter()
                .map(|p| (p.x, p.v))
                .collect();
            let late: Vec<(f64, f64)> = pts[k..].iter().map(|p| (p.x, p.v)).collect();
            thick_line(&mut chart, &early, MASS_LIGHT, 1)?;
            thick_line(&mut chart, &late, MASS, 2)?;
        }
        None => {
            let all: Vec<(f64, f64)> = pts.iter().map(|p| (p.x, p.v)).collect();
            thick_line(&mut chart, &all, MASS, 2)?;
        }
    }
    chart.draw_series(
        data.poincare[..cut]
            .iter()
            .map(|&(x, v)| Circle::new((x, v), 3, POINCARE_LIGHT.filled())),
    )?;
    let r = match n_late {
        0..=60 => 5,
        61..=400 => 4,
        _ => 3,
    };
    chart.draw_series(
        data.poincare[cut..]
            .iter()
            .map(|&(x, v)| Circle::new((x, v), r, IMPACT.filled())),
    )?;
    Ok(())
}

/// The instants of the Poincaré points: the multiples of the shaker period in the window.
fn poincare_times(data: &PlotData) -> impl Iterator<Item = f64> {
    let ts = data.model.shaker_period();
    let k0 = (data.window_start / ts).ceil();
    (0..).map(move |k| (k0 + f64::from(k)) * ts)
}

/// Colour for the fraction `s ∈ [0, 1]` of the run: yellow, red, dark violet.
pub(crate) fn ramp(s: f64) -> RGBColor {
    let s = s.clamp(0.0, 1.0);
    if s < 0.5 {
        mix(EARLY, MIDDLE, 2.0 * s)
    } else {
        mix(MIDDLE, LATE, 2.0 * s - 1.0)
    }
}

/// ΔK/ΔK0 against the impact phase, coloured by time (Fig. 5 of the paper).
fn energy_per_impact(root: &Area<'_>, data: &PlotData) -> DrawResult {
    let n = data.energy.len();
    let dk0 = data.model.delta_k0();
    let subtitle = match (data.energy.first(), data.energy.last()) {
        (Some(first), Some(last)) if (n as u64) < data.total_impacts => format!(
            "impacts {} to {} (the last {n} of {}); ΔK0 = ½((1+e)V)² = {:.4e}",
            first.0, last.0, data.total_impacts, dk0
        ),
        _ => format!(
            "all {} impacts of the run; ΔK0 = ½((1+e)V)² = {:.4e} (Eq. 11)",
            data.total_impacts, dk0
        ),
    };
    // Colour by time, from the first plotted impact to the last.
    let (t_first, t_last) = match (data.energy.first(), data.energy.last()) {
        (Some(a), Some(b)) => (a.1, b.1),
        _ => (0.0, 1.0),
    };
    let t_span = (t_last - t_first).max(f64::MIN_POSITIVE);
    let legend = vec![
        (
            Mark::Dot(ramp(0.5), 5),
            "one impact, coloured by its time (colour bar)".to_string(),
        ),
        (
            Mark::Dashed(BLACK),
            "ΔK = 0 (above: the impact adds energy)".to_string(),
        ),
    ];
    let area = header(
        root,
        &format!("Energy per impact — {}", label(&data.model)),
        &subtitle,
        &legend,
    )?;
    let (w, _) = area.dim_in_pixel();
    let (area, bar) = area.split_horizontally(w - 170);
    let ticks: Vec<(f64, String)> = (0..=4)
        .map(|k| {
            let s = f64::from(k) / 4.0;
            (s, format!("{:.1}", (t_first + s * t_span) / TAU))
        })
        .collect();
    colour_bar(
        &bar,
        ramp,
        &ticks,
        &["time of the impact", "τ/2π (natural periods)"],
        &["linear scale, first to", "last impact plotted"],
    )?;
    let (mut ylo, mut yhi) = range(data.energy.iter().map(|e| e.3).chain([0.0]), 0.08);
    if yhi - ylo < 0.2 {
        let mid = 0.5 * (yhi + ylo);
        ylo = mid - 0.1;
        yhi = mid + 0.1;
    }
    let mut chart = chart(
        &area,
        (0.0, 1.0),
        (ylo, yhi),
        "impact phase φ/2π (cycles)",
        "ΔK/ΔK0",
        None,
    )?;
    hline(&mut chart, 0.0, BLACK)?;
    let r = match n {
        0..=1000 => 4,
        1001..=10_000 => 3,
        _ => 2,
    };
    chart.draw_series(
        data.energy
            .iter()
            .filter(|e| e.2.is_finite())
            .map(|&(_, t, ph, k)| Circle::new((ph, k), r, ramp((t - t_first) / t_span).filled())),
    )?;
    Ok(())
}
