//! `Simulator::mass_at` gives, without advancing, the bits `Simulator::mass` gives after an
//! advance inside the current step; `inside_step` says when that holds.

use bistable_core::{ContactMode, Instant, Params, Simulator, Sinusoid, SolverOptions};

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
