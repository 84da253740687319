//! Set-point ramps (`SetpointRamp`): 100 random sinusoid commands at random instants (many
//! while the previous ramp still runs, some after external plate pieces) keep the plate
//! position and velocity continuous, and leave it on `(V/Ω) sin(·)` about the original
//! centre; `Simulator::set_sinusoid` (kept for the FMU) lets the centre drift.

mod support;

use bistable_core::{
    Event, Instant, Params, PlateMotion, PolyPiece, SetpointRamp, Simulator, Sinusoid,
    SolverOptions,
};
use support::Rng;

/// Largest jumps of plate position and velocity seen where the plate motion changes.
#[derive(Default, Debug)]
struct Jumps {
    z: f64,
    zdot: f64,
    switches: u32,
}

impl Jumps {
    fn record(&mut self, before: (f64, f64, f64), after: (f64, f64, f64)) {
        self.z = self.z.max((after.0 - before.0).abs());
        self.zdot = self.zdot.max((after.1 - before.1).abs());
        self.switches += 1;
    }
}

fn new_sim() -> Simulator {
    let plate = Sinusoid::new(1.75, 0.07).unwrap();
    Simulator::new(Params::paper(), plate.into(), SolverOptions::default()).unwrap()
}

fn motion_now(sim: &Simulator) -> (f64, f64, f64) {
    sim.plate().motion(sim.instant())
}

/// Advances `sim` to `until`, following `ramp` from piece to piece.
fn advance(sim: &mut Simulator, ramp: Option<&SetpointRamp>, until: f64, jumps: &mut Jumps) {
    loop {
        if let Some(r) = ramp {
            let before = motion_now(sim);
            let old = *sim.plate();
            r.follow(sim).unwrap();
            if *sim.plate() != old {
                jumps.record(before, motion_now(sim));
            }
        }
        let target = match sim.plate().horizon() {
            Some(h) if h.to_f64() < until => h.to_f64(),
            _ => until,
        };
        sim.advance_to(target, &mut |_: &Event| {}).unwrap();
        if target >= until {
            return;
        }
    }
}

#[test]
fn random_setpoints_keep_the_plate_continuous_and_centred() {
    let centre = 0.0;
    let mut rng = Rng(2026);
    let mut sim = new_sim();
    let mut ramp = None;
    let mut jumps = Jumps::default();
    let mut t = 0.0;
    for k in 0..100 {
        t += rng.range(0.3, 6.0);
        advance(&mut sim, ramp.as_ref(), t, &mut jumps);
        if k % 10 == 9 {
            // External motion for a while: a Hermite piece to some plate state.
            let end = t + rng.range(0.5, 2.0);
            let now = motion_now(&sim);
            let piece = PolyPiece::hermite(
                sim.instant(),
                Instant::new(end),
                (now.0, now.1),
                (rng.range(-0.3, 0.3), rng.range(-0.2, 0.2)),
            )
            .unwrap();
            sim.set_plate(piece.into()).unwrap();
            t = end;
            advance(&mut sim, None, t, &mut jumps);
        }
        let before = motion_now(&sim);
        let (omega, v) = (rng.range(0.5, 3.0), rng.range(0.0, 0.15));
        ramp = Some(SetpointRamp::start(&mut sim, centre, omega, v, 2.0).unwrap());
        jumps.record(before, motion_now(&sim));
    }
    let last = ramp.unwrap();
    let target = last.target();
    t = last.end().to_f64() + 3.0 * target.period();
    advance(&mut sim, Some(&last), t, &mut jumps);
    // Steady: the target sinusoid about the original centre, exactly.
    assert_eq!(*sim.plate(), PlateMotion::Sinusoid(target));
    assert_eq!(target.origin().2, centre);
    // Its mean over a period and its amplitude, sampled.
    let n = 4096;
    let zs: Vec<f64> = (0..n)
        .map(|j| {
            let tj = t + target.period() * f64::from(j) / f64::from(n);
            sim.plate().motion(Instant::new(tj)).0
        })
        .collect();
    let mean = zs.iter().sum::<f64>() / f64::from(n);
    let amp = zs.iter().fold(0.0_f64, |m, z| m.max((z - centre).abs()));
    let want = target.velocity() / target.omega();
    eprintln!(
        "100 commands, {} plate switches: centre error {mean:e}, amplitude error {:e}, \
         largest jump z {:e}, zdot {:e}",
        jumps.switches,
        amp - want,
        jumps.z,
        jumps.zdot
    );
    assert!(mean.abs() < 1e-15, "centre error {mean:e}");
    assert!(
        (amp - want).abs() < 1e-6 * want.max(1e-3),
        "amplitude {amp} vs {want}"
    );
    // Continuity to rounding wherever the motion changes (commands, knots, ramp ends).
    assert!(jumps.switches > 1000, "{jumps:?}");
    assert!(jumps.z < 1e-14, "{jumps:?}");
    assert!(jumps.zdot < 1e-13, "{jumps:?}");
}

