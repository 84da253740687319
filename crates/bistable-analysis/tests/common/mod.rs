//! Set-up shared by the integration tests: the paper's model at (Ω, V), and the P-1 branches
//! over a grid of models continued by pseudo-arclength (settling 2000 shaker periods, as the
//! CLI's default) with the bifurcation points located on them; and natural continuation by the
//! core's shooting alone, as an independent check of the analyses' locators.

// Each test file uses a part of this module.
#![allow(dead_code)]

use bistable_analysis::arclength::ArcPoint;
use bistable_analysis::bifurcations::{locate, BifurcationPoint, Branch};
use bistable_analysis::continuation::{continue_orbits, Curves, Method};
use bistable_analysis::parallel::Threads;
use bistable_analysis::Model;
use bistable_core::{
    shoot, Params, PeriodicOrbit, ShootError, ShootOptions, SimError, Sinusoid, SolverOptions,
    Width,
};

/// The paper's model (ζ = 0.02, e = 0.85) at shaker frequency `omega` and amplitude `v`.
pub fn model_at(omega: f64, v: f64) -> Model {
    Model::new(
        Params::paper(),
        Sinusoid::new(omega, v).unwrap(),
        SolverOptions::default(),
    )
}

/// The pseudo-arclength traces of the P-1 orbits over `models` (one V, increasing Ω).
pub fn p1_traces(models: &[Model]) -> Vec<Vec<ArcPoint>> {
    let curves = continue_orbits::<SimError>(
        models,
        1,
        2000,
        Method::Arclength,
        Threads::new(2).unwrap(),
        Width::preferred(),
        &mut |_| Ok(()),
    )
    .unwrap();
    let Curves::Arclength(traces) = curves else {
        panic!("arclength continuation gives traces");
    };
    traces
}

/// The P-1 branches over `models` (as [`p1_traces`]) and the bifurcation points on them.
pub fn p1_located(models: &[Model]) -> (Vec<Branch>, Vec<BifurcationPoint>) {
    let branches = Branch::from_traces(&models[0], 1, &p1_traces(models));
    let found = locate::<SimError>(&branches, Threads::new(2).unwrap(), &mut |_| Ok(())).unwrap();
    (branches, found)
}

/// Natural continuation of a branch in `Ω` by the core's shooting: each orbit seeds the next. Stops at the first
/// failure (fold, loss of convergence) and returns the orbits found with the error.
pub fn continue_in_omega(
    params: Params,
    velocity: f64,
    omegas: &[f64],
    opts: SolverOptions,
    periods: u32,
    guess: (f64, f64),
    so: ShootOptions,
) -> (Vec<PeriodicOrbit>, Option<(f64, ShootError)>) {
    let mut out = Vec::new();
    let mut g = guess;
    for &omega in omegas {
        let orbit = Sinusoid::new(omega, velocity)
            .map_err(ShootError::from)
            .and_then(|plate| shoot(params, plate, opts, periods, g, so));
        match orbit {
            Ok(o) => {
                g = (o.x0, o.v0);
                out.push(o);
            }
            Err(e) => return (out, Some((omega, e))),
        }
    }
    (out, None)
}
