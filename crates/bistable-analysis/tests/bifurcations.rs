//! Acceptance checks of issue 22, deliverable 1: bifurcation points located and classified on
//! the branches of `continue_orbits`, against the paper's Fig. 6 (period doublings at V = 0.07)
//! and Fig. 11 (the fold of the P-1 resonance at V = 0.05).
//!
//! Tolerances: a point located on two different grids (the intervals, chords and trial orbits
//! all differ) must agree in Ω to 1e-10, the accuracy; its multiplier must be within
//! 1e-8 of ±1 (a multiplier moves by about 10 per unit of Ω here, so 1e-8 is 1e-9 in Ω).

use bistable_analysis::arclength::ArcPoint;
use bistable_analysis::bifurcations::{locate, BifurcationPoint, Branch, Kind, SMOOTH_TOL};
use bistable_analysis::continuation::{continue_orbits, Curves, Method};
use bistable_analysis::parallel::Threads;
use bistable_analysis::Model;
use bistable_core::{classify, ClassifyOptions, Params, SimError, Sinusoid, SolverOptions, Width};

/// Agreement in Ω of one point located from two grids.
const SAME_OMEGA: f64 = 1e-10;
/// Distance of the critical multiplier from ±1 at a located point.
const AT_CRITICAL: f64 = 1e-8;

fn model(omega: f64, v: f64) -> Model {
    Model::new(
        Params::paper(),
        Sinusoid::new(omega, v).unwrap(),
        SolverOptions::default(),
    )
}

/// `n` models at Ω evenly spaced from `a` to `b` (the CLI's `a:b:n`) and V = `v`.
fn grid(a: f64, b: f64, n: usize, v: f64) -> Vec<Model> {
    (0..n)
        .map(|i| model(a + (b - a) * i as f64 / (n - 1) as f64, v))
        .collect()
}

/// The continued branches and the points located on them.
fn run(models: &[Model], period: u32, method: Method) -> (Curves, Vec<BifurcationPoint>) {
    let threads = Threads::new(2).unwrap();
    let curves = continue_orbits::<SimError>(
        models,
        period,
        2000,
        method,
        threads,
        Width::preferred(),
        &mut |_| Ok(()),
    )
    .unwrap();
    let branches = Branch::from_curves(models, period, &curves);
    let found = locate::<SimError>(&branches, threads, &mut |_| Ok(())).unwrap();
    (curves, found)
}

/// The one period doubling on the natural P-`period` branch over `models`, checked: nothing
/// else changes on that branch, and the located orbit has a multiplier at −1.
fn the_doubling(models: &[Model], period: u32) -> BifurcationPoint {
    let (_, found) = run(models, period, Method::Natural);
    let [p] = found[..] else {
        panic!("P-{period}: one period doubling expected, found {found:#?}");
    };
    assert_eq!(p.kind, Kind::PeriodDoubling, "{p:?}");
    assert_eq!(p.period, period);
    assert!(p.omega_error <= SMOOTH_TOL, "{p:?}");
    let [(l1, i1), (l2, i2)] = p.multipliers;
    assert!(i1 == 0.0 && i2 == 0.0, "{p:?}");
    assert!((l1 + 1.0).abs() <= AT_CRITICAL, "{p:?}");
    assert!(l2.abs() < 1.0, "{p:?}");
    assert_eq!(
        (p.impacts_before, p.impacts_after),
        (period.into(), period.into())
    );
    p
}

/// The steady-state period from the paper's initial condition at `(Ω, 0.07)`.
fn classified_period(omega: f64) -> Option<u32> {
    let m = model(omega, 0.07);
    classify(m.params, m.shaker, m.opts, ClassifyOptions::default())
        .unwrap()
        .period
}

#[test]
fn fig6_period_doublings_located_on_coarse_and_fine_grids() {
    let coarse = grid(2.05, 2.25, 41, 0.07);
    let fine = grid(2.05, 2.25, 101, 0.07);
    let pd1 = the_doubling(&coarse, 1);
    let pd2 = the_doubling(&coarse, 2);
    eprintln!("P-1 → P-2 at Ω = {:.15} {:?}", pd1.omega, pd1.multipliers);
    eprintln!("P-2 → P-4 at Ω = {:.15} {:?}", pd2.omega, pd2.multipliers);
    assert!(2.1 < pd1.omega && pd1.omega < pd2.omega && pd2.omega < 2.3);
    for (p, period) in [(pd1, 1), (pd2, 2)] {
        let again = the_doubling(&fine, period);
        assert!(
            (again.omega - p.omega).abs() <= SAME_OMEGA,
            "P-{period}: {} on the coarse grid, {} on the fine one",
            p.omega,
            again.omega
        );
    }
    // The classifier sees the doubling: the period on either side, 1e-3 away.
    let sides = |w: f64| (classified_period(w - 1e-3), classified_period(w + 1e-3));
    assert_eq!(sides(pd1.omega), (Some(1), Some(2)), "around {}", pd1.omega);
    assert_eq!(sides(pd2.omega), (Some(2), Some(4)), "around {}", pd2.omega);
}

/// Whether the located point is an extremum of Ω along its trace: beyond every traced orbit
/// within three points of its interval.
fn turns_at(trace: &[ArcPoint], p: &BifurcationPoint) -> bool {
    let near = &trace[p.index.saturating_sub(3)..(p.index + 5).min(trace.len())];
    let beyond = |sign: f64| near.iter().all(|a| sign * (p.omega - a.omega) >= -1e-12);
    beyond(1.0) || beyond(-1.0)
}

#[test]
fn fig11_fold_of_the_p1_resonance_located() {
    let folds = |models: &[Model]| {
        let (curves, found) = run(models, 1, Method::Arclength);
        let Curves::Arclength(traces) = curves else {
            panic!("arclength continuation gives traces");
        };
        let folds: Vec<BifurcationPoint> = found
            .into_iter()
            .filter(|p| p.kind == Kind::Fold && (1.35..1.5).contains(&p.omega))
            .collect();
        for p in &folds {
            assert!(p.omega_error <= SMOOTH_TOL, "{p:?}");
            assert!((p.multipliers[0].0 - 1.0).abs() <= AT_CRITICAL, "{p:?}");
            assert!(p.multipliers[1].0.abs() < 1.0, "{p:?}");
            assert!(turns_at(&traces[p.branch], p), "not a turning point: {p:?}");
        }
        folds
    };
    let a = folds(&grid(1.2, 1.6, 41, 0.05));
    let b = folds(&grid(1.3, 1.55, 21, 0.05));
    assert!(!a.is_empty(), "no fold near Ω = 1.4");
    assert_eq!(a.len(), b.len(), "{a:#?}\n{b:#?}");
    for (p, q) in a.iter().zip(&b) {
        eprintln!("fold at Ω = {:.15} {:?}", p.omega, p.multipliers);
        assert!((p.omega - q.omega).abs() <= SAME_OMEGA, "{p:?}\n{q:?}");
    }
}
