//! Issue 22, deliverable 3: the Fig. 6 period doublings P-1 → P-2 and P-2 → P-4 continued in
//! (Ω, V). Points along the curves, re-located by one-parameter continuation in Ω at their V,
//! agree in Ω to 1e-8 (both are located to about 1e-12). The codimension-two points on the
//! curves (`codim2`) are checked against what they mean: a cusp is the extremum of its fold
//! curve, a crossing lies on both curves, a resonant grazing has the one-parameter grazing at
//! its V.

mod common;

use bistable_analysis::bifurcations::{locate, BifurcationPoint, Branch, BranchPoint, Kind};
use bistable_analysis::codim2::{self, Codim2Point, PointKind};
use bistable_analysis::continuation::{continue_orbits, Curves, Method};
use bistable_analysis::parallel::Threads;
use bistable_analysis::twoparam::{continue_point, trace_all, Atlas, CurveOptions};
use bistable_analysis::Model;
use bistable_core::{Params, ShootOptions, SimError, SolverOptions, Width};
use common::{continue_in_omega, model_at, p1_located};

/// Agreement in Ω of a curve point and the point located at its V in one parameter.
const SAME_OMEGA: f64 = 1e-8;

fn grid(a: f64, b: f64, n: usize, v: f64) -> Vec<Model> {
    (0..n)
        .map(|i| model_at(a + (b - a) * i as f64 / (n - 1) as f64, v))
        .collect()
}

