//! Cooperative interruption of long runs.
//!
//! An adapter that must stay responsive (Ctrl-C in Python, a work limit per call) installs a
//! check with [`with_check`] around the work it runs on its thread; every [`Simulator`] that
//! advances on that thread calls it once every [`CHECK_EVERY`] computed steps, before computing
//! the next one, and stops with [`SimError::Interrupted`] when it answers `true`. The simulator
//! then stays at its last consistent state (no step is half done). Without a check installed
//! the cost is a thread-local counter per step.
//!
//! A thread pool that runs work for the caller (`bistable_analysis::parallel`) passes the
//! caller's check ([`current`]) on to its workers and calls it ([`poll`]) while it waits for
//! them, so that the check also sees time pass when the caller itself does not simulate.
//!
//! [`Simulator`]: crate::Simulator
//! [`SimError::Interrupted`]: crate::SimError::Interrupted

use std::cell::{Cell, RefCell};
use std::sync::Arc;

/// Computed steps between two calls of the check (about a millisecond of work or less).
pub const CHECK_EVERY: u32 = 1024;

/// A check: `true` asks the runs to stop. Shared by the threads that work for one caller.
pub type Check = Arc<dyn Fn() -> bool + Send + Sync>;

thread_local! {
    static COUNT: Cell<u32> = const { Cell::new(0) };
    static CHECK: RefCell<Option<Check>> = const { RefCell::new(None) };
}

/// Runs `body` with `check` installed on this thread (in place of any check installed before,
/// which is restored afterwards, also when `body` panics).
pub fn with_check<R>(check: Check, body: impl FnOnce() -> R) -> R {
    struct Restore(Option<Check>);
    impl Drop for Restore {
        fn drop(&mut self) {
            let previous = self.0.take();
            CHECK.with(|c| *c.borrow_mut() = previous);
        }
    }
    let previous = CHECK.with(|c| c.borrow_mut().replace(check));
    let _restore = Restore(previous);
    body()
}

/// The check installed on this thread, to install it on threads that work for this one.
pub fn current() -> Option<Check> {
    CHECK.with(|c| c.borrow().clone())
}

/// Calls the check installed on this thread now: `true` when it asks to stop (`false`
/// without a check).
pub fn poll() -> bool {
    current().is_some_and(|f| f())
}

/// Called by the simulator before each step it computes: `true` when the installed check asks
/// to stop (it is called every [`CHECK_EVERY`] steps).
pub(crate) fn stop_requested() -> bool {
    let n = COUNT.with(|c| {
        let n = c.get().wrapping_add(1);
        c.set(n);
        n
    });
    n.is_multiple_of(CHECK_EVERY) && poll()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicU32, Ordering};

    #[test]
    fn the_check_runs_every_check_every_steps_and_is_restored() {
        let calls = Arc::new(AtomicU32::new(0));
        let seen = calls.clone();
        let check: Check = Arc::new(move || seen.fetch_add(1, Ordering::Relaxed) + 1 == 3);
        let stopped = with_check(check, || {
            assert!(current().is_some());
            (0..10 * CHECK_EVERY).position(|_| stop_requested())
        });
        assert_eq!(calls.load(Ordering::Relaxed), 3);
        assert!(stopped.is_some());
        // Uninstalled afterwards: never stops.
        assert!(current().is_none() && !poll());
        assert!((0..4 * CHECK_EVERY).all(|_| !stop_requested()));
    }
}
