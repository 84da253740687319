//! Branches of periodic orbits along a parameter grid: orbits found by shooting from seeds,
//! continued point by point in both directions (natural continuation), de-duplicated and
//! linked, and the links joined into polylines.

use crate::orbit::{solve, Orbit};
use crate::parallel::{self, Threads};
use crate::progress::{OnProgress, Progress, Stage};
use crate::seeds::Seed;
use crate::Model;

/// Most distinct orbits of one period kept at one grid point.
const MAX_PER_POINT: usize = 8;
/// A continuation step that moves the fixed point further than this (max norm in `x` and
/// `x'`) jumped to another branch (one not related to the simulated attractors): its orbit is
/// dropped.
const MAX_JUMP: f64 = 0.05;
/// Newton from a seed that ends further than this from it found an orbit unrelated to the
/// attractor the seed came from (e.g. the saddle at the barrier): dropped.
const MAX_SEED_DISTANCE: f64 = 0.1;

/// A node of a branch: `(grid point, index of the orbit in that point's slot)`.
pub type Node = (usize, usize);

/// The orbits of one period along the grid and the continuation links between them.
#[derive(Debug, Clone)]
pub struct Branches {
    /// Period in shaker periods.
    pub period: u32,
    /// Distinct orbits at each grid point (at most 8 per point).
    pub slots: Vec<Vec<Orbit>>,
    /// `((i, a), (i + 1, b))`: orbit `b` at point `i + 1` continues orbit `a` at point `i`.
    pub links: Vec<(Node, Node)>,
}

impl Branches {
    /// No orbits of `period` on a grid of `points` points.
    pub fn new(period: u32, points: usize) -> Self {
        Self {
            period,
            slots: vec![Vec::new(); points],
            links: Vec::new(),
        }
    }

    /// Adds `o` at point `i` unless it is there already; its index in the slot, or `None` when
    /// the slot is full.
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

    /// Continues every orbit at `from` to the neighbouring point `to` of the grid `models`.
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

    /// Continues every orbit over the whole grid `models`, forward, then backward.
    fn continue_over(&mut self, models: &[Model]) {
        let n = models.len();
        for i in 0..n.saturating_sub(1) {
            self.step(models, i, i + 1);
        }
        for i in (1..n).rev() {
            self.step(models, i, i - 1);
        }
    }

    /// Number of orbits.
    pub fn len(&self) -> usize {
        self.slots.iter().map(Vec::len).sum()
    }

    /// Whether there are no orbits.
    pub fn is_empty(&self) -> bool {
        self.slots.iter().all(Vec::is_empty)
    }

    /// Number of stable orbits.
    pub fn stable(&self) -> usize {
        self.slots
            .iter()
            .flatten()
            .filter(|o| o.orbit.stable)
            .count()
    }

    /// The orbit at `node`.
    pub fn orbit(&self, (i, k): Node) -> &Orbit {
        &self.slots[i][k]
    }

    /// The links joined into polylines, each a list of nodes with increasing grid points; every
    /// link is in exactly one polyline.
    pub fn paths(&self) -> Vec<Vec<Node>> {
        let mut used = vec![false; self.links.len()];
        let mut out = Vec::new();
        for start in 0..self.links.len() {
            if used[start] {
                continue;
            }
            used[start] = true;
            let (from, to) = self.links[start];
            let mut path = vec![from, to];
            let mut cur = to;
            while let Some(k) = (0..self.links.len()).find(|&k| !used[k] && self.links[k].0 == cur)
            {
                used[k] = true;
                cur = self.links[k].1;
                path.push(cur);
            }
            out.push(path);
        }
        out
    }
}

/// Shoots from every seed (in parallel) and keeps the orbits that Newton found near their seed,
/// in the order of `seeds`. `models[s.point]` is the model of seed `s`.
pub fn solve_seeds<E>(
    models: &[Model],
    seeds: &[Seed],
    threads: Threads,
    progress: &mut OnProgress<'_, E>,
) -> Result<Vec<(Seed, Orbit)>, E> {
    let total = seeds.len();
    let found = parallel::map(
        seeds,
        threads,
        |s| {
            solve(&models[s.point], s.period, s.guess).filter(|o| {
                (o.orbit.x0 - s.guess.0)
                    .abs()
                    .max((o.orbit.v0 - s.guess.1).abs())
                    <= MAX_SEED_DISTANCE
            })
        },
        |done| {
            progress(Progress {
                stage: Stage::Shooting,
                done,
                total,
            })
        },
    )?;
    Ok(seeds
        .iter()
        .zip(found)
        .filter_map(|(&s, o)| o.map(|o| (s, o)))
        .collect())
}

/// Solves the seeds, then continues each period's orbits over the grid `models` forward and
/// backward (one period per thread). One [`Branches`] per entry of `periods`, in that order.
pub fn build<E>(
    models: &[Model],
    periods: &[u32],
    seeds: &[Seed],
    threads: Threads,
    progress: &mut OnProgress<'_, E>,
) -> Result<Vec<Branches>, E> {
    let mut all: Vec<Branches> = periods
        .iter()
        .map(|&period| Branches::new(period, models.len()))
        .collect();
    for (s, o) in solve_seeds(models, seeds, threads, progress)? {
        if let Some(b) = all.iter_mut().find(|b| b.period == s.period) {
            b.insert(s.point, o);
        }
    }
    let total = all.len();
    parallel::map(
        &all,
        threads,
        |b| {
            let mut b = b.clone();
            b.continue_over(models);
            b
        },
        |done| {
            progress(Progress {
                stage: Stage::Continuing,
                done,
                total,
            })
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn links_join_into_paths() {
        let mut b = Branches::new(1, 5);
        b.links = vec![
            ((0, 0), (1, 0)),
            ((2, 1), (3, 0)),
            ((1, 0), (2, 1)),
            ((1, 1), (2, 0)),
        ];
        assert_eq!(
            b.paths(),
            vec![vec![(0, 0), (1, 0), (2, 1), (3, 0)], vec![(1, 1), (2, 0)]]
        );
        assert!(b.is_empty());
        assert_eq!((b.len(), b.stable()), (0, 0));
    }
}
