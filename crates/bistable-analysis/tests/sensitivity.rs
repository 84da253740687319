//! The sensitivity test of `bistable_analysis::sensitivity` through its public API, against
//! expectations that do not come from the test itself: a plain `bistable_core::classify` run,
//! the configured numbers of repeats and windows, and determinism.

use bistable_analysis::sensitivity::{
    classify_sensitive, perturbed_start, Outcome, Sensitivity, SensitivityOptions, Trigger,
};
use bistable_analysis::Model;
use bistable_core::{classify, Classification, ClassifyOptions, Params, Sinusoid, SolverOptions};

fn model(omega: f64, v: f64) -> Model {
    Model::new(
        Params::paper(),
        Sinusoid::new(omega, v).unwrap(),
        SolverOptions::default(),
    )
}

fn sensitive(
    m: &Model,
    co: ClassifyOptions,
    so: SensitivityOptions,
) -> (Classification, Sensitivity) {
    classify_sensitive(m, co, so).unwrap()
}

/// The chaotic attractor at (2.45, 0.07) (`docs/sensitivity.md`) over a shorter run, so that
/// the test stays quick: still aperiodic at the end.
fn short_run() -> ClassifyOptions {
    ClassifyOptions {
        max_natural_periods: 3000.0,
        lyapunov_periods: 300,
        ..ClassifyOptions::default()
    }
}

#[test]
fn a_clearly_periodic_point_is_one_run_equal_to_a_plain_classification() {
    // (1.75, 0.07): the paper's baseline, decided early on a periodic response.
    let m = model(1.75, 0.07);
    let co = ClassifyOptions::default();
    let so = SensitivityOptions::default();
    let (c, s) = sensitive(&m, co, so);
    assert!(c.period.is_some(), "{c:?}");
    assert_eq!(s.trigger, Trigger::None);
    assert!(!s.sensitive);
    assert_eq!(s.runs, 1);
    assert_eq!(s.outcomes, [(Outcome::of(&c), 1)]);
    assert_eq!(s.majority_fraction(), 1.0);
    assert_eq!(s.fractions(), format!("{}=1.000", Outcome::of(&c).key()));
    assert_eq!(s.threshold, Some(so.efoldings));
    let growth = s.efoldings.expect("growth tracked with the test on");
    assert!((0.0..so.efoldings).contains(&growth), "{growth}");

    // The same class, period, well and length as a run without the test.
    let plain = classify(m.params, m.shaker, m.opts, co).unwrap();
    assert_eq!(Outcome::of(&plain), Outcome::of(&c));
    assert_eq!(
        (plain.snap_throughs, plain.periods_simulated),
        (c.snap_throughs, c.periods_simulated)
    );

    // With the test off: the same verdict, nothing tracked.
    let (off, s_off) = sensitive(&m, co, SensitivityOptions::off());
    assert_eq!(Outcome::of(&off), Outcome::of(&c));
    assert_eq!(
        (s_off.trigger, s_off.runs, s_off.sensitive),
        (Trigger::None, 1, false)
    );
    assert_eq!((s_off.efoldings, s_off.threshold), (None, None));
}

#[test]
fn an_aperiodic_point_is_repeated_the_configured_number_of_times() {
    let m = model(2.45, 0.07);
    for repeats in [1, 3, 5] {
        let so = SensitivityOptions {
            repeats,
            windows: 0,
            repeat_periods: 100.0,
            ..SensitivityOptions::default()
        };
        let (c, s) = sensitive(&m, short_run(), so);
        assert_eq!(c.period, None, "{c:?}");
        assert_eq!(s.trigger, Trigger::Aperiodic, "{s:?}");
        // No further windows: the base run and its repeats, one verdict each.
        assert_eq!(s.runs, 1 + repeats, "{s:?}");
        assert_eq!(s.outcomes.iter().map(|o| o.1).sum::<u32>(), s.runs);
        assert_eq!(s.sensitive, s.outcomes.len() > 1);
        // The reported run has the most frequent outcome, listed first.
        assert_eq!(Outcome::of(&c), s.outcomes[0].0);
        assert!(s.outcomes.windows(2).all(|w| w[0].1 >= w[1].1), "{s:?}");
    }
}

