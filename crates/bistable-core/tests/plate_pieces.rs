//! External plate motion given piece by piece (as an FMU input or a ROS command stream would).

use bistable_core::{
    Event, Impact, Instant, Params, PieceMemo, PlateMotion, PolyPiece, Sample, SampleHistory,
    SimError, Simulator, Sinusoid, SolverOptions,
};

fn impacts(ev: &[Event]) -> Vec<Impact> {
    ev.iter().filter_map(Event::impact).collect()
}

/// Largest deviation (impact time or rebound velocity) over τ ≤ 100 between the sinusoid and the
/// same sinusoid fed as cubic Hermite pieces of length `h` built from samples of `(z, ż)`.
fn hermite_deviation(h: f64) -> f64 {
    let shaker = PlateMotion::from(Sinusoid::new(1.75, 0.07).unwrap());
    let t_end = 100.0;
    let mut exact = Simulator::new(Params::paper(), shaker, SolverOptions::default()).unwrap();
    let ev_exact = exact.events_until(t_end).unwrap();
    let piece = |k: u32| {
        let (a, b) = (
            Instant::new(f64::from(k) * h),
            Instant::new(f64::from(k + 1) * h),
        );
        let (za, zda, _) = shaker.motion(a);
        let (zb, zdb, _) = shaker.motion(b);
        PolyPiece::hermite(a, b, (za, zda), (zb, zdb)).unwrap()
    };
    let mut sim =
        Simulator::new(Params::paper(), piece(0).into(), SolverOptions::default()).unwrap();
    let mut ev = Vec::new();
    let n = (t_end / h).round() as u32;
    for k in 0..n {
        if k > 0 {
            sim.set_plate(piece(k).into()).unwrap();
        }
        sim.advance_to(f64::from(k + 1) * h, &mut |e: &Event| ev.push(*e))
            .unwrap();
    }
    let (a, b) = (impacts(&ev_exact), impacts(&ev));
    assert_eq!(a.len(), b.len());
    // Not periodic: no phase.
    assert!(b.iter().all(|i| i.phase.is_none()));
    a.iter()
        .zip(&b)
        .map(|(p, q)| (p.t - q.t).abs().max((p.v_after - q.v_after).abs()))
        .fold(0.0, f64::max)
}

#[test]
fn hermite_pieces_converge_to_the_sinusoid_run() {
    // The plate velocity of a cubic Hermite piece is off by O(h³); the transient amplifies the
    // resulting rebound errors by a fixed factor, so the deviation must fall by 2³ to 2⁴ when h halves.
    let coarse = hermite_deviation(0.004);
    let fine = hermite_deviation(0.002);
    println!("Hermite pieces: deviation {coarse:.2e} (h = 0.004), {fine:.2e} (h = 0.002)");
    let ratio = coarse / fine;
    assert!((5.0..20.0).contains(&ratio), "ratio {ratio}");
    assert!(fine < 1e-7, "{fine}");
}

#[test]
fn pieces_are_checked() {
    let p = PolyPiece::new(Instant::new(0.0), Instant::new(1.0), &[0.0, 0.1]).unwrap();
    let mut sim = Simulator::new(Params::paper(), p.into(), SolverOptions::default()).unwrap();
    // Beyond the piece: refused, nothing done.
    assert!(matches!(
        sim.advance_to(1.5, &mut |_: &Event| {}),
        Err(SimError::BeyondPlate { .. })
    ));
    sim.advance_to(0.5, &mut |_: &Event| {}).unwrap();
    // A piece that would make the plate jump: refused.
    let jump = PolyPiece::new(Instant::new(0.5), Instant::new(2.0), &[0.3]).unwrap();
    assert!(matches!(
        sim.set_plate(jump.into()),
        Err(SimError::PlateJump { .. })
    ));
    // Going back in time: refused.
    assert!(matches!(
        sim.advance_to(0.25, &mut |_: &Event| {}),
        Err(SimError::BackwardTime { .. })
    ));
    // The run goes on after refusals.
    sim.advance_to(1.0, &mut |_: &Event| {}).unwrap();
    assert_eq!(sim.time(), 1.0);
}

