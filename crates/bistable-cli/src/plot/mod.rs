//! PNG figures: the helpers every command's drawing uses (the PNG file and its font, a header
//! with title, subtitle and legend, charts and axes, value ranges, colour bars, lines and
//! colours). Each command draws its own figures: `simulate`'s are in [`simulate`], the others'
//! in the command's module (`map.rs`, `basins.rs`, `diagram.rs`, …).
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

use bistable_analysis::thresholds::{interwell, quasi_static, single_impact};
use bistable_analysis::Model;

use crate::error::CliError;
use crate::ranges::Range;

mod simulate;

pub use simulate::{draw_all, PlotData, Sample};

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

pub(crate) type Area<'a> = DrawingArea<BitMapBackend<'a>, Shift>;
pub(crate) type Chart<'a, 'b> =
    ChartContext<'a, BitMapBackend<'b>, Cartesian2d<RangedCoordf64, RangedCoordf64>>;
pub(crate) type DrawResult = Result<(), Box<dyn std::error::Error>>;

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
    /// A circle of radius `r` px drawn `w` px wide.
    Ring(RGBColor, i32, u32),
    /// A filled square (12 px).
    Square(RGBColor),
    /// A filled triangle.
    Triangle(RGBColor),
    /// A cross.
    Cross(RGBColor),
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

