//! Many trajectories at once: [`Simulator`]s advanced together, their free-flight steps computed
//! in SIMD lanes.
//!
//! Each lane holds its own simulator (its own shaker `Ω`, `V`, restitution and state) and runs to
//! its own target instant. Whenever lanes need a new step, those in free flight under their
//! sinusoid, away from the plate, get it from one pass of the lane kernel: plate series, flight
//! series (with the variational series when a lane integrates them), step size, the gap's cheap
//! root certificates, the barrier bound and the state at the step's end, for all lanes at once
//! ([`crate::lanes`]: the same operations in the same order as the scalar step, lane by lane),
//! unless too few lanes need one for a pass to pay (one of 4, up to two of 8): those take the
//! lone simulator's step.
//! What the kernel leaves open — a root to isolate, the barrier within reach, a non-finite
//! series — and every other step (riding on the plate, the steps right after an impact or a
//! release) is done by the lane's own simulator exactly as it would alone, as is everything
//! that happens at a step's end (impacts, chatter, sticking, snap-throughs, observers).
//! A lane therefore follows bit for bit the trajectory of the same [`Simulator`] run alone, for
//! any width (`tests/batch.rs` checks it on random trajectories).

use std::ops::ControlFlow;

use crate::events::Event;
use crate::lanes::{F64x4, F64x8, Lane, Width};
use crate::params::{Params, SolverOptions};
use crate::roots::certified_clear;
use crate::shaker::scale_by_phase;
use crate::simd;
use crate::simulator::{barrier_far, LaneEnd, LaneStart, Observer, Progress, SimError, Simulator};
use crate::taylor::{self, eval_d, FlightSeries, VariationSeries, BUF};
use crate::time::Instant;

/// Receives the events of every lane of a [`Batch`], tagged with the lane.
pub trait LaneObserver {
    /// Called for each event of `lane` in time order; `Break` stops that lane's advance.
    fn event(&mut self, lane: usize, event: &Event) -> ControlFlow<()>;
}

impl<F: FnMut(usize, &Event) -> ControlFlow<()>> LaneObserver for F {
    fn event(&mut self, lane: usize, event: &Event) -> ControlFlow<()> {
        self(lane, event)
    }
}

/// One lane's events, passed on to the batch's observer.
struct Tagged<'a, O> {
    lane: usize,
    inner: &'a mut O,
}

impl<O: LaneObserver> Observer for Tagged<'_, O> {
    fn event(&mut self, event: &Event) -> ControlFlow<()> {
        self.inner.event(self.lane, event)
    }
}

/// A lane's simulator and where it is going.
struct Slot {
    sim: Simulator,
    target: Instant,
    /// Advancing to `target` (not yet stopped there, nor failed).
    running: bool,
}

/// Simulators advanced together, one per lane (see the module documentation). All lanes share
/// the damping and the solver options given to [`Batch::new`]; each has its own shaker,
/// restitution, state and target.
pub struct Batch {
    width: Width,
    opts: SolverOptions,
    /// What every kernel pass shares: the damping and what follows from `opts`.
    consts: Consts,
    slots: Vec<Option<Slot>>,
    kernel: Kernel,
    /// Scratch of [`Batch::advance`]: the lanes that need a step, and those of them the kernel
    /// computes, with their starts.
    ready: Vec<usize>,
    starts: Vec<(usize, LaneStart)>,
}

/// Why a simulator cannot join a batch.
#[derive(Debug, Clone, PartialEq)]
pub enum JoinError {
    /// Its damping or solver options differ from the batch's.
    Mismatch,
    /// The lane is taken, or there is no such lane.
    Lane(usize),
    /// It cannot advance to the target ([`Simulator::advance_instant`]'s checks).
    Sim(SimError),
}

impl Batch {
    /// An empty batch of `width` lanes for simulators with `params`' damping and `opts`.
    /// [`Width::One`] gives one lane that steps like a lone simulator.
    pub fn new(width: Width, params: &Params, opts: SolverOptions) -> Self {
        Self {
            width,
            opts,
            consts: Consts {
                zeta: params.zeta(),
                order: opts.order(),
                tol: opts.tol(),
                ln_tol: opts.tol().ln(),
            },
            slots: (0..width.lanes()).map(|_| None).collect(),
            kernel: Kernel::new(width),
            ready: Vec::with_capacity(width.lanes()),
            starts: Vec::with_capacity(width.lanes()),
        }
    }