/// The period doublings on the natural P-`period` branches over `models`.
fn doublings(models: &[Model], period: u32) -> Vec<BifurcationPoint> {
    let threads = Threads::new(2).unwrap();
    let Curves::Natural(b) = continue_orbits::<SimError>(
        models,
        period,
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
    let [start] = doublings(&models, 1)[..] else {
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
        let near = relocated(c.omega, c.velocity, (c.x0, c.v0), (1, 0.02));
        eprintln!(
            "V = {:.6}: curve Ω = {:.12}, one-parameter Ω = {:.12}",
            c.velocity, c.omega, near
        );
        assert!((near - c.omega).abs() <= SAME_OMEGA, "{c:?}: {near}");
    }
}

#[test]
fn p2_period_doubling_curve_agrees_with_one_parameter_continuation() {
    // The P-2 → P-4 doubling of Fig. 6 at V = 0.07 (Ω = 2.238388897996).
    let models = grid(2.05, 2.25, 41, 0.07);
    let [start] = doublings(&models, 2)[..] else {
        panic!("one P-2 period doubling expected at V = 0.07");
    };
    assert!((start.omega - 2.238388897996).abs() < 1e-9, "{start:?}");
    let o = CurveOptions {
        omega_bounds: (2.0, 2.4),
        velocity_bounds: (0.065, 0.075),
        ds_max: 0.004,
        max_points: 200,
    };
    let curve = continue_point(&models[0], &start, o).unwrap();
    let (v_min, v_max) = curve.iter().fold((1.0_f64, 0.0_f64), |(a, b), c| {
        (a.min(c.velocity), b.max(c.velocity))
    });
    eprintln!("{} points, V from {v_min} to {v_max}", curve.len());
    assert!(v_min <= 0.0655 && v_max >= 0.0745, "V {v_min}..{v_max}");
    for c in &curve {
        assert!((c.multipliers[0].0 + 1.0).abs() < 1e-8, "{c:?}");
        assert_eq!(c.impacts, 2, "{c:?}");
    }
    for c in curve.iter().step_by(curve.len() / 5) {
        let near = relocated(c.omega, c.velocity, (c.x0, c.v0), (2, 0.005));
        eprintln!(
            "P-2, V = {:.6}: curve Ω = {:.12}, one-parameter Ω = {:.12}",
            c.velocity, c.omega, near
        );
        assert!((near - c.omega).abs() <= SAME_OMEGA, "{c:?}: {near}");
    }
}

/// The models of the P-1 branches followed by arclength over `a..b` (`n` values) at
/// `velocity`, and the bifurcation points located on them.
fn located((a, b, n): (f64, f64, usize), velocity: f64) -> (Vec<Model>, Vec<BifurcationPoint>) {
    let models = grid(a, b, n, velocity);
    let (_, found) = p1_located(&models);
    (models, found)
}

/// The atlas of the P-1 branches followed by arclength over `a..b` (`n` values) at `velocity`,
/// with its codimension-two points.
fn atlas(grid: (f64, f64, usize), velocity: f64, o: CurveOptions) -> (Atlas, Vec<Codim2Point>) {
    let (models, found) = located(grid, velocity);
    let all = trace_all(&models[0], found, o).unwrap();
    let points = codim2::points(&models[0], &all, o);
    (all, points)
}

/// Located to this in the curve parameter (the module brackets to 1e-10).
const LOCATED: f64 = 1e-8;

#[test]
fn the_resonance_fold_ends_in_a_cusp_at_its_extremum() {
    // The fold of the P-1 resonance at V = 0.05 (Ω = 1.4404) traced down to its cusp.
    let o = CurveOptions {
        omega_bounds: (1.0, 2.5),
        velocity_bounds: (0.001, 0.2),
        ds_max: 0.005,
        max_points: 2000,
    };
    let (all, points) = atlas((1.2, 1.6, 41), 0.05, o);
    let k = all
        .iter()
        .position(|(s, _)| s.kind == Kind::Fold)
        .expect("the resonance fold");
    let curve = &all[k].1;
    let cusps: Vec<&Codim2Point> = points
        .iter()
        .filter(|p| p.kind == PointKind::Cusp && p.curve == k)
        .collect();
    let [c] = cusps[..] else {
        panic!("one cusp expected on the fold curve: {points:?}");
    };
    eprintln!("cusp {c:?}");
    assert!(c.error <= LOCATED, "{c:?}");
    assert!((c.multipliers[0].0 - 1.0).abs() < 1e-8, "{c:?}");
    // Independent of the normal-form coefficient: the cusp is the tip of the curve's
    // projection, its lowest V and largest Ω (the curve's points lie within 1e-12 of the
    // other side of neither).
    let v_min = curve.iter().map(|q| q.velocity).fold(1.0, f64::min);
    let w_max = curve.iter().map(|q| q.omega).fold(0.0, f64::max);
    eprintln!("curve: V >= {v_min}, Ω <= {w_max}");
    assert!(c.velocity <= v_min + 1e-12, "{} > {v_min}", c.velocity);
    assert!(c.omega >= w_max - 1e-12, "{} < {w_max}", c.omega);
    // ... and the projection turns back there: the steps in (Ω, V) before and after it point
    // in opposite directions.
    let step = |i: usize| {
        (
            curve[i + 1].omega - curve[i].omega,
            curve[i + 1].velocity - curve[i].velocity,
        )
    };
    let (a, b) = (step(c.index - 1), step(c.index + 1));
    assert!(a.0 * b.0 + a.1 * b.1 < 0.0, "{a:?} {b:?}");
    // ... and two folds meet there: by one-parameter arclength continuation over Ω 1.70..1.90,
    // 3e-4 above its V two folds lie within 0.01 of its Ω (the hysteresis), 1.2e-3 below
    // none.
    let folds = |v: f64| -> Vec<f64> {
        let (_, found) = located((1.70, 1.90, 81), v);
        found
            .iter()
            .filter(|p| p.kind == Kind::Fold)
            .map(|p| p.omega)
            .collect()
    };
    let above = folds(c.velocity + 3e-4);
    eprintln!("folds at V = cusp + 3e-4: {above:?}");
    assert_eq!(above.len(), 2, "{above:?}");
    assert!(
        above.iter().all(|w| (w - c.omega).abs() < 0.01),
        "{above:?}"
    );
    let below = folds(c.velocity - 1.2e-3);
    assert!(below.is_empty(), "{below:?}");
    // No fold–flip: det M = λ1·λ2 lies in (0, 1) all along (the other multiplier cannot be −1).
    assert!(points.iter().all(|p| p.kind != PointKind::FoldFlip));
    for (_, curve) in &all {
        for q in curve {
            let det =
                q.multipliers[0].0 * q.multipliers[1].0 - q.multipliers[0].1 * q.multipliers[1].1;
            assert!(det > 0.0 && det < 1.0, "{q:?}");
        }
    }
}

#[test]
fn a_crossing_lies_on_both_curves() {
    // At V = 0.05 the resonance fold and the high-energy branch's doubling cross near
    // (1.3805, 0.0606).
    let o = CurveOptions {
        omega_bounds: (1.2, 1.6),
        velocity_bounds: (0.03, 0.07),
        ds_max: 0.005,
        max_points: 200,
    };
    let (all, points) = atlas((1.2, 1.6, 41), 0.05, o);
    let crossings: Vec<&Codim2Point> = points
        .iter()
        .filter(|p| p.kind == PointKind::Crossing)
        .collect();
    let [c] = crossings[..] else {
        panic!("one crossing expected: {points:?}");
    };
    eprintln!("crossing {c:?}");
    assert!(c.error <= 1e-12, "{c:?}");
    let (other, _) = c.other.unwrap();
    let kinds = (all[c.curve].0.kind, all[other].0.kind);
    assert_eq!(kinds, (Kind::Fold, Kind::PeriodDoubling));
    assert!((c.multipliers[0].0 - 1.0).abs() < 1e-8, "{c:?}");
    // The doubling at its V, re-located by one-parameter continuation from the doubling
    // curve's orbit there, is at its Ω.
    let pd = &all[other].1[c.other.unwrap().1];
    let near = relocated(c.omega, c.velocity, (pd.x0, pd.v0), (1, 0.02));
    eprintln!(
        "crossing Ω = {:.12}, doubling at its V: {near:.12}",
        c.omega
    );
    assert!((near - c.omega).abs() <= SAME_OMEGA, "{near}");
}

#[test]
fn a_doubling_curve_ends_in_resonant_grazing() {
    // At V = 0.1 the doubling of the one-impact P-1 orbit at Ω = 0.6285 meets the grazing
    // where a second impact appears.
    let o = CurveOptions {
        omega_bounds: (0.5, 0.7),
        velocity_bounds: (0.05, 0.15),
        ds_max: 0.002,
        max_points: 200,
    };
    let (all, points) = atlas((0.5, 0.7, 81), 0.1, o);
    let grazing: Vec<&Codim2Point> = points
        .iter()
        .filter(|p| p.kind == PointKind::ResonantGrazing && p.impacts == 1)
        .collect();
    let [g] = grazing[..] else {
        panic!("one resonant grazing of a one-impact orbit expected: {points:?}");
    };
    eprintln!("resonant grazing {g:?}");
    assert_eq!(all[g.curve].0.kind, Kind::PeriodDoubling);
    assert_eq!(g.impacts_beyond, 2);
    assert!(g.error <= LOCATED, "{g:?}");
    assert!((g.multipliers[0].0 + 1.0).abs() < 1e-6, "{g:?}");
    // Independent: at its V, the core's shooting (Newton on the one-period map with the
    // variational equations) from its orbit, at Ω 1e-8 either side: a one-impact orbit on one
    // side only (on the other, two impacts or none found).
    let params = Params::paper();
    let shoot = |w: f64| {
        let (orbits, _) = continue_in_omega(
            params,
            g.velocity,
            &[w],
            SolverOptions::default(),
            1,
            (g.x0, g.v0),
            ShootOptions::default(),
        );
        orbits.first().map(|o| o.impacts)
    };
    let sides = [shoot(g.omega - 1e-8), shoot(g.omega + 1e-8)];
    eprintln!("impacts at Ω ∓ 1e-8: {sides:?}");
    assert!(
        sides.contains(&Some(1)) && sides.iter().any(|s| *s != Some(1)),
        "{sides:?}"
    );
}

/// The period doubling nearest `omega` on the P-`period` branch through `guess` at
/// `velocity`, natural continuation over `omega + half/16 ± half` (9 values, from the middle
/// out; off `omega` by a sixteenth, so that the test function is not 0 at a grid point, where
/// the locator sees no sign change).
fn relocated(omega: f64, velocity: f64, guess: (f64, f64), (period, half): (u32, f64)) -> f64 {
    let mid = omega + half / 16.0;
    let models = grid(mid - half, mid + half, 9, velocity);
    let m = &models[0];
    let so = ShootOptions::default();
    let ws: Vec<f64> = models.iter().map(Model::omega).collect();
    let shoot_over = |ws: &[f64]| {
        let (orbits, _) = continue_in_omega(m.params, velocity, ws, m.opts, period, guess, so);
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
        period,
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
