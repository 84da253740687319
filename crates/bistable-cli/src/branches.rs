//! Branches of periodic orbits along a parameter grid: orbits found by shooting from seeds
//! (simulated attractors), continued point by point in both directions (natural continuation),
//! de-duplicated, linked, written as CSV and drawn over a chart (stable thick and solid,
//! unstable thin and dashed).

use std::collections::HashSet;

use plotters::prelude::*;

use bistable_core::{shoot, PeriodicOrbit, ShootOptions, Simulator};

use crate::attractor::record_cycles;
use crate::common::Model;
use crate::error::CliError;
use crate::output::{CsvFile, Field};
use crate::parallel;
use crate::plot::{dashed_line, thick_line, Chart, DrawResult};

/// Samples per shaker period for the orbits' per-cycle maxima.
const SAMPLES: u32 = 128;
/// Most distinct orbits of one period kept at one grid point.
const MAX_PER_POINT: usize = 8;
/// A continuation step that moves the fixed point further than this (in `x` and `x'`) jumped
/// to another branch (one not related to the simulated attractors): its orbit is dropped.
const MAX_JUMP: f64 = 0.05;
/// Newton from a seed that ends further than this from it found an orbit unrelated to the
/// attractor the seed came from (e.g. the saddle at the barrier): dropped.
const MAX_SEED_DISTANCE: f64 = 0.1;
/// Two orbits are the same when a section point of one is this close to the other's.
const SAME: f64 = 1e-6;

/// A periodic orbit at one grid point, with what the plots need.
#[derive(Debug, Clone)]
pub struct Orbit {
    /// The shooting result.
    pub orbit: PeriodicOrbit,
    /// Largest `x` in each of its shaker cycles, ascending.
    pub cycle_max: Vec<f64>,
    /// Its section points `(x, x')` at plate phase 0, one per shaker cycle.
    pub sections: Vec<(f64, f64)>,
}

impl Orbit {
    /// The fixed point.
    pub fn point(&self) -> (f64, f64) {
        (self.orbit.x0, self.orbit.v0)
    }

    /// Largest modulus of the Floquet multipliers.
    pub fn abs_multiplier(&self) -> f64 {
        let (re, im) = self.orbit.multipliers[0];
        re.hypot(im)
    }

    fn same_as(&self, other: &Orbit) -> bool {
        self.orbit.periods == other.orbit.periods
            && self
                .sections
                .iter()
                .any(|&(x, v)| (x - other.orbit.x0).abs().max((v - other.orbit.v0).abs()) < SAME)
    }
}

/// Shoots the `period`-periodic orbit at `model` from `guess`; `None` when Newton fails, the
/// orbit has a smaller period (it is then found as that period's orbit) or no impacts (the
/// equilibria at the barrier and in well 2, which are not impact orbits).
pub fn solve(model: &Model, period: u32, guess: (f64, f64)) -> Option<Orbit> {
    let so = ShootOptions::default();
    let orbit = shoot(model.params, model.shaker, model.opts, period, guess, so).ok()?;
    if orbit.impacts == 0 {
        return None;
    }
    analyse(model, orbit).ok().flatten()
}

/// Per-cycle maxima and section points of `orbit`; `None` if its minimal period is smaller.
pub fn analyse(model: &Model, orbit: PeriodicOrbit) -> Result<Option<Orbit>, CliError> {
    let mut sim = Simulator::with_state(
        model.params,
        model.shaker.into(),
        model.opts,
        0.0,
        orbit.x0,
        orbit.v0,
    )?;
    let c = record_cycles(&mut sim, model.shaker, 0, orbit.periods, SAMPLES)?;
    let q = orbit.periods as usize;
    let y0 = c.sections[0];
    let scale = y0.0.abs().max(y0.1.abs()).max(1.0);
    let minimal = (1..q).filter(|&d| q.is_multiple_of(d)).any(|d| {
        let y = c.sections[d];
        (y.0 - y0.0).abs().max((y.1 - y0.1).abs()) < 1e-7 * scale
    });
    if minimal {
        return Ok(None);
    }
    let mut cycle_max = c.max_x;
    cycle_max.sort_by(f64::total_cmp);
    let mut sections = c.sections;
    sections.truncate(q);
    Ok(Some(Orbit {
        orbit,
        cycle_max,
        sections,
    }))
}

/// Where to start shooting: grid point, period and guess `(x, x')` at plate phase 0.
#[derive(Debug, Clone, Copy)]
pub struct Seed {
    /// Grid index.
    pub point: usize,
    /// Period in shaker periods.
    pub period: u32,
    /// Initial guess.
    pub guess: (f64, f64),
}

/// Seeds from a simulated attractor's section points `sections` (most recent last) whose
/// period is `attractor` (`None`: aperiodic): the attractor itself for its own period, and
/// for each smaller period `q` in `periods` that divides it, the mean of the section points
/// `q` apart (where the orbit that lost stability by period doubling lies); for an aperiodic
/// attractor, the mean of all points for period 1.
pub fn seeds_from(
    point: usize,
    sections: &[(f64, f64)],
    attractor: Option<usize>,
    periods: &[u32],
) -> Vec<Seed> {
    let Some(&last) = sections.last() else {
        return Vec::new();
    };
    let mean = |pts: &mut dyn Iterator<Item = (f64, f64)>| {
        let (mut sx, mut sv, mut n) = (0.0, 0.0, 0.0);
        for (x, v) in pts {
            sx += x;
            sv += v;
            n += 1.0;
        }
        (sx / n, sv / n)
    };
    let mut out = Vec::new();
    for &q in periods {
        let qu = q as usize;
        let guess = match attractor {
            Some(p) if p == qu => last,
            Some(p) if p > qu && p.is_multiple_of(qu) && sections.len() >= p => {
                mean(&mut sections[sections.len() - p..].iter().step_by(qu).copied())
            }
            None if q == 1 => mean(&mut sections.iter().copied()),
            _ => continue,
        };
        out.push(Seed {
            point,
            period: q,
            guess,
        });
    }
    out
}