    /// Number of lanes.
    pub fn lanes(&self) -> usize {
        self.slots.len()
    }

    /// Lane width.
    pub fn width(&self) -> Width {
        self.width
    }

    /// A lane without a simulator, if any.
    pub fn free_lane(&self) -> Option<usize> {
        self.slots.iter().position(Option::is_none)
    }

    /// Whether any lane holds a simulator.
    pub fn is_empty(&self) -> bool {
        self.slots.iter().all(Option::is_none)
    }

    /// Puts `sim` in the free `lane`, to run to `target`.
    pub fn put(
        &mut self,
        lane: usize,
        mut sim: Simulator,
        target: Instant,
    ) -> Result<(), (JoinError, Box<Simulator>)> {
        if sim.params().zeta().to_bits() != self.consts.zeta.to_bits()
            || *sim.options() != self.opts
        {
            return Err((JoinError::Mismatch, Box::new(sim)));
        }
        if !matches!(self.slots.get(lane), Some(None)) {
            return Err((JoinError::Lane(lane), Box::new(sim)));
        }
        if let Err(e) = sim.begin_advance(target) {
            return Err((JoinError::Sim(e), Box::new(sim)));
        }
        self.slots[lane] = Some(Slot {
            sim,
            target,
            running: true,
        });
        Ok(())
    }

    /// Sends the simulator in `lane` on to `target` (after it stopped).
    pub fn retarget(&mut self, lane: usize, target: Instant) -> Result<(), SimError> {
        let Some(slot) = self.slots.get_mut(lane).and_then(Option::as_mut) else {
            return Ok(());
        };
        slot.running = false;
        slot.sim.begin_advance(target)?;
        slot.target = target;
        slot.running = true;
        Ok(())
    }

    /// The simulator in `lane`.
    pub fn sim(&self, lane: usize) -> Option<&Simulator> {
        self.slots.get(lane)?.as_ref().map(|s| &s.sim)
    }

    /// The simulator in `lane`, to read or change between advances (changing its plate, its
    /// variational equations or its state is allowed; the batch reads everything afresh).
    pub fn sim_mut(&mut self, lane: usize) -> Option<&mut Simulator> {
        self.slots.get_mut(lane)?.as_mut().map(|s| &mut s.sim)
    }

    /// Takes the simulator out of `lane`, freeing it.
    pub fn take(&mut self, lane: usize) -> Option<Simulator> {
        self.slots.get_mut(lane)?.take().map(|s| s.sim)
    }

    /// Advances every running lane until at least one stops: it reached its target (`Ok(true)`),
    /// its observer stopped it (`Ok(false)`) or it failed (`Err`, the simulator stays usable at
    /// its last consistent state, as alone). The lanes that stopped are appended to `stopped`
    /// with their result; they wait for [`Batch::retarget`] or [`Batch::take`]. Returns at
    /// once when no lane is running.
    pub fn advance(
        &mut self,
        obs: &mut impl LaneObserver,
        stopped: &mut Vec<(usize, Result<bool, SimError>)>,
    ) {
        let first = stopped.len();
        let Batch {
            width,
            consts,
            slots,
            kernel,
            ready,
            starts,
            ..
        } = self;
        loop {
            ready.clear();
            let mut any = false;
            for (lane, slot) in slots.iter_mut().enumerate() {
                let Some(slot) = slot.as_mut().filter(|s| s.running) else {
                    continue;
                };
                any = true;
                let mut tag = Tagged { lane, inner: obs };
                match slot.sim.resume(slot.target, &mut tag) {
                    Ok(Progress::NeedStep) => ready.push(lane),
                    Ok(Progress::Stopped(reached)) => {
                        slot.running = false;
                        stopped.push((lane, Ok(reached)));
                    }
                    Err(e) => {
                        slot.running = false;
                        stopped.push((lane, Err(e)));
                    }
                }
            }
            if !any || stopped.len() > first {
                return;
            }
            starts.clear();
            for &lane in ready.iter() {
                let slot = slots[lane].as_mut().expect("ready lanes are occupied");
                if let Err(e) = slot.sim.interruption() {
                    slot.running = false;
                    stopped.push((lane, Err(e)));
                    continue;
                }
                let start = match width {
                    Width::One => None,
                    _ => slot.sim.lane_start(),
                };
                match start {
                    Some(st) => starts.push((lane, st)),
                    None => lone_step(lane, slot, obs, stopped),
                }
            }
            // Too few lanes for a pass of the kernel, which costs more for one lane than the
            // lone simulator's step: each takes that step instead (the same step, bit for bit).
            if starts.len() < width.min_kernel_lanes() {
                for &(lane, _) in starts.iter() {
                    lone_step(lane, slots[lane].as_mut().expect("occupied"), obs, stopped);
                }
                continue;
            }
            for &(lane, _) in starts.iter() {
                let sim = &slots[lane].as_ref().expect("occupied").sim;
                kernel.load_magnitudes(lane, sim.plate_magnitudes());
            }
            kernel.run(consts, starts);
            for &(lane, st) in starts.iter() {
                let slot = slots[lane].as_mut().expect("occupied");
                let out = kernel.verdict(lane);
                let kernel = &*kernel;
                let taken = slot.sim.take_lane_step(st.leaving, out, |series, var, b| {
                    kernel.copy_lane(lane, consts.order, series, var, b)
                });
                match taken {
                    Ok(()) => {
                        let mut tag = Tagged { lane, inner: obs };
                        slot.sim.step_ready(&mut tag);
                    }
                    Err(e) => {
                        slot.running = false;
                        stopped.push((lane, Err(e)));
                    }
                }
            }
        }
    }
}

