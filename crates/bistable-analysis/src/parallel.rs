//! Work spread over threads: items are handed out one at a time (so uneven costs balance) and
//! the results come back to the calling thread in completion order, where the caller can show
//! progress, store or write them, or cancel the run.

use std::num::NonZeroUsize;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::mpsc::{self, RecvTimeoutError};
use std::time::Duration;

use bistable_core::interrupt;

/// How often the calling thread calls its interrupt check while it waits for the workers.
const POLL: Duration = Duration::from_millis(20);

/// How long the calling thread lets results gather while they keep coming ([`receive`]).
const BATCH: Duration = Duration::from_millis(2);

/// A number of worker threads (at least one).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Threads(NonZeroUsize);

impl Threads {
    /// `n` threads; `None` for 0.
    pub fn new(n: usize) -> Option<Self> {
        NonZeroUsize::new(n).map(Self)
    }

    /// One thread per core (2 if the number of cores is unknown).
    pub fn all() -> Self {
        const UNKNOWN: NonZeroUsize = NonZeroUsize::new(2).expect("2 > 0");
        Self(std::thread::available_parallelism().unwrap_or(UNKNOWN))
    }

    /// The number of threads.
    pub fn get(self) -> usize {
        self.0.get()
    }
}

/// Computes `work(item)` for every item on `threads` threads (at most one per item) and passes
/// each `(index, result)` to `done` on the calling thread as it completes.
///
/// `done` is the progress callback and the cancellation point: when it returns an error the
/// workers take no new items, the items in progress finish and are dropped, and the error is
/// returned.
///
/// The calling thread's interrupt check ([`bistable_core::interrupt`]), if any, is installed
/// on the workers too (their simulations stop when it asks, and `work` returns what they
/// return then), and the calling thread calls it every 20 ms while it waits for results.
pub fn run<T: Sync, R: Send, E>(
    items: &[T],
    threads: Threads,
    work: impl Fn(&T) -> R + Sync,
    done: impl FnMut(usize, R) -> Result<(), E>,
) -> Result<(), E> {
    run_workers(
        items,
        threads,
        |pull, send| {
            while let Some((i, item)) = pull() {
                if !send(i, work(item)) {
                    break;
                }
            }
        },
        done,
    )
}

