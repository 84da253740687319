//! PNG figures of one run: waveform, phase portrait with Poincaré section, energy per impact.
//!
//! Text is drawn with ab_glyph from a TrueType file found at run time ([`ensure_font`]), so no
//! fontconfig is needed: DejaVu Sans (Debian's `fonts-dejavu-core`) or `$BISTABLE_FONT`.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters::style::FontStyle;

use bistable_analysis::Model;
use bistable_core::State;

use crate::error::CliError;
use crate::ranges::Range;

/// The axis of a grid of cells centred on the values of `r`: the values' span padded by half a
/// cell (by 1 % of the value for a single value), and the half-width of a cell on that axis.
pub fn grid_axis(r: Range) -> ((f64, f64), f64) {
    let (lo, hi) = r.bounds();
    let h = if r.n > 1 {
        0.5 * r.step().abs()
    } else {
        0.01 * lo.abs().max(1.0)
    };
    let axis = (lo - h, hi + h);
    (axis, 0.5 * (axis.1 - axis.0) / r.n as f64)
}

const TAU: f64 = std::f64::consts::TAU;
pub(crate) const FONT: &str = "sans-serif";

/// Files tried in order when `$BISTABLE_FONT` is not set.
const FONT_FILES: &[&str] = &[
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu-sans-fonts/DejaVuSans.ttf",
    "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf",
    "/usr/share/fonts/truetype/freefont/FreeSans.ttf",
    "/Library/Fonts/Arial Unicode.ttf",
    "/System/Library/Fonts/Supplemental/Arial.ttf",
];

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

pub(crate) type Area<'a> = DrawingArea<BitMapBackend<'a>, Shift>;
pub(crate) type Chart<'a, 'b> =
    ChartContext<'a, BitMapBackend<'b>, Cartesian2d<RangedCoordf64, RangedCoordf64>>;
