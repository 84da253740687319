//! Issue 37: the coexistence sweep (`bistable_analysis::coexistence`) at points with
//! coexisting periodic and chaotic attractors: the same result for every thread count and
//! lane width, the same attractors and counts as the full decision of every start, the
//! paper's start decided as `classify` decides it, and branches that keep their id along Ω.

use bistable_analysis::basins::{Decision, Steady};
use bistable_analysis::coexistence::{
    coexistence, match_branches, CoexistenceOptions, PointCoexistence, Sampling, StartBox, Starts,
};
use bistable_analysis::parallel::Threads;
use bistable_analysis::recurrence::RecurrenceOptions;
use bistable_analysis::sensitivity::SensitivityOptions;
use bistable_analysis::sweep::classify_point_with;
use bistable_analysis::Model;
use bistable_core::{ClassifyOptions, Params, SimError, Sinusoid, SolverOptions, Width};

/// Rest and P-1/P-4 in well 1 (1.45, 0.05); rest, chaos in well 1 and P-8 across the barrier
/// (2.45, 0.07); rest, P-1 across and P-4 in well 1 (0.85, 0.11).
const POINTS: [(f64, f64); 3] = [(1.45, 0.05), (2.45, 0.07), (0.85, 0.11)];

fn model() -> Model {
    Model::new(
        Params::paper(),
        Sinusoid::new(1.0, 0.1).unwrap(),
        SolverOptions::default(),
    )
}

fn options(decision: Decision, n: usize) -> CoexistenceOptions {
    CoexistenceOptions {
        starts: Starts {
            bounds: StartBox::default(),
            sampling: Sampling::Grid { nx: n, nv: n },
        },
        classify: ClassifyOptions {
            max_natural_periods: 2_000.0,
            lyapunov_periods: 300,
            ..ClassifyOptions::default()
        },
        decision,
        ..CoexistenceOptions::default()
    }
}

fn recurrence() -> Decision {
    Decision::Recurrence(RecurrenceOptions {
        first_round: 16,
        ..RecurrenceOptions::default()
    })
}

fn sweep(
    points: &[(f64, f64)],
    o: CoexistenceOptions,
    threads: usize,
    width: Width,
) -> Vec<PointCoexistence> {
    let mut out: Vec<Option<PointCoexistence>> = vec![None; points.len()];
    coexistence::<SimError>(
        &model(),
        points,
        o,
        Threads::new(threads).unwrap(),
        width,
        |i, r| {
            out[i] = Some(r?);
            Ok(())
        },
    )
    .unwrap();
    out.into_iter().map(Option::unwrap).collect()
}

/// The attractors of a point as comparable keys: steady state, anchor to 1e-5, count.
fn keys(p: &PointCoexistence) -> Vec<(Steady, Option<[i64; 2]>, usize)> {
    let mut k: Vec<_> = p
        .attractors
        .iter()
        .map(|a| {
            let anchor = a
                .anchor
                .filter(|_| a.steady.period.is_some())
                .map(|x| [(x[0] * 1e5).round() as i64, (x[1] * 1e5).round() as i64]);
            (a.steady, anchor, a.count)
        })
        .collect();
    k.sort_by_key(|k| format!("{k:?}"));
    k
}

#[test]
fn recurrence_agrees_with_the_full_decision_and_ignores_threads_and_lanes() {
    let fast = sweep(&POINTS, options(recurrence(), 24), 2, Width::Four);
    let full = sweep(&POINTS, options(Decision::Full, 24), 2, Width::Four);
    for (f, g) in fast.iter().zip(&full) {
        assert_eq!(keys(f), keys(g), "({}, {})", f.omega, f.velocity);
        assert_eq!(f.paper, g.paper);
        assert_eq!(f.starts, 576);
        let captured: usize = f.attractors.iter().map(|a| a.by_recurrence).sum();
        let periods = |p: &PointCoexistence| {
            p.attractors
                .iter()
                .map(|a| a.periods_simulated)
                .sum::<f64>()
        };
        eprintln!(
            "({}, {}): {} attractors, {captured} of 576 starts by recurrence, natural periods \
             {:.0} against {:.0} in full",
            f.omega,
            f.velocity,
            f.attractors.len(),
            periods(f),
            periods(g)
        );
    }
    // The chaotic attractor's starts stop by recurrence, long before the limit.
    let chaos = &fast[1];
    let a = chaos
        .attractors
        .iter()
        .find(|a| a.steady.period.is_none())
        .expect("an aperiodic attractor at (2.45, 0.07)");
    assert!(a.by_recurrence * 10 >= a.count * 8, "{a:?}");
    // Every point the same on one thread without lanes.
    assert_eq!(
        sweep(&POINTS, options(recurrence(), 24), 1, Width::One),
        fast
    );
}

