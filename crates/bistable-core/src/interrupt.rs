//! Cooperative interruption of long runs on one thread.
//!
//! An adapter that must stay responsive (Ctrl-C in Python, a wall-time limit per call) installs
//! a check with [`with_check`] around the work it runs on its thread; every [`Simulator`] that
//! advances on that thread calls it once every [`CHECK_EVERY`] computed steps, before computing
//! the next one, and stops with [`SimError::Interrupted`] when it answers `true`. The simulator
//! then stays at its last consistent state (no step is half done). Without a check installed
//! the cost is a thread-local counter per step. Runs on other threads (e.g. the workers of a
//! parallel sweep) are not affected: they have their own (empty) check.
//!
//! [`Simulator`]: crate::Simulator
//! [`SimError::Interrupted`]: crate::SimError::Interrupted

use std::cell::{Cell, RefCell};

/// Computed steps between two calls of the check (about a millisecond of work or less).
pub const CHECK_EVERY: u32 = 1024;

type Check = Box<dyn FnMut() -> bool>;

thread_local! {
    static COUNT: Cell<u32> = const { Cell::new(0) };
    static CHECK: RefCell<Option<Check>> = const { RefCell::new(None) };
}

/// Runs `body` with `check` installed on this thread (in place of any check installed before,
/// which is restored afterwards, also when `body` panics).
pub fn with_check<R>(check: impl FnMut() -> bool + 'static, body: impl FnOnce() -> R) -> R {
    struct Restore(Option<Check>);
    impl Drop for Restore {
        fn drop(&mut self) {
            let previous = self.0.take();
            CHECK.with(|c| *c.borrow_mut() = previous);
        }
    }
    let previous = CHECK.with(|c| c.borrow_mut().replace(Box::new(check)));
    let _restore = Restore(previous);
    body()
}

/// Called by the simulator before each step it computes: `true` when the installed check asks
/// to stop. The check is not called again while it runs (a check that runs code which
/// simulates on the same thread does not recurse).
pub(crate) fn stop_requested() -> bool {
    let n = COUNT.with(|c| {
        let n = c.get().wrapping_add(1);
        c.set(n);
        n
    });
    if !n.is_multiple_of(CHECK_EVERY) {
        return false;
    }
    CHECK.with(|c| match c.try_borrow_mut() {
        Ok(mut f) => f.as_mut().is_some_and(|f| f()),
        Err(_) => false,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_check_runs_every_check_every_steps_and_is_restored() {
        let calls = std::rc::Rc::new(Cell::new(0u32));
        let seen = calls.clone();
        let stopped = with_check(
            move || {
                seen.set(seen.get() + 1);
                seen.get() == 3
            },
            || (0..10 * CHECK_EVERY).position(|_| stop_requested()),
        );
        assert_eq!(calls.get(), 3);
        assert!(stopped.is_some());
        // Uninstalled afterwards: never stops.
        assert!((0..4 * CHECK_EVERY).all(|_| !stop_requested()));
    }
}
