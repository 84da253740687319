//! Work spread over threads: items are handed out one at a time (so uneven costs balance) and
//! the results come back to the calling thread in completion order, where they can be written
//! out at once.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::mpsc;

use crate::error::CliError;
use crate::progress::Progress;

/// The number of worker threads: `requested` (validated, the error names `option`) or all
/// cores.
pub fn threads(requested: Option<usize>, option: &str) -> Result<usize, CliError> {
    match requested {
        Some(n) => CliError::at_least(option, n, 1).map(|()| n),
        None => Ok(std::thread::available_parallelism().map_or(2, |n| n.get())),
    }
}

/// Computes `work(item)` for every item on `threads` threads and passes each `(index, result)`
/// to `done` on the calling thread as it completes, with a progress bar labelled `message`.
/// An error from `done` stops the workers (items in progress finish) and is returned.
pub fn run<T: Sync, R: Send>(
    items: &[T],
    threads: usize,
    message: &str,
    work: impl Fn(&T) -> R + Sync,
    mut done: impl FnMut(usize, R) -> Result<(), CliError>,
) -> Result<(), CliError> {
    if items.is_empty() {
        return Ok(());
    }
    let next = AtomicUsize::new(0);
    let stop = AtomicBool::new(false);
    let mut progress = Progress::new(items.len() as f64, message);
    let result = std::thread::scope(|s| {
        let (tx, rx) = mpsc::channel::<(usize, R)>();
        for _ in 0..threads.clamp(1, items.len()) {
            let tx = tx.clone();
            let (next, stop, work) = (&next, &stop, &work);
            s.spawn(move || {
                while !stop.load(Ordering::Relaxed) {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    let Some(item) = items.get(i) else { break };
                    if tx.send((i, work(item))).is_err() {
                        break;
                    }
                }
            });
        }
        drop(tx);
        let mut finished = 0usize;
        let mut result = Ok(());
        for (i, r) in rx.iter() {
            result = done(i, r);
            if result.is_err() {
                break;
            }
            finished += 1;
            progress.set(finished as f64);
        }
        stop.store(true, Ordering::Relaxed);
        result
    });
    progress.finish();
    result
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_item_once_and_errors_stop_the_run() {
        let items: Vec<u64> = (0..500).collect();
        let mut seen = vec![0u32; items.len()];
        run(
            &items,
            3,
            "test",
            |&x| x * x,
            |i, r| {
                assert_eq!(r, items[i] * items[i]);
                seen[i] += 1;
                Ok(())
            },
        )
        .unwrap();
        assert!(seen.iter().all(|&n| n == 1));
        let mut calls = 0;
        let r = run(
            &items,
            2,
            "test",
            |&x| x,
            |_, _| {
                calls += 1;
                if calls == 10 {
                    Err(CliError::Failed("stop".into()))
                } else {
                    Ok(())
                }
            },
        );
        assert!(r.is_err());
        assert_eq!(calls, 10);
    }
}