/// The lone simulator's step for `lane` (computed and taken); a failure stops the lane.
fn lone_step(
    lane: usize,
    slot: &mut Slot,
    obs: &mut impl LaneObserver,
    stopped: &mut Vec<(usize, Result<bool, SimError>)>,
) {
    let mut tag = Tagged { lane, inner: obs };
    match slot.sim.compute_step() {
        Ok(()) => slot.sim.step_ready(&mut tag),
        Err(e) => {
            slot.running = false;
            stopped.push((lane, Err(e)));
        }
    }
}

/// What every lane of a kernel pass shares.
struct Consts {
    zeta: f64,
    order: usize,
    tol: f64,
    ln_tol: f64,
}

/// The kernel's working storage for one width, lanes side by side.
struct Soa<T: Lane> {
    mags: [T; BUF],
    /// `(Ω, V)` whose magnitudes each lane of `mags` holds.
    mag_keys: Vec<[u64; 2]>,
    z: [T; BUF],
    series: FlightSeries<T>,
    var: VariationSeries<T>,
    /// Bernstein coefficients of each lane's gap over its step.
    bern: [T; BUF],
    out: Verdicts<T>,
}

/// Per-lane results of a kernel pass.
#[derive(Clone, Copy)]
struct Verdicts<T: Lane> {
    finite: T::Mask,
    h: T,
    clear: T::Mask,
    far: T::Mask,
    u1: T,
    w1: T,
}

enum Kernel {
    Scalar,
    X4(Box<Soa<F64x4>>),
    X8(Box<Soa<F64x8>>),
}

impl<T: Lane> Soa<T> {
    fn new() -> Box<Self>
    where
        T::Mask: Default,
    {
        let zero = T::splat(0.0);
        Box::new(Self {
            mags: [zero; BUF],
            mag_keys: vec![[u64::MAX; 2]; T::LANES],
            z: [zero; BUF],
            series: FlightSeries::default(),
            var: VariationSeries::default(),
            bern: [zero; BUF],
            out: Verdicts {
                finite: T::Mask::default(),
                h: zero,
                clear: T::Mask::default(),
                far: T::Mask::default(),
                u1: zero,
                w1: zero,
            },
        })
    }

    fn load_magnitudes(&mut self, i: usize, (key, mags): ([u64; 2], &[f64; BUF])) {
        if self.mag_keys[i] != key {
            self.mag_keys[i] = key;
            for (m, &v) in self.mags.iter_mut().zip(mags) {
                m.set_lane(i, v);
            }
        }
    }

