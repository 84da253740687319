//! Criterion benchmark of the sampled plate's reconstruction (`SampleHistory::push` and
//! `SampleHistory::piece_with`), the part of a co-simulation step with sampled inputs that the
//! FMU adds to a step in internal mode: the paper's baseline plate `(Ω, V) = (1.75, 0.07)`
//! sampled every `Δτ = 0.01` (the C host bench's `h = 0.01` s at `omega0 = 1`), 10,000 samples
//! per iteration, each followed by the piece to the next sample (the quintic, after the first
//! few). Reported per iteration; divide by 10,000 for one step.

use std::hint::black_box;
use std::time::Duration;

use bistable_core::{Instant, PieceMemo, Sample, SampleHistory};
use criterion::{criterion_group, criterion_main, Criterion};

const OMEGA: f64 = 1.75;
const V: f64 = 0.07;
const DT: f64 = 0.01;
const N: usize = 10_000;

/// The pieces of `samples` in turn; returns the last piece's position at its end.
fn reconstruct(samples: &[Sample]) -> f64 {
    let (mut hist, mut memo) = (SampleHistory::new(), PieceMemo::default());
    let mut now = (samples[0].z, samples[0].zdot);
    for w in samples.windows(2) {
        hist.push(w[0]).expect("finite, increasing samples");
        let piece = hist
            .piece_with(w[1].t, now, &mut memo)
            .expect("a piece after the newest sample");
        let (c, s) = (piece.coeffs(), w[1].t.since(w[0].t));
        // Where the next piece starts: the piece's end (Horner with the derivative).
        let (mut z, mut d) = (0.0, 0.0);
        for &ck in c.iter().rev() {
            d = d * s + z;
            z = z * s + ck;
        }
        now = (z, d);
    }
    now.0
}

fn bench_reconstruction(c: &mut Criterion) {
    let samples: Vec<Sample> = (0..=N)
        .map(|k| {
            let t = k as f64 * DT;
            Sample {
                t: Instant::new(t),
                z: V / OMEGA * (OMEGA * t).sin(),
                zdot: V * (OMEGA * t).cos(),
            }
        })
        .collect();
    let mut g = c.benchmark_group("sampled_plate_baseline_dt0.01");
    g.sample_size(20)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3));
    g.bench_function("push_and_piece_x10000", |b| {
        b.iter(|| reconstruct(black_box(&samples)))
    });
    g.finish();
}

criterion_group!(benches, bench_reconstruction);
criterion_main!(benches);