#[test]
fn switching_sinusoid_keeps_the_plate_continuous() {
    let plate = Sinusoid::new(1.75, 0.07).unwrap();
    let mut sim = Simulator::new(Params::paper(), plate.into(), SolverOptions::default()).unwrap();
    sim.advance_to(37.3, &mut |_: &Event| {}).unwrap();
    let before = sim.state();
    sim.set_sinusoid(2.5, 0.1).unwrap();
    let after = sim.state();
    // The mass keeps its position and velocity (to the rounding of gap + plate).
    assert!((before.x - after.x).abs() <= f64::EPSILON * before.x.abs());
    assert!((before.v - after.v).abs() <= f64::EPSILON * before.v.abs());
    assert!((before.z - after.z).abs() < 1e-16);
    let ev = sim.events_until(200.0).unwrap();
    assert!(!impacts(&ev).is_empty());
    assert!(sim.state().gap() >= 0.0);
}

/// The baseline sinusoid as cubic Hermite pieces of length `h`, piece `k` over `[kh, (k+1)h]`.
fn sinusoid_piece(h: f64, k: u32) -> PolyPiece {
    let shaker = PlateMotion::from(Sinusoid::new(1.75, 0.07).unwrap());
    let (a, b) = (
        Instant::new(f64::from(k) * h),
        Instant::new(f64::from(k + 1) * h),
    );
    let (za, zda, _) = shaker.motion(a);
    let (zb, zdb, _) = shaker.motion(b);
    PolyPiece::hermite(a, b, (za, zda), (zb, zdb)).unwrap()
}

/// Runs pieces `from..to` of length `h` on `sim`, with `fly_over` first when `fly`, recording
/// the state at each piece's end and the events.
fn run_pieces(
    sim: &mut Simulator,
    h: f64,
    from: u32,
    to: u32,
    fly: bool,
) -> (Vec<[f64; 4]>, Vec<Event>) {
    let (mut states, mut ev) = (Vec::new(), Vec::new());
    for k in from..to {
        let piece = sinusoid_piece(h, k);
        if k > 0 && !(fly && sim.fly_over(&piece, f64::INFINITY)) {
            sim.set_plate(piece.into()).unwrap();
        }
        sim.advance_instant(piece.end(), &mut |e: &Event| ev.push(*e))
            .unwrap();
        let s = sim.state();
        states.push([s.x, s.v, s.z, s.zdot]);
    }
    (states, ev)
}

#[test]
fn kept_flights_follow_the_restarted_run_and_restore_bit_for_bit() {
    let (h, n) = (0.01, 10_000);
    let start = || {
        Simulator::new(
            Params::paper(),
            sinusoid_piece(h, 0).into(),
            SolverOptions::default(),
        )
        .unwrap()
    };
    // Restarted at every piece (the default) and kept across pieces: the same impacts, the
    // states within rounding amplified by the transient, far fewer steps.
    let mut restarted = start();
    let (a, ev_a) = run_pieces(&mut restarted, h, 0, n, false);
    let mut kept = start();
    kept.keep_flight(true);
    let (b, ev_b) = run_pieces(&mut kept, h, 0, n, false);
    let (ia, ib) = (impacts(&ev_a), impacts(&ev_b));
    assert_eq!(ia.len(), ib.len());
    assert!(ia.len() > 20);
    let dt = ia
        .iter()
        .zip(&ib)
        .map(|(p, q)| (p.t - q.t).abs())
        .fold(0.0, f64::max);
    let dx = a
        .iter()
        .zip(&b)
        .map(|(p, q)| (p[0] - q[0]).abs())
        .fold(0.0, f64::max);
    assert!(dt < 1e-12 && dx < 1e-12, "impact times {dt:e}, x {dx:e}");
    // The plate is the same pieces: bit for bit.
    assert!(a.iter().zip(&b).all(|(p, q)| p[2] == q[2] && p[3] == q[3]));
    let (sa, sb) = (restarted.stats().steps, kept.stats().steps);
    assert!(sb * 10 < sa, "steps: restarted {sa}, kept {sb}");
    // fly_over is set_plate and an advance, when it applies.
    let mut flown = start();
    flown.keep_flight(true);
    let (c, ev_c) = run_pieces(&mut flown, h, 0, n, true);
    assert_eq!(b, c);
    assert_eq!(ev_b, ev_c);
    // A checkpoint inside a kept flight (and its bytes) goes on bit for bit.
    let mut sim = start();
    sim.keep_flight(true);
    let mut checked = 0;
    for k in (0..n).step_by(997) {
        run_pieces(&mut sim, h, k, k + 997, true);
        let cp = sim.checkpoint();
        checked += usize::from(cp.kept.is_some());
        let bytes = cp.to_bytes();
        let cp = bistable_core::Checkpoint::from_bytes(&bytes).unwrap();
        let mut back = Simulator::from_checkpoint(&cp).unwrap();
        back.keep_flight(true);
        let mut twin = sim.clone();
        let to = (k + 997 + 300).min(n + 300);
        let (p, ev_p) = run_pieces(&mut twin, h, k + 997, to, true);
        let (q, ev_q) = run_pieces(&mut back, h, k + 997, to, true);
        assert_eq!(p, q);
        assert_eq!(ev_p, ev_q);
    }
    assert!(checked >= 5, "{checked} checkpoints inside kept flights");
}

