//! Issue 22's acceptance at V = 0.05: at an Ω where the atlas says two stable P-1 orbits
//! coexist (above the high-energy orbit's doubling, below the low-energy orbit's fold),
//! the basins of attraction (`basins::classify_starts` and `identify`, as `bistable basins`
//! runs them) reach both, at the continuation's fixed points.

mod common;

use bistable_analysis::basins::{classify_starts, identify, Cell, Decision};
use bistable_analysis::bifurcations::Kind;
use bistable_analysis::parallel::Threads;
use bistable_analysis::twoparam::{trace_all, CurveOptions};
use bistable_analysis::Model;
use bistable_core::{ClassifyOptions, Params, ShootOptions, SimError, SolverOptions, Width};
use common::{continue_in_omega, model_at, p1_located};

/// A basin attractor's anchor (its cycle's section point at plate phase 0) and the fixed
/// point of the orbit continued there agree to this (max norm, units of Δx and ω0·Δx): the
/// classification stops when section points one period apart agree to 1e-8.
const SAME_ORBIT: f64 = 1e-6;

#[test]
fn basins_find_both_stable_p1_orbits_inside_the_folds_hysteresis() {
    let v = 0.05;
    let models: Vec<Model> = (0..41)
        .map(|i| model_at(1.2 + 0.01 * f64::from(i), v))
        .collect();
    let (branches, found) = p1_located(&models);
    // The atlas's run: the fold and the doubling at V = 0.05 with their curves.
    let o = CurveOptions {
        omega_bounds: (1.2, 1.6),
        velocity_bounds: (0.03, 0.07),
        ds_max: 0.005,
        max_points: 200,
    };
    let atlas = trace_all(&models[0], found, o).unwrap();
    let at = |kind| {
        atlas
            .iter()
            .find(|(s, _)| s.kind == kind)
            .map(|(s, _)| s.omega)
            .unwrap()
    };
    let (fold, pd) = (at(Kind::Fold), at(Kind::PeriodDoubling));
    eprintln!("fold at Ω = {fold}, doubling at Ω = {pd}");
    let omega = 1.35;
    assert!(pd < omega && omega < fold, "{pd} {fold}");

    // The stable orbits of the branches at Ω: the branch point nearest it, polished by the
    // core's shooting at Ω.
    let mut orbits: Vec<(f64, f64)> = Vec::new();
    for b in &branches {
        for pair in b.points.windows(2) {
            let (a, c) = (&pair[0], &pair[1]);
            if (a.omega - omega) * (c.omega - omega) > 0.0 {
                continue;
            }
            let near = if (a.omega - omega).abs() < (c.omega - omega).abs() {
                a
            } else {
                c
            };
            let (solved, _) = continue_in_omega(
                Params::paper(),
                v,
                &[omega],
                SolverOptions::default(),
                1,
                (near.x0, near.v0),
                ShootOptions::default(),
            );
            if let Some(s) = solved.first().filter(|s| s.stable) {
                if !orbits
                    .iter()
                    .any(|o| (o.0 - s.x0).abs().max((o.1 - s.v0).abs()) < SAME_ORBIT)
                {
                    orbits.push((s.x0, s.v0));
                }
            }
        }
    }
    eprintln!("stable P-1 orbits at Ω = {omega}: {orbits:?}");
    assert_eq!(orbits.len(), 2, "{orbits:?}");

    // Basins over x0 in [0, 0.3] (the plate is at 0 at phase 0), x0' in [-0.3, 0.3], 16 × 16.
    let model = models[0].at(omega, v).unwrap();
    let starts: Vec<(f64, f64)> = (0..256)
        .map(|k| {
            let (i, j) = (f64::from(k % 16), f64::from(k / 16));
            (0.3 * i / 15.0, -0.3 + 0.6 * j / 15.0)
        })
        .collect();
    let mut cells: Vec<Option<Cell>> = vec![None; starts.len()];
    classify_starts::<SimError>(
        &model,
        0.0,
        ClassifyOptions::default(),
        Decision::Full,
        &starts,
        Threads::new(2).unwrap(),
        Width::preferred(),
        |i, r| {
            cells[i] = Some(r?);
            Ok(())
        },
    )
    .unwrap();
    let cells: Vec<Cell> = cells.into_iter().map(Option::unwrap).collect();
    let (attractors, _) = identify(&cells);
    for a in &attractors {
        eprintln!("{}: {:?}, {} cells", a.steady.label(), a.anchor, a.cells);
    }
    let p1: Vec<[f64; 2]> = attractors
        .iter()
        .filter(|a| a.steady.period == Some(1))
        .filter_map(|a| a.anchor)
        .collect();
    assert!(p1.len() >= 2, "{attractors:?}");
    for o in &orbits {
        let d = p1
            .iter()
            .map(|a| (a[0] - o.0).abs().max((a[1] - o.1).abs()))
            .fold(f64::INFINITY, f64::min);
        eprintln!("orbit {o:?}: nearest P-1 attractor at {d:e}");
        assert!(d <= SAME_ORBIT, "{o:?}: {p1:?}");
    }
}
