//! The node's simulation loop against the core simulator: every impact, in order, at its
//! located time; commands at their documented instants; bad input refused.

use bistable_core::{Event, Params, SetpointRamp, Simulator, Sinusoid, SolverOptions};
use bistable_impact_node::msg::{Header, ImpactEvent, ShakerCommand, Time};
use bistable_impact_node::params::Settings;
use bistable_impact_node::sim::{Outcome, Runner, MAX_QUEUED_COMMANDS, RAMP_CYCLES};

fn settings(omega: f64, v: f64, rate: f64) -> Settings {
    Settings {
        omega,
        v,
        publish_rate: rate,
        ..Settings::default()
    }
}

/// Runs until simulation time `t_end` \[s\], returning the impacts and the tick times.
fn run_until(r: &mut Runner, t_end: f64) -> (Vec<ImpactEvent>, Vec<f64>) {
    let (mut impacts, mut ticks) = (Vec::new(), Vec::new());
    while r.now() < t_end {
        match r.advance(&mut impacts) {
            Outcome::Tick => ticks.push(r.now()),
            Outcome::Command => {}
            other => panic!("unexpected {other:?} at {}", r.now()),
        }
    }
    (impacts, ticks)
}

fn core_impacts(sim: &mut Simulator, t: f64) -> Vec<bistable_core::Impact> {
    sim.events_until(t)
        .unwrap()
        .into_iter()
        .filter_map(|e| match e {
            Event::Impact(i) => Some(i),
            _ => None,
        })
        .collect()
}

fn paper_sim(omega: f64, v: f64) -> Simulator {
    let plate = Sinusoid::new(omega, v).unwrap();
    Simulator::new(Params::paper(), plate.into(), SolverOptions::default()).unwrap()
}

fn cmd(mode: u8, stamp: f64, omega: f64, velocity: f64, z: f64, zdot: f64) -> ShakerCommand {
    ShakerCommand {
        header: Header {
            stamp: Time::from_seconds(stamp),
            frame_id: String::new(),
        },
        mode,
        omega,
        velocity,
        z,
        zdot,
    }
}

#[test]
fn every_impact_in_order_equal_to_the_core() {
    let mut r = Runner::new(&settings(1.75, 0.07, 7.0)).unwrap();
    let (impacts, ticks) = run_until(&mut r, 300.0);
    let reference = core_impacts(&mut paper_sim(1.75, 0.07), 300.0);
    // The last impact may still wait for its sticking decision.
    assert!(
        impacts.len() + 1 >= reference.len() && impacts.len() > 30,
        "{}",
        impacts.len()
    );
    for (k, (got, want)) in impacts.iter().zip(&reference).enumerate() {
        assert_eq!(got.index, k as u64);
        // Output ticks never restart the integration: the values are identical.
        assert_eq!(
            (
                got.t,
                got.x,
                got.v_before,
                got.v_after,
                got.zdot,
                got.delta_k
            ),
            (
                want.t,
                want.x,
                want.v_before,
                want.v_after,
                want.zdot,
                want.delta_k
            )
        );
        assert_eq!(got.phase, want.phase.unwrap());
        assert_eq!(
            got.header.stamp,
            Time::from_seconds(want.t),
            "stamped at the impact"
        );
        assert!(!got.ended_in_sticking);
    }
    // Ticks every 1/7 s of simulation time.
    for (k, t) in ticks.iter().enumerate() {
        assert!((t - (k + 1) as f64 / 7.0).abs() < 1e-12, "tick {k} at {t}");
    }
    assert_eq!(r.state().impact_count, reference.len() as u64);
}

