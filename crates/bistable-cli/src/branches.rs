//! Branches of periodic orbits (computed by `bistable_analysis::branches`) written as CSV rows
//! and drawn over a chart: stable thick and solid, unstable thin and dashed.

use std::collections::HashSet;

use plotters::prelude::*;

use bistable_analysis::branches::Branches;

use crate::error::CliError;
use crate::output::{CsvFile, Field};
use crate::plot::{dashed_line, thick_line, Chart, DrawResult};

/// Header of the orbits CSV.
pub const CSV_HEADER: &str = "omega,velocity,period,stable,x0,v0,max_x,cycle_max,\
multiplier_1_re,multiplier_1_im,multiplier_2_re,multiplier_2_im,abs_multiplier,impacts,\
snap_throughs,sticks";

/// Writes one row per orbit (`cycle_max`: the per-cycle maxima joined by `;`).
pub fn write_csv(csv: &mut CsvFile, branches: &[Branches]) -> Result<(), CliError> {
    for b in branches {
        for o in b.slots.iter().flatten() {
            let p = &o.orbit;
            let cycle_max = o
                .cycle_max
                .iter()
                .map(|&x| crate::output::num(x))
                .collect::<Vec<_>>()
                .join(";");
            csv.row(&[
                Field::F(p.omega),
                Field::F(p.velocity),
                Field::I(u64::from(p.periods)),
                Field::flag(p.stable),
                Field::F(p.x0),
                Field::F(p.v0),
                Field::F(o.cycle_max.last().copied().unwrap_or(p.max_x)),
                Field::S(&cycle_max),
                Field::F(p.multipliers[0].0),
                Field::F(p.multipliers[0].1),
                Field::F(p.multipliers[1].0),
                Field::F(p.multipliers[1].1),
                Field::F(o.abs_multiplier()),
                Field::I(p.impacts),
                Field::I(p.snap_throughs),
                Field::flag(p.sticks),
            ])?;
        }
    }
    Ok(())
}

/// Draws the branches on `chart` in `colour`, with `x[i]` the abscissa of grid point `i`:
/// each per-cycle maximum as a curve, thick and solid where the orbit is stable, thin and
/// dashed where it is unstable; orbits without neighbours as dots (filled: stable).
pub fn draw(chart: &mut Chart<'_, '_>, b: &Branches, x: &[f64], colour: RGBColor) -> DrawResult {
    let mut linked: HashSet<(usize, usize)> = HashSet::new();
    for path in b.paths() {
        linked.extend(path.iter().copied());
        for r in 0..b.period as usize {
            let pts: Vec<(f64, f64, bool)> = path
                .iter()
                .map(|&n| (x[n.0], b.orbit(n).cycle_max[r], b.orbit(n).orbit.stable))
                .collect();
            draw_curve(chart, &pts, colour)?;
        }
    }
    for (i, slot) in b.slots.iter().enumerate() {
        for (k, o) in slot.iter().enumerate() {
            if linked.contains(&(i, k)) {
                continue;
            }
            for &m in &o.cycle_max {
                let style = if o.orbit.stable {
                    colour.filled()
                } else {
                    colour.stroke_width(1)
                };
                chart.draw_series([Circle::new((x[i], m), 3, style)])?;
            }
        }
    }
    Ok(())
}

/// A curve of `(x, y, stable)` points: thick and solid where stable, thin and dashed where
/// unstable; a change of stability splits the segment at its midpoint.
pub fn draw_curve(
    chart: &mut Chart<'_, '_>,
    pts: &[(f64, f64, bool)],
    colour: RGBColor,
) -> DrawResult {
    let Some(&(x0, y0, mut stable)) = pts.first() else {
        return Ok(());
    };
    let mut run = vec![(x0, y0)];
    for w in pts.windows(2) {
        let (pa, pc) = ((w[0].0, w[0].1), (w[1].0, w[1].1));
        if w[1].2 == stable {
            run.push(pc);
        } else {
            let mid = (0.5 * (pa.0 + pc.0), 0.5 * (pa.1 + pc.1));
            run.push(mid);
            segment(chart, &run, stable, colour)?;
            run = vec![mid, pc];
            stable = w[1].2;
        }
    }
    segment(chart, &run, stable, colour)
}

fn segment(
    chart: &mut Chart<'_, '_>,
    pts: &[(f64, f64)],
    stable: bool,
    colour: RGBColor,
) -> DrawResult {
    if pts.len() < 2 {
        return Ok(());
    }
    if stable {
        thick_line(chart, pts, colour, 3)
    } else {
        dashed_line(chart, pts, colour, (7, 5))
    }
}