#[test]
fn a_ramp_interpolates_its_closed_form_and_runs_at_the_target_phase() {
    let mut sim = new_sim();
    sim.advance_to(10.0, &mut |_: &Event| {}).unwrap();
    let ramp = SetpointRamp::start(&mut sim, 0.0, 2.5, 0.1, 2.0).unwrap();
    let (a, b) = (ramp.start_instant().to_f64(), ramp.end().to_f64());
    assert!((b - a - 2.0 * std::f64::consts::TAU / 2.5).abs() < 1e-12);
    let mut worst = 0.0_f64;
    for j in 0..=1000 {
        let t = Instant::new(a + (b - a) * f64::from(j) / 1000.0);
        let piece = ramp.plate_at(t).unwrap();
        worst = worst.max((piece.motion(t).0 - ramp.motion(t).0).abs());
    }
    // Quintic pieces at 32 per period: a few 1e-11 of the 0.04 amplitude.
    assert!(worst < 1e-10, "{worst:e}");
    // The amplitude moves, the phase does not: z − c = |P| sin(phase) with |P| > 0, so z has
    // the sign of the sine of the target's phase.
    for j in 0..1000 {
        let t = Instant::new(a + (b - a) * f64::from(j) / 1000.0);
        let sin = (ramp.phase_cycles(t) * std::f64::consts::TAU).sin();
        if sin.abs() > 1e-6 {
            assert_eq!(ramp.motion(t).0 > 0.0, sin > 0.0, "at {j}");
        }
    }
}

#[test]
fn set_sinusoid_keeps_its_semantics_and_lets_the_centre_drift() {
    // The FMU's `set_sinusoid` continues position and phase and moves the centre: after a
    // few amplitude changes the mean position is far from 0, while the ramps keep it at 0.
    let mut old = new_sim();
    let mut new = new_sim();
    let mut ramp = None;
    let mut jumps = Jumps::default();
    let mut t = 0.0;
    for k in 0..7 {
        t += 1.3;
        old.advance_to(t, &mut |_: &Event| {}).unwrap();
        advance(&mut new, ramp.as_ref(), t, &mut jumps);
        let v = if k % 2 == 0 { 0.3 } else { 0.05 };
        old.set_sinusoid(1.75, v).unwrap();
        ramp = Some(SetpointRamp::start(&mut new, 0.0, 1.75, v, 2.0).unwrap());
    }
    let PlateMotion::Sinusoid(s) = *old.plate() else {
        panic!("set_sinusoid gives a sinusoid")
    };
    let drift = s.origin().2;
    let last = ramp.unwrap();
    advance(&mut new, Some(&last), last.end().to_f64() + 1.0, &mut jumps);
    let PlateMotion::Sinusoid(r) = *new.plate() else {
        panic!("after the ramp the plate is a sinusoid")
    };
    eprintln!(
        "centre after 7 commands: set_sinusoid {drift:e}, ramps {:e}",
        r.origin().2
    );
    assert!(drift.abs() > 0.01 && r.origin().2 == 0.0);
}
