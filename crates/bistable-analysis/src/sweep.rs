//! Classification sweeps: the response class (paper Sec. 3.4, the core's
//! [`bistable_core::classify()`]) at every point of a list of shaker points `(Ω, V)`, on several
//! threads, each result handed to the caller as it completes.

use std::time::Instant as WallClock;

use bistable_core::{Classification, ClassifyOptions, SimError, Width};

use crate::ensemble::{self, Run, Task};
use crate::parallel::Threads;
use crate::sensitivity::{classify_sensitive, PointTest, Sensitivity, SensitivityOptions};
use crate::Model;

/// One classified point.
#[derive(Debug, Clone)]
pub struct Classified {
    /// The model at the point.
    pub model: Model,
    /// The reported classification (of the most frequent outcome when the point was repeated).
    pub classification: Classification,
    /// The final-state sensitivity test ([`crate::sensitivity`]).
    pub sensitivity: Sensitivity,
    /// Wall-clock time of the classification (all its runs), in seconds.
    pub wall_time_s: f64,
}

/// Classifies `model`'s point from the paper's initial condition with the sensitivity test's
/// settings ([`SensitivityOptions::default`] for the default test, [`SensitivityOptions::off`]
/// for a single run), and times it.
pub fn classify_point_with(
    model: &Model,
    options: ClassifyOptions,
    sensitivity: SensitivityOptions,
) -> Result<Classified, SimError> {
    let start = WallClock::now();
    let (classification, sensitivity) = classify_sensitive(model, options, sensitivity)?;
    Ok(Classified {
        model: *model,
        classification,
        sensitivity,
        wall_time_s: start.elapsed().as_secs_f64(),
    })
}

/// Classifies `model` at every `(Ω, V)` of `points` on `threads` threads, `width` trajectories
/// per thread in SIMD lanes ([`crate::ensemble`]; [`Width::One`]: one run at a time, the
/// results are the same). Each result (a point that cannot be simulated, e.g. with `Ω <= 0`,
/// gives an error) is passed with its index to `done` on the calling thread as it completes, in
/// completion order: `done` is the progress callback and the place to store or write results,
/// and it cancels the sweep by returning an error (points in progress are dropped), which is
/// returned. A point's `wall_time_s` is the time from its start to its end; with lanes, the
/// point shared its thread with the other lanes' points meanwhile.
pub fn classify_points_with<E>(
    model: &Model,
    points: &[(f64, f64)],
    options: ClassifyOptions,
    sensitivity: SensitivityOptions,
    threads: Threads,
    width: Width,
    done: impl FnMut(usize, Result<Classified, SimError>) -> Result<(), E>,
) -> Result<(), E> {
    ensemble::run(
        points,
        threads,
        width,
        |&(w, v)| {
            let m = model.at(w, v)?;
            Ok(TimedPoint {
                model: m,
                test: PointTest::new(&m, options, sensitivity),
                start: WallClock::now(),
            })
        },
        done,
    )
}

/// A point of a sweep: its sensitivity test, timed.
struct TimedPoint {
    model: Model,
    test: PointTest,
    start: WallClock,
}

impl Task for TimedPoint {
    type Run = Run;
    type Output = Classified;

    fn start(&mut self) -> Result<Vec<Run>, SimError> {
        self.test.start()
    }

    fn run_done(&mut self, i: usize, result: Classification) -> Result<Vec<Run>, SimError> {
        self.test.run_done(i, result)
    }

    fn finish(self) -> Classified {
        let wall_time_s = self.start.elapsed().as_secs_f64();
        let (classification, sensitivity) = self.test.finish();
        Classified {
            model: self.model,
            classification,
            sensitivity,
            wall_time_s,
        }
    }
}

/// The indices `0..n` in an order that spreads over the whole range early (a stride coprime
/// with `n` near `n/φ`), so that partial results of a sweep over a grid are representative.
pub fn interleaved(n: usize) -> impl Iterator<Item = usize> {
    let mut stride = ((n as f64) * 0.618_033_988_749_894_9) as usize;
    stride = stride.max(1);
    while gcd(stride, n) != 1 {
        stride += 1;
    }
    (0..n).map(move |k| ((k as u128 * stride as u128) % n as u128) as usize)
}

fn gcd(mut a: usize, mut b: usize) -> usize {
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

#[cfg(test)]
mod tests {
    use super::*;
    use bistable_core::{Params, ResponseClass, Sinusoid, SolverOptions};

    #[test]
    fn interleaved_order_is_a_permutation() {
        for n in [1, 2, 7, 60, 2400, 60_000] {
            let mut seen = vec![false; n];
            for i in interleaved(n) {
                assert!(!seen[i], "n = {n}: {i} twice");
                seen[i] = true;
            }
            assert!(seen.iter().all(|&s| s));
        }
    }

    #[test]
    fn sweep_classifies_every_point_and_reports_bad_ones() {
        let model = Model::new(
            Params::paper(),
            Sinusoid::new(0.85, 0.11).unwrap(),
            SolverOptions::default(),
        );
        let points = [(0.85, 0.11), (0.85, 0.15), (-1.0, 0.1)];
        let mut got: Vec<Option<Result<Classified, SimError>>> = vec![None, None, None];
        classify_points_with(
            &model,
            &points,
            ClassifyOptions::default(),
            SensitivityOptions::default(),
            Threads::new(2).unwrap(),
            Width::Eight,
            |i, r| {
                got[i] = Some(r);
                Ok::<(), ()>(())
            },
        )
        .unwrap();
        let c = |i: usize| got[i].as_ref().unwrap().as_ref().unwrap();
        assert_eq!(c(0).classification.class, ResponseClass::Intrawell);
        assert_eq!(c(0).classification.period, Some(4));
        assert!(c(1).classification.at_rest_in_second_well);
        assert_eq!(c(1).model.velocity(), 0.15);
        assert!(got[2].as_ref().unwrap().is_err());
        // Cancelling after the first result stops the sweep with the caller's error.
        let r = classify_points_with(
            &model,
            &points,
            ClassifyOptions::default(),
            SensitivityOptions::default(),
            Threads::new(1).unwrap(),
            Width::Four,
            |_, _| Err("cancelled"),
        );
        assert_eq!(r, Err("cancelled"));
    }
}
