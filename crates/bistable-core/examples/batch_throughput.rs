//! Trajectory-steps per second of lone simulators against batches of 4 and 8 lanes, on one
//! core (thread CPU time), alternated: `cargo run --release -p bistable-core --example batch_throughput -- [N]
//! [PERIODS] [ROUNDS] [flight]` (defaults 64 trajectories of 2,000 natural periods, 3 rounds;
//! `BATCH_WIDTH=n` runs only that width). The trajectories are aperiodic runs of the paper's
//! map (Ω from 2.40 to 2.50 at V = 0.07, e = 0.85), the runs a sweep spends most of its time
//! on; with `flight`, free flights without impacts instead (the plate at rest, starts in well
//! 2 below the barrier energy: the work of heyoka's batch-mode comparison,
//! `bench/heyoka_batch.py`).

use std::ops::ControlFlow;

use bistable_core::{Batch, Event, Instant, Params, Simulator, Sinusoid, SolverOptions, Width};

/// CPU time of this thread [s]: unlike wall time, not stretched when other work shares the cores.
fn thread_cpu_seconds() -> f64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `ts` is a valid timespec to write; CLOCK_THREAD_CPUTIME_ID exists on Linux.
    let rc = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) };
    assert_eq!(rc, 0, "clock_gettime(CLOCK_THREAD_CPUTIME_ID) failed");
    ts.tv_sec as f64 + 1e-9 * ts.tv_nsec as f64
}

fn sims(n: usize, flight: bool) -> Vec<(Simulator, Instant)> {
    (0..n)
        .map(|i| {
            let f = i as f64 / n as f64;
            let sim = if flight {
                let plate = Sinusoid::new(1.0, 0.0).unwrap();
                let (x0, v0) = (0.8 + 0.4 * f, 0.0);
                let opts = SolverOptions::default();
                Simulator::with_state(Params::paper(), plate.into(), opts, 0.0, x0, v0)
            } else {
                let plate = Sinusoid::new(2.40 + 0.1 * f, 0.07).unwrap();
                Simulator::new(Params::paper(), plate.into(), SolverOptions::default())
            };
            (sim.unwrap(), Instant::new(0.0))
        })
        .collect()
}

/// Steps taken and seconds for `n` runs to `t_end`, lone or in a batch of `width`.
fn run(width: Width, n: usize, t_end: f64, flight: bool) -> (u64, f64) {
    let start = thread_cpu_seconds();
    let mut steps = 0;
    let target = Instant::new(t_end);
    if width == Width::One {
        for (mut sim, _) in sims(n, flight) {
            sim.advance_instant(target, &mut |_: &Event| {}).unwrap();
            steps += sim.stats().steps;
        }
        return (steps, thread_cpu_seconds() - start);
    }
    let mut batch = Batch::new(width, &Params::paper(), SolverOptions::default());
    let mut queue = sims(n, flight).into_iter();
    let mut stopped = Vec::new();
    loop {
        while let Some(lane) = batch.free_lane() {
            let Some((sim, _)) = queue.next() else { break };
            assert!(batch.put(lane, sim, target).is_ok());
        }
        if batch.is_empty() {
            return (steps, thread_cpu_seconds() - start);
        }
        stopped.clear();
        batch.advance(
            &mut |_: usize, _: &Event| ControlFlow::Continue(()),
            &mut stopped,
        );
        for &(lane, ref r) in &stopped {
            assert!(r.is_ok());
            steps += batch.take(lane).unwrap().stats().steps;
        }
    }
}

fn main() {
    let arg = |i: usize, d: f64| std::env::args().nth(i).map_or(d, |s| s.parse().unwrap());
    let n = arg(1, 64.0) as usize;
    let periods = arg(2, 2000.0);
    let rounds = arg(3, 3.0) as usize;
    let flight = std::env::args().nth(4).is_some_and(|a| a == "flight");
    let t_end = periods * std::f64::consts::TAU;
    let only = std::env::var("BATCH_WIDTH")
        .ok()
        .and_then(|w| w.parse().ok());
    let widths: Vec<Width> = [Width::One, Width::Four, Width::Eight]
        .into_iter()
        .filter(|w| only.is_none_or(|n| w.lanes() == n))
        .collect();
    let mut best = vec![f64::INFINITY; widths.len()];
    let mut steps = vec![0; widths.len()];
    for _ in 0..rounds {
        for (i, &w) in widths.iter().enumerate() {
            let (s, t) = run(w, n, t_end, flight);
            steps[i] = s;
            best[i] = best[i].min(t);
        }
    }
    let kind = if flight {
        "free flights"
    } else {
        "aperiodic runs"
    };
    println!(
        "{n} {kind} x {periods} natural periods, best of {rounds} (alternated), thread CPU time"
    );
    println!("| lanes | steps | s | M traj-steps/s | x lone |");
    println!("|---|---|---|---|---|");
    for (i, w) in widths.iter().enumerate() {
        println!(
            "| {} | {} | {:.3} | {:.2} | {:.2} |",
            w.lanes(),
            steps[i],
            best[i],
            steps[i] as f64 / best[i] / 1e6,
            best[0] / best[i]
        );
    }
}