/// The orbits of one period along the grid and the continuation links between them.
#[derive(Debug, Clone)]
pub struct Branches {
    /// Period in shaker periods.
    pub period: u32,
    /// Distinct orbits at each grid point.
    pub slots: Vec<Vec<Orbit>>,
    /// `((i, a), (i + 1, b))`: orbit `b` at point `i + 1` continues orbit `a` at point `i`.
    pub links: Vec<((usize, usize), (usize, usize))>,
}

impl Branches {
    fn insert(&mut self, i: usize, o: Orbit) -> Option<usize> {
        let slot = &mut self.slots[i];
        if let Some(k) = slot.iter().position(|s| s.same_as(&o)) {
            return Some(k);
        }
        if slot.len() >= MAX_PER_POINT {
            return None;
        }
        slot.push(o);
        Some(slot.len() - 1)
    }

    /// Continues every orbit at `from` to the neighbouring point `to`.
    fn step(&mut self, models: &[Model], from: usize, to: usize) {
        for a in 0..self.slots[from].len() {
            let guess = self.slots[from][a].point();
            let Some(o) = solve(&models[to], self.period, guess) else {
                continue;
            };
            let jump = (o.orbit.x0 - guess.0)
                .abs()
                .max((o.orbit.v0 - guess.1).abs());
            if jump > MAX_JUMP {
                continue;
            }
            if let Some(b) = self.insert(to, o) {
                let link = if from < to {
                    ((from, a), (to, b))
                } else {
                    ((to, b), (from, a))
                };
                if !self.links.contains(&link) {
                    self.links.push(link);
                }
            }
        }
    }

    /// Number of orbits.
    pub fn len(&self) -> usize {
        self.slots.iter().map(Vec::len).sum()
    }
}

/// Shoots from every seed (in parallel); keeps the orbits that Newton found near their seed.
pub fn solve_seeds(
    models: &[Model],
    seeds: &[Seed],
    threads: usize,
) -> Result<Vec<(Seed, Orbit)>, CliError> {
    let mut out = Vec::new();
    parallel::run(
        seeds,
        threads,
        &format!("shooting from {} seeds", seeds.len()),
        |s| {
            solve(&models[s.point], s.period, s.guess).filter(|o| {
                (o.orbit.x0 - s.guess.0)
                    .abs()
                    .max((o.orbit.v0 - s.guess.1).abs())
                    <= MAX_SEED_DISTANCE
            })
        },
        |i, o| {
            out.extend(o.map(|o| (seeds[i], o)));
            Ok(())
        },
    )?;
    Ok(out)
}

/// Solves the seeds, then continues each period's orbits over the grid `models` forward and
/// backward, on `threads` threads. One [`Branches`] per entry of `periods`.
pub fn build(
    models: &[Model],
    periods: &[u32],
    seeds: &[Seed],
    threads: usize,
) -> Result<Vec<Branches>, CliError> {
    let mut all: Vec<Branches> = periods
        .iter()
        .map(|&period| Branches {
            period,
            slots: vec![Vec::new(); models.len()],
            links: Vec::new(),
        })
        .collect();
    for (s, o) in solve_seeds(models, seeds, threads)? {
        if let Some(b) = all.iter_mut().find(|b| b.period == s.period) {
            b.insert(s.point, o);
        }
    }
    let n = models.len();
    let mut done: Vec<Option<Branches>> = vec![None; all.len()];
    parallel::run(
        &all,
        threads,
        "continuing the orbits",
        |b| {
            let mut b = b.clone();
            for i in 0..n.saturating_sub(1) {
                b.step(models, i, i + 1);
            }
            for i in (1..n).rev() {
                b.step(models, i, i - 1);
            }
            b
        },
        |i, b| {
            done[i] = Some(b);
            Ok(())
        },
    )?;
    all = done.into_iter().flatten().collect();
    Ok(all)
}

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

/// Polylines through the links: each is a list of `(point, orbit)` nodes.
fn paths(b: &Branches) -> Vec<Vec<(usize, usize)>> {
    let mut used = vec![false; b.links.len()];
    let mut out = Vec::new();
    for start in 0..b.links.len() {
        if used[start] {
            continue;
        }
        used[start] = true;
        let (from, to) = b.links[start];
        let mut path = vec![from, to];
        let mut cur = to;
        while let Some(k) = (0..b.links.len()).find(|&k| !used[k] && b.links[k].0 == cur) {
            used[k] = true;
            cur = b.links[k].1;
            path.push(cur);
        }
        out.push(path);
    }
    out
}

/// Draws the branches on `chart` in `colour`, with `x[i]` the abscissa of grid point `i`:
/// each per-cycle maximum as a curve, thick and solid where the orbit is stable, thin and
/// dashed where it is unstable; orbits without neighbours as dots (filled: stable).
pub fn draw(chart: &mut Chart<'_, '_>, b: &Branches, x: &[f64], colour: RGBColor) -> DrawResult {
    let mut linked: HashSet<(usize, usize)> = HashSet::new();
    for path in paths(b) {
        linked.extend(path.iter().copied());
        let orbit = |(i, k): (usize, usize)| &b.slots[i][k];
        for r in 0..b.period as usize {
            let pts: Vec<(f64, f64, bool)> = path
                .iter()
                .map(|&n| (x[n.0], orbit(n).cycle_max[r], orbit(n).orbit.stable))
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
