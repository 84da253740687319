//! Response classes, periodic orbits and Lyapunov exponents against the paper and against
//! long simulations.

use bistable_core::{
    classify, largest_lyapunov, shoot, ClassifyOptions, Event, Params, ResponseClass, ShootOptions,
    Simulator, Sinusoid, SolverOptions, Well,
};

fn class_at(omega: f64, v: f64) -> bistable_core::Classification {
    let plate = Sinusoid::new(omega, v).unwrap();
    classify(
        Params::paper(),
        plate,
        SolverOptions::default(),
        ClassifyOptions::default(),
    )
    .unwrap()
}

#[test]
fn paper_classes() {
    // Ω = 0.85, V = 0.11: period-4 intrawell, five impacts per four shaker periods.
    let c = class_at(0.85, 0.11);
    assert_eq!(c.class, ResponseClass::Intrawell);
    assert_eq!(c.period, Some(4));
    assert_eq!(c.impacts_per_period, Some(5));
    assert!(c.stopped_early);
    // V = 0.12: escapes in the transient and returns to a period-8 intrawell response.
    let c = class_at(0.85, 0.12);
    assert_eq!(c.class, ResponseClass::TransientInterwell);
    assert_eq!(c.period, Some(8));
    assert_eq!(c.final_well, Well::One);
    // V = 0.15: one impact, then at rest in well 2.
    let c = class_at(0.85, 0.15);
    assert_eq!(c.class, ResponseClass::TransientInterwell);
    assert!(c.at_rest_in_second_well);
    assert_eq!((c.snap_throughs, c.final_well), (1, Well::Two));
}

#[test]
fn period_doubling_into_chaos_at_v_0_07() {
    // Paper: at V = 0.07, period 1 → 2 → 4 → chaos as Ω grows from about 2.
    let periods: Vec<Option<u32>> = [2.0, 2.2, 2.45]
        .iter()
        .map(|&w| class_at(w, 0.07).period)
        .collect();
    assert_eq!(periods, vec![Some(1), Some(2), None]);
    let chaotic = class_at(2.45, 0.07);
    assert!(chaotic.chaotic, "{chaotic:?}");
    println!("Ω = 2.45: Lyapunov exponent {:?}", chaotic.lyapunov);
    // Negative exponent on the periodic branches.
    for w in [2.0, 2.2] {
        let plate = Sinusoid::new(w, 0.07).unwrap();
        let l = largest_lyapunov(Params::paper(), plate, SolverOptions::default(), 500, 500)
            .unwrap()
            .unwrap();
        println!("Ω = {w}: Lyapunov exponent {l:.4}");
        assert!(l < -1e-3, "{l}");
    }
}

#[test]
fn stable_orbit_is_the_attractor_and_satisfies_the_identities() {
    let (omega, v) = (1.75, 0.07);
    let plate = Sinusoid::new(omega, v).unwrap();
    let opts = SolverOptions::default();
    // Long run: the section point after 2000 shaker periods.
    let mut sim = Simulator::new(Params::paper(), plate.into(), opts).unwrap();
    sim.advance_to(2000.0 * plate.period(), &mut |_: &Event| {})
        .unwrap();
    let st = sim.state();
    // Shooting from a rough guess.
    let orbit = shoot(
        Params::paper(),
        plate,
        opts,
        1,
        (0.05, 0.0),
        ShootOptions::default(),
    )
    .unwrap();
    println!("{orbit:?}");
    assert!(orbit.stable && !orbit.sticks);
    assert_eq!(orbit.impacts, 1);
    assert!((orbit.x0 - st.x).abs() < 1e-10 && (orbit.v0 - st.v).abs() < 1e-10);
    let m = orbit.monodromy;
    let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
    assert!(((det - orbit.det_identity) / orbit.det_identity).abs() < 1e-10);
}

#[test]
fn unstable_period_one_orbit_after_the_doubling() {
    // At Ω = 2.2 the attractor has period 2; the period-1 orbit still exists but is unstable
    // with a multiplier below −1 (it lost stability by period doubling).
    let plate = Sinusoid::new(2.2, 0.07).unwrap();
    let opts = SolverOptions::default();
    let p2 = shoot(
        Params::paper(),
        plate,
        opts,
        2,
        (0.05, 0.0),
        ShootOptions::default(),
    );
    let mut sim = Simulator::new(Params::paper(), plate.into(), opts).unwrap();
    sim.advance_to(2000.0 * plate.period(), &mut |_: &Event| {})
        .unwrap();
    let a = sim.state();
    sim.advance_to(2001.0 * plate.period(), &mut |_: &Event| {})
        .unwrap();
    let b = sim.state();
    let guess = (0.5 * (a.x + b.x), 0.5 * (a.v + b.v));
    let p1 = shoot(
        Params::paper(),
        plate,
        opts,
        1,
        guess,
        ShootOptions::default(),
    )
    .unwrap();
    println!(
        "P1: {:?}\nP2: {:?}",
        p1.multipliers,
        p2.as_ref().map(|o| o.multipliers)
    );
    assert!(!p1.stable);
    assert!(p1.multipliers[0].0 < -1.0 && p1.multipliers[0].1 == 0.0);
    let p2 = p2.unwrap();
    assert!(p2.stable);
}
