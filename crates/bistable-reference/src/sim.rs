//! The event-driven simulation loop.
//!
//! Two modes: free flight (state: gap `u = x - z` and its rate `w = u' = x' - ż`) and sticking
//! (`x = z`, `x' = ż`). Each step starts from the current time `τ0`, builds the Taylor series,
//! picks a step size from the series, and then looks for events inside `(0, h]`:
//! - free flight: the first sign change of the gap (impact) and every sign change of `x - 1/2`
//!   before it (snap-through);
//! - sticking: the first sign change of the contact force `N` (release) and every sign change of
//!   `z - 1/2` before it.
//!
//! New time values are formed as `τ1 = round(τ0 + s)` and the step actually taken is the exactly
//! representable `τ1 - τ0`, so positions and times stay consistent.

use crate::poly::{eval_with_derivative, strip_zero_root, RootFinder};
use crate::real::{sgn, to_decimal_string, to_f64, Prec, Real};
use crate::taylor::Model;
use crate::{
    RefChatter, RefError, RefEvent, RefEventKind, RefOptions, RefParams, RefSample, RefStart,
};

enum Mode {
    /// Free flight with gap `u` and gap rate `w`.
    Free { u: Real, w: Real },
    /// Mass glued to the plate.
    Stuck,
}

/// One simulation run (events and, optionally, samples).
pub(crate) struct Run {
    m: Model,
    rf: RootFinder,
    chatter: RefChatter,
    max_events: usize,
    /// Events so far.
    pub events: Vec<RefEvent>,
    tau: Real,
    mode: Mode,
    well: u8,
    impacts: usize,
    stick_starts: usize,
    stick_ends: usize,
    snaps: usize,
    last_impact: Option<Real>,
    /// The next free-flight step starts exactly at a release, where `N(τ0) = 0` by definition.
    release_pending: bool,
    done: bool,
    /// Sample times, their order (ascending), next one due, results.
    sample_times: Vec<f64>,
    sample_order: Vec<usize>,
    next_sample: usize,
    samples: Vec<Option<RefSample>>,
}

impl Run {
    /// A run from `start`, taken exactly (validated by the caller, see [`crate::simulate_from`]);
    /// refused if it is below the plate in working precision.
    pub fn new(
        p: &RefParams,
        o: &RefOptions,
        start: &RefStart,
        times: &[f64],
        max_events: usize,
    ) -> Result<Run, RefError> {
        let prec = Prec { bits: o.bits };
        let m = Model::new(prec, p.zeta, p.restitution, p.omega, p.velocity);
        // In flight with gap u = x − z ≥ 0 and rate w = x' − ż (from the paper's start, u = 0
        // and w = −V: impact 0 happens at once).
        let tau = prec.exact(start.t0);
        let (z, zd) = m.plate(&tau);
        let u = prec.exact(start.x0) - z;
        if sgn(&u) < 0 {
            return Err(RefError::InvalidInput(format!(
                "start x0 = {} is below the plate at t0 = {}",
                start.x0, start.t0
            )));
        }
        let w = prec.exact(start.v0) - zd;
        let (mode, well) = (Mode::Free { u, w }, if start.x0 > 0.5 { 2 } else { 1 });
        let mut sample_order: Vec<usize> = (0..times.len()).collect();
        sample_order.sort_by(|&a, &b| times[a].total_cmp(&times[b]));
        Ok(Run {
            rf: RootFinder::new(prec),
            m,
            chatter: o.chatter,
            max_events,
            events: Vec::new(),
            tau,
            mode,
            well,
            impacts: 0,
            stick_starts: 0,
            stick_ends: 0,
            snaps: 0,
            last_impact: None,
            release_pending: false,
            done: false,
            sample_times: times.to_vec(),
            sample_order,
            next_sample: 0,
            samples: vec![None; times.len()],
        })
    }

    fn prec(&self) -> Prec {
        self.m.prec
    }

    /// Integrate until `τ = t_end` (or until `max_events` events were recorded).
    pub fn run(&mut self, t_end: f64) -> Result<(), RefError> {
        let t_end = self.prec().exact(t_end);
        while !self.done {
            // An impact due right now (gap closed, approaching): handle it before anything else.
            if let Mode::Free { u, w } = &self.mode {
                if sgn(u) == 0 && sgn(w) < 0 {
                    let w_minus = w.clone();
                    self.impact(w_minus)?;
                    continue;
                }
            }
            if self.tau >= t_end {
                break;
            }
            match self.mode {
                Mode::Free { .. } => self.free_step(&t_end)?,
                Mode::Stuck => self.stuck_step(&t_end)?,
            }
        }
        // Samples due exactly at the final time.
        if !self.done {
            let (z, zd) = self.m.plate(&self.tau);
            let (x, v, stuck) = match &self.mode {
                Mode::Free { u, w } => (&z + u, &zd + w, false),
                Mode::Stuck => (z, zd, true),
            };
            while self.next_sample < self.sample_order.len() {
                let i = self.sample_order[self.next_sample];
                if self.prec().exact(self.sample_times[i]) > self.tau {
                    break;
                }
                self.store_sample(i, x.clone(), v.clone(), stuck);
            }
        }
        Ok(())
    }

