//! Measuring the transient growth alongside a classification (variational equations,
//! `classify_from` with `Tracking`) never changes the trajectory: every field of the
//! classification but the measured ones is bit-identical to a plain run, with sticking
//! (the variation is reseeded without restarting a step), chaos, rest and periodic orbits.

use bistable_core::{
    classify, classify_from, Classification, ClassifyOptions, Params, Sinusoid, SolverOptions,
    Tracking,
};

#[test]
fn tracking_leaves_the_classification_unchanged() {
    let co = ClassifyOptions {
        lyapunov_periods: 300,
        ..ClassifyOptions::default()
    };
    // Chatter and sticking at low Ω; a period-4 orbit; rest in well 2; the paper's sensitive
    // point; chaos (a shorter run keeps the test fast).
    for (w, v, periods) in [
        (0.3, 0.05, 20_000.0),
        (0.2, 0.05, 20_000.0),
        (0.85, 0.11, 20_000.0),
        (0.85, 0.15, 20_000.0),
        (0.85, 0.13, 20_000.0),
        (2.45, 0.07, 3_000.0),
    ] {
        let plate = Sinusoid::new(w, v).unwrap();
        let co = ClassifyOptions {
            max_natural_periods: periods,
            ..co
        };
        let plain = classify(Params::paper(), plate, SolverOptions::default(), co).unwrap();
        for track in [
            Tracking {
                efoldings_cap: Some(20.0),
                track_periods: 0,
                extra_windows: 2,
                no_lyapunov: false,
            },
            Tracking {
                efoldings_cap: Some(700.0),
                track_periods: 500,
                extra_windows: 0,
                no_lyapunov: false,
            },
        ] {
            let t = tracked(plate, co, track);
            assert!(t.transient_efoldings.is_some(), "({w}, {v})");
            let strip = |mut c: Classification| {
                c.transient_efoldings = None;
                c.chaos_votes = None;
                c
            };
            assert_eq!(strip(t), strip(plain), "({w}, {v}) {track:?}");
        }
        if plain.period.is_none() {
            let track = Tracking {
                extra_windows: 3,
                efoldings_cap: Some(20.0),
                ..Tracking::default()
            };
            let t = tracked(plate, co, track);
            let (chaotic, n) = t.chaos_votes.unwrap();
            assert_eq!(n, 3);
            assert!(chaotic <= n);
        }
    }
}

/// The further Lyapunov windows are the last stretches of the run itself: as many as fit in its
/// last quarter, each a verdict that agrees with the exponent's sign where the dynamics leaves
/// no doubt.
#[test]
fn window_votes_come_from_the_end_of_the_run() {
    let votes = |w: f64, v: f64, periods: f64, max_period: u32, windows: u32| {
        let co = ClassifyOptions {
            max_natural_periods: periods,
            max_period,
            lyapunov_periods: 300,
            ..ClassifyOptions::default()
        };
        let track = Tracking {
            extra_windows: windows,
            ..Tracking::default()
        };
        let t = tracked(Sinusoid::new(w, v).unwrap(), co, track);
        assert_eq!(t.period, None, "({w}, {v}) must run to the end");
        t.chaos_votes.unwrap()
    };
    // Chaos (λ = 0.177 over long runs): every window is chaotic. 5,000 natural periods at
    // Ω = 2.45 are 12,250 sections, whose last quarter holds 10 windows of 300.
    assert_eq!(votes(2.45, 0.07, 5_000.0, 16, 8), (8, 8));
    // The stable P-2 orbit at Ω = 2.2 with only period 1 looked for runs to the end; its
    // windows contract (Floquet multipliers inside the unit circle): none is chaotic.
    assert_eq!(votes(2.2, 0.07, 5_000.0, 1, 8), (0, 8));
    // 4,000 natural periods at Ω = 2.45 are 9,800 sections: 8 windows of 300 fit in the last
    // quarter (2,450 sections), 9 do not.
    assert_eq!(votes(2.45, 0.07, 4_000.0, 16, 64).1, 8);
}

/// The paper's point classified from rest with the default solver, measuring what `track` asks.
fn tracked(plate: Sinusoid, co: ClassifyOptions, track: Tracking) -> Classification {
    classify_from(
        Params::paper(),
        plate,
        SolverOptions::default(),
        co,
        (0.0, 0.0),
        track,
    )
    .unwrap()
}
