//! `Simulator::mass_at` gives, without advancing, the bits `Simulator::mass` gives after an
//! advance inside the current step; `inside_step` says when that holds.

use bistable_core::{
    ContactMode, Flights, Instant, Params, Simulator, Sinusoid, SolverOptions, FLIGHT_LANES,
};

#[test]
fn mass_at_is_the_mass_after_advancing_inside_the_step() {
    // Chatter at Omega = 0.2, V = 0.05: steps in flight and riding the plate.
    let params = Params::new(0.02, 0.85).unwrap();
    let plate = Sinusoid::new(0.2, 0.05).unwrap();
    let mut sim = Simulator::new(params, plate.into(), SolverOptions::default()).unwrap();
    let (mut inside, mut riding, mut outside) = (0, 0, 0);
    for k in 1..=20_000 {
        let t = Instant::new(f64::from(k) * 0.003);
        let before = sim.clone();
        let predicted = sim.mass_at(t);
        assert_eq!(predicted.is_some(), sim.inside_step(t));
        sim.advance_instant(t, &mut |_: &bistable_core::Event| {})
            .unwrap();
        let after = sim.mass();
        match predicted {
            Some(m) => {
                inside += 1;
                riding += usize::from(m.2 == ContactMode::Sticking);
                let bits = |m: (f64, f64, ContactMode, bistable_core::Well)| {
                    (m.0.to_bits(), m.1.to_bits(), m.2, m.3)
                };
                assert_eq!(bits(m), bits(after), "at t = {}", t.to_f64());
                // Only the current time moved: the step is the same.
                assert_eq!(before.stats().steps, sim.stats().steps);
            }
            None => outside += 1,
        }
    }
    assert!(
        inside > 10_000 && riding > 1_000 && outside > 100,
        "{inside} {riding} {outside}"
    );
}

#[test]
fn flights_at_is_mass_at_in_each_lane_and_the_key_follows_the_step() {
    // Chatter at Omega = 0.2 (flight, riding, steps ending inside the eight instants) and the
    // baseline at Omega = 1.75 (long flights).
    for (omega, v) in [(0.2, 0.05), (1.75, 0.07)] {
        let params = Params::new(0.02, 0.85).unwrap();
        let plate = Sinusoid::new(omega, v).unwrap();
        let mut sim = Simulator::new(params, plate.into(), SolverOptions::default()).unwrap();
        let (mut lanes, mut flights, mut keys_kept, mut keys_changed) = (0, 0, 0, 0);
        for k in 1..=5_000 {
            let taus: [f64; FLIGHT_LANES] =
                std::array::from_fn(|i| f64::from(k) * 0.01 + i as f64 * 0.0123);
            let ts = taus.map(Instant::new);
            let mut batch = Flights::default();
            sim.flights_at(&taus, &mut batch);
            for (i, &t) in ts.iter().enumerate() {
                lanes += 1;
                let one = sim.mass_at(t);
                if batch.flying[i] {
                    flights += 1;
                    let one = one.expect("a flight lane lies inside the step");
                    assert_eq!(
                        (batch.x[i].to_bits(), batch.v[i].to_bits()),
                        (one.0.to_bits(), one.1.to_bits()),
                        "Omega {omega}, lane {i} at t = {}",
                        t.to_f64()
                    );
                    assert_eq!((one.2, one.3), (ContactMode::Free, sim.well()));
                } else {
                    // Not in flight inside the step (or at its very start).
                    assert!(one.is_none_or(|m| m.2 == ContactMode::Sticking
                        || t.since(Instant::new(sim.time())) <= 0.0
                        || sim.stats().steps == 0));
                }
            }
            let key = sim.step_key();
            let steps = sim.stats().steps;
            sim.advance_instant(ts[0], &mut |_: &bistable_core::Event| {})
                .unwrap();
            if sim.stats().steps == steps {
                assert_eq!(key, sim.step_key(), "only the time moved");
                keys_kept += 1;
            } else {
                assert_ne!(key, sim.step_key(), "a new step");
                keys_changed += 1;
            }
        }
        assert!(
            flights > lanes / 4 && keys_kept > 1_000 && keys_changed > 20,
            "Omega {omega}: {flights} of {lanes} lanes in flight, keys {keys_kept} kept, {keys_changed} changed"
        );
    }
}
