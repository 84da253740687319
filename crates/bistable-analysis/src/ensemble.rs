//! Many runs at once: the runs of a sweep's items (a map point with its sensitivity repeats, a
//! basin cell, a bifurcation diagram's point) advanced in the SIMD lanes of
//! [`bistable_core::Batch`]es, one batch per thread and per solver setting.
//!
//! A run is a [`RunSpec`]: it starts a simulator and a [`LaneRun`], which names the instant to
//! advance to next, takes the events on the way and, at that instant, either gives its result
//! or names the next instant. An item is a [`Task`]: it asks for runs, takes their results, may
//! ask for more (the repeats of a suspect point) and then gives its output. [`run_alone`] makes
//! its runs one after the other ([`RunSpec::alone`]), in the order they were asked for; [`run`]
//! spreads items over threads and, with a lane width above 1, keeps every lane of each thread's
//! batches busy: a lane whose run is over takes the next run waiting (a repeat of a point in
//! progress first, else the first run of the next item), so runs of uneven length leave no lane
//! idle. Each lane follows bit for bit the run made alone, so every output is the same for every
//! width; only the order in which items complete differs.

use std::collections::VecDeque;
use std::ops::ControlFlow;

pub use bistable_core::{drive, LaneRun};
use bistable_core::{
    Batch, ClassifyOptions, ClassifyRun, Event, Params, SimError, Simulator, Sinusoid,
    SolverOptions, Tracking, Width,
};

use crate::parallel::{self, Threads};

/// A run to make: what starts it, and the setting it shares a batch with other runs by.
pub trait RunSpec {
    /// The run in progress.
    type Lane: LaneRun;

    /// The damping (`ζ`, of the parameters) and solver options: runs that agree in these can
    /// share a batch.
    fn setting(&self) -> (Params, SolverOptions);

    /// The run and its simulator, at the start.
    fn begin(&self) -> Result<(Self::Lane, Simulator), SimError>;

    /// The run made alone.
    fn alone(&self) -> Result<RunResult<Self>, SimError> {
        let (mut run, mut sim) = self.begin()?;
        drive(&mut run, &mut sim)
    }
}

/// What a run of `S` gives.
pub type RunResult<S> = <<S as RunSpec>::Lane as LaneRun>::Result;

/// One classification run ([`bistable_core::classify_from`]'s arguments).
#[derive(Debug, Clone, Copy)]
pub struct Run {
    /// Damping and restitution.
    pub params: Params,
    /// The shaker.
    pub plate: Sinusoid,
    /// Tolerance and chatter rule.
    pub opts: SolverOptions,
    /// Classification settings.
    pub co: ClassifyOptions,
    /// Initial state `(x0, x0')` at `τ = 0`.
    pub start: (f64, f64),
    /// What to measure besides the class.
    pub track: Tracking,
}

impl RunSpec for Run {
    type Lane = ClassifyRun;

    fn setting(&self) -> (Params, SolverOptions) {
        (self.params, self.opts)
    }

    fn begin(&self) -> Result<(ClassifyRun, Simulator), SimError> {
        ClassifyRun::start(
            self.params,
            self.plate,
            self.opts,
            self.co,
            self.start,
            self.track,
        )
    }
}

/// An item of a sweep, made of runs.
pub trait Task {
    /// The runs it asks for.
    type Run: RunSpec;
    /// What the item gives once its runs are done.
    type Output;

    /// The runs to make first (numbered from 0 in this order).
    fn start(&mut self) -> Result<Vec<Self::Run>, SimError>;

    /// Takes the result of run `i`; returns further runs to make (numbered on from the runs
    /// asked for so far).
    fn run_done(
        &mut self,
        i: usize,
        result: RunResult<Self::Run>,
    ) -> Result<Vec<Self::Run>, SimError>;

    /// The output, once every run asked for is done.
    fn finish(self) -> Self::Output;
}

/// The task of one run, whose output is the run's result.
pub struct Single<S: RunSpec> {
    spec: Option<S>,
    result: Option<RunResult<S>>,
}

impl<S: RunSpec> Single<S> {
    /// The task of making `spec`'s run.
    pub fn new(spec: S) -> Self {
        Self {
            spec: Some(spec),
            result: None,
        }
    }
}

impl<S: RunSpec> Task for Single<S> {
    type Run = S;
    type Output = RunResult<S>;

    fn start(&mut self) -> Result<Vec<S>, SimError> {
        Ok(self.spec.take().into_iter().collect())
    }

    fn run_done(&mut self, _: usize, result: RunResult<S>) -> Result<Vec<S>, SimError> {
        self.result = Some(result);
        Ok(Vec::new())
    }

    fn finish(self) -> RunResult<S> {
        self.result.expect("the run is done")
    }
}

