//! Acceptance checks of issue 22 for grazing: a grazing point on the P-1 branch at V = 0.05
//! located to `GRAZING_TOL` in Ω, the pseudo-arclength branch passing through it (orbits with
//! either impact count on it), and direct simulations on both sides of it.
//!
//! The point (Ω ≈ 0.8407977) is a grazing corner: the stable one-impact P-1 orbit's low flight
//! touches the plate there and the branch turns back as the unstable two-impact orbit, so
//! both orbits exist only above it. A simulation started on the one-impact orbit's fixed point
//! therefore keeps one impact per shaker period at Ω = Ω_g + 1e-6 and falls to another
//! attractor at Ω_g − 1e-6. The offset 1e-6 is 1e4 times the located error and far below the
//! distance to the next change on the branch (the fold at Ω = 0.8758), so each side is the
//! located point's.

mod common;

use bistable_analysis::bifurcations::Kind;
use bistable_analysis::grazing::{CROSSING_TOL, GRAZING_TOL};
use bistable_analysis::Model;
use bistable_core::Event;
use common::{model_at, p1_located};

fn model(omega: f64) -> Model {
    model_at(omega, 0.05)
}

/// Impacts per shaker period over `record` periods after `settle`, from `(x, x')` at phase 0,
/// at `(Ω, V)`.
fn impacts_at(omega: f64, velocity: f64, x: f64, v: f64, settle: u32, record: u32) -> f64 {
    let m = model_at(omega, velocity);
    let mut sim = m.simulator_from(x, v).unwrap();
    let t = m.shaker_period();
    sim.advance_to(f64::from(settle) * t, &mut |_: &Event| {})
        .unwrap();
    let before = sim.stats().impacts;
    sim.advance_to(f64::from(settle + record) * t, &mut |_: &Event| {})
        .unwrap();
    (sim.stats().impacts - before) as f64 / f64::from(record)
}

#[test]
fn grazing_corner_of_the_p1_branch_located_and_simulated() {
    let models: Vec<Model> = (0..31).map(|i| model(0.8 + 0.005 * f64::from(i))).collect();
    let (branches, found) = p1_located(&models);
    let grazings: Vec<_> = found.iter().filter(|p| p.kind == Kind::Grazing).collect();
    let [g] = grazings[..] else {
        panic!("one grazing point expected: {found:#?}");
    };
    eprintln!(
        "grazing at Ω = {:.13} ± {:e}: {g:?}",
        g.omega, g.omega_error
    );
    assert!(g.omega_error <= GRAZING_TOL, "{g:?}");
    assert!((0.84..0.842).contains(&g.omega), "{g:?}");
    assert_eq!((g.impacts_before, g.impacts_after), (2, 1), "{g:?}");
    // The branch passes through the point: two-impact orbits up to it, one-impact orbits
    // from it, both only above it (a corner), the one-impact side approached to
    // `CROSSING_TOL` and followed on up to the end of the grid.
    let b = &branches[g.branch].points;
    let (before, after) = (&b[..=g.index], &b[g.index + 1..]);
    assert!(
        before.iter().rev().take(10).all(|p| p.impacts == 2),
        "{before:?}"
    );
    assert!(after.iter().all(|p| p.impacts == 1), "{after:?}");
    let mut near = before.iter().rev().take(10).chain(after.iter().take(10));
    assert!(near.all(|p| p.omega >= g.omega - g.omega_error), "{b:?}");
    assert!(after[0].omega - g.omega <= CROSSING_TOL, "{:?}", after[0]);
    assert!(before.last().unwrap().omega - g.omega <= 1e-3, "{before:?}");
    assert!(after.last().unwrap().omega >= 0.95, "{:?}", after.last());
    // Direct simulations from the one-impact orbit's fixed point at the point.
    let above = impacts_at(g.omega + 1e-6, 0.05, g.x0, g.v0, 2000, 200);
    let below = impacts_at(g.omega - 1e-6, 0.05, g.x0, g.v0, 2000, 200);
    eprintln!("impacts per period: {above} above, {below} below");
    assert_eq!(above, 1.0);
    assert_ne!(below, 1.0);
}

/// V = 0.03 over Ω 0.6..1.0: the branch turns at two grazing corners, 3 → 2 impacts near
/// Ω = 0.5866 and 2 → 1 near 0.8848 (folds of the 3- and 2-impact orbits lie between). Each
/// is located to `GRAZING_TOL` on one trace through both, and simulations from the located
/// (stable, fewer-impact) orbit keep its impacts per period 1e-6 above the corner and lose
/// them 1e-6 below (same offset and reasons as above).
#[test]
fn both_grazing_corners_at_v003_located_and_passed() {
    let models: Vec<Model> = (0..21)
        .map(|i| model_at(0.6 + 0.02 * f64::from(i), 0.03))
        .collect();
    let (_, found) = p1_located(&models);
    let mut corners: Vec<_> = found.iter().filter(|p| p.kind == Kind::Grazing).collect();
    corners.sort_by(|p, q| p.omega.total_cmp(&q.omega));
    let [low, high] = corners[..] else {
        panic!("two grazing points expected: {found:#?}");
    };
    assert_eq!(
        low.branch, high.branch,
        "one trace through both: {low:?} {high:?}"
    );
    for (g, sides, near) in [(low, (3, 2), 0.5866), (high, (2, 1), 0.8848)] {
        eprintln!("grazing at Ω = {:.13} ± {:e}", g.omega, g.omega_error);
        assert!(g.omega_error <= GRAZING_TOL, "{g:?}");
        assert!((g.omega - near).abs() < 1e-3, "{g:?}");
        assert_eq!((g.impacts_before, g.impacts_after), sides, "{g:?}");
        let kept = g.impacts_after as f64;
        let above = impacts_at(g.omega + 1e-6, 0.03, g.x0, g.v0, 2000, 200);
        let below = impacts_at(g.omega - 1e-6, 0.03, g.x0, g.v0, 2000, 200);
        eprintln!("impacts per period: {above} above, {below} below");
        assert_eq!(above, kept);
        assert_ne!(below, kept);
    }
}