#[test]
fn si_units_scale_the_nondimensional_solution() {
    let (w, l) = (std::f64::consts::TAU * 3.08, 0.028_19);
    let s = Settings {
        omega0: w,
        delta_x: l,
        ..settings(1.75, 0.07, 50.0)
    };
    let mut r = Runner::new(&s).unwrap();
    let (impacts, _) = run_until(&mut r, 60.0 / w);
    let reference = core_impacts(&mut paper_sim(1.75, 0.07), 59.0);
    assert!(impacts.len() >= reference.len() - 1 && reference.len() > 5);
    for (got, want) in impacts.iter().zip(&reference) {
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-14 * b.abs().max(1e-300);
        assert!(close(got.t, want.t / w) && close(got.x, want.x * l));
        assert!(close(got.v_after, want.v_after * w * l));
        assert!(close(got.delta_k, want.delta_k * (w * l).powi(2)));
    }
    let st = r.state();
    assert!(
        (st.shaker_omega - 1.75 * w).abs() < 1e-12
            && (st.shaker_velocity - 0.07 * w * l).abs() < 1e-15
    );
    assert!(st.kinetic_energy >= 0.0 && (st.kinetic_energy - 0.5 * st.v * st.v).abs() < 1e-15);
}

#[test]
fn sinusoid_command_takes_effect_at_its_stamp_without_a_jump() {
    let mut r = Runner::new(&settings(1.75, 0.07, 10.0)).unwrap();
    let (mut impacts, _) = run_until(&mut r, 20.0);
    let what = r
        .command(&cmd(
            ShakerCommand::MODE_SINUSOID,
            40.25,
            2.5,
            0.1,
            0.0,
            0.0,
        ))
        .unwrap();
    assert!(what.contains("40.25"), "{what}");
    let (before, _) = run_until(&mut r, 40.25);
    impacts.extend(before);
    let z_before = r.state().z;
    let (after, _) = run_until(&mut r, 150.0);
    impacts.extend(after);
    let st = r.state();
    assert_eq!((st.shaker_omega, st.shaker_velocity), (2.5, 0.1));

    let mut sim = paper_sim(1.75, 0.07);
    let mut reference = core_impacts(&mut sim, 40.25);
    assert!(
        (sim.state().z - z_before).abs() < 1e-15,
        "plate position is continuous"
    );
    // The node ramps to the new set-point about the initial centre.
    let ramp = SetpointRamp::start(&mut sim, 0.0, 2.5, 0.1, RAMP_CYCLES).unwrap();
    reference.extend(
        ramp.events_through(&mut sim)
            .unwrap()
            .into_iter()
            .filter_map(|e| e.impact()),
    );
    let on_ramp = reference.len();
    reference.extend(core_impacts(&mut sim, 149.0));
    assert!(reference.len() > 20);
    // Impacts on the ramp (40.25 s to 45.3 s) have the ramp's phase.
    let ramp_end = ramp.end().to_f64();
    let during: Vec<_> = reference
        .iter()
        .filter(|i| i.t > 40.25 && i.t < ramp_end)
        .collect();
    assert!(!during.is_empty() && on_ramp > during.len());
    assert!(during
        .iter()
        .all(|i| i.phase.is_some_and(|p| (0.0..1.0).contains(&p))));
    for (got, want) in impacts.iter().zip(&reference) {
        assert_eq!(
            (got.index, got.t, got.v_after, got.phase),
            (want.index, want.t, want.v_after, want.phase.unwrap())
        );
    }
    // A zero stamp means "now"; a stamp in the past too.
    let now = r.now();
    let what = r.command(&cmd(0, 0.0, 1.0, 0.05, 0.0, 0.0)).unwrap();
    assert!(what.contains(&format!("t = {now} s")), "{what}");
    let what = r.command(&cmd(0, 1.0, 1.0, 0.05, 0.0, 0.0)).unwrap();
    assert!(what.contains(&format!("t = {now} s")), "{what}");
}

