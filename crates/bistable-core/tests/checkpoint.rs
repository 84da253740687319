//! Checkpoints restore a run bit for bit, and bad checkpoints are refused.

use bistable_core::{Checkpoint, Event, Params, Simulator, Sinusoid, SolverOptions};

fn continue_from(sim: &mut Simulator, t_end: f64) -> (Vec<Event>, (f64, f64, f64)) {
    let ev = sim.events_until(t_end).unwrap();
    let s = sim.state();
    (ev, (s.x, s.v, s.t))
}

#[test]
fn restored_runs_continue_identically() {
    // Baseline case and the chatter case; checkpoints at many instants, including inside
    // steps and inside the accumulated tail of a chatter sequence.
    for (omega, v, t_end) in [(1.75, 0.07, 120.0), (0.2, 0.05, 60.0)] {
        let plate = Sinusoid::new(omega, v).unwrap();
        let mut sim =
            Simulator::new(Params::paper(), plate.into(), SolverOptions::default()).unwrap();
        let mut k = 0;
        let mut t = 0.0;
        while t < t_end - 1.0 {
            k += 1;
            // Irregular increments from 0.37 to 2.6 time units.
            t = (t + 0.37 * f64::from(k % 7 + 1)).min(t_end - 1.0);
            sim.advance_to(t, &mut |_: &Event| {}).unwrap();
            let cp: Checkpoint = sim.checkpoint();
            let mut original = sim.clone();
            let mut restored = Simulator::from_checkpoint(&cp).unwrap();
            assert_eq!(restored.checkpoint(), cp);
            // The state right after the restore is the original's (mid-flight: the dense output
            // at `now`, not the step's start gap moved with the plate).
            assert_eq!(restored.state(), sim.state(), "Ω = {omega}, t = {t}");
            assert_eq!(
                continue_from(&mut original, t_end),
                continue_from(&mut restored, t_end),
                "Ω = {omega}, checkpoint at t = {t}"
            );
            assert_eq!(restored.stats(), original.stats());
        }
    }
}

#[test]
fn corrupt_checkpoints_are_refused() {
    let plate = Sinusoid::new(1.75, 0.07).unwrap();
    let mut sim = Simulator::new(Params::paper(), plate.into(), SolverOptions::default()).unwrap();
    sim.advance_to(10.0, &mut |_: &Event| {}).unwrap();
    let good = sim.checkpoint();
    let cases: Vec<(&str, Checkpoint)> = vec![
        (
            "nan gap",
            Checkpoint {
                u0: f64::NAN,
                ..good
            },
        ),
        ("negative gap", Checkpoint { u0: -1e-3, ..good }),
        (
            "now before t0",
            Checkpoint {
                now: (good.t0.0 - 1.0, 0.0),
                ..good
            },
        ),
        ("pinned", Checkpoint { pinned: 9, ..good }),
        (
            "restitution",
            Checkpoint {
                restitution: 2.0,
                ..good
            },
        ),
        ("order", Checkpoint { order: 99, ..good }),
        (
            "bad instant",
            Checkpoint {
                t0: (1.0, 1.0),
                ..good
            },
        ),
        (
            "infinite w",
            Checkpoint {
                w0: f64::INFINITY,
                ..good
            },
        ),
    ];
    for (what, cp) in cases {
        let err = Simulator::from_checkpoint(&cp).err();
        assert!(err.is_some(), "{what} accepted");
        println!("{what}: {}", err.unwrap());
    }
}

#[test]
fn checkpoints_inside_a_chatter_sequence() {
    // Stop at every impact of the chatter sequence before sticking (the last stop leaves the
    // accumulated tail pending) and compare restored and original continuations.
    use std::ops::ControlFlow;
    struct StopAtImpacts;
    impl bistable_core::Observer for StopAtImpacts {
        fn event(&mut self, e: &Event) -> ControlFlow<()> {
            match e {
                Event::Impact(i) if i.t > 10.2 => ControlFlow::Break(()),
                _ => ControlFlow::Continue(()),
            }
        }
    }
    let plate = Sinusoid::new(0.2, 0.05).unwrap();
    let mut sim = Simulator::new(Params::paper(), plate.into(), SolverOptions::default()).unwrap();
    let mut stops = 0;
    let mut tails = 0;
    while !sim.advance(12.0, &mut StopAtImpacts).unwrap() {
        stops += 1;
        let cp = sim.checkpoint();
        tails += usize::from(cp.tail.is_some());
        let mut restored = Simulator::from_checkpoint(&cp).unwrap();
        let mut original = sim.clone();
        assert_eq!(
            continue_from(&mut original, 20.0),
            continue_from(&mut restored, 20.0)
        );
    }
    assert!(stops > 50, "{stops}");
    assert_eq!(tails, 1);
}
