//! Issue 37: basins decided by recurrence (`bistable_analysis::recurrence`) against the full
//! decision of every start, on small grids at two points with coexisting attractors: the same
//! attractors, the same cell outcome (class, period, chaos, final well, at rest) and attractor
//! in at least 99.9 % of the cells, and the same cells for every thread count and lane width.

use bistable_analysis::basins::{classify_starts, identify, Attractor, Cell, DecidedBy, Decision};
use bistable_analysis::parallel::Threads;
use bistable_analysis::recurrence::{Ellipse, Known, RecurrenceOptions};
use bistable_analysis::sweep::interleaved;
use bistable_analysis::Model;
use bistable_core::{ClassifyOptions, Event, Params, SimError, Sinusoid, SolverOptions, Width};

/// Agreement required between the two decisions, as the issue asks on the large grids.
const AGREEMENT: f64 = 0.999;

/// `bistable basins`'s classification settings.
fn options() -> ClassifyOptions {
    ClassifyOptions {
        max_natural_periods: 2_000.0,
        lyapunov_periods: 300,
        ..ClassifyOptions::default()
    }
}

/// The `n × n` grid over x0 ∈ [0, 1.2], x0' ∈ [−0.6, 0.6] in the CLI's interleaved order.
fn grid(n: usize) -> Vec<(f64, f64)> {
    let step = 1.2 / (n - 1) as f64;
    interleaved(n * n)
        .map(|k| ((k % n) as f64 * step, -0.6 + (k / n) as f64 * step))
        .collect()
}

fn cells(
    model: &Model,
    decision: Decision,
    starts: &[(f64, f64)],
    threads: usize,
    width: Width,
) -> (Vec<Cell>, Known) {
    let mut out: Vec<Option<Cell>> = vec![None; starts.len()];
    let known = classify_starts::<SimError>(
        model,
        0.0,
        options(),
        decision,
        starts,
        Threads::new(threads).unwrap(),
        width,
        |i, r| {
            out[i] = Some(r?);
            Ok(())
        },
    )
    .unwrap();
    (out.into_iter().map(Option::unwrap).collect(), known)
}

/// The attractors without their basin sizes, for comparing two grids' sets.
fn set(attractors: &[Attractor]) -> Vec<Attractor> {
    let mut s: Vec<Attractor> = attractors
        .iter()
        .map(|a| Attractor { cells: 0, ..*a })
        .collect();
    s.sort_by_key(|a| a.steady.label());
    s
}

fn compare(omega: f64, velocity: f64, n: usize) -> (Model, Known) {
    let model = Model::new(
        Params::paper(),
        Sinusoid::new(omega, velocity).unwrap(),
        SolverOptions::default(),
    );
    let starts = grid(n);
    let rec = Decision::Recurrence(RecurrenceOptions::default());
    let (full, none) = cells(&model, Decision::Full, &starts, 2, Width::Four);
    assert_eq!(none, Known::default());
    let (fast, known) = cells(&model, rec, &starts, 2, Width::Four);

    // The same attractors (steady state and cycle anchor within the grouping tolerance).
    let (a_full, i_full) = identify(&full);
    let (a_fast, i_fast) = identify(&fast);
    let (s_full, s_fast) = (set(&a_full), set(&a_fast));
    assert_eq!(s_full.len(), s_fast.len(), "{a_full:?}\n{a_fast:?}");
    for (a, b) in s_full.iter().zip(&s_fast) {
        assert_eq!(a.steady, b.steady);
        let (x, y) = (a.anchor.unwrap_or_default(), b.anchor.unwrap_or_default());
        assert!(
            (x[0] - y[0]).abs().max((x[1] - y[1]).abs()) < 1e-5,
            "{a:?} {b:?}"
        );
    }
    // Every periodic attractor other than rest is known.
    let periodic = a_full.iter().filter(|a| a.anchor.is_some()).count();
    assert_eq!(known.periodic.len(), periodic, "{known:?}");
    // Those found in the first round were probed (probing pays with thousands of starts
    // left), and every probed one has a capture radius somewhere on its cycle.
    let first_round = RecurrenceOptions::default().first_round;
    for k in &known.periodic {
        let found = starts.iter().position(|&s| s == k.found_by).unwrap();
        assert!(k.probed || found >= first_round, "{k:?}");
        assert!(!k.probed || k.radii.iter().any(|&r| r > 0.0), "{k:?}");
    }

    // The same outcome and attractor per cell, but for at most 0.1 %.
    let label = |a: &[Attractor], i: usize| {
        a[i].steady.label() + &format!("{:?}", a[i].anchor.map(|x| (x[0] * 1e4).round()))
    };
    let differ: Vec<usize> = (0..starts.len())
        .filter(|&k| {
            full[k].outcome != fast[k].outcome
                || full[k].at_rest != fast[k].at_rest
                || label(&a_full, i_full[k]) != label(&a_fast, i_fast[k])
        })
        .collect();
    let captured = fast
        .iter()
        .filter(|c| c.decided_by == DecidedBy::Recurrence)
        .count();
    let periods = |c: &[Cell]| c.iter().map(|c| c.periods_simulated).sum::<f64>();
    eprintln!(
        "({omega}, {velocity}) {n} × {n}: {} cells differ, {captured} captured, natural periods \
         {:.0} against {:.0} in full",
        differ.len(),
        periods(&fast),
        periods(&full)
    );
    for &k in &differ {
        eprintln!("  {:?}: {:?} / {:?}", starts[k], full[k], fast[k]);
    }
    assert!(
        (differ.len() as f64) <= (1.0 - AGREEMENT) * starts.len() as f64,
        "{} of {} cells differ",
        differ.len(),
        starts.len()
    );
    // Recurrence decided most periodic cells and shortened the runs.
    assert!(captured > 0 && periods(&fast) < 0.6 * periods(&full));

    // The same cells whatever the threads and lanes (the rounds fix the known attractors).
    let (alone, known1) = cells(&model, rec, &starts, 1, Width::One);
    assert_eq!(alone, fast);
    assert_eq!(known1, known);
    (model, known)
}