#[test]
fn further_windows_add_at_most_their_number_of_verdicts() {
    let m = model(2.45, 0.07);
    let so = SensitivityOptions {
        repeats: 2,
        windows: 4,
        repeat_periods: 100.0,
        ..SensitivityOptions::default()
    };
    let (_, s) = sensitive(&m, short_run(), so);
    assert_eq!(s.trigger, Trigger::Aperiodic);
    assert!((3..=3 + 4).contains(&s.runs), "{s:?}");
    assert_eq!(s.outcomes.iter().map(|o| o.1).sum::<u32>(), s.runs);
}

#[test]
fn results_are_identical_between_two_calls() {
    let so = SensitivityOptions {
        repeats: 3,
        windows: 2,
        repeat_periods: 100.0,
        ..SensitivityOptions::default()
    };
    for (omega, v) in [(1.75, 0.07), (2.45, 0.07)] {
        let m = model(omega, v);
        let first = sensitive(&m, short_run(), so);
        let second = sensitive(&m, short_run(), so);
        assert_eq!(first, second, "({omega}, {v})");
    }
}

#[test]
fn perturbed_starts_lie_on_the_half_circle_above_the_plate() {
    let delta = 1e-12;
    for k in [1, 2, 6] {
        let starts: Vec<(f64, f64)> = (1..=k).map(|j| perturbed_start(j, k, delta)).collect();
        for &(x0, v0) in &starts {
            assert!(x0 > 0.0, "x0 = {x0} for k = {k}");
            assert!((x0.hypot(v0) - delta).abs() < 1e-12 * delta, "{x0} {v0}");
        }
        for (i, a) in starts.iter().enumerate() {
            for b in &starts[i + 1..] {
                assert_ne!(a, b, "k = {k}: repeated start");
            }
        }
    }
}

#[test]
fn options_are_checked_and_name_the_bad_setting() {
    assert!(SensitivityOptions::default().check().is_ok());
    assert!(SensitivityOptions::off().check().is_ok());
    let d = SensitivityOptions::default();
    for (bad, name) in [
        (SensitivityOptions { repeats: 65, ..d }, "repeats"),
        (
            SensitivityOptions {
                efoldings: 0.0,
                ..d
            },
            "efoldings",
        ),
        (
            SensitivityOptions {
                efoldings: f64::NAN,
                ..d
            },
            "efoldings",
        ),
        (
            SensitivityOptions {
                perturbation: 1e-2,
                ..d
            },
            "perturbation",
        ),
        (SensitivityOptions { horizon: 0.5, ..d }, "horizon"),
        (
            SensitivityOptions {
                repeat_periods: 1e9,
                ..d
            },
            "repeat_periods",
        ),
        (
            SensitivityOptions { windows: 1025, ..d },
            "lyapunov_windows",
        ),
    ] {
        let e = bad.check().unwrap_err();
        assert_eq!(e.name, name, "{bad:?}");
    }
}

#[test]
fn a_chaotic_attractor_every_run_keeps_is_determinate() {
    // (2.45, 0.07) with the defaults (`docs/sensitivity.md`): chaotic in the base run, its 8
    // repeats and its further Lyapunov windows (as many of the 8 as fit in the last quarter of
    // the run), hence not sensitive.
    let so = SensitivityOptions::default();
    let (c, s) = sensitive(&model(2.45, 0.07), ClassifyOptions::default(), so);
    assert!(c.chaotic && c.period.is_none(), "{c:?}");
    assert_eq!(s.trigger, Trigger::Aperiodic);
    assert!(!s.sensitive, "{s:?}");
    let repeated = 1 + so.repeats;
    assert!(
        (repeated + 1..=repeated + so.windows).contains(&s.runs),
        "{s:?}"
    );
    assert_eq!(s.outcomes, [(Outcome::of(&c), s.runs)]);
    assert_eq!(s.fractions(), "intrawell:chaotic:1=1.000");
}
