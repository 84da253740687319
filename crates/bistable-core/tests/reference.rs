//! Accuracy against the project's independent high-precision reference (`bistable-reference`,
//! 128-bit Taylor method whose two precisions are checked against each other in its own tests).
//!
//! Times are compared impact by impact; every figure is printed (run with `--nocapture`).

use bistable_core::{
    ChatterRule, Event, GapAudit, Impact, Params, Simulator, Sinusoid, SolverOptions,
};
use bistable_reference::{simulate, RefChatter, RefEvent, RefEventKind, RefOptions, RefParams};

const ZETA: f64 = 0.02;
const E: f64 = 0.85;

fn reference(omega: f64, v: f64, t_end: f64, chatter: RefChatter) -> Vec<RefEvent> {
    let p = RefParams {
        zeta: ZETA,
        restitution: E,
        omega,
        velocity: v,
    };
    let o = RefOptions {
        bits: 128,
        chatter,
        t_end,
        ..RefOptions::default()
    };
    simulate(&p, &o).expect("reference run")
}

fn ours(omega: f64, v: f64, t_end: f64, opts: SolverOptions) -> (Vec<Event>, GapAudit) {
    let plate = Sinusoid::new(omega, v).unwrap();
    let mut sim = Simulator::new(Params::new(ZETA, E).unwrap(), plate.into(), opts).unwrap();
    let mut audit = GapAudit::new(32);
    sim.advance_to(t_end, &mut audit).unwrap();
    (audit.events.clone(), audit)
}

fn impacts(ev: &[Event]) -> Vec<Impact> {
    ev.iter().filter_map(Event::impact).collect()
}

fn ref_impacts(ev: &[RefEvent]) -> Vec<&RefEvent> {
    ev.iter()
        .filter(|e| e.kind == RefEventKind::Impact)
        .collect()
}

#[test]
fn baseline_impact_times_to_1e_12() {
    // (Ω, V) = (1.75, 0.07), τ ≤ 1000: 278 impacts.
    let r = reference(
        1.75,
        0.07,
        1000.0,
        RefChatter::Accumulation { delta: 1e-20 },
    );
    let ri = ref_impacts(&r);
    let (ev, audit) = ours(1.75, 0.07, 1000.0, SolverOptions::default());
    let oi = impacts(&ev);
    assert_eq!(oi.len(), ri.len(), "impact count");
    assert_eq!(oi.len(), 278);
    let mut dt: f64 = 0.0;
    let mut dv: f64 = 0.0;
    for (o, r) in oi.iter().zip(&ri) {
        dt = dt.max((o.t - r.t).abs());
        dv = dv.max((o.v_after - r.v_after).abs());
    }
    println!(
        "baseline: {} impacts, max |Δt| = {dt:.2e}, max |Δv_after| = {dv:.2e}, worst sampled gap {:.1e}",
        oi.len(),
        audit.worst.0
    );
    assert!(dt <= 1e-12, "max impact-time error {dt}");
    assert!(dv <= 1e-12, "max rebound-velocity error {dv}");
    assert!(audit.worst.0 > -1e-14);
}

#[test]
fn chaotic_case_no_missed_impact_and_tracking_until_divergence() {
    // (Ω, V) = (2.5, 0.07), τ ≤ 1000: audit every step; compare with the reference until the
    // trajectories separate (chaos amplifies the last-bit differences).
    let (ev, audit) = ours(2.5, 0.07, 1000.0, SolverOptions::default());
    println!(
        "chaotic: {} steps audited at 32 points each, worst gap {:.2e} at t = {:.3}",
        audit.steps, audit.worst.0, audit.worst.1
    );
    assert!(audit.worst.0 > -1e-14, "penetration {:?}", audit.worst);
    let r = reference(2.5, 0.07, 400.0, RefChatter::Accumulation { delta: 1e-20 });
    let ri = ref_impacts(&r);
    let oi = impacts(&ev);
    // Errors of order 1e-14 in the first impacts grow like e^{λτ} (λ ≈ 0.3 here): the runs agree
    // to 1e-10 for τ < 60 and part macroscopically (|Δt| > 1e-3) near τ ≈ 130.
    let first_above = |limit: f64| {
        oi.iter()
            .zip(&ri)
            .find(|(o, r)| (o.t - r.t).abs() > limit)
            .map_or(400.0, |(_, r)| r.t)
    };
    let early = oi
        .iter()
        .zip(&ri)
        .filter(|(_, r)| r.t < 60.0)
        .map(|(o, r)| (o.t - r.t).abs())
        .fold(0.0, f64::max);
    let (micro, macro_) = (first_above(1e-6), first_above(1e-3));
    println!(
        "chaotic: max |Δt| {early:.2e} for τ < 60; |Δt| > 1e-6 from τ = {micro:.1}; \
         divergence (|Δt| > 1e-3) at τ = {macro_:.1}"
    );
    assert!(early <= 1e-10, "{early}");
    assert!(macro_ >= 120.0, "diverged at {macro_}");
}