/// The thread pool under [`run`], for workers that keep state across items (a batch of SIMD
/// lanes, [`crate::ensemble`]): `worker(pull, send)` runs on each of `threads` threads (at
/// most one per item); `pull()` hands out the next item with its index (`None` when there are
/// none left or the run is cancelled) and `send(index, result)` passes a result to `done` on
/// the calling thread (`false`: the run is cancelled, the worker should return). `done`, the
/// interrupt check and cancellation behave as in [`run`].
pub fn run_workers<'a, T: Sync, R: Send, E>(
    items: &'a [T],
    threads: Threads,
    worker: impl Fn(&mut dyn FnMut() -> Option<(usize, &'a T)>, &mut dyn FnMut(usize, R) -> bool) + Sync,
    mut done: impl FnMut(usize, R) -> Result<(), E>,
) -> Result<(), E> {
    if items.is_empty() {
        return Ok(());
    }
    let next = AtomicUsize::new(0);
    let stop = AtomicBool::new(false);
    let check = interrupt::current();
    let caller = std::thread::current();
    std::thread::scope(|s| {
        let (tx, rx) = mpsc::channel::<(usize, R)>();
        for _ in 0..threads.get().min(items.len()) {
            let tx = tx.clone();
            let (next, stop, worker) = (&next, &stop, &worker);
            let check = check.clone();
            let caller = caller.clone();
            s.spawn(move || {
                let work_items = || {
                    let mut pull = || {
                        if stop.load(Ordering::Relaxed) {
                            return None;
                        }
                        let i = next.fetch_add(1, Ordering::Relaxed);
                        items.get(i).map(|item| (i, item))
                    };
                    let mut send =
                        |i: usize, r: R| !stop.load(Ordering::Relaxed) && tx.send((i, r)).is_ok();
                    worker(&mut pull, &mut send);
                };
                match check {
                    Some(c) => interrupt::with_check(c, work_items),
                    None => work_items(),
                }
                // Done: a caller letting results gather need not wait out its pause.
                drop(tx);
                caller.unpark();
            });
        }
        drop(tx);
        let result = receive(&rx, &mut done);
        stop.store(true, Ordering::Relaxed);
        result
    })
}

/// Passes the results of `rx` to `done` until the workers are gone or `done` fails. While
/// results keep coming, this thread takes them [`BATCH`] apart, all that arrived, instead of
/// waiting on the channel: a worker's send then finds no waiting receiver to wake, which would
/// cost a system call and a context switch per result. A worker that finishes unparks this
/// thread, so the last results are not held for the rest of a pause. When a batch brings none,
/// it waits on the channel again (calling the interrupt check every [`POLL`]).
fn receive<R, E>(
    rx: &mpsc::Receiver<(usize, R)>,
    done: &mut impl FnMut(usize, R) -> Result<(), E>,
) -> Result<(), E> {
    loop {
        match rx.recv_timeout(POLL) {
            Ok((i, r)) => done(i, r)?,
            Err(RecvTimeoutError::Timeout) => {
                // What the check decides reaches the workers through their own calls.
                interrupt::poll();
                continue;
            }
            Err(RecvTimeoutError::Disconnected) => return Ok(()),
        }
        loop {
            std::thread::park_timeout(BATCH);
            let mut got = false;
            for (i, r) in rx.try_iter() {
                got = true;
                done(i, r)?;
            }
            if !got {
                break;
            }
        }
    }
}

/// Computes `work(item)` for every item on `threads` threads and returns the results in the
/// order of `items`; `progress(done)` is called on the calling thread after each completed
/// item (with the number completed so far) and cancels the run by returning an error.
pub fn map<T: Sync, R: Send, E>(
    items: &[T],
    threads: Threads,
    work: impl Fn(&T) -> R + Sync,
    mut progress: impl FnMut(usize) -> Result<(), E>,
) -> Result<Vec<R>, E> {
    let mut out: Vec<Option<R>> = std::iter::repeat_with(|| None).take(items.len()).collect();
    let mut finished = 0;
    run(items, threads, work, |i, r| {
        out[i] = Some(r);
        finished += 1;
        progress(finished)
    })?;
    Ok(out.into_iter().flatten().collect())
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
            Threads::new(3).unwrap(),
            |&x| x * x,
            |i, r| {
                assert_eq!(r, items[i] * items[i]);
                seen[i] += 1;
                Ok::<(), ()>(())
            },
        )
        .unwrap();
        assert!(seen.iter().all(|&n| n == 1));
        let mut calls = 0;
        let r = run(
            &items,
            Threads::new(2).unwrap(),
            |&x| x,
            |_, _| {
                calls += 1;
                if calls == 10 {
                    Err("stop")
                } else {
                    Ok(())
                }
            },
        );
        assert_eq!(r, Err("stop"));
        assert_eq!(calls, 10);
    }

    #[test]
    fn a_result_reaches_done_while_other_items_still_run() {
        // On one worker, item 1 waits until item 0's result has reached `done`: a worker does
        // not hold results back until its items are done (the wait gives up after 10 s, and
        // the test then fails).
        let delivered = AtomicBool::new(false);
        let mut order = Vec::new();
        run(
            &[0u32, 1],
            Threads::new(1).unwrap(),
            |&i| {
                if i == 1 {
                    let t = std::time::Instant::now();
                    while !delivered.load(Ordering::SeqCst) && t.elapsed().as_secs() < 10 {
                        std::thread::sleep(Duration::from_millis(1));
                    }
                    return delivered.load(Ordering::SeqCst);
                }
                true
            },
            |i, saw_zero| {
                if i == 0 {
                    delivered.store(true, Ordering::SeqCst);
                }
                order.push((i, saw_zero));
                Ok::<(), ()>(())
            },
        )
        .unwrap();
        assert_eq!(order, vec![(0, true), (1, true)]);
    }

    #[test]
    fn map_keeps_the_order_of_the_items() {
        let items: Vec<u64> = (0..100).collect();
        let mut last = 0;
        let out = map(
            &items,
            Threads::new(4).unwrap(),
            |&x| 2 * x,
            |n| {
                last = n;
                Ok::<(), ()>(())
            },
        );
        assert_eq!(
            out.unwrap(),
            items.iter().map(|x| 2 * x).collect::<Vec<_>>()
        );
        assert_eq!(last, 100);
        assert!(Threads::new(0).is_none() && Threads::all().get() >= 1);
    }
}
