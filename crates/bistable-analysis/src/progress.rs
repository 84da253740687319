//! Progress reports of the multi-stage analyses (bifurcation data, continuation), given to a
//! caller's callback on the calling thread; the callback cancels the analysis by returning an
//! error.

/// What an analysis is doing.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stage {
    /// Simulating the response at the grid points (transient, then recorded cycles).
    Simulating,
    /// Shooting for periodic orbits from seeds.
    Shooting,
    /// Continuing the orbits of each period along the grid.
    Continuing,
    /// Locating the bifurcation points on the branches (one item per interval with a change).
    Locating,
}

/// `done` of `total` items of `stage` finished (`done <= total`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Progress {
    /// The current stage.
    pub stage: Stage,
    /// Items finished.
    pub done: usize,
    /// Items in this stage.
    pub total: usize,
}

/// The callback that receives progress reports and cancels by returning an error.
pub type OnProgress<'a, E> = dyn FnMut(Progress) -> Result<(), E> + 'a;