#[test]
fn the_papers_start_is_decided_as_the_map_decides_it() {
    let o = options(recurrence(), 6);
    for p in sweep(&POINTS, o, 2, Width::Four) {
        let m = model().at(p.omega, p.velocity).unwrap();
        let point = classify_point_with(&m, o.classify, SensitivityOptions::default()).unwrap();
        let c = point.classification;
        assert_eq!(p.paper.outcome.class, c.class);
        assert_eq!(p.paper.outcome.period, c.period);
        assert_eq!(p.paper.periods_simulated, c.periods_simulated);
        assert_eq!(p.paper_sensitive, point.sensitivity.sensitive);
        let a = &p.attractors[p.paper_attractor];
        assert_eq!(a.steady, p.paper.steady());
    }
}

#[test]
fn the_two_p1_orbits_keep_their_branches_along_omega() {
    // At V = 0.05 a low- and a high-energy P-1 orbit in well 1 coexist for Ω up to the low
    // one's fold near 1.44 (see tests/coexistence.rs).
    let line: Vec<(f64, f64)> = (0..6).map(|i| (1.3 + 0.025 * f64::from(i), 0.05)).collect();
    let pts = sweep(&line, options(recurrence(), 16), 2, Width::Four);
    let refs: Vec<Option<&PointCoexistence>> = pts.iter().map(Some).collect();
    let (ids, _) = match_branches(line.len(), &refs, 0.2);
    let p1 = |p: &PointCoexistence, ids: &[usize]| -> Vec<(f64, usize)> {
        let mut v: Vec<(f64, usize)> = p
            .attractors
            .iter()
            .zip(ids)
            .filter(|(a, _)| a.steady.period == Some(1) && !a.steady.at_rest && !a.steady.across)
            .map(|(a, &id)| (a.anchor.unwrap()[0], id))
            .collect();
        v.sort_by(|a, b| a.0.total_cmp(&b.0));
        v
    };
    let first = p1(&pts[0], &ids[0]);
    assert_eq!(first.len(), 2, "{:?}", pts[0]);
    for (p, i) in pts.iter().zip(&ids) {
        let here = p1(p, i);
        assert_eq!(here.len(), 2, "{p:?}");
        // The lower orbit (smaller anchor x) keeps the lower orbit's id.
        assert_eq!(here[0].1, first[0].1);
        assert_eq!(here[1].1, first[1].1);
    }
}

/// The starts of each steady state with the chaos verdict left out: the full decision judges
/// each aperiodic run's chaos by its own Lyapunov estimate, which splits the starts of one
/// marginally chaotic attractor, while the sweep gives them the verdict of the run that found
/// it (`docs/coexistence.md`).
fn counts_by_steady_state(p: &PointCoexistence) -> Vec<(Steady, usize)> {
    let mut k: Vec<(Steady, usize)> = Vec::new();
    for a in &p.attractors {
        let steady = Steady {
            chaotic: false,
            ..a.steady
        };
        match k.iter_mut().find(|(s, _)| *s == steady) {
            Some((_, n)) => *n += a.count,
            None => k.push((steady, a.count)),
        }
    }
    k.sort_by_key(|k| format!("{k:?}"));
    k
}

/// At (3.05, 0.015) a P-8 orbit in well 1 lies among the cells of an aperiodic attractor, and
/// many of its starts spend a hundred sections and more in those cells while they settle onto
/// it, with lag distances too irregular for the settling test. With the default aperiodic
/// hits the sweep sends as many starts to each steady state as the full decision; with 100
/// (Attractors.jl's `consecutive_recurrences`) some of them were captured as aperiodic.
#[test]
fn runs_settling_irregularly_onto_a_periodic_orbit_keep_their_starts() {
    let point = [(3.052542372881356, 0.015)];
    let full = sweep(&point, options(Decision::Full, 20), 2, Width::Four);
    let fast = sweep(&point, options(recurrence(), 20), 2, Width::Four);
    assert_eq!(
        counts_by_steady_state(&fast[0]),
        counts_by_steady_state(&full[0])
    );
    let eager = Decision::Recurrence(RecurrenceOptions {
        first_round: 16,
        aperiodic_hits: 100,
        ..RecurrenceOptions::default()
    });
    let eager = sweep(&point, options(eager, 20), 2, Width::Four);
    assert_ne!(
        counts_by_steady_state(&eager[0]),
        counts_by_steady_state(&full[0])
    );
}