/// Makes `task`'s runs one after the other, in the order they are asked for; the first run
/// that fails ends the task with its error.
pub fn run_alone<T: Task>(mut task: T) -> Result<T::Output, SimError> {
    let mut queue: VecDeque<(usize, T::Run)> = task.start()?.into_iter().enumerate().collect();
    let mut next = queue.len();
    while let Some((i, run)) = queue.pop_front() {
        let c = run.alone()?;
        for r in task.run_done(i, c)? {
            queue.push_back((next, r));
            next += 1;
        }
    }
    Ok(task.finish())
}

/// Computes the task `make(item)` for every item on `threads` threads, `width` lanes each, and
/// passes each `(index, output)` to `done` on the calling thread as it completes (in completion
/// order). A task fails with the error of its first failing run, counted in the order the runs
/// were asked for, as [`run_alone`] does. `done` is the progress callback and cancels the sweep
/// by returning an error: the workers stop at once, dropping the items in progress, and the
/// error is returned. With [`Width::One`] each item is [`run_alone`].
pub fn run<I: Sync, T: Task, E>(
    items: &[I],
    threads: Threads,
    width: Width,
    make: impl Fn(&I) -> Result<T, SimError> + Sync,
    done: impl FnMut(usize, Result<T::Output, SimError>) -> Result<(), E>,
) -> Result<(), E>
where
    T::Output: Send,
{
    if width == Width::One {
        return parallel::run(items, threads, |item| make(item).and_then(run_alone), done);
    }
    parallel::run_workers(
        items,
        threads,
        |pull, send| {
            let mut pull = || pull().map(|(i, item)| (i, make(item)));
            Worker::new(width).work(&mut pull, send);
        },
        done,
    )
}

/// Where a worker sends each finished item (`false`: the sweep is cancelled).
type Sink<'a, O> = dyn FnMut(usize, Result<O, SimError>) -> bool + 'a;

/// A task in progress on a worker.
struct Live<T> {
    item: usize,
    task: T,
    /// Runs asked for so far.
    asked: usize,
    /// Runs asked for and not yet done.
    open: usize,
    /// The failed run with the lowest number, and its error.
    failed: Option<(usize, SimError)>,
}

/// A run waiting for a lane, or in one: its task's slot and its number there.
struct Job<S> {
    task: usize,
    index: usize,
    run: S,
}

/// The runs of one solver setting (damping and options): a batch and the runs waiting for it.
struct Group<S: RunSpec> {
    zeta: u64,
    opts: SolverOptions,
    batch: Batch,
    queue: VecDeque<Job<S>>,
    /// Per lane: the run in it.
    lanes: Vec<Option<(usize, usize, S::Lane)>>,
}

/// One thread's share of a sweep.
struct Worker<T: Task> {
    width: Width,
    groups: Vec<Group<T::Run>>,
    tasks: Vec<Option<Live<T>>>,
}

impl<T: Task> Worker<T> {
    fn new(width: Width) -> Self {
        Self {
            width,
            groups: Vec::new(),
            tasks: Vec::new(),
        }
    }

    /// Takes items from `pull` until there are none and their tasks are done, or `send` fails
    /// (the sweep is cancelled); each finished item goes to `send`.
    fn work(
        &mut self,
        pull: &mut impl FnMut() -> Option<(usize, Result<T, SimError>)>,
        send: &mut Sink<'_, T::Output>,
    ) {
        let mut exhausted = false;
        let mut stopped = Vec::new();
        loop {
            // New items while the first group (that of every item's first run) has lanes
            // with nothing to do.
            while !exhausted
                && self
                    .groups
                    .first()
                    .is_none_or(|g| g.queue.is_empty() && g.batch.free_lane().is_some())
            {
                match pull() {
                    None => exhausted = true,
                    Some((item, Err(e))) => {
                        if !send(item, Err(e)) {
                            return;
                        }
                    }
                    Some((item, Ok(task))) => {
                        if !self.begin(item, task, send) {
                            return;
                        }
                    }
                }
                if !self.fill(send) {
                    return;
                }
            }
            if !self.fill(send) {
                return;
            }
            if self.groups.iter().all(|g| g.batch.is_empty()) {
                if exhausted {
                    return;
                }
                continue;
            }
            for g in 0..self.groups.len() {
                if self.groups[g].batch.is_empty() {
                    continue;
                }
                stopped.clear();
                let Group { batch, lanes, .. } = &mut self.groups[g];
                batch.advance(
                    &mut |lane: usize, e: &Event| {
                        if let Some((_, _, run)) = lanes[lane].as_mut() {
                            run.event(e);
                        }
                        ControlFlow::Continue(())
                    },
                    &mut stopped,
                );
                for (lane, r) in stopped.drain(..) {
                    if !self.lane_stopped(g, lane, r, send) {
                        return;
                    }
                }
            }
        }
    }

    /// Starts `task` for `item`: queues its first runs.
    fn begin(&mut self, item: usize, mut task: T, send: &mut Sink<'_, T::Output>) -> bool {
        let runs = match task.start() {
            Ok(r) => r,
            Err(e) => return send(item, Err(e)),
        };
        let slot = match self.tasks.iter().position(Option::is_none) {
            Some(s) => s,
            None => {
                self.tasks.push(None);
                self.tasks.len() - 1
            }
        };
        self.tasks[slot] = Some(Live {
            item,
            task,
            asked: 0,
            open: 0,
            failed: None,
        });
        self.ask(slot, runs, send)
    }

