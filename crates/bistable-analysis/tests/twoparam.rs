//! Issue 22, deliverable 3: the Fig. 6 period doubling P-1 → P-2 continued in (Ω, V). Points
//! along the curve, re-located by one-parameter continuation in Ω at their V, agree in Ω to
//! 1e-8 (both are located to about 1e-12).

use bistable_analysis::bifurcations::{locate, BifurcationPoint, Branch, BranchPoint, Kind};
use bistable_analysis::continuation::{continue_orbits, Curves, Method};
use bistable_analysis::parallel::Threads;
use bistable_analysis::twoparam::{continue_point, CurveOptions};
use bistable_analysis::Model;
use bistable_core::{
    continue_in_omega, Params, ShootOptions, SimError, Sinusoid, SolverOptions, Width,
};

/// Agreement in Ω of a curve point and the point located at its V in one parameter.
const SAME_OMEGA: f64 = 1e-8;

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

/// The period doublings on the natural P-1 branches over `models`.
fn doublings(models: &[Model]) -> Vec<BifurcationPoint> {
    let threads = Threads::new(2).unwrap();
    let Curves::Natural(b) = continue_orbits::<SimError>(
        models,
        1,
        2000,
        Method::Natural,
        threads,
        Width::preferred(),
        &mut |_| Ok(()),
    )
    .unwrap() else {
        panic!("natural continuation gives branches");
    };
    locate::<SimError>(&Branch::from_natural(models, &b), threads, &mut |_| Ok(()))
        .unwrap()
        .into_iter()
        .filter(|p| p.kind == Kind::PeriodDoubling)
        .collect()
}

#[test]
fn period_doubling_curve_agrees_with_one_parameter_continuation() {
    let models = grid(2.05, 2.25, 41, 0.07);
    let [start] = doublings(&models)[..] else {
        panic!("one period doubling expected at V = 0.07");
    };
    let o = CurveOptions {
        omega_bounds: (1.5, 3.0),
        velocity_bounds: (0.06, 0.08),
        ds_max: 0.004,
        max_points: 200,
    };
    let curve = continue_point(&models[0], &start, o).unwrap();
    let vs: Vec<f64> = curve.iter().map(|c| c.velocity).collect();
    let (v_min, v_max) = vs
        .iter()
        .fold((1.0_f64, 0.0_f64), |(a, b), &v| (a.min(v), b.max(v)));
    eprintln!("{} points, V from {v_min} to {v_max}", curve.len());
    // Down to the lower bound; upwards the curve turns back near V = 0.0787 (Ω ≈ 1.85).
    assert!(v_min <= 0.0605 && v_max >= 0.078, "{vs:?}");
    for c in &curve {
        assert!((c.multipliers[0].0 + 1.0).abs() < 1e-8, "{c:?}");
        assert_eq!(c.impacts, 1, "{c:?}");
    }
    // Every eighth point, re-located in Ω at its V: the P-1 orbit continued by natural
    // continuation over 9 values of Ω within ±0.02 of it (from the curve's orbit, since past
    // the curve's turn in V no simulated attractor seeds that orbit), then the doubling on it
    // located.
    for c in curve.iter().step_by(8) {
        let near = relocated(c.omega, c.velocity, (c.x0, c.v0));
        eprintln!(
            "V = {:.6}: curve Ω = {:.12}, one-parameter Ω = {:.12}",
            c.velocity, c.omega, near
        );
        assert!((near - c.omega).abs() <= SAME_OMEGA, "{c:?}: {near}");
    }
}

/// The period doubling nearest `omega` on the P-1 branch through `guess` at `velocity`,
/// natural continuation over `omega ± 0.02` (9 values, from the middle out).
fn relocated(omega: f64, velocity: f64, guess: (f64, f64)) -> f64 {
    let models = grid(omega - 0.02, omega + 0.02, 9, velocity);
    let m = &models[0];
    let so = ShootOptions::default();
    let ws: Vec<f64> = models.iter().map(Model::omega).collect();
    let shoot_over = |ws: &[f64]| {
        let (orbits, _) = continue_in_omega(m.params, velocity, ws, m.opts, 1, guess, so);
        orbits
    };
    // Down from the middle, then up from it.
    let mut down: Vec<f64> = ws[..5].to_vec();
    down.reverse();
    let mut orbits = shoot_over(&down);
    orbits.reverse();
    orbits.extend(shoot_over(&ws[4..]).into_iter().skip(1));
    let points: Vec<BranchPoint> = orbits
        .iter()
        .map(|o| BranchPoint {
            omega: o.omega,
            x0: o.x0,
            v0: o.v0,
            multipliers: o.multipliers,
            impacts: o.impacts,
            sticks: o.sticks,
        })
        .collect();
    assert_eq!(
        points.len(),
        9,
        "the branch through {guess:?} at V = {velocity}"
    );
    let branch = Branch {
        model: *m,
        period: 1,
        points,
    };
    let found = locate::<SimError>(&[branch], Threads::new(2).unwrap(), &mut |_| Ok(())).unwrap();
    found
        .iter()
        .filter(|p| p.kind == Kind::PeriodDoubling)
        .map(|p| p.omega)
        .min_by(|a, b| (a - omega).abs().total_cmp(&(b - omega).abs()))
        .unwrap_or_else(|| panic!("no period doubling near Ω = {omega}, V = {velocity}"))
}