    /// All samples, in the order requested.
    pub fn finish_samples(self) -> Result<Vec<RefSample>, RefError> {
        self.samples
            .into_iter()
            .map(|s| s.ok_or_else(|| RefError::Numerical("a sample time was not reached".into())))
            .collect()
    }

    fn store_sample(&mut self, i: usize, x: Real, v: Real, stuck: bool) {
        self.samples[i] = Some(RefSample {
            t: self.sample_times[i],
            x,
            v,
            stuck,
        });
        self.next_sample += 1;
    }

    /// Samples with `τ0 <= t < τ0 + s_end`, from position/velocity series `xs`, `vs` (in `s`).
    fn samples_in_step(&mut self, xs: &[Real], s_end: &Real, stuck: bool) {
        while self.next_sample < self.sample_order.len() {
            let i = self.sample_order[self.next_sample];
            let s = self.prec().exact(self.sample_times[i]) - &self.tau;
            if s >= *s_end {
                break;
            }
            let (x, v) = eval_with_derivative(xs, &s);
            self.store_sample(i, x, v, stuck);
        }
    }

    fn emit(&mut self, ev: RefEvent) {
        self.events.push(ev);
        if self.events.len() >= self.max_events {
            self.done = true;
        }
    }

    fn event(
        &self,
        kind: RefEventKind,
        index: usize,
        tau: &Real,
        x: &Real,
        (v_before, v_after): (&Real, &Real),
        to_well: u8,
    ) -> RefEvent {
        let mut phase = to_f64(&self.m.phase(tau));
        if phase >= 1.0 {
            phase = 0.0;
        }
        RefEvent {
            kind,
            index,
            t: to_f64(tau),
            t_str: to_decimal_string(tau, self.prec().digits()),
            phase,
            x: to_f64(x),
            v_before: to_f64(v_before),
            v_after: to_f64(v_after),
            to_well,
        }
    }

    /// Snap-through events: sign changes of the series `xh` (= `x - 1/2`) in `(0, s_end]`;
    /// `xs` is the position series (for the velocity at the crossing).
    fn snap_throughs(&mut self, xh: &[Real], xs: &[Real], s_end: &Real) {
        let (q, _) = strip_zero_root(xh);
        if sgn(&q[0]) == 0 {
            return;
        }
        for s in self.rf.roots(q, s_end, usize::MAX) {
            let (_, v) = eval_with_derivative(xs, &s);
            let tau = &self.tau + &s;
            let to_well = if sgn(&v) > 0 { 2 } else { 1 };
            self.well = to_well;
            let ev = self.event(
                RefEventKind::SnapThrough,
                self.snaps,
                &tau,
                &self.m.half,
                (&v, &v),
                to_well,
            );
            self.snaps += 1;
            self.emit(ev);
            if self.done {
                return;
            }
        }
    }

    /// `τ1 = round(τ0 + s)` clipped to `t_end`; returns `(τ1, τ1 - τ0)` (the latter exact).
    fn advance(&self, s: &Real, t_end: &Real) -> (Real, Real) {
        let mut t1 = &self.tau + s;
        if t1 > *t_end {
            t1 = t_end.clone();
        }
        let h = &t1 - &self.tau;
        (t1, h)
    }

    fn free_step(&mut self, t_end: &Real) -> Result<(), RefError> {
        let (u0, w0) = match &self.mode {
            Mode::Free { u, w } => (u.clone(), w.clone()),
            Mode::Stuck => unreachable!("free_step in stuck mode"),
        };
        let n = self.m.order;
        let mut ps = self.m.plate_series(&self.tau);
        if self.release_pending {
            ps.force[0] = self.prec().zero();
            self.release_pending = false;
        }
        let u = self.m.gap_series(&ps, &u0, &w0);
        let (q, _) = strip_zero_root(&u);
        match sgn(&q[0]) {
            0 => {
                return Err(RefError::Numerical(
                    "gap series vanishes identically".into(),
                ))
            }
            s if s < 0 => {
                if sgn(&u0) < 0 {
                    return Err(RefError::Numerical(format!(
                        "mass below the plate at t = {}",
                        to_f64(&self.tau)
                    )));
                }
                // u = u' = 0 and the gap would close (N > 0): the mass rides on the plate.
                let tau = self.tau.clone();
                self.start_stick(tau);
                return Ok(());
            }
            _ => {}
        }
        let z = &ps.z[..=n];
        let h = self.m.step_size(&[&u, z]);
        let (mut t1, mut h) = self.advance(&self.prec().exact(h), t_end);
        if sgn(&h) <= 0 {
            return Err(RefError::Numerical("step size underflow".into()));
        }
        // Impact: first sign change of the gap in (0, h].
        let roots = self.rf.roots(q, &h, 1);
        let impact = !roots.is_empty();
        if let Some(s) = roots.first() {
            (t1, h) = self.advance(s, t_end);
        }
        // Position series x = u + z, and x - 1/2.
        let xs: Vec<Real> = u.iter().zip(z).map(|(a, b)| a + b).collect();
        let mut xh = xs.clone();
        xh[0] -= &self.m.half;
        self.snap_throughs(&xh, &xs, &h);
        if self.done {
            return Ok(());
        }
        self.samples_in_step(&xs, &h, false);
        let (u1, w1) = eval_with_derivative(&u, &h);
        self.tau = t1;
        if impact {
            self.impact(w1)?;
        } else {
            // A gap that is negative at working precision at a step end (no sign change found
            // inside the step) is a contact exactly at the step end: it is treated as gap 0, and
            // the next iteration applies the impact if the mass approaches.
            let u1 = if sgn(&u1) < 0 { self.prec().zero() } else { u1 };
            self.mode = Mode::Free { u: u1, w: w1 };
        }
        Ok(())
    }