    /// One pass of the kernel over the lanes of `starts` (each with its batch lane, which is
    /// its lane here); the other lanes repeat the first start, and their results are ignored.
    /// Inlined into each caller, so that it is compiled for the caller's target features.
    #[inline(always)]
    fn run(&mut self, c: &Consts, starts: &[(usize, LaneStart)]) {
        let mut inp = Inputs::<T>::default();
        let mut var = false;
        let mut by_lane = [None; 8];
        for (lane, st) in starts {
            by_lane[*lane] = Some(st);
        }
        for (i, st) in by_lane.iter().enumerate().take(T::LANES) {
            let s = st.unwrap_or(&starts[0].1);
            inp.u0.set_lane(i, s.u0);
            inp.w0.set_lane(i, s.w0);
            inp.sin.set_lane(i, s.sin);
            inp.cos.set_lane(i, s.cos);
            inp.offset.set_lane(i, s.offset);
            inp.sign.set_lane(i, if s.above { 1.0 } else { -1.0 });
            inp.leaving.set_lane(i, if s.leaving { 1.0 } else { 0.0 });
            inp.free_of_barrier
                .set_lane(i, if s.on_barrier { 0.0 } else { 1.0 });
            if let Some(phi) = s.phi {
                var = true;
                for (r, row) in phi.iter().enumerate() {
                    for (col, &v) in row.iter().enumerate() {
                        inp.phi[r][col].set_lane(i, v);
                    }
                }
            }
        }
        let (z, series, v, b) = (&mut self.z, &mut self.series, &mut self.var, &mut self.bern);
        self.out = if var {
            kernel::<T, true>(c, &self.mags, &inp, z, series, v, b)
        } else {
            kernel::<T, false>(c, &self.mags, &inp, z, series, v, b)
        };
    }

    fn verdict(&self, i: usize) -> LaneEnd {
        let o = &self.out;
        LaneEnd {
            finite: T::test_lane(o.finite, i),
            h: o.h.lane(i),
            clear: T::test_lane(o.clear, i),
            far: T::test_lane(o.far, i),
            end_gap: (o.u1.lane(i), o.w1.lane(i)),
        }
    }

    /// Copies lane `i`'s series (coefficients `0..=order + 1`) into a lone simulator's, and
    /// its gap's Bernstein coefficients into `bernstein` when given.
    fn copy_lane(
        &self,
        i: usize,
        order: usize,
        series: &mut FlightSeries,
        var: Option<&mut VariationSeries>,
        bernstein: Option<&mut [f64; BUF]>,
    ) {
        if let Some(b) = bernstein {
            for (b, v) in b.iter_mut().zip(&self.bern).take(order + 2) {
                *b = v.lane(i);
            }
        }
        for k in 0..=order + 1 {
            series.x[k] = self.series.x[k].lane(i);
            series.u[k] = self.series.u[k].lane(i);
        }
        if let Some(v) = var {
            for k in 0..=order + 1 {
                v.d[k] = [self.var.d[k][0].lane(i), self.var.d[k][1].lane(i)];
            }
        }
    }
}

impl Kernel {
    fn new(width: Width) -> Self {
        match width {
            Width::One => Kernel::Scalar,
            Width::Four => Kernel::X4(Soa::new()),
            Width::Eight => Kernel::X8(Soa::new()),
        }
    }

    fn load_magnitudes(&mut self, i: usize, m: ([u64; 2], &[f64; BUF])) {
        match self {
            Kernel::Scalar => {}
            Kernel::X4(s) => s.load_magnitudes(i, m),
            Kernel::X8(s) => s.load_magnitudes(i, m),
        }
    }

    fn run(&mut self, c: &Consts, starts: &[(usize, LaneStart)]) {
        match self {
            Kernel::Scalar => unreachable!("a batch of width 1 computes no lane steps"),
            Kernel::X4(s) => run4(s, c, starts),
            Kernel::X8(s) => run8(s, c, starts),
        }
    }

    fn verdict(&self, i: usize) -> LaneEnd {
        match self {
            Kernel::Scalar => unreachable!("a batch of width 1 computes no lane steps"),
            Kernel::X4(s) => s.verdict(i),
            Kernel::X8(s) => s.verdict(i),
        }
    }

    fn copy_lane(
        &self,
        i: usize,
        order: usize,
        series: &mut FlightSeries,
        var: Option<&mut VariationSeries>,
        bernstein: Option<&mut [f64; BUF]>,
    ) {
        match self {
            Kernel::Scalar => {}
            Kernel::X4(s) => s.copy_lane(i, order, series, var, bernstein),
            Kernel::X8(s) => s.copy_lane(i, order, series, var, bernstein),
        }
    }
}

