//! Analytic identities: energy conservation without damping, the impact law's energy balance,
//! and independence of the trajectory from the output times.

use bistable_core::{
    potential, ChatterRule, Event, Params, PlateMotion, Simulator, Sinusoid, SolverOptions, State,
};

fn energy(s: &State) -> f64 {
    s.kinetic_energy() + s.potential_energy()
}

/// Largest relative energy error over `periods` undamped natural periods in well 2, sampled
/// 100 times; the run must see no event at all.
fn energy_drift(opts: SolverOptions, periods: u32) -> f64 {
    // ζ = 0, plate at rest at z = 0, mass oscillating in well 2 between 0.8 and 1.2: no impact.
    let plate: PlateMotion = Sinusoid::new(1.0, 0.0).unwrap().into();
    let params = Params::new(0.0, 0.85).unwrap();
    let mut sim = Simulator::with_state(params, plate, opts, 0.0, 1.2, 0.0).unwrap();
    let e0 = energy(&sim.state());
    let mut events = 0;
    let mut worst: f64 = 0.0;
    for k in 1..=100 {
        let t = f64::from(k) * f64::from(periods) / 100.0 * std::f64::consts::TAU;
        sim.advance_to(t, &mut |_: &Event| events += 1).unwrap();
        worst = worst.max(((energy(&sim.state()) - e0) / e0).abs());
    }
    assert_eq!(events, 0);
    worst
}

#[test]
fn energy_is_conserved_without_damping_over_ten_thousand_periods() {
    for tol in [1e-16, 1e-17] {
        let opts = SolverOptions::new(tol, ChatterRule::Accumulation { horizon: 1e-7 }).unwrap();
        let drift = energy_drift(opts, 10_000);
        println!("tol {tol:e}: relative energy drift over 10^4 natural periods {drift:.2e}");
        assert!(drift < 1e-12, "tol {tol}: {drift}");
    }
}

#[test]
fn impacts_obey_the_impact_law() {
    let plate = Sinusoid::new(2.5, 0.07).unwrap();
    let e = 0.85;
    let mut sim = Simulator::new(Params::paper(), plate.into(), SolverOptions::default()).unwrap();
    let mut n = 0;
    sim.advance_to(500.0, &mut |ev: &Event| {
        if let Event::Impact(i) = ev {
            n += 1;
            // Newton's law on the relative velocity (Eq. 5), and Eq. 10 for ΔK.
            let w_minus = i.v_before - i.zdot;
            let w_plus = i.v_after - i.zdot;
            assert!(w_minus <= 0.0);
            // (velocities are stored as mass velocities: one rounding each)
            let scale = i.v_before.abs() + i.v_after.abs() + i.zdot.abs();
            assert!((w_plus + e * w_minus).abs() <= 4e-16 * scale);
            let dk = 0.5 * (i.v_after.powi(2) - i.v_before.powi(2));
            assert!((dk - i.delta_k).abs() < 1e-17);
            // Eq. 14/15: contact needs v_before/V <= cos φ (grazing at equality).
            let phi = i.phase.unwrap() * std::f64::consts::TAU;
            assert!(i.v_before / 0.07 <= phi.cos() + 1e-9);
        }
    })
    .unwrap();
    assert!(n > 100);
}

#[test]
fn output_times_do_not_change_the_trajectory() {
    let plate = Sinusoid::new(1.75, 0.07).unwrap();
    let run = |dt: f64| {
        let mut sim =
            Simulator::new(Params::paper(), plate.into(), SolverOptions::default()).unwrap();
        let mut impacts = Vec::new();
        let mut t = 0.0;
        let mut k = 0u32;
        while t < 200.0 {
            k += 1;
            t = (f64::from(k) * dt).min(200.0);
            sim.advance_to(t, &mut |e: &Event| impacts.push(*e))
                .unwrap();
        }
        (sim.state(), impacts)
    };
    let (s_ref, i_ref) = run(200.0);
    for dt in [1e-3, 0.01, 0.1, 1.0, 10.0] {
        let (s, i) = run(dt);
        assert_eq!(i, i_ref, "dt = {dt}");
        assert_eq!((s.x, s.v), (s_ref.x, s_ref.v), "dt = {dt}");
    }
}

#[test]
fn barrier_energy_constant() {
    assert_eq!(potential::energy(0.5), 1.0 / 32.0);
}
