//! An observer that proves no impact was missed: it samples the gap inside every step.

use std::ops::ControlFlow;

use crate::events::Event;
use crate::simulator::{Observer, StepView};

/// Samples `x − z` at `samples` interior points of every free-flight step (the plate evaluated
/// directly, not from the step's series) and records the most negative value seen.
#[derive(Debug, Clone)]
pub struct GapAudit {
    samples: usize,
    /// Most negative gap found (0 if none), and where.
    pub worst: (f64, f64),
    /// Steps inspected.
    pub steps: u64,
    /// Events seen.
    pub events: Vec<Event>,
}

impl GapAudit {
    /// An audit with `samples ≥ 1` interior points per step.
    pub fn new(samples: usize) -> Self {
        Self {
            samples: samples.max(1),
            worst: (0.0, f64::NAN),
            steps: 0,
            events: Vec::new(),
        }
    }
}

impl Observer for GapAudit {
    fn event(&mut self, event: &Event) -> ControlFlow<()> {
        self.events.push(*event);
        ControlFlow::Continue(())
    }

    fn step(&mut self, step: &StepView<'_>) {
        self.steps += 1;
        if step.riding() || step.is_empty() {
            return;
        }
        for i in 1..=self.samples {
            let s = step.len() * i as f64 / (self.samples + 1) as f64;
            let g = step.gap_at(s);
            if g < self.worst.0 {
                self.worst = (g, step.t0() + s);
            }
        }
    }
}
