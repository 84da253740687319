//! A progress bar on stderr for long runs: shown only when stderr is a terminal and the run has
//! already taken a while, so short runs, pipes and tests print nothing.

use std::io::IsTerminal;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// Resolution of the bar.
const TICKS: u64 = 1000;
/// The bar appears once a run has lasted this long.
const DELAY: Duration = Duration::from_millis(700);

/// Progress of a run over `[0, total]` in some unit (e.g. simulated time).
pub struct Progress {
    enabled: bool,
    total: f64,
    start: Instant,
    bar: Option<ProgressBar>,
    message: String,
}

impl Progress {
    /// A progress indicator for a run up to `total`, labelled `message`.
    pub fn new(total: f64, message: impl Into<String>) -> Self {
        Self {
            enabled: std::io::stderr().is_terminal() && total > 0.0,
            total,
            start: Instant::now(),
            bar: None,
            message: message.into(),
        }
    }

    /// Reports that the run has reached `done` (same unit as `total`).
    pub fn set(&mut self, done: f64) {
        if !self.enabled {
            return;
        }
        if self.bar.is_none() {
            if self.start.elapsed() < DELAY {
                return;
            }
            let bar = ProgressBar::with_draw_target(Some(TICKS), ProgressDrawTarget::stderr())
                .with_elapsed(self.start.elapsed());
            bar.set_style(
                ProgressStyle::with_template(
                    "{msg} [{bar:40}] {percent:>3}% ({elapsed}, ETA {eta})",
                )
                .unwrap_or_else(|_| ProgressStyle::default_bar())
                .progress_chars("=> "),
            );
            bar.set_message(self.message.clone());
            self.bar = Some(bar);
        }
        if let Some(bar) = &self.bar {
            let frac = (done / self.total).clamp(0.0, 1.0);
            bar.set_position((frac * TICKS as f64) as u64);
        }
    }

    /// Removes the bar.
    pub fn finish(&mut self) {
        if let Some(bar) = self.bar.take() {
            bar.finish_and_clear();
        }
    }
}

impl Drop for Progress {
    fn drop(&mut self) {
        self.finish();
    }
}
