//! Reading ahead: the mass at the host's next communication points, evaluated together.
//!
//! A co-simulation host that reads `x` or `v` after every step asks for the core's Taylor
//! series at one instant per step. Evaluating it is a chain of dependent operations whose
//! latency, not its work, is the cost of the read. When the host's communication points follow
//! a pattern this module reproduces bit for bit, the first read inside a Taylor step evaluates
//! the series at that point and at the host's next fifteen at once, one SIMD lane each
//! ([`Simulator::flights_at`]), for about the latency of one; the reads that follow take their
//! values from there. The patterns are the two ways hosts count time:
//! - *sum*: the next point is the last one plus the same step (`t += h`);
//! - *grid*: the points are `start + n·Δt` (fmpy, the project's C host), each step of size
//!   `next − t`.
//!
//! A value is used only for the exact `τ` and the Taylor step ([`StepKey`]) it was computed for,
//! so a point the pattern does not predict is evaluated as before: every value is the one of
//! [`Simulator::mass_at`], bit for bit, whatever the host does. A host that does not read the
//! mass costs only the recording of its step arguments (the work is done on a read, or by the
//! model's own check of the outputs after a step that ran the core, when the host read after
//! its previous step); one that reads it at points of no pattern costs one check of the step
//! sizes per read.

use std::cmp::Ordering;

use bistable_core::{Flights, Instant, Simulator, StepKey, FLIGHT_LANES as LANES};

use crate::model::si::Scale;

/// The mass read ahead in the current Taylor step (derived data, not part of the model's
/// state: an empty one gives the same values).
#[derive(Clone, Default)]
pub struct Ahead {
    /// The host's last two communication steps `(t, h)` (s), the newest last.
    steps: [(f64, f64); 2],
    /// The start time of the host's run (s).
    start: f64,
    /// The Taylor step the values belong to.
    key: StepKey,
    /// `τ` of each lane.
    tau: [f64; LANES],
    /// The core's current time (its parts' bits) when the values were computed: while it is
    /// the same, each of them is still after it.
    now: (u64, u64),
    /// The mass at each `tau[i]`.
    mass: Flights,
    /// The lane after the last one read (the host's next point if it keeps to its pattern).
    next: usize,
    /// The host read the mass since its last step ([`Ahead::host_reads`]), and did after the
    /// step before.
    reads: (bool, bool),
}

impl Ahead {
    /// Records a communication step `doStep(t, h)` of a run started at `start` (s).
    #[inline]
    pub fn host_step(&mut self, start: f64, t: f64, h: f64) {
        self.start = start;
        self.steps = [self.steps[1], (t, h)];
        self.reads = (false, self.reads.0);
    }

    /// Records that the host read the mass's position or velocity.
    #[inline]
    pub fn host_reads(&mut self) {
        self.reads.0 = true;
    }

    /// Whether the host read the mass after its previous step: it will likely read it after
    /// this one, so the model's own reads may read ahead for it.
    pub fn host_will_read(&self) -> bool {
        self.reads.1
    }

    /// The lane holding the mass at `τ = tau` if it was read ahead ([`Ahead::mass`]).
    #[inline]
    pub fn lookup(&mut self, sim: &Simulator, tau: f64) -> Option<usize> {
        if self.key != sim.step_key() {
            return None;
        }
        let hit = |i: &usize| self.tau[*i].to_bits() == tau.to_bits() && self.mass.flying[*i];
        let lane = Some(self.next)
            .filter(hit)
            .or_else(|| (0..LANES).find(hit))?;
        let now = sim.instant();
        // `mass_at` asks `now <= t`: it held when the lane was computed, and holds while the
        // core's time has not moved.
        let after_now = || {
            matches!(
                now.partial_cmp(&Instant::new(tau)),
                Some(Ordering::Less | Ordering::Equal)
            )
        };
        if bits(now) != self.now && !after_now() {
            return None;
        }
        self.next = (lane + 1) % LANES;
        Some(lane)
    }

    /// Reads the mass at `τ = tau` (the end of the host's last step), with the host's next
    /// points if they follow a pattern; the lane holding it if it is in free flight inside the
    /// core's current step after its start, `None` otherwise (and when there is no pattern:
    /// then ask [`Simulator::mass_at`]).
    pub fn read(&mut self, sim: &Simulator, scale: &Scale, tau: f64) -> Option<usize> {
        if !self.next_points(scale, tau) {
            return None;
        }
        sim.flights_at(&self.tau, &mut self.mass);
        self.key = sim.step_key();
        self.now = bits(sim.instant());
        self.next = 1;
        self.mass.flying[0].then_some(0)
    }

    /// Position and velocity of the mass in `lane` (from [`Ahead::lookup`] or [`Ahead::read`]):
    /// those of [`Simulator::mass_at`] at that lane's `τ`, an instant in free flight inside the
    /// current step.
    #[inline]
    pub fn mass(&self, lane: usize) -> (f64, f64) {
        (self.mass.x[lane], self.mass.v[lane])
    }

    /// Sets `tau` to `τ` now (`now`, the end of the host's last step) and of the host's next
    /// `LANES − 1` communication points, as the FMU will compute them from the host's arguments
    /// (`τ(t + h)`), if the host's steps follow a pattern (see the module documentation);
    /// whether they do. The values read ahead before are dropped either way.
    fn next_points(&mut self, scale: &Scale, now: f64) -> bool {
        let [(t0, h0), (t1, h1)] = self.steps;
        let end = t1 + h1;
        // No values until they are computed for these points.
        self.mass.flying = [false; LANES];
        self.tau[0] = now;
        if h1 == h0 && t1 == t0 + h0 {
            let mut t = end;
            for tau in &mut self.tau[1..] {
                t += h1;
                *tau = scale.tau(t);
            }
            return true;
        }
        let Some((start, dt, n)) = self.grid(t1, end) else {
            return false;
        };
        let mut t = end;
        for (k, tau) in (1..).zip(&mut self.tau[1..]) {
            let next = start + (n + k) as f64 * dt;
            *tau = scale.tau(t + (next - t));
            t = next;
        }
        true
    }

    /// `(start, Δt, n)` with `start + (n − 1)·Δt = t` and `start + n·Δt = end` as doubles, if
    /// the step `[t, end]` is one of a grid from the run's start.
    fn grid(&self, t: f64, end: f64) -> Option<(f64, f64, u64)> {
        let start = self.start;
        let n = ((end - start) / (end - t)).round();
        if !(1.0..=9.0e15).contains(&n) {
            return None;
        }
        let dt = (end - start) / n;
        let on_grid = |dt: f64| start + n * dt == end && start + (n - 1.0) * dt == t;
        [dt, dt.next_up(), dt.next_down()]
            .into_iter()
            .find(|&dt| on_grid(dt))
            .map(|dt| (start, dt, n as u64))
    }
}

/// The bits of an instant's parts.
fn bits(t: Instant) -> (u64, u64) {
    let (hi, lo) = t.parts();
    (hi.to_bits(), lo.to_bits())
}