/// The baseline sinusoid sampled every `h` for `n` steps and fed to a simulator that keeps
/// flights, as the FMU feeds it: each sample is added to the history and the piece to the next
/// sample either flown over or taken by `set_plate` and an advance. With `fast` the flight is
/// tried by `fly_over_sampled`, otherwise by `push`, `piece_with` and `fly_over`. Every 97th
/// sample has a non-finite velocity and is skipped (refused). Returns the state bits after
/// each step, the events, the history and how many steps were flown over.
fn run_samples(h: f64, n: u32, fast: bool) -> (Vec<[u64; 4]>, Vec<Event>, SampleHistory, u32) {
    let shaker = PlateMotion::from(Sinusoid::new(1.75, 0.07).unwrap());
    let mut sim = Simulator::new(Params::paper(), shaker, SolverOptions::default()).unwrap();
    sim.keep_flight(true);
    let (mut hist, mut memo) = (SampleHistory::new(), PieceMemo::default());
    let (mut states, mut ev, mut flown) = (Vec::new(), Vec::new(), 0);
    for k in 0..n {
        let now = sim.instant();
        let (z, zdot, _) = shaker.motion(now);
        let zdot = if k % 97 == 50 { f64::NAN } else { zdot };
        let sample = Sample { t: now, z, zdot };
        let end = Instant::new(f64::from(k + 1) * h);
        let before = hist;
        let fly = if fast {
            sim.fly_over_sampled(&mut hist, sample, end, &mut memo, 1e50)
        } else {
            let mut pushed = hist;
            let fly = pushed.push(sample).is_ok() && {
                let (z, zd, _) = sim.plate().motion(now);
                let piece = pushed.piece_with(end, (z, zd), &mut memo).unwrap();
                sim.fly_over(&piece, 1e50)
            };
            if fly {
                hist = pushed;
            }
            fly
        };
        if !fly {
            assert_eq!(hist, before, "a flight not continued leaves the history");
            if hist.push(sample).is_err() {
                continue;
            }
            let (z, zd, _) = sim.plate().motion(now);
            let piece = hist.piece_with(end, (z, zd), &mut memo).unwrap();
            sim.set_plate(piece.into()).unwrap();
            sim.advance_instant(end, &mut |e: &Event| ev.push(*e))
                .unwrap();
        }
        flown += u32::from(fly);
        let s = sim.state();
        states.push([s.x, s.v, s.z, s.zdot].map(f64::to_bits));
    }
    (states, ev, hist, flown)
}

#[test]
fn sampled_fly_overs_are_the_push_the_piece_and_the_fly_over() {
    let (h, n) = (0.01, 20_000);
    let (a, ev_a, hist_a, flown_a) = run_samples(h, n, false);
    let (b, ev_b, hist_b, flown_b) = run_samples(h, n, true);
    let first = a.iter().zip(&b).position(|(p, q)| p != q);
    assert!(
        a.len() == b.len() && first.is_none(),
        "states differ from step {first:?}"
    );
    assert_eq!(ev_a, ev_b);
    assert_eq!(hist_a, hist_b);
    assert_eq!(flown_a, flown_b);
    assert!(
        impacts(&ev_a).len() > 20,
        "{} impacts",
        impacts(&ev_a).len()
    );
    assert!(flown_b > n * 9 / 10, "{flown_b} of {n} steps flown over");
    assert!(flown_b < n - 200, "{flown_b} of {n} steps flown over");
}