/// Draws the marker `mark` at the data point `at` of `chart`, as its legend entry shows it
/// (the point markers: dot, ring, square, triangle, cross; the line-like marks draw nothing).
pub(crate) fn draw_point(chart: &mut Chart<'_, '_>, at: (f64, f64), mark: Mark) -> DrawResult {
    match mark {
        Mark::Dot(c, r) => chart.draw_series([Circle::new(at, r, c.filled())])?,
        Mark::Ring(c, r, w) => chart.draw_series([Circle::new(at, r, c.stroke_width(w))])?,
        Mark::Square(c) => chart
            .draw_series([EmptyElement::at(at) + Rectangle::new([(-6, -6), (6, 6)], c.filled())])?,
        Mark::Triangle(c) => chart.draw_series([TriangleMarker::new(at, 8, c.filled())])?,
        Mark::Cross(c) => chart.draw_series([Cross::new(at, 7, c.stroke_width(3))])?,
        Mark::Line(..) | Mark::Dashed(_) | Mark::Band(_) | Mark::Halo(..) => return Ok(()),
    };
    Ok(())
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
        Mark::Ring(c, r, w) => area.draw(&Circle::new((x + 15, y), r, c.stroke_width(w)))?,
        Mark::Square(c) => area.draw(&Rectangle::new(
            [(x + 9, y - 6), (x + 21, y + 6)],
            c.filled(),
        ))?,
        Mark::Triangle(c) => area.draw(&TriangleMarker::new((x + 15, y), 8, c.filled()))?,
        Mark::Cross(c) => area.draw(&Cross::new((x + 15, y), 7, c.stroke_width(3)))?,
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

/// A figure over a grid of cells `xs × ys` in `area`: a chart with the axes of [`grid_axis`]
/// on the left and a side panel `panel` pixels wide on the right (for the legend). `draw` gets
/// the chart, the panel and, for each axis, its range and the half-width of a cell.
pub(crate) fn grid_figure(
    area: &Area<'_>,
    panel: u32,
    (xs, ys): (Range, Range),
    (x_desc, y_desc): (&str, &str),
    draw: impl FnOnce(&mut Chart<'_, '_>, &Area<'_>, [((f64, f64), f64); 2]) -> DrawResult,
) -> DrawResult {
    let (w, _) = area.dim_in_pixel();
    let (left, right) = area.split_horizontally(w - panel);
    let (x, y) = (grid_axis(xs), grid_axis(ys));
    let mut chart = chart(&left, x.0, y.0, x_desc, y_desc, None)?;
    draw(&mut chart, &right, [x, y])
}

/// The cell of a grid figure centred on `(x, y)` with half-widths `(hx, hy)`, filled with `fill`.
pub(crate) fn cell(
    (x, y): (f64, f64),
    (hx, hy): (f64, f64),
    fill: RGBColor,
) -> Rectangle<(f64, f64)> {
    Rectangle::new([(x - hx, y - hy), (x + hx, y + hy)], fill.filled())
}

/// An entry of a side panel's legend at height `y`: a swatch of `fill`, `label` beside it and
/// `note` below the label in a smaller font (`note_size` pixels, `note_colour`).
pub(crate) fn swatch(
    area: &Area<'_>,
    y: i32,
    fill: RGBColor,
    label: String,
    (note, note_size, note_colour): (String, u32, RGBColor),
) -> DrawResult {
    let text = |size| (FONT, size).into_font().color(&BLACK);
    area.draw(&Rectangle::new([(14, y - 11), (36, y + 11)], fill.filled()))?;
    area.draw(&Text::new(label, (46, y - 1), left(text(15))))?;
    area.draw(&Text::new(
        note,
        (46, y + 17),
        left(text(note_size).color(&note_colour)),
    ))?;
    Ok(())
}

/// The `i`-th of 20 distinct colours for categories (attractors, branches), repeating after
/// that: the ten of Vega's `category10`, then their light tints.
pub(crate) fn category_colour(i: usize) -> RGBColor {
    const PALETTE: [RGBColor; 20] = [
        RGBColor(31, 119, 180),
        RGBColor(255, 127, 14),
        RGBColor(44, 160, 44),
        RGBColor(214, 39, 40),
        RGBColor(148, 103, 189),
        RGBColor(140, 86, 75),
        RGBColor(227, 119, 194),
        RGBColor(127, 127, 127),
        RGBColor(188, 189, 34),
        RGBColor(23, 190, 207),
        RGBColor(174, 199, 232),
        RGBColor(255, 187, 120),
        RGBColor(152, 223, 138),
        RGBColor(255, 152, 150),
        RGBColor(197, 176, 213),
        RGBColor(196, 156, 148),
        RGBColor(247, 182, 210),
        RGBColor(199, 199, 199),
        RGBColor(219, 219, 141),
        RGBColor(158, 218, 229),
    ];
    PALETTE[i % PALETTE.len()]
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

// ---------------------------------------------------------------------------------------------
// The thresholds of Eq. 16–18 over an (Ω, V) chart (`map`, `atlas`).

const LINE_SINGLE: RGBColor = RGBColor(255, 255, 255);
const LINE_INTERWELL: RGBColor = RGBColor(0, 225, 255);
const LINE_QUASI: RGBColor = RGBColor(255, 230, 0);

/// The legend entries of the thresholds of Eq. 16–18 for restitution `e` (as
/// [`draw_thresholds`] draws them).
pub(crate) fn threshold_legend(e: f64) -> Vec<(Mark, String)> {
    vec![
        (
            Mark::Halo(LINE_SINGLE, None),
            format!("single impact V = 1/(4(1+e)) = {:.4}", single_impact(e)),
        ),
        (
            Mark::Halo(LINE_INTERWELL, Some((10, 6))),
            format!("interwell V = (1−e)/(2(1+e)) = {:.4}", interwell(e)),
        ),
        (
            Mark::Halo(LINE_QUASI, Some((3, 4))),
            "quasi-static V = Ω/2".to_string(),
        ),
    ]
}

/// The thresholds of Eq. 16–18 for restitution `e` on an (Ω, V) `chart` drawn in `root`:
/// haloed lines clipped to the chart, the horizontal ones named at their right end.
pub(crate) fn draw_thresholds(root: &Area<'_>, chart: &Chart<'_, '_>, e: f64) -> DrawResult {
    let to_px = |p: (f64, f64)| chart.backend_coord(&p);
    let (xr, yr) = (chart.x_range(), chart.y_range());
    let (x0, x1, y0, y1) = (xr.start, xr.end, yr.start, yr.end);
    let mut labels = Vec::new();
    for (v, colour, dash, name) in [
        (single_impact(e), LINE_SINGLE, None, "single impact"),
        (interwell(e), LINE_INTERWELL, Some((10, 6)), "interwell"),
    ] {
        if v > y0 && v < y1 {
            halo_segments(root, &[to_px((x0, v)), to_px((x1, v))], colour, dash)?;
            labels.push((to_px((x1, v)), name));
        }
    }
    // V = Ω/2 from where it enters the chart to where it leaves.
    let a = x0.max(2.0 * y0);
    let b = x1.min(2.0 * y1);
    if b > a {
        halo_segments(
            root,
            &[to_px((a, quasi_static(a))), to_px((b, quasi_static(b)))],
            LINE_QUASI,
            Some((3, 4)),
        )?;
    }
    for ((px, py), name) in labels {
        let style = left((FONT, 16).into_font().color(&BLACK));
        let text = format!("{name} ");
        let (tw, _) = root.estimate_text_size(&text, &style)?;
        let x = px - tw as i32 - 8;
        root.draw(&Rectangle::new(
            [(x - 4, py - 22), (x + tw as i32 + 2, py - 4)],
            WHITE.mix(0.85).filled(),
        ))?;
        root.draw(&Text::new(text, (x, py - 13), style))?;
    }
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

/// The colour a fraction `s ∈ [0, 1]` of the way from `a` to `b`.
pub(crate) fn mix(a: RGBColor, b: RGBColor, s: f64) -> RGBColor {
    let m = |p: u8, q: u8| (f64::from(p) + s * (f64::from(q) - f64::from(p))).round() as u8;
    RGBColor(m(a.0, b.0), m(a.1, b.1), m(a.2, b.2))
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