    /// Apply an impact at the current time with relative approach velocity `w_minus < 0`, then
    /// decide between free flight and sticking.
    fn impact(&mut self, w_minus: Real) -> Result<(), RefError> {
        let tau = self.tau.clone();
        let (z, zd) = self.m.plate(&tau);
        let w_plus = -(&self.m.e * &w_minus);
        let ev = self.event(
            RefEventKind::Impact,
            self.impacts,
            &tau,
            &z,
            (&(&zd + &w_minus), &(&zd + &w_plus)),
            self.well,
        );
        self.impacts += 1;
        self.emit(ev);
        let force = self.m.contact_force(&z, &zd);
        let previous = self.last_impact.replace(tau.clone());
        let one = self.prec().int(1);

        // e = 0 (zero rebound): stick if the plate pushes, separate otherwise.
        if sgn(&w_plus) == 0 {
            if sgn(&force) >= 0 {
                self.start_stick(tau);
            } else {
                self.mode = Mode::Free {
                    u: self.prec().zero(),
                    w: w_plus,
                };
            }
            return Ok(());
        }
        // Time resolution floor: two impacts at the same representable time. Chatter has reached
        // the working precision; stick if the plate pushes.
        if previous.as_ref() == Some(&tau) {
            if sgn(&force) >= 0 {
                self.start_stick(tau);
                return Ok(());
            }
            return Err(RefError::Numerical(format!(
                "repeated impact at t = {} with negative contact force",
                to_f64(&tau)
            )));
        }
        match self.chatter {
            RefChatter::Accumulation { delta } => {
                if self.m.e < one && sgn(&w_plus) > 0 && sgn(&force) > 0 {
                    let remaining = &w_plus * 2u8 / (&force * (&one - &self.m.e));
                    if remaining <= self.prec().exact(delta) {
                        self.start_stick(&tau + &remaining);
                        return Ok(());
                    }
                }
            }
            RefChatter::FixedGap { gap } => {
                if let Some(prev) = previous {
                    if &tau - &prev < self.prec().exact(gap) && sgn(&force) >= 0 {
                        self.start_stick(tau);
                        return Ok(());
                    }
                }
            }
        }
        self.mode = Mode::Free {
            u: self.prec().zero(),
            w: w_plus,
        };
        Ok(())
    }

    fn start_stick(&mut self, tau: Real) {
        self.tau = tau;
        let (z, zd) = self.m.plate(&self.tau);
        let ev = self.event(
            RefEventKind::StickStart,
            self.stick_starts,
            &self.tau,
            &z,
            (&zd, &zd),
            self.well,
        );
        self.stick_starts += 1;
        self.mode = Mode::Stuck;
        self.emit(ev);
    }

    fn release(&mut self, exact_root: bool) {
        let (z, zd) = self.m.plate(&self.tau);
        let ev = self.event(
            RefEventKind::StickEnd,
            self.stick_ends,
            &self.tau,
            &z,
            (&zd, &zd),
            self.well,
        );
        self.stick_ends += 1;
        self.mode = Mode::Free {
            u: self.prec().zero(),
            w: self.prec().zero(),
        };
        self.release_pending = exact_root;
        self.emit(ev);
    }

    fn stuck_step(&mut self, t_end: &Real) -> Result<(), RefError> {
        let n = self.m.order;
        let ps = self.m.plate_series(&self.tau);
        let (fq, _) = strip_zero_root(&ps.force);
        if sgn(&fq[0]) < 0 {
            // The plate pulls already: separate now.
            self.release(false);
            return Ok(());
        }
        let z = &ps.z[..=n];
        let h = self.m.step_size(&[z, &ps.force]);
        let (mut t1, mut h) = self.advance(&self.prec().exact(h), t_end);
        if sgn(&h) <= 0 {
            return Err(RefError::Numerical("step size underflow".into()));
        }
        let roots = if sgn(&fq[0]) == 0 {
            Vec::new()
        } else {
            self.rf.roots(fq, &h, 1)
        };
        let released = !roots.is_empty();
        if let Some(s) = roots.first() {
            (t1, h) = self.advance(s, t_end);
        }
        let mut zh = z.to_vec();
        zh[0] -= &self.m.half;
        self.snap_throughs(&zh, z, &h);
        if self.done {
            return Ok(());
        }
        self.samples_in_step(z, &h, true);
        self.tau = t1;
        if released {
            self.release(true);
        }
        Ok(())
    }
}