#[test]
fn external_samples_are_followed_then_the_simulation_waits() {
    let mut r = Runner::new(&settings(1.75, 0.07, 10.0)).unwrap();
    run_until(&mut r, 5.0);
    // Plate samples of z = 0.04 sin(t) for t = 5.5, 6.0, ..., 8.0.
    for k in 1..=6 {
        let t = 5.0 + 0.5 * k as f64;
        r.command(&cmd(
            ShakerCommand::MODE_EXTERNAL,
            t,
            0.0,
            0.0,
            0.04 * t.sin(),
            0.04 * t.cos(),
        ))
        .unwrap();
    }
    let mut impacts = Vec::new();
    let mut checked = 0;
    loop {
        match r.advance(&mut impacts) {
            Outcome::Blocked => break,
            Outcome::Halted => panic!("{:?}", r.halted()),
            _ => {}
        }
        let st = r.state();
        let t = r.now();
        if ((t - 5.0) * 2.0).fract() == 0.0 && t > 5.0 {
            assert!(
                (st.z - 0.04 * t.sin()).abs() < 1e-12 && (st.zdot - 0.04 * t.cos()).abs() < 1e-12
            );
            assert_eq!(st.shaker_mode, ShakerCommand::MODE_EXTERNAL);
            assert!(st.shaker_omega.is_nan());
            checked += 1;
        }
    }
    assert_eq!(checked, 6);
    assert_eq!(r.now(), 8.0, "waits at the last sample");
    assert_eq!(r.advance(&mut impacts), Outcome::Blocked);
    // Out of order or non-advancing samples are refused; a zero stamp means one period later.
    let err = r.command(&cmd(1, 7.0, 0.0, 0.0, 0.0, 0.0)).unwrap_err();
    assert!(err.contains("not after"), "{err}");
    let ok = r
        .command(&cmd(1, 0.0, 0.0, 0.0, 0.04 * 8.1f64.sin(), 0.0))
        .unwrap();
    assert!(ok.contains("t = 8.1 s"), "{ok}");
    // A sinusoid after external motion takes over where the samples end, whatever its stamp.
    let ok = r.command(&cmd(0, 100.0, 1.75, 0.07, 0.0, 0.0)).unwrap();
    assert!(ok.contains("from t = 8.1 s"), "{ok}");
    let z_end = 0.04 * 8.1f64.sin();
    while r.now() < 8.1 {
        assert_ne!(r.advance(&mut impacts), Outcome::Halted);
    }
    assert!((r.state().z - z_end).abs() < 1e-12);
    run_until(&mut r, 20.0);
    assert_eq!(r.state().shaker_mode, ShakerCommand::MODE_SINUSOID);
}

