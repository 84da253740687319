//! Trajectory-steps per second of lone simulators against batches of 4 and 8 lanes, on one
//! core, alternated: `cargo run --release -p bistable-core --example batch_throughput -- [N]
//! [PERIODS] [ROUNDS]` (defaults 64 trajectories of 2,000 natural periods, 3 rounds). The
//! trajectories are aperiodic runs of the paper's map (Ω from 2.40 to 2.50 at V = 0.07,
//! e = 0.85), the runs a sweep spends most of its time on.

use std::ops::ControlFlow;
use std::time::Instant as Clock;

use bistable_core::{Batch, Event, Instant, Params, Simulator, Sinusoid, SolverOptions, Width};

fn sims(n: usize) -> Vec<(Simulator, Instant)> {
    (0..n)
        .map(|i| {
            let omega = 2.40 + 0.1 * i as f64 / n as f64;
            let plate = Sinusoid::new(omega, 0.07).unwrap();
            let sim = Simulator::new(Params::paper(), plate.into(), SolverOptions::default());
            (sim.unwrap(), Instant::new(0.0))
        })
        .collect()
}

/// Steps taken and seconds for `n` runs to `t_end`, lone or in a batch of `width`.
fn run(width: Width, n: usize, t_end: f64) -> (u64, f64) {
    let start = Clock::now();
    let mut steps = 0;
    let target = Instant::new(t_end);
    if width == Width::One {
        for (mut sim, _) in sims(n) {
            sim.advance_instant(target, &mut |_: &Event| {}).unwrap();
            steps += sim.stats().steps;
        }
        return (steps, start.elapsed().as_secs_f64());
    }
    let mut batch = Batch::new(width, &Params::paper(), SolverOptions::default());
    let mut queue = sims(n).into_iter();
    let mut stopped = Vec::new();
    loop {
        while let Some(lane) = batch.free_lane() {
            let Some((sim, _)) = queue.next() else { break };
            assert!(batch.put(lane, sim, target).is_ok());
        }
        if batch.is_empty() {
            return (steps, start.elapsed().as_secs_f64());
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
            let (s, t) = run(w, n, t_end);
            steps[i] = s;
            best[i] = best[i].min(t);
        }
    }
    println!("{n} trajectories x {periods} natural periods, best of {rounds} (alternated)");
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