    /// Queues `runs` for the task in `slot` (finishing it if it has nothing left to do).
    fn ask(&mut self, slot: usize, runs: Vec<T::Run>, send: &mut Sink<'_, T::Output>) -> bool {
        let live = self.tasks[slot].as_mut().expect("live task");
        for run in runs {
            let index = live.asked;
            live.asked += 1;
            live.open += 1;
            let g = group_of(&mut self.groups, self.width, &run);
            self.groups[g].queue.push_back(Job {
                task: slot,
                index,
                run,
            });
        }
        if live.open == 0 {
            return self.finish(slot, send);
        }
        true
    }

    /// Puts waiting runs in free lanes.
    fn fill(&mut self, send: &mut Sink<'_, T::Output>) -> bool {
        for g in 0..self.groups.len() {
            while let Some(lane) = self.groups[g].batch.free_lane() {
                let Some(job) = self.groups[g].queue.pop_front() else {
                    break;
                };
                let started = job.run.begin().and_then(|(run, sim)| {
                    let target = run.target();
                    self.groups[g]
                        .batch
                        .put(lane, sim, target)
                        .map_err(|(e, _)| match e {
                            bistable_core::JoinError::Sim(e) => e,
                            other => unreachable!("runs are grouped by setting: {other:?}"),
                        })
                        .map(|()| run)
                });
                match started {
                    Ok(run) => self.groups[g].lanes[lane] = Some((job.task, job.index, run)),
                    Err(e) => {
                        if !self.run_over(job.task, job.index, Err(e), send) {
                            return false;
                        }
                    }
                }
            }
        }
        true
    }

    /// Handles a lane of group `g` that stopped at its target (or failed).
    fn lane_stopped(
        &mut self,
        g: usize,
        lane: usize,
        r: Result<bool, SimError>,
        send: &mut Sink<'_, T::Output>,
    ) -> bool {
        let group = &mut self.groups[g];
        let (task, index, run) = group.lanes[lane].as_mut().expect("a run in the lane");
        let (task, index) = (*task, *index);
        let outcome = r.and_then(|_| {
            let sim = group.batch.sim_mut(lane).expect("a simulator in the lane");
            run.reached(sim)
        });
        let over = match outcome {
            Ok(None) => match group.batch.retarget(lane, run.target()) {
                Ok(()) => return true,
                Err(e) => Err(e),
            },
            Ok(Some(c)) => Ok(c),
            Err(e) => Err(e),
        };
        group.lanes[lane] = None;
        group.batch.take(lane);
        self.run_over(task, index, over, send)
    }

    /// Takes the result of run `index` of the task in `slot`.
    fn run_over(
        &mut self,
        slot: usize,
        index: usize,
        result: Result<RunResult<T::Run>, SimError>,
        send: &mut Sink<'_, T::Output>,
    ) -> bool {
        let live = self.tasks[slot].as_mut().expect("live task");
        live.open -= 1;
        let more = match result {
            Ok(c) if live.failed.is_none() => live.task.run_done(index, c),
            Ok(_) => Ok(Vec::new()),
            Err(e) => Err(e),
        };
        match more {
            Ok(runs) => self.ask(slot, runs, send),
            Err(e) => {
                if live.failed.as_ref().is_none_or(|(i, _)| index < *i) {
                    live.failed = Some((index, e));
                }
                if live.open == 0 {
                    return self.finish(slot, send);
                }
                true
            }
        }
    }

    /// Sends the output of the task in `slot`, whose runs are all done.
    fn finish(&mut self, slot: usize, send: &mut Sink<'_, T::Output>) -> bool {
        let live = self.tasks[slot].take().expect("live task");
        let out = match live.failed {
            Some((_, e)) => Err(e),
            None => Ok(live.task.finish()),
        };
        send(live.item, out)
    }
}

/// The group for `run`'s setting, made if new.
fn group_of<S: RunSpec>(groups: &mut Vec<Group<S>>, width: Width, run: &S) -> usize {
    let (params, opts) = run.setting();
    let zeta = params.zeta().to_bits();
    if let Some(g) = groups.iter().position(|g| g.zeta == zeta && g.opts == opts) {
        return g;
    }
    // Runs of other settings than the first (the tolerance repeats of a suspect point) come a
    // few at a time: narrower lanes leave fewer of them idle.
    let width = if groups.is_empty() {
        width
    } else {
        Width::Four.min_with(width)
    };
    let batch = Batch::new(width, &params, opts);
    groups.push(Group {
        zeta,
        opts,
        lanes: (0..batch.lanes()).map(|_| None).collect(),
        batch,
        queue: VecDeque::new(),
    });
    groups.len() - 1
}
