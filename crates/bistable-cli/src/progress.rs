//! Progress bars on stderr for long runs: shown only when stderr is a terminal and the run has
//! already taken a while, so short runs, pipes and tests print nothing.

use std::io::IsTerminal;
use std::time::{Duration, Instant};

use bistable_analysis::{self as analysis, Stage};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use crate::error::CliError;

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

/// Progress bars for the stages of a library analysis: one bar per stage, removed when the
/// stage completes.
pub struct StageBars {
    context: String,
    current: Option<(Stage, Progress)>,
}

impl StageBars {
    /// Bars whose simulation stage is labelled `simulating N points{context}`.
    pub fn new(context: impl Into<String>) -> Self {
        Self {
            context: context.into(),
            current: None,
        }
    }

    /// Shows a report of the analysis (never cancels it).
    pub fn report(&mut self, p: analysis::Progress) -> Result<(), CliError> {
        if self.current.as_ref().is_none_or(|(s, _)| *s != p.stage) {
            let label = match p.stage {
                Stage::Simulating => format!("simulating {} points{}", p.total, self.context),
                Stage::Shooting => format!("shooting from {} seeds", p.total),
                Stage::Continuing => "continuing the orbits".to_string(),
                Stage::Locating => format!("locating bifurcations in {} intervals", p.total),
            };
            self.current = Some((p.stage, Progress::new(p.total as f64, label)));
        }
        if let Some((_, bar)) = &mut self.current {
            bar.set(p.done as f64);
            if p.done >= p.total {
                self.current = None;
            }
        }
        Ok(())
    }
}