#[test]
fn bad_commands_are_refused_with_reasons_and_change_nothing() {
    let mut r = Runner::new(&settings(1.75, 0.07, 10.0)).unwrap();
    run_until(&mut r, 3.0);
    let nan = f64::NAN;
    for (c, needle) in [
        (cmd(0, 0.0, nan, 0.1, 0.0, 0.0), "omega = NaN"),
        (cmd(0, 0.0, f64::INFINITY, 0.1, 0.0, 0.0), "not finite"),
        (cmd(0, 0.0, 1.0, -0.1, 0.0, 0.0), "velocity"),
        (cmd(0, 0.0, 0.0, 0.1, 0.0, 0.0), "omega"),
        (cmd(0, 0.0, -1.0, 0.1, 0.0, 0.0), "omega"),
        (cmd(0, 0.0, 1e300, 0.1, 0.0, 0.0), "omega"),
        // Beyond the core's range of Ω (a slow shaker below it, a fast one above it).
        (
            cmd(0, 0.0, 5e-324, 0.07, 0.0, 0.0),
            "omega = 5e-324 rad/s must be in [1e-6, 1e6]·omega0",
        ),
        (
            cmd(0, 0.0, 1.0000000000000002e6, 0.07, 0.0, 0.0),
            "must be in [1e-6, 1e6]·omega0",
        ),
        (cmd(0, 0.0, 1.0, 1.0000000000000002e6, 0.0, 0.0), "velocity"),
        // An in-range Ω and V whose displacement amplitude V/Ω is too large (the core could not
        // continue the plate position with it when it became due).
        (cmd(0, 0.0, 1e-6, 2.0, 0.0, 0.0), "displacement amplitude"),
        (cmd(0, 0.0, 1e-3, 2e3, 0.0, 0.0), "displacement amplitude"),
        (cmd(0, 0.0, 1.0, 0.1, f64::NEG_INFINITY, 0.0), "z = -inf"),
        (cmd(1, 0.0, 0.0, 0.0, 0.0, nan), "zdot"),
        (cmd(1, 0.0, 0.0, 0.0, 1e9, 0.0), "out of range"),
        (cmd(1, 2.0, 0.0, 0.0, 0.0, 0.0), "not after"),
        (cmd(7, 0.0, 1.0, 0.1, 0.0, 0.0), "unknown mode 7"),
        (cmd(255, 0.0, 1.0, 0.1, 0.0, 0.0), "unknown mode"),
        // Fields the mode does not use must be 0.
        (
            cmd(0, 0.0, 1.75, 0.07, 0.01, 0.0),
            "z = 0.01 is not used by MODE_SINUSOID and must be 0",
        ),
        (cmd(0, 0.0, 1.75, 0.07, 0.0, -1e-300), "zdot = -1e-300"),
        (
            cmd(1, 0.0, 1.75, 0.0, 0.01, 0.0),
            "omega = 1.75 is not used by MODE_EXTERNAL",
        ),
        (cmd(1, 0.0, 0.0, 0.07, 0.01, 0.0), "velocity = 0.07"),
    ] {
        let err = r.command(&c).unwrap_err();
        assert!(err.contains(needle), "{c:?}: {err}");
    }
    let mut bad_stamp = cmd(0, 0.0, 1.0, 0.1, 0.0, 0.0);
    bad_stamp.header.stamp = Time {
        sec: -1,
        nanosec: 0,
    };
    assert!(r.command(&bad_stamp).unwrap_err().contains("stamp"));
    bad_stamp.header.stamp = Time {
        sec: 1,
        nanosec: 1_000_000_000,
    };
    assert!(r.command(&bad_stamp).unwrap_err().contains("stamp"));
    // A negative velocity that scales to −0 (ω0 = 20 rad/s) is still negative: refused.
    let mut fast = Runner::new(&Settings {
        omega0: 20.0,
        ..settings(1.75, 0.07, 10.0)
    })
    .unwrap();
    let err = fast.command(&cmd(0, 0.0, 35.0, -5e-324, 0.0, 0.0));
    assert!(err.unwrap_err().contains("velocity = -5e-324"));
    // Nothing was queued: the simulation goes on with the old shaker and matches the core.
    let (impacts, _) = run_until(&mut r, 60.0);
    let reference = core_impacts(&mut paper_sim(1.75, 0.07), 60.0);
    let last = impacts.last().unwrap();
    assert_eq!(last.t, reference[last.index as usize].t);
    assert_eq!(r.state().shaker_omega, 1.75);
    // -0 is zero.
    r.command(&cmd(0, 0.0, 1.75, 0.07, -0.0, -0.0)).unwrap();
    // Commands due now take effect at once: any number of them between two steps is accepted
    // (regression: under a flood of such commands the queue filled and valid ones were
    // refused).
    for k in 0..5 * MAX_QUEUED_COMMANDS {
        let v = if k % 2 == 0 { 0.07 } else { 0.08 };
        r.command(&cmd(0, 0.0, 1.75, v, 0.0, 0.0)).unwrap();
    }
    assert_eq!(r.state().shaker_velocity, 0.08);
    assert_eq!(r.commands_dropped(), 0);
    r.command(&cmd(0, 0.0, 1.75, 0.07, 0.0, 0.0)).unwrap();
    // The queue is bounded.
    for k in 0..MAX_QUEUED_COMMANDS {
        r.command(&cmd(0, 100.0 + k as f64, 1.75, 0.07, 0.0, 0.0))
            .unwrap();
    }
    assert!(r
        .command(&cmd(0, 0.0, 1.75, 0.07, 0.0, 0.0))
        .unwrap_err()
        .contains("waiting"));
}

