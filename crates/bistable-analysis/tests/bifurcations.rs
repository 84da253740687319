//! Acceptance checks of issue 22, deliverable 1: bifurcation points located and classified on
//! the branches of `continue_orbits` (the paper's Fig. 6 period doublings at V = 0.07, the
//! folds of the P-1 resonance at V = 0.05, Fig. 11).

use bistable_analysis::bifurcations::{locate, BifurcationPoint, Branch, Kind};
use bistable_analysis::continuation::{continue_orbits, Curves, Method};
use bistable_analysis::parallel::Threads;
use bistable_analysis::Model;
use bistable_core::{classify, ClassifyOptions, Params, SimError, Sinusoid, SolverOptions, Width};

fn grid(a: f64, b: f64, n: usize, v: f64) -> Vec<Model> {
    (0..n)
        .map(|i| {
            let w = a + (b - a) * i as f64 / (n - 1) as f64;
            Model::new(
                Params::paper(),
                Sinusoid::new(w, v).unwrap(),
                SolverOptions::default(),
            )
        })
        .collect()
}

fn points(models: &[Model], period: u32, method: Method) -> Vec<BifurcationPoint> {
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
    let branches = match &curves {
        Curves::Natural(b) => Branch::from_natural(models, b),
        Curves::Arclength(t) => Branch::from_traces(&models[0], period, t),
    };
    let found = locate::<SimError>(&branches, threads, &mut |_| Ok(())).unwrap();
    for p in &found {
        eprintln!("{p:?}");
    }
    found
}

#[test]
fn explore() {
    let m = grid(2.05, 2.25, 41, 0.07);
    points(&m, 1, Method::Natural);
    points(&m, 2, Method::Natural);
    let m = grid(2.05, 2.25, 101, 0.07);
    points(&m, 1, Method::Natural);
    points(&m, 2, Method::Natural);
    points(&m, 1, Method::Arclength);
    let m = grid(1.2, 1.6, 41, 0.05);
    points(&m, 1, Method::Arclength);
}
