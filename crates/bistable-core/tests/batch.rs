//! A batch's lanes against lone simulators: every event, state and variational matrix bit for
//! bit, for every lane width, on random trajectories with chatter, sticking and snap-throughs.

use std::ops::ControlFlow;

use bistable_core::{
    Batch, ChatterRule, Event, Instant, Params, Simulator, Sinusoid, SolverOptions, Width,
};

/// Deterministic uniform numbers in `[0, 1)` (SplitMix64).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }

    fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.next()
    }
}

/// One trajectory of the test: its shaker, restitution, start and whether it integrates the
/// variational equations.
#[derive(Clone, Copy)]
struct Case {
    omega: f64,
    velocity: f64,
    restitution: f64,
    x0: f64,
    v0: f64,
    variational: bool,
}

impl Case {
    fn random(rng: &mut Rng) -> Self {
        // Slow shakers chatter and stick; fast ones snap through; starts in both wells.
        let omega = if rng.next() < 0.25 {
            rng.range(0.15, 0.4)
        } else {
            rng.range(0.5, 3.5)
        };
        Self {
            omega,
            velocity: rng.range(0.01, 0.25),
            restitution: rng.range(0.5, 0.95),
            x0: rng.range(0.05, 1.3),
            v0: rng.range(-0.5, 0.5),
            variational: rng.next() < 0.3,
        }
    }

    fn simulator(&self, opts: SolverOptions) -> Simulator {
        let params = Params::new(Params::paper().zeta(), self.restitution).unwrap();
        let plate = Sinusoid::new(self.omega, self.velocity).unwrap();
        let mut sim = Simulator::with_state(params, plate.into(), opts, 0.0, self.x0, self.v0)
            .unwrap_or_else(|_| Simulator::new(params, plate.into(), opts).unwrap());
        if self.variational {
            sim.start_variational();
        }
        sim
    }

    fn sections(&self) -> Sinusoid {
        Sinusoid::new(self.omega, self.velocity).unwrap()
    }
}

/// What a run records at each target: the events on the way, then the state, the variational
/// matrix and the work counters, as bits.
fn record(sim: &Simulator, events: &mut Vec<u64>) {
    let st = sim.state();
    events.extend([st.t, st.x, st.v, st.z, st.zdot].map(f64::to_bits));
    if let Some(phi) = sim.variational() {
        events.extend(phi.iter().flatten().map(|v| v.to_bits()));
    }
    let s = sim.stats();
    events.extend([s.steps, s.impacts, s.sticks, s.snap_throughs]);
}

fn event_bits(e: &Event, out: &mut Vec<u64>) {
    out.extend(format!("{e:?}").bytes().map(u64::from));
}

/// The lone simulator's record over `sections` shaker sections.
fn alone(case: &Case, opts: SolverOptions, sections: u64) -> Vec<u64> {
    let mut sim = case.simulator(opts);
    let plate = case.sections();
    let mut out = Vec::new();
    for k in 1..=sections {
        let mut evs = Vec::new();
        let r = sim.advance_instant(plate.section(k), &mut |e: &Event| event_bits(e, &mut evs));
        out.extend(evs);
        if r.is_err() {
            out.push(u64::MAX);
            return out;
        }
        record(&sim, &mut out);
        if k.is_multiple_of(7) {
            // Sticking forgets the past; the classifier renormalises like this every section.
            let _ = sim.renormalize_variational();
        }
    }
    out
}

