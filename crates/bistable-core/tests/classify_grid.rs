//! Early stopping never changes the classification: a 30 × 30 grid over Ω ∈ [0.2, 3.5],
//! V ∈ [0, 0.2], each point classified with early stopping and with the full 20,000 natural
//! periods (the full run decides on its final sections).

use std::sync::atomic::{AtomicUsize, Ordering};

use bistable_core::{
    classify, Classification, ClassifyOptions, Params, ResponseClass, Sinusoid, SolverOptions,
};

fn run(omega: f64, v: f64, full: bool) -> Classification {
    let plate = Sinusoid::new(omega, v).unwrap();
    let co = ClassifyOptions {
        full_length: full,
        ..ClassifyOptions::default()
    };
    classify(Params::paper(), plate, SolverOptions::default(), co).unwrap()
}

#[test]
fn early_stopping_keeps_the_class_on_a_30_by_30_grid() {
    let n = 30;
    let points: Vec<(f64, f64)> = (0..n * n)
        .map(|i| {
            let (a, b) = ((i % n) as f64, (i / n) as f64);
            (0.2 + 3.3 * a / (n - 1) as f64, 0.2 * b / (n - 1) as f64)
        })
        .collect();
    let next = AtomicUsize::new(0);
    let threads = std::thread::available_parallelism().map_or(2, |c| c.get());
    let results: Vec<Vec<(usize, Classification, Classification)>> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..threads)
            .map(|_| {
                s.spawn(|| {
                    let mut out = Vec::new();
                    loop {
                        let i = next.fetch_add(1, Ordering::Relaxed);
                        let Some(&(w, v)) = points.get(i) else { break };
                        out.push((i, run(w, v, false), run(w, v, true)));
                    }
                    out
                })
            })
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    let mut early_stops = 0;
    let mut saved = 0.0;
    let mut total = 0;
    for (i, early, full) in results.into_iter().flatten() {
        total += 1;
        let (w, v) = points[i];
        // The final well is a property of the steady state unless the orbit itself crosses
        // the barrier (then it is where the run happened to stop).
        let key = |c: &Classification| {
            let well = (c.class != ResponseClass::ContinuousInterwell).then_some(c.final_well);
            (c.class, c.period, c.chaotic, well, c.at_rest_in_second_well)
        };
        assert_eq!(key(&early), key(&full), "Ω = {w}, V = {v}");
        if early.stopped_early {
            early_stops += 1;
            saved += full.periods_simulated - early.periods_simulated;
        }
    }
    assert_eq!(total, n * n);
    println!(
        "{total} points: {early_stops} decided early, {:.0} natural periods saved on average",
        saved / total as f64
    );
    assert!(early_stops > total / 2);
}