#[test]
fn impacts_that_end_in_sticking_are_flagged() {
    // Slow shaking: chatter sequences that end with the mass riding on the plate.
    let mut r = Runner::new(&settings(0.2, 0.05, 10.0)).unwrap();
    let (impacts, _) = run_until(&mut r, 100.0);
    let mut sim = paper_sim(0.2, 0.05);
    let events = sim.events_until(100.0).unwrap();
    let sticking: Vec<u64> = events
        .iter()
        .filter_map(|e| match e {
            Event::StickStart { impacts, .. } if *impacts > 0 => Some(impacts - 1),
            _ => None,
        })
        .collect();
    assert!(!sticking.is_empty(), "the case must stick");
    let flagged: Vec<u64> = impacts
        .iter()
        .filter(|i| i.ended_in_sticking)
        .map(|i| i.index)
        .collect();
    let published = impacts.len() as u64;
    let expected: Vec<u64> = sticking.into_iter().filter(|&k| k < published).collect();
    assert_eq!(flagged, expected);
    for (k, i) in impacts.iter().enumerate() {
        assert_eq!(i.index, k as u64);
    }
}

#[test]
fn runtime_changes_of_parameters_and_rate() {
    let mut r = Runner::new(&settings(1.75, 0.07, 10.0)).unwrap();
    run_until(&mut r, 10.0);
    let before = r.state();
    r.set_params(0.3, 0.5).unwrap();
    let after = r.state();
    assert!((before.x - after.x).abs() < 1e-15 && (before.v - after.v).abs() < 1e-15);
    assert!(r.set_params(f64::NAN, 0.5).unwrap_err().contains("zeta"));
    assert!(r.set_params(0.1, 1.5).unwrap_err().contains("restitution"));
    // Heavy damping: the energy decays.
    run_until(&mut r, 40.0);
    r.set_rate(4.0);
    let (_, ticks) = run_until(&mut r, 42.0);
    assert_eq!(ticks, [40.25, 40.5, 40.75, 41.0, 41.25, 41.5, 41.75, 42.0]);
    r.set_frame_id("lab");
    assert_eq!(r.state().header.frame_id, "lab");
}

#[test]
fn sinusoid_commands_end_on_the_set_point_about_the_initial_centre() {
    // SI units (omega0 = 2 rad/s, delta_x = 0.5 m); 30 commands at random stamps, many while
    // the previous ramp runs, two after external samples.
    let mut r = Runner::new(&Settings {
        omega0: 2.0,
        delta_x: 0.5,
        ..settings(1.75, 0.07, 20.0)
    })
    .unwrap();
    let mut seed = 7u64;
    let mut uniform = |a: f64, b: f64| {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        a + (b - a) * ((seed >> 11) as f64 / (1u64 << 53) as f64)
    };
    let mut impacts = Vec::new();
    let mut t = 0.0;
    for k in 0..30 {
        t += uniform(0.2, 4.0);
        if k % 15 == 14 {
            r.command(&cmd(1, t, 0.0, 0.0, 0.1, -0.05)).unwrap();
            t += 0.5;
        }
        let (omega, velocity) = (uniform(2.0, 5.0), uniform(0.05, 0.3));
        r.command(&cmd(0, t, omega, velocity, 0.0, 0.0)).unwrap();
        while r.now() < t {
            assert_ne!(r.advance(&mut impacts), Outcome::Halted, "{:?}", r.halted());
        }
    }
    assert_eq!(r.commands_dropped(), 0);
    // After the last ramp (2 periods of at least pi s): z = (V/omega) sin(.) about 0, so
    // z^2 + (zdot/omega)^2 = (V/omega)^2 at every tick.
    let (_, ticks) = run_until(&mut r, t + 2.0 * std::f64::consts::PI);
    assert!(ticks.len() > 100);
    let mut worst = 0.0_f64;
    for _ in 0..200 {
        r.advance(&mut impacts);
        let st = r.state();
        assert_eq!(st.shaker_mode, ShakerCommand::MODE_SINUSOID);
        let a = st.shaker_velocity / st.shaker_omega;
        let got = st.z.hypot(st.zdot / st.shaker_omega);
        worst = worst.max((got - a).abs());
    }
    assert!(worst < 1e-14, "{worst:e}");
}