pub(crate) type DrawResult = Result<(), Box<dyn std::error::Error>>;
/// A figure: file name, size in pixels, drawing function.
type Figure = (
    &'static str,
    (u32, u32),
    fn(&Area<'_>, &PlotData) -> DrawResult,
);

pub(crate) fn plot_err(path: &Path, e: impl std::fmt::Display) -> CliError {
    CliError::Plot {
        path: path.to_path_buf(),
        message: e.to_string(),
    }
}

/// Registers a TrueType font for all text (once per process).
pub fn ensure_font() -> Result<(), String> {
    static FONT_STATE: OnceLock<Result<(), String>> = OnceLock::new();
    FONT_STATE
        .get_or_init(|| {
            let from_env = std::env::var_os("BISTABLE_FONT").filter(|p| !p.is_empty());
            let candidates: Vec<PathBuf> = match &from_env {
                Some(p) => vec![PathBuf::from(p)],
                None => FONT_FILES.iter().map(PathBuf::from).collect(),
            };
            for path in &candidates {
                let Ok(bytes) = std::fs::read(path) else {
                    continue;
                };
                // The font must live as long as the process: plotters keeps a reference.
                let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
                if plotters::style::register_font(FONT, FontStyle::Normal, bytes).is_ok() {
                    return Ok(());
                }
            }
            Err(match from_env {
                Some(p) => format!(
                    "BISTABLE_FONT = '{}' is not a readable TrueType font",
                    PathBuf::from(p).display()
                ),
                None => "no TrueType font found; install Debian's fonts-dejavu-core or set \
                         BISTABLE_FONT to a .ttf file"
                    .to_string(),
            })
        })
        .clone()
}

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

/// Draws one PNG of `size` pixels on a white background with `draw` (creates missing parent
/// directories; errors name the file).
pub(crate) fn png(
    path: &Path,
    size: (u32, u32),
    draw: impl FnOnce(&Area<'_>) -> DrawResult,
) -> Result<(), CliError> {
    ensure_font().map_err(|e| plot_err(path, e))?;
    crate::output::create_parent(path)?;
    let root = BitMapBackend::new(path, size).into_drawing_area();
    root.fill(&WHITE).map_err(|e| plot_err(path, e))?;
    draw(&root).map_err(|e| plot_err(path, e))?;
    root.present().map_err(|e| plot_err(path, e))
}

/// `(lo, hi)` of the finite values with a relative margin; a small span around a constant.
pub(crate) fn range(values: impl Iterator<Item = f64>, margin: f64) -> (f64, f64) {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    if !lo.is_finite() {
        return (-1.0, 1.0);
    }
    let span = hi - lo;
    if span <= 1e-12 * lo.abs().max(1.0) {
        let d = 0.05 * lo.abs().max(1.0);
        return (lo - d, hi + d);
    }
    (lo - margin * span, hi + margin * span)
}

/// The upper end of a y axis for `groups` (the values drawn at each x) that keeps the data
/// readable when a few groups lie far above the rest: when leaving out the highest values of at
/// most `max(1, groups/20)` groups shrinks the span from `lo` to less than half, the largest
/// value of the others (else the largest of all). `None` when nothing is left out.
pub(crate) fn trimmed_top(groups: &[Vec<f64>], lo: f64) -> Option<f64> {
    let mut tops: Vec<f64> = groups
        .iter()
        .filter_map(|g| {
            g.iter()
                .copied()
                .filter(|v| v.is_finite())
                .fold(None, |a: Option<f64>, v| Some(a.map_or(v, |a| a.max(v))))
        })
        .collect();
    tops.sort_by(|a, b| b.total_cmp(a));
    let all = *tops.first()?;
    let most = (tops.len() / 20).max(1);
    (1..=most.min(tops.len() - 1))
        .map(|k| tops[k])
        .find(|&hi| hi - lo < 0.5 * (all - lo))
}

/// A vertical colour bar in `area` (its left part): `colour(s)` for `s` from 0 (bottom) to 1
/// (top), ticks `(s, label)` on its right, `caption` lines above it and `note` lines below
/// (the scale).
pub(crate) fn colour_bar(
    area: &Area<'_>,
    colour: impl Fn(f64) -> RGBColor,
    ticks: &[(f64, String)],
    caption: &[&str],
    note: &[&str],
) -> DrawResult {
    let (_, h) = area.dim_in_pixel();
    let top = 24 + 20 * caption.len() as i32;
    let bottom = h as i32 - 70 - 18 * note.len() as i32;
    let (x0, x1) = (20i32, 48i32);
    let y_of = |s: f64| bottom - (s.clamp(0.0, 1.0) * f64::from(bottom - top)).round() as i32;
    for y in top..=bottom {
        let s = f64::from(bottom - y) / f64::from((bottom - top).max(1));
        area.draw(&Rectangle::new([(x0, y), (x1, y + 1)], colour(s).filled()))?;
    }
    area.draw(&Rectangle::new(
        [(x0, top), (x1, bottom)],
        RGBColor(60, 60, 60).stroke_width(1),
    ))?;
    let style = left((FONT, 15).into_font().color(&BLACK));
    for (s, text) in ticks {
        let y = y_of(*s);
        area.draw(&PathElement::new(
            [(x1, y), (x1 + 6, y)],
            BLACK.stroke_width(1),
        ))?;
        area.draw(&Text::new(text.clone(), (x1 + 10, y), style.clone()))?;
    }
    for (k, line) in caption.iter().enumerate() {
        area.draw(&Text::new(
            line.to_string(),
            (x0 - 12, 12 + 20 * k as i32),
            left((FONT, 16).into_font().color(&BLACK)),
        ))?;
    }
    for (k, line) in note.iter().enumerate() {
        area.draw(&Text::new(
            line.to_string(),
            (x0 - 12, bottom + 22 + 18 * k as i32),
            left((FONT, 14).into_font().color(&RGBColor(60, 60, 60))),
        ))?;
    }
    Ok(())
}

/// Formats an axis label value without trailing zeros (`0.25`, `10`, `-0.05`).
pub(crate) fn tick(v: &f64) -> String {
    let s = format!("{:.6}", v);
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".to_string()
    } else {
        s.to_string()
    }
}

// ---------------------------------------------------------------------------------------------
// Header: title, subtitle and a legend row above the chart (so the legend never hides data).

/// How a legend entry is drawn.
#[derive(Clone, Copy)]
pub(crate) enum Mark {
    Line(RGBColor, u32),
    Dashed(RGBColor),
    Dot(RGBColor, i32),
    Ring(RGBColor, i32),
    Band(RGBColor),
    /// A line with a dark halo, `dash` = (on, off) pixels or solid.
    Halo(RGBColor, Option<(i32, i32)>),
}

pub(crate) fn centred(style: TextStyle<'_>) -> TextStyle<'_> {
    style.pos(Pos::new(HPos::Center, VPos::Center))
}

pub(crate) fn left(style: TextStyle<'_>) -> TextStyle<'_> {
    style.pos(Pos::new(HPos::Left, VPos::Center))
}

/// Draws the title, subtitle and legend at the top of `root`; returns the area below.
pub(crate) fn header<'a>(
    root: &Area<'a>,
    title: &str,
    subtitle: &str,
    legend: &[(Mark, String)],
) -> Result<Area<'a>, Box<dyn std::error::Error>> {
    let (w, _) = root.dim_in_pixel();
    let label_style: TextStyle<'_> = (FONT, 17).into_font().color(&BLACK);
    // Flow layout of the legend entries into rows.
    const MARK_W: i32 = 30;
    const GAP: i32 = 34;
    let max_w = w as i32 - 80;
    let mut rows: Vec<Vec<(Mark, &str, i32)>> = vec![Vec::new()];
    let mut row_w = 0;
    for (mark, text) in legend {
        let tw = root.estimate_text_size(text, &label_style)?.0 as i32;
        let ew = MARK_W + 8 + tw;
        let cur = rows.last_mut().expect("one row");
        if !cur.is_empty() && row_w + GAP + ew > max_w {
            rows.push(Vec::new());
            row_w = 0;
        }
        let cur = rows.last_mut().expect("one row");
        if !cur.is_empty() {
            row_w += GAP;
        }
        row_w += ew;
        cur.push((*mark, text.as_str(), ew));
    }
    let n_rows = if legend.is_empty() { 0 } else { rows.len() };
    let height = 64 + 28 * n_rows as u32 + 6;
    let (top, rest) = root.split_vertically(height);
    let centre = (w / 2) as i32;
    top.draw(&Text::new(
        title.to_string(),
        (centre, 18),
        centred((FONT, 25).into_font().color(&BLACK)),
    ))?;
    top.draw(&Text::new(
        subtitle.to_string(),
        (centre, 46),
        centred((FONT, 17).into_font().color(&RGBColor(70, 70, 70))),
    ))?;
    for (r, row) in rows.iter().enumerate().take(n_rows) {
        let total: i32 = row.iter().map(|e| e.2).sum::<i32>() + GAP * (row.len() as i32 - 1);
        let mut x = centre - total / 2;
        let y = 78 + 28 * r as i32;
        for &(mark, text, ew) in row {
            draw_mark(&top, mark, x, y)?;
            top.draw(&Text::new(
                text.to_string(),
                (x + MARK_W + 8, y),
                left(label_style.clone()),
            ))?;
            x += ew + GAP;
        }
    }
    Ok(rest)
}

fn draw_mark(area: &Area<'_>, mark: Mark, x: i32, y: i32) -> DrawResult {
    match mark {
        Mark::Line(c, w) => area.draw(&PathElement::new(
            [(x, y), (x + 30, y)],
            c.stroke_width(w.max(2)),
        ))?,
        Mark::Dashed(c) => {
            for k in 0..3 {
                area.draw(&PathElement::new(
                    [(x + 11 * k, y), (x + 11 * k + 7, y)],
                    c.stroke_width(2),
                ))?;
            }
        }
        Mark::Dot(c, r) => area.draw(&Circle::new((x + 15, y), r, c.filled()))?,
        Mark::Ring(c, r) => area.draw(&Circle::new((x + 15, y), r, c.stroke_width(2)))?,
        Mark::Band(c) => area.draw(&Rectangle::new(
            [(x + 2, y - 8), (x + 28, y + 8)],
            c.mix(0.35).filled(),
        ))?,
        Mark::Halo(c, dash) => {
            area.draw(&Rectangle::new(
                [(x - 2, y - 8), (x + 32, y + 8)],
                RGBColor(150, 150, 150).filled(),
            ))?;
            halo_segments(area, &[(x, y), (x + 30, y)], c, dash)?;
        }
    }
    Ok(())
}

/// A polyline in pixel coordinates, 2 px wide in `c` over a 4 px dark halo, dashed as
/// `(on, off)` pixels or solid.
pub(crate) fn halo_segments(
    area: &Area<'_>,
    pts: &[(i32, i32)],
    c: RGBColor,
    dash: Option<(i32, i32)>,
) -> DrawResult {
    let pieces: Vec<[(i32, i32); 2]> = match dash {
        None => pts.windows(2).map(|w| [w[0], w[1]]).collect(),
        Some((on, off)) => dashes(pts, on, off),
    };
    for (colour, width) in [(RGBColor(25, 25, 25), 5), (c, 2)] {
        for seg in &pieces {
            area.draw(&PathElement::new(seg.to_vec(), colour.stroke_width(width)))?;
        }
    }
    Ok(())
}

/// Cuts a polyline into dashes of `on` pixels separated by `off` pixels.
fn dashes(pts: &[(i32, i32)], on: i32, off: i32) -> Vec<[(i32, i32); 2]> {
    let mut out = Vec::new();
    let period = f64::from(on + off);
    let mut walked = 0.0;
    for w in pts.windows(2) {
        let (a, b) = (
            (f64::from(w[0].0), f64::from(w[0].1)),
            (f64::from(w[1].0), f64::from(w[1].1)),
        );
        let len = (b.0 - a.0).hypot(b.1 - a.1);
        if len == 0.0 {
            continue;
        }
        let at = |d: f64| {
            let s = (d / len).clamp(0.0, 1.0);
            (
                (a.0 + s * (b.0 - a.0)).round() as i32,
                (a.1 + s * (b.1 - a.1)).round() as i32,
            )
        };
        let mut d = -(walked % period);
        while d < len {
            let (s, e) = (d.max(0.0), (d + f64::from(on)).min(len));
            if e > s {
                out.push([at(s), at(e)]);
            }
            d += period;
        }
        walked += len;
    }
    out
}

// ---------------------------------------------------------------------------------------------
// Chart helpers.

pub(crate) fn chart<'a, 'b>(
    area: &'a Area<'b>,
    x: (f64, f64),
    y: (f64, f64),
    x_desc: &str,
    y_desc: &str,
    caption: Option<&str>,
) -> Result<Chart<'a, 'b>, Box<dyn std::error::Error>> {
    let mut builder = ChartBuilder::on(area);
    builder
        .margin(10)
        .margin_right(36)
        .x_label_area_size(58)
        .y_label_area_size(92);
    if let Some(c) = caption {
        builder.caption(c, (FONT, 18).into_font().color(&RGBColor(50, 50, 50)));
    }
    let mut chart = builder.build_cartesian_2d(x.0..x.1, y.0..y.1)?;
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc(y_desc)
        .x_label_formatter(&tick)
        .y_label_formatter(&tick)
        .axis_desc_style((FONT, 20))
        .label_style((FONT, 16))
        .light_line_style(RGBColor(244, 244, 244))
        .bold_line_style(RGBColor(220, 220, 220))
        .draw()?;
    Ok(chart)
}

/// Drops points closer than about a pixel to the previous kept one (keeps the last point).
fn thin(chart: &Chart<'_, '_>, pts: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let mut out: Vec<(f64, f64)> = Vec::with_capacity(pts.len().min(100_000));
    let mut last_px: Option<(i32, i32)> = None;
    for (i, p) in pts.iter().enumerate() {
        let px = chart.backend_coord(p);
        let keep = match last_px {
            None => true,
            Some(q) => (px.0 - q.0).abs() + (px.1 - q.1).abs() >= 1 || i + 1 == pts.len(),
        };
        if keep {
            out.push(*p);
            last_px = Some(px);
        }
    }
    out
}

/// A polyline `width` pixels wide, drawn as one-pixel lines shifted by whole pixels (plotters'
/// own wide lines break up into dots on dense curves).
pub(crate) fn thick_line(
    chart: &mut Chart<'_, '_>,
    pts: &[(f64, f64)],
    color: RGBColor,
    width: u32,
) -> DrawResult {
    let pts = thin(chart, pts);
    let (w, h) = chart.plotting_area().dim_in_pixel();
    let (xr, yr) = (chart.x_range(), chart.y_range());
    let dx = (xr.end - xr.start) / f64::from(w.max(1));
    let dy = (yr.end - yr.start) / f64::from(h.max(1));
    let offsets: &[(f64, f64)] = match width {
        0 | 1 => &[(0.0, 0.0)],
        2 => &[(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)],
        _ => &[(0.0, 0.0), (1.0, 0.0), (-1.0, 0.0), (0.0, 1.0), (0.0, -1.0)],
    };
    for &(ox, oy) in offsets {
        chart.draw_series(LineSeries::new(
            pts.iter().map(|&(x, y)| (x + ox * dx, y + oy * dy)),
            color.stroke_width(1),
        ))?;
    }
    Ok(())
}

/// A thin dashed polyline of `on`/`off` pixels whose pattern runs on along the whole line (a
/// dense curve of short segments stays dashed).
pub(crate) fn dashed_line(
    chart: &mut Chart<'_, '_>,
    pts: &[(f64, f64)],
    color: RGBColor,
    (on, off): (i32, i32),
) -> DrawResult {
    let area = chart.plotting_area().strip_coord_spec();
    let base = chart.plotting_area().get_base_pixel();
    let px: Vec<(i32, i32)> = pts
        .iter()
        .map(|p| {
            let (x, y) = chart.backend_coord(p);
            (x - base.0, y - base.1)
        })
        .collect();
    for seg in dashes(&px, on, off) {
        area.draw(&PathElement::new(seg.to_vec(), color.stroke_width(1)))?;
    }
    Ok(())
}

pub(crate) fn hline(chart: &mut Chart<'_, '_>, y: f64, color: RGBColor) -> DrawResult {
    let xr = chart.x_range();
    chart.draw_series(DashedLineSeries::new(
        [(xr.start, y), (xr.end, y)],
        8,
        6,
        color.stroke_width(1),
    ))?;
    Ok(())
}

pub(crate) fn vline(chart: &mut Chart<'_, '_>, x: f64, color: RGBColor) -> DrawResult {
    let yr = chart.y_range();
    chart.draw_series(DashedLineSeries::new(
        [(x, yr.start), (x, yr.end)],
        8,
        6,
        color.stroke_width(1),
    ))?;
    Ok(())
}

/// Short description of a model for titles: `Ω = 1.75, V = 0.07, ζ = 0.02, e = 0.85`.
pub(crate) fn label(m: &Model) -> String {
    format!(
        "Ω = {}, V = {}, ζ = {}, e = {}",
        m.omega(),
        m.velocity(),
        m.params.zeta(),
        m.restitution()
    )
}

/// `1 impact`, `2 impacts`.
pub(crate) fn plural(n: u64, what: &str) -> String {
    if n == 1 {
        format!("1 {what}")
    } else {
        format!("{n} {what}s")
    }
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
        (Mark::Ring(IMPACT, 4), "impacts".to_string()),
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

/// The colour a fraction `s ∈ [0, 1]` of the way from `a` to `b`.
pub(crate) fn mix(a: RGBColor, b: RGBColor, s: f64) -> RGBColor {
    let m = |p: u8, q: u8| (f64::from(p) + s * (f64::from(q) - f64::from(p))).round() as u8;
    RGBColor(m(a.0, b.0), m(a.1, b.1), m(a.2, b.2))
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_few_far_points_are_left_out_of_the_axis_range() {
        // 40 parameter values in [0, 0.2], one at rest in well 2 (x = 1).
        let mut groups: Vec<Vec<f64>> = (0..40).map(|k| vec![0.005 * f64::from(k)]).collect();
        groups.push(vec![1.0, 1.0]);
        assert_eq!(trimmed_top(&groups, 0.0), Some(0.195));
        // Spread data: nothing left out.
        let spread: Vec<Vec<f64>> = (0..40).map(|k| vec![f64::from(k) / 39.0]).collect();
        assert_eq!(trimmed_top(&spread, 0.0), None);
        // More far groups than 1 in 20: they are data, not outliers.
        let mut many = groups.clone();
        many.extend((0..5).map(|_| vec![1.0]));
        assert_eq!(trimmed_top(&many, 0.0), None);
        assert_eq!(trimmed_top(&[], 0.0), None);
        assert_eq!(trimmed_top(&[vec![1.0]], 0.0), None);
    }
}
