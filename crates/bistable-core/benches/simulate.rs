//! Criterion benchmarks of the event-driven simulator on the cases of `docs/benchmarks.md`:
//!
//! - `(Ω, V) = (1.75, 0.07)` for 20,000 natural periods (`τ = 40000π`) at `tol = 1e-15` and at a
//!   looser `tol = 1e-10` (the paper's map-point workload);
//! - the chatter case `(0.2, 0.05)` to `τ = 60` (chatter, sticking, release);
//! - `(2.5, 0.07)` to `τ = 1000` (period-doubling/chaotic regime, where peers miss impacts).
//!
//! Sample counts are kept small so that `cargo bench -p bistable-core` takes well under three
//! minutes on two cores.

use std::f64::consts::PI;
use std::hint::black_box;
use std::time::Duration;

use bistable_core::{ChatterRule, Event, Params, Simulator, Sinusoid, SolverOptions};
use criterion::{criterion_group, criterion_main, Criterion, SamplingMode};

/// Runs one simulation from the paper's initial condition and returns (impacts, last impact time).
fn run(omega: f64, velocity: f64, t_end: f64, tol: f64) -> (u64, f64) {
    let plate = Sinusoid::new(omega, velocity).expect("valid shaker");
    let opts = SolverOptions::new(tol, ChatterRule::Accumulation { horizon: 1e-7 })
        .expect("valid options");
    let mut sim = Simulator::new(Params::paper(), plate.into(), opts).expect("valid simulator");
    let mut count = 0u64;
    let mut last = 0.0;
    sim.advance_to(t_end, &mut |e: &Event| {
        if let Event::Impact(i) = e {
            count += 1;
            last = i.t;
        }
    })
    .expect("simulation runs");
    (count, last)
}

fn bench_long(c: &mut Criterion) {
    let mut g = c.benchmark_group("omega1.75_v0.07_20000_periods");
    // One run takes a few hundred milliseconds: flat sampling, one run per iteration.
    g.sampling_mode(SamplingMode::Flat)
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(5));
    for tol in [1e-15, 1e-10] {
        g.bench_function(format!("tol{tol:e}"), |b| {
            b.iter(|| run(black_box(1.75), black_box(0.07), 40000.0 * PI, tol))
        });
    }
    g.finish();
}

fn bench_chatter(c: &mut Criterion) {
    let mut g = c.benchmark_group("omega0.2_v0.05_chatter_t60");
    g.sample_size(20)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3));
    g.bench_function("tol1e-15", |b| {
        b.iter(|| run(black_box(0.2), black_box(0.05), 60.0, 1e-15))
    });
    g.finish();
}

fn bench_chaotic(c: &mut Criterion) {
    let mut g = c.benchmark_group("omega2.5_v0.07_t1000");
    g.sample_size(20)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3));
    g.bench_function("tol1e-15", |b| {
        b.iter(|| run(black_box(2.5), black_box(0.07), 1000.0, 1e-15))
    });
    g.finish();
}

criterion_group!(benches, bench_long, bench_chatter, bench_chaotic);
criterion_main!(benches);