#[test]
fn chatter_sticking_and_release_match() {
    // (Ω, V) = (0.2, 0.05): chatter, sticking, release. Reference: accumulation rule with a
    // negligible horizon (its prediction error is far below its precision).
    let t_end = 20.0;
    let r = reference(0.2, 0.05, t_end, RefChatter::Accumulation { delta: 1e-20 });
    let (ev, _) = ours(0.2, 0.05, t_end, SolverOptions::default());
    let r_stick = r
        .iter()
        .find(|e| e.kind == RefEventKind::StickStart)
        .unwrap();
    let r_release = r.iter().find(|e| e.kind == RefEventKind::StickEnd).unwrap();
    let (o_stick, cause) = ev
        .iter()
        .find_map(|e| match e {
            Event::StickStart { t, cause, .. } => Some((*t, *cause)),
            _ => None,
        })
        .unwrap();
    let o_release = ev
        .iter()
        .find_map(|e| match e {
            Event::StickEnd { t, .. } => Some(*t),
            _ => None,
        })
        .unwrap();
    // Impacts before sticking: ours resolves them down to the 1e-7 horizon; each one that both
    // runs have must agree.
    let oi: Vec<Impact> = impacts(&ev).into_iter().filter(|i| i.t < o_stick).collect();
    let ri: Vec<&RefEvent> = ref_impacts(&r)
        .into_iter()
        .filter(|e| e.t < r_stick.t)
        .collect();
    let mut dt: f64 = 0.0;
    for (o, r) in oi.iter().zip(&ri) {
        dt = dt.max((o.t - r.t).abs());
    }
    let onset = (o_stick - r_stick.t).abs();
    let release = (o_release - r_release.t).abs();
    println!(
        "chatter: {} impacts resolved (reference {} down to its 1e-20 horizon), max |Δt| {dt:.2e}; \
         sticking onset {o_stick:.12} ({cause:?}), error {onset:.2e}; release {o_release:.12}, error {release:.2e}",
        oi.len(),
        ri.len()
    );
    assert!(oi.len() >= 100 && ri.len() >= oi.len());
    assert!(dt <= 1e-10, "{dt}");
    assert!(onset <= 1e-8, "{onset}");
    assert!(release <= 1e-10, "{release}");
}

#[test]
fn paper_rule_matches_the_reference_with_the_same_rule() {
    let t_end = 20.0;
    let r = reference(0.2, 0.05, t_end, RefChatter::FixedGap { gap: 1e-9 });
    let opts = SolverOptions::new(1e-16, ChatterRule::paper()).unwrap();
    let (ev, _) = ours(0.2, 0.05, t_end, opts);
    let stick_o = ev.iter().find_map(|e| match e {
        Event::StickStart { t, impacts, .. } => Some((*t, *impacts)),
        _ => None,
    });
    let r_stick = r
        .iter()
        .find(|e| e.kind == RefEventKind::StickStart)
        .unwrap();
    let r_count = ref_impacts(&r).iter().filter(|e| e.t <= r_stick.t).count() as u64;
    let (t, n) = stick_o.unwrap();
    println!(
        "paper rule: sticking after {n} impacts at {t:.12} (reference {r_count} at {:.12})",
        r_stick.t
    );
    assert_eq!(n, r_count);
    assert!((t - r_stick.t).abs() < 1e-9);
}