#[test]
fn reset_restarts_from_the_requested_state_with_indices_from_0() {
    let mut r = Runner::new(&settings(1.75, 0.07, 7.0)).unwrap();
    // A set-point change in the queue and one applied: both are discarded by the reset.
    r.command(&cmd(ShakerCommand::MODE_SINUSOID, 20.0, 2.5, 0.1, 0.0, 0.0))
        .unwrap();
    r.command(&cmd(ShakerCommand::MODE_SINUSOID, 90.0, 2.0, 0.1, 0.0, 0.0))
        .unwrap();
    let (before, _) = run_until(&mut r, 50.0);
    assert!(before.len() > 10);
    let count = r.impact_count();
    let mut flushed = Vec::new();
    let note = r
        .reset(&settings(1.75, 0.07, 7.0), None, &mut flushed)
        .unwrap();
    assert!(note.contains("restart at 0"), "{note}");
    // The impact held back for its sticking decision belongs to the run before.
    assert!(flushed.len() <= 1);
    if let Some(last) = flushed.first() {
        assert_eq!(last.index, before.last().unwrap().index + 1);
        assert_eq!(count, last.index + 1);
    } else {
        assert_eq!(count, before.last().unwrap().index + 1);
    }
    assert_eq!((r.now(), r.impact_count()), (0.0, 0));
    let st = r.state();
    assert_eq!((st.x, st.v, st.z, st.t), (0.0, 0.0, 0.0, 0.0));
    assert_eq!(st.shaker_omega, 1.75);
    // After the reset: exactly a fresh run from the initial condition (no command applies).
    let (impacts, ticks) = run_until(&mut r, 120.0);
    let reference = core_impacts(&mut paper_sim(1.75, 0.07), 120.0);
    assert!(impacts.len() + 1 >= reference.len() && impacts.len() > 20);
    for (k, (got, want)) in impacts.iter().zip(&reference).enumerate() {
        assert_eq!(got.index, k as u64);
        assert_eq!((got.t, got.x, got.v_after), (want.t, want.x, want.v_after));
    }
    assert!((ticks[0] - 1.0 / 7.0).abs() < 1e-15);
    assert_eq!(
        r.state().shaker_omega,
        1.75,
        "queued commands are discarded"
    );

    // To a given state, in SI units: the core's run from that state.
    let s = Settings {
        omega0: 2.0,
        delta_x: 0.5,
        ..settings(1.75, 0.07, 7.0)
    };
    let mut r = Runner::new(&s).unwrap();
    run_until(&mut r, 10.0);
    r.reset(&s, Some((0.01, -0.05)), &mut Vec::new()).unwrap();
    let (impacts, _) = run_until(&mut r, 40.0);
    let plate = Sinusoid::new(1.75, 0.07).unwrap();
    let mut sim = Simulator::with_state(
        Params::paper(),
        plate.into(),
        SolverOptions::default(),
        0.0,
        0.02,
        -0.05,
    )
    .unwrap();
    let reference = core_impacts(&mut sim, 79.0);
    assert!(
        impacts.len() > 5 && impacts.len() + 1 >= reference.len(),
        "{} {}",
        impacts.len(),
        reference.len()
    );
    for (k, (got, want)) in impacts.iter().zip(&reference).enumerate() {
        assert_eq!(got.index, k as u64);
        assert_eq!((got.t, got.x), (want.t / 2.0, want.x * 0.5));
    }
}

#[test]
fn bad_reset_states_are_refused_and_change_nothing() {
    let s = settings(1.75, 0.07, 7.0);
    let mut r = Runner::new(&s).unwrap();
    run_until(&mut r, 10.0);
    let (t, count) = (r.now(), r.impact_count());
    for (x, v, needle) in [
        (-0.01, 0.0, "below the plate"),
        (f64::NAN, 0.0, "x = NaN is not finite"),
        (0.5, f64::INFINITY, "v = inf is not finite"),
        (2e6, 0.0, "out of range"),
        (0.5, -3e6, "out of range"),
    ] {
        let mut flushed = Vec::new();
        let why = r.reset(&s, Some((x, v)), &mut flushed).unwrap_err();
        assert!(why.contains(needle), "{x} {v}: {why}");
        assert!(flushed.is_empty());
        assert_eq!((r.now(), r.impact_count()), (t, count));
    }
    // The run goes on as if nothing happened.
    let (more, _) = run_until(&mut r, 30.0);
    assert!(more.first().is_some_and(|i| i.index + 1 >= count));
}