/// `$name` runs the kernel over `$lanes` in registers of `$feature` where the SIMD path in use
/// allows it (`$allowed`: the CPU has it and `BISTABLE_SIMD` does not rule it out, see
/// [`crate::simd`]; the kernel is compiled a second time, in `$fast`, for that feature),
/// portably otherwise; the results are the same.
macro_rules! dispatch {
    ($name:ident, $fast:ident, $lanes:ty, $feature:tt, $allowed:path) => {
        fn $name(s: &mut Soa<$lanes>, c: &Consts, starts: &[(usize, LaneStart)]) {
            #[cfg(target_arch = "x86_64")]
            if $allowed() {
                // SAFETY: the CPU has the feature (the path allows only features it has).
                return unsafe { $fast(s, c, starts) };
            }
            s.run(c, starts)
        }

        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = $feature)]
        fn $fast(s: &mut Soa<$lanes>, c: &Consts, starts: &[(usize, LaneStart)]) {
            s.run(c, starts)
        }
    };
}

dispatch!(run8, run8_avx512, F64x8, "avx512f", simd::avx512f);
dispatch!(run4, run4_avx2, F64x4, "avx2", simd::avx2);

/// The lanes' starts, side by side ([`LaneStart`]).
struct Inputs<T> {
    u0: T,
    w0: T,
    sin: T,
    cos: T,
    offset: T,
    /// `+1` in well 2, `−1` in well 1.
    sign: T,
    /// `1` where the step starts on the plate, leaving it (the gap's root at 0 divided out).
    leaving: T,
    /// `1` where the step does not start on the barrier.
    free_of_barrier: T,
    phi: [[T; 2]; 2],
}

impl<T: Lane> Default for Inputs<T> {
    fn default() -> Self {
        let z = T::splat(0.0);
        Self {
            u0: z,
            w0: z,
            sin: z,
            cos: z,
            offset: z,
            sign: z,
            leaving: z,
            free_of_barrier: z,
            phi: [[z; 2]; 2],
        }
    }
}

/// The free step of every lane: what `Simulator::compute_step` computes for a free flight
/// away from the plate up to the root search, and the state at the step's end, with the same
/// operations in the same order in each lane (`ln` and `exp` lane by lane, by the scalar
/// functions).
#[inline(always)]
fn kernel<T: Lane, const VAR: bool>(
    c: &Consts,
    mags: &[T; BUF],
    inp: &Inputs<T>,
    z: &mut [T; BUF],
    s: &mut FlightSeries<T>,
    var: &mut VariationSeries<T>,
    bern: &mut [T; BUF],
) -> Verdicts<T> {
    let p = c.order;
    let zero = T::splat(0.0);
    // Plate series: the magnitudes scaled by the phase, as `PlateEval::series` computes them.
    z[..p + 3].copy_from_slice(&mags[..p + 3]);
    z[p + 3..].fill(zero);
    scale_by_phase(inp.sin, inp.cos, inp.offset, &mut z[..p + 3]);
    if VAR {
        var.d[0] = inp.phi[0];
        var.d[1] = inp.phi[1];
    }
    taylor::flight_pass::<T, VAR>(c.zeta, inp.u0, inp.w0, z, p, s, VAR.then_some(var));
    // Every coefficient finite: `0·x` is ±0 for a finite `x`, NaN otherwise, and NaN stays.
    let mut spread = zero;
    for &xk in &s.x[..=p + 1] {
        spread += zero * xk;
    }
    let finite = spread.equal(zero);
    // Step size over the series of x and of the gap (a sinusoid has no horizon to cut it).
    let (x, u) = (&s.x, &s.u);
    let h = taylor::step_size(&[&x[..=p], &u[..=p]], p, c.tol, c.ln_tol);
    let free = inp.free_of_barrier.equal(T::splat(1.0));
    let far = barrier_far(free, inp.sign, &x[..=p + 1], h);
    // The gap from its first coefficient that does not vanish: from `u_1` where the step
    // leaves the plate (`u_0 = 0` divided out; the top coefficient padded with zero, which
    // changes no comparison of the certificates).
    let leaving = inp.leaving.equal(T::splat(1.0));
    let mut gap = [zero; BUF];
    for k in 0..=p + 1 {
        let next = if k < p + 1 { u[k + 1] } else { zero };
        gap[k] = T::select(leaving, next, u[k]);
    }
    let clear = certified_clear(&gap[..=p + 1], h, bern);
    // Gap and gap rate at h.
    let (u1, w1) = eval_d(&u[..=p + 1], h);
    Verdicts {
        finite,
        h,
        clear,
        far,
        u1,
        w1,
    }
}