/// The same cases as lanes of one batch of `width`, lanes refilled as cases finish.
fn batched(cases: &[Case], opts: SolverOptions, sections: u64, width: Width) -> Vec<Vec<u64>> {
    let mut batch = Batch::new(width, &Params::paper(), opts);
    let mut out: Vec<Vec<u64>> = vec![Vec::new(); cases.len()];
    let mut next = 0;
    let mut lane_case = vec![usize::MAX; batch.lanes()];
    let mut lane_k = vec![0u64; batch.lanes()];
    let mut pending: Vec<Vec<u64>> = vec![Vec::new(); batch.lanes()];
    let mut stopped = Vec::new();
    loop {
        while let Some(lane) = batch.free_lane() {
            if next == cases.len() {
                break;
            }
            let sim = cases[next].simulator(opts);
            batch
                .put(lane, sim, cases[next].sections().section(1))
                .map_err(|e| e.0)
                .unwrap();
            lane_case[lane] = next;
            lane_k[lane] = 1;
            next += 1;
        }
        if batch.is_empty() {
            return out;
        }
        stopped.clear();
        batch.advance(
            &mut |lane: usize, e: &Event| {
                event_bits(e, &mut pending[lane]);
                ControlFlow::Continue(())
            },
            &mut stopped,
        );
        for (lane, r) in stopped.drain(..) {
            let case = lane_case[lane];
            out[case].append(&mut pending[lane]);
            let failed = r.is_err();
            if failed {
                out[case].push(u64::MAX);
            } else {
                assert_eq!(r, Ok(true));
                let sim = batch.sim_mut(lane).unwrap();
                record(sim, &mut out[case]);
                if lane_k[lane].is_multiple_of(7) {
                    let _ = sim.renormalize_variational();
                }
            }
            if failed || lane_k[lane] == sections {
                batch.take(lane);
            } else {
                lane_k[lane] += 1;
                let target = cases[case].sections().section(lane_k[lane]);
                batch.retarget(lane, target).unwrap();
            }
        }
    }
}

fn check_widths(seed: u64, n: usize, opts: SolverOptions, sections: u64) {
    let mut rng = Rng(seed);
    let cases: Vec<Case> = (0..n).map(|_| Case::random(&mut rng)).collect();
    let expected: Vec<Vec<u64>> = cases.iter().map(|c| alone(c, opts, sections)).collect();
    for width in [Width::One, Width::Four, Width::Eight] {
        let got = batched(&cases, opts, sections, width);
        for (i, (g, e)) in got.iter().zip(&expected).enumerate() {
            let c = &cases[i];
            assert!(
                g == e,
                "width {width:?}, case {i} (Ω {}, V {}, e {}, start ({}, {}), var {}) differs",
                c.omega,
                c.velocity,
                c.restitution,
                c.x0,
                c.v0,
                c.variational
            );
        }
    }
}

#[test]
fn lanes_follow_lone_simulators_bit_for_bit() {
    check_widths(1, 24, SolverOptions::default(), 120);
}

#[test]
fn lanes_follow_lone_simulators_at_other_tolerances_and_chatter_rules() {
    check_widths(
        2,
        12,
        SolverOptions::new(1e-14, SolverOptions::default().chatter()).unwrap(),
        80,
    );
    check_widths(
        3,
        12,
        SolverOptions::new(1e-16, ChatterRule::paper()).unwrap(),
        80,
    );
}

#[test]
fn chatter_sticking_and_snap_throughs_are_exercised() {
    // The random cases above must meet every kind of event, or the comparison proves little.
    let mut rng = Rng(1);
    let (mut impacts, mut sticks, mut snaps) = (0, 0, 0);
    for _ in 0..24 {
        let c = Case::random(&mut rng);
        let mut sim = c.simulator(SolverOptions::default());
        let plate = c.sections();
        if sim
            .advance_instant(plate.section(120), &mut |_: &Event| {})
            .is_ok()
        {
            let s = sim.stats();
            impacts += s.impacts;
            sticks += s.sticks;
            snaps += s.snap_throughs;
        }
    }
    assert!(
        impacts > 1000 && sticks > 10 && snaps > 10,
        "{impacts} {sticks} {snaps}"
    );
}

#[test]
fn a_batch_refuses_simulators_it_cannot_run() {
    let opts = SolverOptions::default();
    let mut batch = Batch::new(Width::Four, &Params::paper(), opts);
    let plate = Sinusoid::new(1.75, 0.07).unwrap();
    let other = SolverOptions::new(1e-12, opts.chatter()).unwrap();
    let sim = Simulator::new(Params::paper(), plate.into(), other).unwrap();
    assert!(batch.put(0, sim, Instant::new(1.0)).is_err());
    let sim = Simulator::new(Params::paper(), plate.into(), opts).unwrap();
    assert!(batch.put(7, sim.clone(), Instant::new(1.0)).is_err());
    assert!(batch.put(0, sim.clone(), Instant::new(-1.0)).is_err());
    assert!(batch.put(0, sim.clone(), Instant::new(1.0)).is_ok());
    assert!(batch.put(0, sim, Instant::new(1.0)).is_err());
    assert_eq!(batch.free_lane(), Some(1));
}
