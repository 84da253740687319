//! The paper's reported results (model.md Sec. 5) reproduced by the simulator.

use bistable_core::{Event, Impact, Params, Simulator, Sinusoid, SolverOptions, Well};

fn run(omega: f64, v: f64, t_end: f64) -> (Simulator, Vec<Event>) {
    let plate = Sinusoid::new(omega, v).unwrap();
    let mut sim = Simulator::new(Params::paper(), plate.into(), SolverOptions::default()).unwrap();
    let events = sim.events_until(t_end).unwrap();
    (sim, events)
}

fn impacts(ev: &[Event]) -> Vec<Impact> {
    ev.iter().filter_map(Event::impact).collect()
}

#[test]
fn second_impact_phase() {
    // Paper: 0.0507 at Ω = 1.75 and 0.5943 at Ω = 2.5 (V = 0.07), ±0.0005 cycles.
    for (omega, expected) in [(1.75, 0.0507), (2.5, 0.5943)] {
        let (_, ev) = run(omega, 0.07, 30.0);
        let imp = impacts(&ev);
        assert_eq!(imp[0].index, 0);
        assert_eq!(imp[0].t, 0.0);
        assert!((imp[0].v_after - 1.85 * 0.07).abs() < 1e-16);
        let ph = imp[1].phase.unwrap();
        println!("Ω = {omega}: second impact phase {ph:.6} cycles (paper {expected})");
        assert!((ph - expected).abs() <= 5e-4, "{ph}");
    }
}

#[test]
fn period_four_intrawell_at_v_0_11() {
    // Ω = 0.85, V = 0.11: period-4 intrawell, five impacts per four shaker periods.
    let omega = 0.85;
    let period = std::f64::consts::TAU / omega;
    let (_, ev) = run(omega, 0.11, 3000.0 * period);
    assert!(!ev.iter().any(|e| matches!(e, Event::SnapThrough { .. })));
    let imp = impacts(&ev);
    // Steady state: the last 40 shaker periods, in windows of 4 periods.
    let t_end = 3000.0 * period;
    let in_window = |k: f64| {
        imp.iter()
            .filter(|i| i.t > t_end - (k + 1.0) * 4.0 * period && i.t <= t_end - k * 4.0 * period)
            .count()
    };
    for k in 0..10 {
        assert_eq!(in_window(f64::from(k)), 5, "window {k}");
    }
    // Period 4 exactly (not 1 or 2): phases repeat after 5 impacts, not after fewer.
    let n = imp.len();
    let ph: Vec<f64> = imp[n - 10..].iter().map(|i| i.phase.unwrap()).collect();
    for j in 0..5 {
        assert!((ph[j] - ph[j + 5]).abs() < 1e-9, "{ph:?}");
    }
    assert!((ph[0] - ph[1]).abs() > 1e-3 && (ph[0] - ph[2]).abs() > 1e-3);
}

#[test]
fn single_impact_escape_at_v_0_15() {
    // Ω = 0.85, V = 0.15: the impact at τ = 0 alone throws the mass into well 2, where it stays.
    let (sim, ev) = run(0.85, 0.15, 2000.0);
    let imp = impacts(&ev);
    assert_eq!(imp.len(), 1, "{ev:?}");
    let snaps: Vec<_> = ev
        .iter()
        .filter(|e| matches!(e, Event::SnapThrough { .. }))
        .collect();
    assert_eq!(snaps.len(), 1);
    let st = sim.state();
    assert_eq!(st.well, Well::Two);
    // At rest in the second well (decay e^{-ζτ} over 2000 time units).
    assert!((st.x - 1.0).abs() < 1e-12 && st.v.abs() < 1e-12, "{st:?}");
}
