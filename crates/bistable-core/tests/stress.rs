//! Quick stress part: random parameters, states and tolerances, and edge cases. Every run must
//! end cleanly (or with a typed error), never put the mass below the plate by more than rounding,
//! keep every impact consistent with the impact law, and stay within a bounded amount of work.

use bistable_core::{
    ChatterRule, Event, GapAudit, Params, SimError, Simulator, Sinusoid, SolverOptions, Well,
};

/// xorshift64*: a small deterministic generator, so that failures reproduce.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
    }

    fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.next()
    }
}

#[test]
fn random_parameters_states_and_tolerances() {
    let mut rng = Rng(0x5eed_1234_abcd_0001);
    let (mut runs, mut impacts, mut sticks, mut worst_gap) = (0, 0u64, 0u64, 0.0_f64);
    let mut worst_law: f64 = 0.0;
    for case in 0..300 {
        let zeta = rng.range(0.0, 0.5);
        let e = if case % 10 == 0 {
            0.0
        } else {
            rng.range(0.0, 1.0)
        };
        let omega = 10f64.powf(rng.range(-2.0, 1.7)); // 0.01 … 50
        let v = rng.range(0.0, 2.0);
        let tol = 10f64.powf(rng.range(-16.0, -8.0));
        let plate = Sinusoid::new(omega, v).unwrap();
        let t0 = rng.range(0.0, 10.0);
        let z0 = v / omega * (omega * t0).sin();
        let x0 = z0 + rng.range(0.0, 1.0).powi(3);
        let v0 = rng.range(-1.0, 1.0);
        let params = Params::new(zeta, e).unwrap();
        let opts = SolverOptions::new(tol, ChatterRule::Accumulation { horizon: 1e-7 })
            .unwrap()
            .with_max_chatter_impacts(10_000)
            .unwrap();
        let what = format!("case {case}: ζ={zeta} e={e} Ω={omega} V={v} tol={tol} x0={x0} v0={v0}");
        let mut sim = Simulator::with_state(params, plate.into(), opts, t0, x0, v0).unwrap();
        let mut audit = GapAudit::new(8);
        match sim.advance_to(t0 + 40.0, &mut audit) {
            Ok(()) => {}
            Err(SimError::Zeno { .. }) => {}
            Err(err) => panic!("{what}: {err}"),
        }
        runs += 1;
        let st = sim.state();
        assert!(st.x.is_finite() && st.v.is_finite(), "{what}: {st:?}");
        assert!(
            st.gap() >= -1e-12 * (1.0 + v / omega),
            "{what}: gap {}",
            st.gap()
        );
        // Penetration bound: rounding of x − z, relative to the plate amplitude.
        let bound = 1e-12 * (1.0 + v / omega + x0.abs());
        assert!(
            audit.worst.0 >= -bound,
            "{what}: sampled gap {:?}",
            audit.worst
        );
        worst_gap = worst_gap.min(audit.worst.0);
        // Bounded work: at most 2e5 steps for 40 time units, whatever the parameters.
        assert!(sim.stats().steps < 200_000, "{what}: {:?}", sim.stats());
        for ev in &audit.events {
            match ev {
                Event::Impact(i) => {
                    impacts += 1;
                    let (wm, wp) = (i.v_before - i.zdot, i.v_after - i.zdot);
                    let scale = i.v_before.abs() + i.v_after.abs() + i.zdot.abs();
                    let law = (wp + e * wm).abs() / scale.max(1e-300);
                    worst_law = worst_law.max(law);
                    assert!(wm <= 1e-15 * scale, "{what}: approaching from below {i:?}");
                    assert!(law <= 4e-16, "{what}: impact law {law:e}");
                    let dk = 0.5 * (i.v_after.powi(2) - i.v_before.powi(2));
                    assert!((dk - i.delta_k).abs() <= 1e-15 * (1.0 + i.v_before.powi(2)));
                }
                Event::StickStart { .. } => sticks += 1,
                _ => {}
            }
        }
    }
    println!(
        "{runs} random runs: {impacts} impacts, {sticks} sticking phases, worst sampled gap {worst_gap:.1e}, worst impact-law residual {worst_law:.1e}"
    );
}

#[test]
fn plastic_impact_sticks_at_once_and_no_shaking_means_no_motion() {
    // e = 0: the first impact ends in sticking at the same instant (pushed by the plate).
    let plate = Sinusoid::new(1.75, 0.07).unwrap();
    let mut sim = Simulator::new(
        Params::new(0.02, 0.0).unwrap(),
        plate.into(),
        SolverOptions::default(),
    )
    .unwrap();
    let ev = sim.events_until(1.0).unwrap();
    assert!(matches!(ev[0], Event::Impact(i) if i.t == 0.0 && i.v_after == 0.07));
    assert!(matches!(ev[1], Event::StickStart { t, .. } if t == 0.0));
    // V = 0: the mass rests at x = 0 on a plate at rest, forever.
    let plate = Sinusoid::new(1.0, 0.0).unwrap();
    let mut sim = Simulator::new(Params::paper(), plate.into(), SolverOptions::default()).unwrap();
    let ev = sim.events_until(1000.0).unwrap();
    assert!(
        ev.iter().all(|e| matches!(e, Event::StickStart { .. })),
        "{ev:?}"
    );
    let st = sim.state();
    assert_eq!((st.x, st.v), (0.0, 0.0));
}

#[test]
fn elastic_impacts_conserve_energy_without_damping() {
    // e = 1, ζ = 0, plate at rest (V = 0) at z = 0: the mass bounces forever on the plate in
    // well 1 with constant energy.
    let plate = Sinusoid::new(1.0, 0.0).unwrap();
    let params = Params::new(0.0, 1.0).unwrap();
    let mut sim = Simulator::with_state(
        params,
        plate.into(),
        SolverOptions::default(),
        0.0,
        0.2,
        0.0,
    )
    .unwrap();
    let e0 = sim.state().potential_energy();
    let ev = sim.events_until(1000.0).unwrap();
    let st = sim.state();
    let drift = ((st.kinetic_energy() + st.potential_energy()) - e0).abs() / e0;
    println!(
        "e = 1, ζ = 0: {} impacts over τ = 1000, energy drift {drift:.1e}",
        ev.len()
    );
    assert!(ev.len() > 100);
    assert!(drift < 1e-12, "{drift}");
}

#[test]
fn quasi_static_escape_threshold() {
    // Eq. 18: slow shaking lifts the mass on the plate; it escapes to well 2 when the plate's
    // amplitude V/Ω reaches the barrier at x = ½.
    let omega = 0.01;
    let escapes = |v: f64| {
        let plate = Sinusoid::new(omega, v).unwrap();
        let mut sim =
            Simulator::new(Params::paper(), plate.into(), SolverOptions::default()).unwrap();
        sim.advance_to(1.2 * plate.period(), &mut |_: &Event| {})
            .unwrap();
        sim.stats().snap_throughs > 0 && sim.state().well == Well::Two
    };
    assert!(!escapes(0.49 * omega), "amplitude 0.49 escaped");
    assert!(escapes(0.51 * omega), "amplitude 0.51 did not escape");
}