/// The section point one shaker period after `y` (plate phase 0).
fn next_section(model: &Model, y: [f64; 2]) -> [f64; 2] {
    let mut sim = model.simulator_from(y[0], y[1]).unwrap();
    sim.advance_to(model.shaker_period(), &mut |_: &Event| {})
        .unwrap();
    let st = sim.state();
    [st.x, st.v]
}

#[test]
fn recurrence_agrees_with_the_full_decision_at_1_45_0_05() {
    // Rest in well 2, P-1 and P-4 in well 1, fractal boundaries.
    let (model, known) = compare(1.45, 0.05, 60);

    // The P-1 orbit (a stable focus) is captured in an ellipse shaped by its monodromy: in
    // that metric the shaker-period map shrinks every displacement near the orbit (by the
    // multipliers' modulus, 0.78), so a start that comes near stays near. In the plain distance
    // it does not: points on a circle around the orbit leave it (they wind in along the
    // ellipse). Checked on the edges at a tenth of the capture radius, where the map is close
    // to its linearisation (at the radius itself, 0.025, the map's curvature already shows).
    let p1 = known.periodic.iter().find(|k| k.cycle.len() == 1).unwrap();
    let (shape, c) = (p1.shapes[0], p1.cycle[0]);
    assert!(shape != Ellipse::CIRCLE && p1.radii[0] > 0.0, "{p1:?}");
    let r = p1.radii[0] / 10.0;
    let (mut ellipse, mut circle) = (0.0_f64, 0.0_f64);
    for n in 0..64 {
        let t = std::f64::consts::TAU * f64::from(n) / 64.0;
        let y = next_section(&model, shape.at(c, r, t));
        ellipse = ellipse.max(shape.norm([y[0] - c[0], y[1] - c[1]]) / r);
        let z = next_section(&model, Ellipse::CIRCLE.at(c, r, t));
        circle = circle.max((z[0] - c[0]).hypot(z[1] - c[1]) / r);
    }
    assert!(
        ellipse < 0.9,
        "the ellipse's edge maps out to {ellipse} of its radius"
    );
    assert!(
        circle > 1.0,
        "the circle's edge maps inside, to {circle} of its radius"
    );
}

#[test]
fn recurrence_agrees_with_the_full_decision_at_1_75_0_07() {
    // Rest in well 2, P-1 and P-3 in well 1, P-6 across the barrier.
    compare(1.75, 0.07, 60);
}

#[test]
fn a_periodic_orbit_among_chaotic_cells_keeps_its_starts() {
    // Rest in well 2, chaos in well 1 on a few cells, and a P-1 orbit in well 1 whose section
    // point lies among them, with a multiplier of −0.989: its starts stay in the chaotic
    // cells for many sections while they settle (without the settling test, 43 of these 900
    // cells were captured as chaotic).
    let (_, known) = compare(0.927, 0.065, 30);
    assert!(
        !known.aperiodic.is_empty() && !known.periodic.is_empty(),
        "{known:?}"
    );
}

#[test]
fn bad_recurrence_options_are_named() {
    let bad = RecurrenceOptions {
        hits: 0,
        ..RecurrenceOptions::default()
    };
    assert_eq!(bad.check().unwrap_err().name, "recurrence_hits");
    let bad = RecurrenceOptions {
        directions: 2,
        ..RecurrenceOptions::default()
    };
    assert_eq!(bad.check().unwrap_err().name, "probe_directions");
    assert!(RecurrenceOptions::default().check().is_ok());
}
