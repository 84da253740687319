//! The co-simulation model: a running simulation in SI units ([`Model`]) that steps, reads its
//! outputs and saves and restores itself; and, in its submodules, what Model Exchange
//! (`me.rs`) shares with it.
//!
//! - [`si`]: the SI units and the FMU's words for core errors and events;
//! - [`setup`]: the parameters checked and converted for a start ([`setup::Setup`]);
//! - [`plate`]: what moves the plate, and its pieces from the inputs in external mode;
//! - [`outputs`]: the output variables, state derivatives and event indicators
//!   ([`outputs::Observed`]);
//! - [`checkpoint`]: the parts of an FMU state and the checks of a restored one.

pub mod checkpoint;
pub mod outputs;
pub mod plate;
pub mod setup;
pub mod si;

use std::cell::RefCell;
use std::ops::ControlFlow;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

use bistable_core::interrupt::{with_check, Check, CHECK_EVERY};
use bistable_core::{
    potential, Checkpoint, ContactMode, Event, Instant, Observer, PieceMemo, PlateMotion,
    PlateRecord, PolyPiece, Sample, SampleHistory, SimError, Simulator, Sinusoid, SolverOptions,
    StepView, Well,
};

use crate::ahead::Ahead;
use crate::md::var;
use checkpoint::{
    check_checkpoint, check_inside_step, restore_phase_ref, save_phase_ref, sinusoid_record,
    SavedModel,
};
use outputs::{bit, fly_limit, mass_acceleration, Observed, VarSet, ALL, XV};
use plate::{is_hermite, moderate, plate_inputs, plate_piece, PlateInputs, ShakerMode};
use setup::{below_plate, chatter_rule, Setup};
use si::{describe, describe_event, describe_param, scale_of, Scale};

/// Largest span `Ω·(τ_end − τ)` (time units when `Ω < 1`) of one `fmi2DoStep`: the work of a
/// step grows with it (about 0.5 µs per shaker radian at the paper's baseline), so a longer step
/// is refused rather than left to run for seconds; split it into several. Runs in the model's
/// scope need at most about 4 core steps per radian, so a step of this span stays within half
/// of [`MAX_STEP_BUDGET`].
pub(crate) const MAX_STEP_SPAN: f64 = 3e4;

/// Most core steps one `fmi2DoStep` may compute (see [`step_budget`]): at about 1 µs per core
/// step on the slowest states measured (chatter with `e = 1`), a step stops with a Discard
/// within about 0.3 s of wall time.
pub(crate) const MAX_STEP_BUDGET: u64 = 250_000;

/// A running simulation in SI units.
#[derive(Clone)]
pub struct Model {
    /// The core simulator (nondimensional).
    pub sim: Simulator,
    /// Unit conversions.
    pub scale: Scale,
    /// Plate source.
    pub mode: ShakerMode,
    /// Reference sinusoid of the impact phase (the plate itself in internal mode).
    pub phase_ref: Sinusoid,
    /// `(Ω, V)` in force (a tunable change is applied at the next step).
    pub applied: (f64, f64),
    /// Communication time (s): where the last step ended.
    pub time: f64,
    /// `τ` of the communication time when the core has not been advanced there yet: a step
    /// that ends inside the core's current Taylor step only records its end (no event can lie
    /// before the Taylor step's end); [`Model::sync`] advances the core when a result is needed.
    pending: Option<f64>,
    /// A lower bound on the end (`τ`) of the core's current Taylor step (`-inf`: unknown).
    taylor_end: f64,
    /// External mode: the plate samples of the last communication points.
    pub history: SampleHistory,
    /// Momentum per unit mass given to the plate by the impacts of the last step,
    /// `Σ (v_before − v_after)` (units of `ω0 Δx`).
    pub impulse: f64,
    /// The last step stopped at an event (early return): `time` is the event's time (before
    /// the requested end, or that end) and the event has been applied.
    pub at_event: bool,
    /// The divided differences of the last sampled piece's nodes (derived data, not saved).
    pub memo: PieceMemo,
    /// The mass read ahead at the host's next communication points (derived data, not saved).
    pub ahead: Ahead,
    /// External plates are rebuilt by the Hermite scheme (`plate_reconstruction`, a fixed
    /// parameter).
    hermite: bool,
    /// [`fly_limit`] of the model's scale.
    limit: f64,
}

/// Collects the events of an advance and the end of the last Taylor step computed.
struct Collect<'a> {
    events: &'a mut Vec<Event>,
    taylor_end: &'a mut f64,
    /// Taylor steps computed so far in this advance.
    steps: u64,
    /// Most steps this advance may compute (see [`step_budget`]).
    budget: u64,
    /// Stop the advance at the first event (early return).
    stop_at_events: bool,
    /// The advance was stopped at an event because of `stop_at_events`.
    stopped: bool,
}

/// Most Taylor steps a step spanning `radians` (`max(Ω, 1)·Δτ`) may compute: beyond it the
/// advance stops at the next event, or at the latest about 2,048 steps later
/// ([`budget_check`]), and the step is a Discard. Runs inside the model's scope take at most
/// about 4 steps per radian (measured from chatter at Omega = 0.2 to Omega = 100, e from 0 to
/// 1), at least twice less than the allowance; a state driven far outside it (the plate
/// velocity V = 1e6, a plate input of 1e24 in units of delta_x*omega0, whose oscillations need
/// ever shorter steps, or e = 1 with zeta = 5 and omega0 = 1e8, chatter that never ends) is
/// stopped after at most [`MAX_STEP_BUDGET`] steps, within about 0.3 s, instead of integrating
/// for hours.
fn step_budget(radians: f64) -> u64 {
    (100_000.0 + 50.0 * radians.max(0.0)).min(MAX_STEP_BUDGET as f64) as u64
}

/// The check installed in the core ([`bistable_core::interrupt`]) during an advance with
/// `budget`: it stops the advance between two steps once more than `budget` have been computed
/// (it is called every [`CHECK_EVERY`] steps), also when no event comes to stop it there.
fn budget_check(budget: u64) -> Check {
    let calls = AtomicU64::new(0);
    Arc::new(move || {
        calls.fetch_add(1, Ordering::Relaxed) + 1 > budget / u64::from(CHECK_EVERY) + 1
    })
}

impl Observer for Collect<'_> {
    fn event(&mut self, e: &Event) -> ControlFlow<()> {
        self.events.push(*e);
        if self.steps > self.budget {
            ControlFlow::Break(())
        } else if self.stop_at_events {
            self.stopped = true;
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    }

    fn step(&mut self, step: &StepView<'_>) {
        self.steps += 1;
        // Rounded end, lowered by a few ulps so that "target < taylor_end" implies the core
        // would find the target inside this step.
        let end = step.t0() + step.len();
        *self.taylor_end = end - 8.0 * f64::EPSILON * end.abs();
    }
}

/// Why a step stopped short.
pub enum StepFailure {
    /// The model cannot go on (Zeno sequence, overflow): report `fmi2Discard` and terminate.
    Stopped(String),
    /// A refused request (bad plate data, time mismatch): report `fmi2Error`.
    Refused(String),
}

impl Model {
    /// Builds the model at `t_start` (s) from the variable values and processes the events at
    /// the start instant (with the paper's initial condition: impact 0), reporting them to
    /// `events`.
    pub fn start(
        values: &[f64],
        derivatives: &PlateInputs,
        t_start: f64,
        events: &mut Vec<Event>,
    ) -> Result<Self, String> {
        let Setup {
            scale,
            mode,
            params,
            opts,
            phase_ref,
            origin,
            x0,
            v0,
        } = Setup::of(values, t_start)?;
        let tau0 = origin.to_f64();
        let plate: PlateMotion = match mode {
            ShakerMode::Internal => phase_ref.into(),
            // Only its start matters: every step replaces it with a piece over the step.
            ShakerMode::External => {
                let inputs = plate_inputs(values, derivatives);
                moderate(
                    plate_piece(&scale, origin, tau0 + 1.0, &inputs, None)?,
                    &scale,
                )?
                .into()
            }
        };
        let mut sim =
            Simulator::with_state(params, plate, opts, tau0, x0, v0).map_err(|e| match e {
                SimError::Param(p) if p.name == "x0" => {
                    below_plate(values, scale.length(plate.motion(origin).0))
                }
                other => describe(&other, &scale),
            })?;
        let mut taylor_end = f64::NEG_INFINITY;
        let mut obs = Collect {
            events,
            taylor_end: &mut taylor_end,
            steps: 0,
            budget: step_budget(0.0),
            stop_at_events: false,
            stopped: false,
        };
        sim.advance_to(tau0, &mut obs)
            .map_err(|e| describe(&e, &scale))?;
        sim.keep_flight(mode == ShakerMode::External);
        Ok(Self {
            sim,
            scale,
            mode,
            phase_ref,
            applied: (phase_ref.omega(), phase_ref.velocity()),
            time: t_start,
            pending: None,
            taylor_end,
            history: SampleHistory::new(),
            impulse: impulse_of(events),
            at_event: false,
            memo: PieceMemo::default(),
            ahead: Ahead::default(),
            hermite: is_hermite(values),
            limit: fly_limit(&scale),
        })
    }

    /// Rebuilds a model from its saved parts (see `state.rs`).
    pub fn restore(values: &[f64], saved: &SavedModel) -> Result<Self, String> {
        let scale = scale_of(values);
        let cp = &saved.checkpoint;
        let same = [
            (cp.zeta, values[var::zeta]),
            (cp.restitution, values[var::e]),
            (cp.tol, values[var::tol]),
        ];
        if same.iter().any(|(a, b)| a != b) {
            return Err("the FMU state's simulator does not match its parameters".into());
        }
        let external = matches!(cp.plate, PlateRecord::Poly { .. });
        if external != (ShakerMode::of(values[var::shaker_mode]) == Some(ShakerMode::External)) {
            return Err("the FMU state's plate does not match its shaker_mode".into());
        }
        check_checkpoint(cp)?;
        // The solver settings are the ones this FMU uses for the state's `tol`.
        let opts =
            SolverOptions::new(values[var::tol], chatter_rule()).map_err(|e| describe_param(&e))?;
        let settings = (
            opts.tol(),
            opts.order(),
            opts.chatter(),
            opts.max_chatter_impacts(),
        );
        if (cp.tol, cp.order, cp.chatter, cp.max_chatter_impacts) != settings {
            return Err("the FMU state's solver settings are not this FMU's".into());
        }
        let mut sim = Simulator::from_checkpoint(cp).map_err(|e| describe(&e, &scale))?;
        sim.keep_flight(external);
        let phase_ref = restore_phase_ref(&scale, saved.phase_ref, saved.applied, sim.instant())?;
        // In internal mode the phase reference is the plate itself.
        if !external && cp.plate != sinusoid_record(&phase_ref) {
            return Err(
                "the FMU state's phase reference does not match its shaker or plate".into(),
            );
        }
        let mode = ShakerMode::of(values[var::shaker_mode])
            .ok_or("invalid shaker_mode in the FMU state")?;
        // The communication time must be where the simulator is (a step or a Discard leaves
        // them equal up to the rounding of `t = τ/ω0`): a state claiming another time would
        // refuse every step or make the next one integrate across the difference.
        let tau = sim.time();
        if !(saved.time.is_finite()
            && (scale.tau(saved.time) - tau).abs() <= 1e-12 * tau.abs().max(1.0))
        {
            return Err(format!(
                "the FMU state's time {} s does not match its simulator's time {} s",
                saved.time,
                scale.time(tau)
            ));
        }
        check_inside_step(&sim, if external { 1.0 } else { phase_ref.omega() })?;
        let history = SampleHistory::from_entries(&saved.history)
            .filter(|h| {
                h.newest().is_none_or(|s| s.t <= sim.instant())
                    && (external || h.newest().is_none())
            })
            .ok_or(
                "the FMU state's plate samples are not increasing, not finite or after its time",
            )?;
        if !saved.impulse.is_finite() {
            return Err("the FMU state's plate impulse is not finite".into());
        }
        let mut model = Self {
            sim,
            scale,
            mode,
            phase_ref,
            applied: saved.applied,
            time: saved.time,
            pending: None,
            taylor_end: f64::NEG_INFINITY,
            history,
            impulse: saved.impulse,
            at_event: saved.at_event,
            memo: PieceMemo::default(),
            ahead: Ahead::default(),
            hermite: is_hermite(values),
            limit: fly_limit(&scale),
        };
        model.check_physical(values)?;
        Ok(model)
    }

    /// What every state the model reaches satisfies (checked on restored states): the mass is
    /// not below the plate (beyond rounding), its well is the side of the barrier it is on, the
    /// last impact is not in the future, and every output is finite.
    fn check_physical(&mut self, values: &[f64]) -> Result<(), String> {
        let st = self.sim.state();
        let size = 1f64.max(st.x.abs()).max(st.z.abs());
        let above = st.x - st.z >= -1e-12 * size; // false for NaN
        if !above {
            return Err(format!(
                "the FMU state puts the mass below the plate (x - z = {} m)",
                self.scale.length(st.x - st.z)
            ));
        }
        if (st.x - potential::BARRIER).abs() > 1e-9 && st.well != Well::of(st.x) {
            return Err(format!(
                "the FMU state's well {} does not match the mass position x = {} m",
                st.well.number(),
                self.scale.length(st.x)
            ));
        }
        if let Some(i) = self.sim.last_impact() {
            let past = i.t <= st.t;
            if !past || !i.phase.is_none_or(|p| (0.0..1.0).contains(&p)) {
                return Err(format!(
                    "the FMU state's last impact (t = {} s, phase {:?}) is not a past impact",
                    self.scale.time(i.t),
                    i.phase
                ));
            }
        }
        // On the stack: this runs after every step that runs the core. For a host that reads
        // the mass after each step, the mass now is read ahead with its next points.
        let mut buf = [0.0; 64];
        let out = &mut buf[..values.len()];
        out.copy_from_slice(values);
        self.write(out, ALL, self.ahead.host_will_read())?;
        if let Some(k) = out.iter().position(|v| !v.is_finite()) {
            return Err(format!(
                "the FMU state gives the non-finite output {} = {}",
                crate::md::VARS[k].name,
                out[k]
            ));
        }
        Ok(())
    }

    /// Advances the core to the communication time if a step left it behind (see `pending`).
    pub fn sync(&mut self) -> Result<(), String> {
        if let Some(tau) = self.pending.take() {
            let mut ignore = |_: &Event| {};
            self.sim
                .advance_to(tau, &mut ignore)
                .map_err(|e| describe(&e, &self.scale))?;
        }
        Ok(())
    }

    /// The parts to save (pointer-free).
    pub fn save(&mut self) -> Result<SavedModel, String> {
        self.sync()?;
        Ok(SavedModel {
            checkpoint: self.sim.checkpoint(),
            phase_ref: save_phase_ref(&self.phase_ref),
            applied: self.applied,
            time: self.time,
            history: self.history.entries().collect(),
            impulse: self.impulse,
            at_event: self.at_event,
        })
    }

    /// Integrates from the current time to exactly `t_end` (s), continuing the trajectory (no
    /// restart) unless the plate changes: a tunable `Omega`/`V` change, or, in external mode, the
    /// piece built from the inputs. Events go to `events`. With `stop_at_events` (early return)
    /// the step ends at the first event after the current time (applied, `at_event` set) if
    /// that is before `t_end`; the next step continues from there as if it had not stopped.
    #[inline]
    pub fn step(
        &mut self,
        t_end: f64,
        values: &[f64],
        derivatives: &PlateInputs,
        events: &mut Vec<Event>,
        stop_at_events: bool,
    ) -> Result<(), StepFailure> {
        let (tau_end, _, same_plate) = self.plan(t_end, values);
        // The impulse is replaced only by a step that is not refused (a refusal leaves the
        // model as it was). No event lies before the end of the current Taylor step.
        if same_plate && tau_end < self.taylor_end {
            self.impulse = 0.0;
            self.at_event = false;
            self.pending = Some(tau_end);
            self.time = t_end;
            return Ok(());
        }
        if self.mode == ShakerMode::External {
            let keep = self.hermite && derivatives[2..].iter().all(Option::is_none);
            self.sim.keep_flight(keep);
            if keep && self.fly_over(t_end, values) {
                return Ok(());
            }
        }
        self.step_core(t_end, values, derivatives, events, stop_at_events)
    }

    /// External mode with the Hermite plate: the step when the core's current flight covers
    /// the plate piece rebuilt from the inputs' sample without an event
    /// (`Simulator::fly_over_sampled`: no step to compute, no event, so nothing to undo or
    /// check); `false` (nothing changed) when it does not, or the sample or the piece is
    /// refused (`step_core` then takes the step or reports why).
    fn fly_over(&mut self, t_end: f64, values: &[f64]) -> bool {
        let (tau_end, wanted, _) = self.plan(t_end, values);
        if wanted != self.applied || self.pending.is_some() {
            return false;
        }
        let sample = Sample {
            t: self.sim.instant(),
            z: self.scale.plate_coefficient(0, values[var::z_in]),
            zdot: self.scale.plate_coefficient(1, values[var::zdot_in]),
        };
        let end = Instant::new(tau_end);
        if !self
            .sim
            .fly_over_sampled(&mut self.history, sample, end, &mut self.memo, self.limit)
        {
            return false;
        }
        self.impulse = impulse_of(&[]);
        self.at_event = false;
        self.time = t_end;
        true
    }

    /// The external plate over `[now, tau_end]` from the inputs (the plate is at `(z, zdot)`
    /// now), after the inputs' sample is added to `history`.
    fn external_piece(
        &mut self,
        now: Instant,
        tau_end: f64,
        (z, zdot): (f64, f64),
        values: &[f64],
        derivatives: &PlateInputs,
        history: &mut SampleHistory,
    ) -> Result<PolyPiece, String> {
        let inputs = plate_inputs(values, derivatives);
        let sample = Sample {
            t: now,
            z: self.scale.plate_coefficient(0, values[var::z_in]),
            zdot: self.scale.plate_coefficient(1, values[var::zdot_in]),
        };
        history.push(sample).map_err(|e| describe_param(&e))?;
        let derivatives_given = inputs[2..].iter().any(Option::is_some);
        if derivatives_given || !self.hermite {
            plate_piece(&self.scale, now, tau_end, &inputs, Some(z))
        } else {
            history
                .piece_with(Instant::new(tau_end), (z, zdot), &mut self.memo)
                .map_err(|e| describe_param(&e))
        }
    }

    /// What a step to `t_end` (s) asks for: the end in core time `τ`, the requested `(Ω, V)`,
    /// and whether the plate stays the one being integrated.
    fn plan(&self, t_end: f64, values: &[f64]) -> (f64, (f64, f64), bool) {
        let wanted = (values[var::Omega], values[var::V]);
        let same_plate = self.mode == ShakerMode::Internal && wanted == self.applied;
        (self.scale.tau(t_end), wanted, same_plate)
    }

    /// The part of [`Model::step`] that runs the core.
    #[inline(never)]
    fn step_core(
        &mut self,
        t_end: f64,
        values: &[f64],
        derivatives: &PlateInputs,
        events: &mut Vec<Event>,
        stop_at_events: bool,
    ) -> Result<(), StepFailure> {
        let (tau_end, wanted, same_plate) = self.plan(t_end, values);
        self.sync().map_err(StepFailure::Refused)?;
        let now = self.sim.instant();
        let moves = Instant::new(tau_end).since(now) > 0.0;
        if !moves {
            // A step shorter than the resolution of the core's time (e.g. h = 5e-324 s, or
            // omega0 < 1): nothing moves, only the communication time.
            self.impulse = 0.0;
            self.at_event = false;
            self.time = t_end;
            return Ok(());
        }
        let refuse = |e: &SimError, s: &Scale| StepFailure::Refused(describe(e, s));
        // The model at the communication point, to go back to if the step fails in a way that
        // leaves no usable state (a few hundred bytes; this path computes Taylor steps anyway).
        let undo = (
            self.sim.checkpoint(),
            self.phase_ref,
            self.applied,
            self.history,
            self.impulse,
        );
        let undo_time = self.time;
        // A refused step leaves the model as it was: everything that can fail comes before the
        // first change (the phase reference, the plate), and each change is checked by the core
        // before it takes effect.
        let (omega, v) = wanted;
        let phase_ref = if wanted != self.applied {
            PlateMotion::from(self.phase_ref)
                .continued_by_sinusoid(now, omega, v)
                .map_err(|e| StepFailure::Refused(describe_param(&e)))?
        } else {
            self.phase_ref
        };
        match self.mode {
            ShakerMode::External => {
                let st = self.sim.state();
                let mut history = self.history;
                let piece = self
                    .external_piece(
                        now,
                        tau_end,
                        (st.z, st.zdot),
                        values,
                        derivatives,
                        &mut history,
                    )
                    .map_err(StepFailure::Refused)?;
                self.history = history;
                if let Err(e) = self.sim.set_plate(piece.into()) {
                    self.undo(&undo);
                    return Err(refuse(&e, &self.scale));
                }
            }
            ShakerMode::Internal if wanted != self.applied => self
                .sim
                .set_sinusoid(omega, v)
                .map_err(|e| refuse(&e, &self.scale))?,
            ShakerMode::Internal => {}
        }
        self.phase_ref = phase_ref;
        self.applied = wanted;
        if !same_plate {
            self.taylor_end = f64::NEG_INFINITY;
        }
        let radians = Instant::new(tau_end).since(now) * omega.max(1.0);
        let mut obs = Collect {
            events: &mut *events,
            taylor_end: &mut self.taylor_end,
            steps: 0,
            budget: step_budget(radians),
            stop_at_events,
            stopped: false,
        };
        let obs_budget = obs.budget;
        let first_event = obs.events.len();
        let sim = &mut self.sim;
        let advanced = with_check(budget_check(obs_budget), || sim.advance(tau_end, &mut obs));
        let at_event = obs.stopped;
        self.impulse = impulse_of(&events[first_event..]);
        // Stopped by the observer for another reason than an early return, or by the budget's
        // check between events: the work budget is spent.
        let over_budget = matches!(advanced, Ok(false)) && !at_event
            || matches!(advanced, Err(SimError::Interrupted { .. }));
        // An event exactly at the end is not an early return (the rest of the instant's events
        // come with the next step).
        let early = at_event && self.sim.instant() < Instant::new(tau_end);
        self.at_event = at_event;
        let result = match advanced {
            Ok(true) => Ok(()),
            Ok(false) if at_event => Ok(()),
            Ok(false) => Err(SimError::NonFinite { t: self.sim.time() }),
            Err(e) => Err(e),
        };
        // A step that ends in a state with non-finite outputs (energies of a solution near the
        // overflow range) or one the core should never reach is not a success either.
        let result = result.and_then(|()| match self.check_physical(values) {
            Ok(()) => Ok(()),
            Err(_) => Err(SimError::NonFinite { t: self.sim.time() }),
        });
        match result {
            Ok(()) => {
                // The event's time in seconds, kept inside the step against the rounding of
                // `τ/ω0`.
                self.time = if early {
                    self.scale.time(self.sim.time()).clamp(undo_time, t_end)
                } else {
                    t_end
                };
                Ok(())
            }
            Err(
                e @ (SimError::Zeno { .. }
                | SimError::NonFinite { .. }
                | SimError::Interrupted { .. }),
            ) => {
                let msg = if over_budget {
                    format!(
                        "more than {} integration steps in one step at t = {} s: the state is far outside the model's scope",
                        obs_budget,
                        self.scale.time(self.sim.time())
                    )
                } else {
                    describe(&e, &self.scale)
                };
                self.time = self.scale.time(self.sim.time()).clamp(undo_time, t_end);
                self.at_event = false;
                // Where the core stopped is kept only if it is a usable state (a solution that
                // overflowed may leave huge velocities whose energies are infinite, or a mass
                // that crossed the barrier inside the failed step); otherwise the model goes back
                // to the communication point, which was.
                if let Err(why) = self.check_physical(values) {
                    self.undo(&undo);
                    self.time = undo_time;
                    events.clear();
                    return Err(StepFailure::Stopped(format!(
                        "{msg}; the state where it stopped is not usable ({why}), so the FMU stays at the start of the step"
                    )));
                }
                Err(StepFailure::Stopped(msg))
            }
            Err(e) => {
                self.undo(&undo);
                Err(refuse(&e, &self.scale))
            }
        }
    }

    /// Back to the state saved before a step (see [`Model::step_core`]).
    fn undo(&mut self, (cp, phase_ref, applied, history, impulse): &Undo) {
        if let Ok(mut sim) = Simulator::from_checkpoint(cp) {
            sim.keep_flight(self.mode == ShakerMode::External);
            self.sim = sim;
            self.phase_ref = *phase_ref;
            self.applied = *applied;
            self.history = *history;
            self.impulse = *impulse;
            self.taylor_end = f64::NEG_INFINITY;
            self.pending = None;
        }
    }

    /// Writes every output variable (and the state derivatives) into `values`, for the model's
    /// own use (nothing is read ahead).
    pub fn write_outputs(&mut self, values: &mut [f64]) -> Result<(), String> {
        self.write(values, ALL, false)
    }

    /// Writes the variables of `want` (see [`Observed::write`]) into `values` for the host,
    /// evaluating only what they need; the mass may be read ahead at the host's next points
    /// ([`Ahead`]).
    pub fn write_some(&mut self, values: &mut [f64], want: VarSet) -> Result<(), String> {
        if want & XV != 0 {
            self.ahead.host_reads();
        }
        self.write(values, want, true)
    }

    /// The communication time (`τ`) the outputs are taken at without advancing the core, when
    /// it is inside the core's step (see [`Model::write`]): the pending one, or the core's when
    /// a step ran it there (a time the host's points can give exactly).
    #[inline]
    fn communication_tau(&self) -> Option<f64> {
        self.pending.or_else(|| {
            let (hi, lo) = self.sim.instant().parts();
            (lo.to_bits() == 0).then_some(hi)
        })
    }

    /// Writes `x` and `v` of `want` from the mass read ahead in `lane`: the values
    /// `Observed::write` gives from it.
    #[inline]
    fn write_xv(&self, values: &mut [f64], want: VarSet, lane: usize) {
        let (x, v) = self.ahead.mass(lane);
        if want & bit(var::x) != 0 {
            values[var::x] = self.scale.length(x);
        }
        if want & bit(var::v) != 0 {
            values[var::v] = self.scale.velocity(v);
        }
    }

    /// [`Model::write_some`], reading ahead only if `ahead` (the same values either way).
    fn write(&mut self, values: &mut [f64], want: VarSet, ahead: bool) -> Result<(), String> {
        // At a communication time inside the core's current step the outputs come from that
        // step as they would after advancing the core there (which only moves its time). The
        // mass there may have been read ahead, or is read now with the host's next points
        // (`Ahead`, keyed by that time: the pending one, or the core's when a step ran it to
        // the communication time).
        let at = self.communication_tau();
        // Where the mass may be read ahead (only for a host's read).
        let key = at.filter(|_| ahead);
        let mut read = key.and_then(|tau| self.ahead.lookup(&self.sim, tau));
        let xv_only = want & !XV == 0;
        if let (Some(tau), None, true) = (key, read, xv_only) {
            // `Some` only at an instant in flight inside the core's step.
            read = self.ahead.read(&self.sim, &self.scale, tau);
        }
        if let (Some(lane), true) = (read, xv_only) {
            // A host reading the position and velocity in flight: nothing else computed.
            self.write_xv(values, want, lane);
            return Ok(());
        }
        let ahead_tau = at.filter(|&tau| read.is_some() || self.sim.inside_step(Instant::new(tau)));
        let now = match ahead_tau {
            Some(tau) => Instant::new(tau),
            None => {
                self.sync()?;
                self.sim.instant()
            }
        };
        // Not read again when the position and velocity alone were asked for just above.
        let fill = ahead_tau.filter(|_| ahead && !xv_only);
        let (sim, scale) = (&self.sim, &self.scale);
        let ahead = RefCell::new(&mut self.ahead);
        let stats = sim.stats();
        Observed {
            params: sim.params(),
            tau: now.to_f64(),
            mass: || {
                let mut ahead = ahead.borrow_mut();
                match read.or_else(|| fill.and_then(|tau| ahead.read(sim, scale, tau))) {
                    Some(lane) => {
                        let (x, v) = ahead.mass(lane);
                        (x, v, ContactMode::Free, sim.well())
                    }
                    None => sim.mass_at(now).unwrap_or_else(|| sim.mass()),
                }
            },
            plate: || sim.plate().motion(now),
            impacts: stats.impacts,
            snap_throughs: stats.snap_throughs,
            last_impact: sim.last_impact(),
            impulse: self.impulse,
        }
        .write(&self.scale, &self.phase_ref, values, want);
        Ok(())
    }

    /// First time derivative (SI) of the output `index`, for `x`, `v`, `z`, `zdot` (after
    /// [`Model::sync`]).
    pub fn output_derivative(&self, index: usize) -> Option<f64> {
        let s = &self.scale;
        let st = self.sim.state();
        let zdd = self.sim.plate().motion(self.sim.instant()).2;
        let a = mass_acceleration(self.sim.params(), &st, zdd);
        Some(match index {
            i if i == var::x => s.velocity(st.v),
            i if i == var::v => s.acceleration(a),
            i if i == var::z => s.velocity(st.zdot),
            i if i == var::zdot => s.acceleration(zdd),
            _ => return None,
        })
    }

    /// A line for the `logEvents` category (SI units, full precision).
    pub fn describe_event(&self, e: &Event) -> String {
        describe_event(&self.scale, &self.phase_ref, e)
    }
}

/// The model at a communication point, to go back to when a step fails: core, phase reference,
/// `(Ω, V)` in force, plate samples, plate impulse.
type Undo = (Checkpoint, Sinusoid, (f64, f64), SampleHistory, f64);

/// `Σ (v_before − v_after)` over the impacts among `events`: the momentum per unit mass they
/// gave the plate.
fn impulse_of(events: &[Event]) -> f64 {
    events
        .iter()
        .filter_map(Event::impact)
        .map(|i| i.v_before - i.v_after)
        // From +0 (`sum` starts at −0): a step without impacts reports 0 whichever path it took.
        .fold(0.0, |a, b| a + b)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::md::{Causality, VARS};
    use crate::model::plate::MAX_PLATE_ORDER;

    fn defaults() -> Vec<f64> {
        VARS.iter().map(|v| v.start).collect()
    }

    #[test]
    fn every_output_is_written() {
        let mut values = defaults();
        let mut events = Vec::new();
        let none = [None; MAX_PLATE_ORDER + 1];
        let mut m = Model::start(&values, &none, 0.0, &mut events).unwrap();
        m.step(3.0, &values, &none, &mut events, false)
            .ok()
            .unwrap();
        let outputs: Vec<usize> = (0..VARS.len())
            .filter(|&i| VARS[i].causality == Causality::Output)
            .collect();
        outputs.iter().for_each(|&i| values[i] = f64::NAN);
        m.write_outputs(&mut values).unwrap();
        for i in outputs {
            assert!(values[i].is_finite(), "{} not written", VARS[i].name);
        }
    }

    #[test]
    fn every_variable_has_a_bit() {
        // `VarSet` and the output buffer of `check_physical` hold 64 variables.
        assert!(VARS.len() <= 64, "{} variables", VARS.len());
    }

    /// Each computed variable written alone has the bits it has when all are written, in
    /// flight and while riding the plate (chatter at Omega = 0.2, V = 0.05), both interfaces.
    #[test]
    fn outputs_on_demand_are_bit_identical_to_all_outputs() {
        let mut values = defaults();
        values[var::Omega] = 0.2;
        values[var::V] = 0.05;
        let computed: Vec<usize> = (0..VARS.len())
            .filter(|&i| {
                matches!(
                    VARS[i].causality,
                    Causality::Output | Causality::Local | Causality::Independent
                )
            })
            .collect();
        let same = |all: &[f64], one: &[f64], i: usize, t: f64| {
            assert_eq!(
                all[i].to_bits(),
                one[i].to_bits(),
                "{} at t = {t}: {} alone, {} with all",
                VARS[i].name,
                one[i],
                all[i]
            );
        };
        let mut events = Vec::new();
        let none = [None; MAX_PLATE_ORDER + 1];
        let mut m = Model::start(&values, &none, 0.0, &mut events).unwrap();
        let (mut riding, mut flying, mut pending) = (0, 0, 0);
        for k in 1..=3000 {
            let t = f64::from(k) * 0.01;
            m.step(t, &values, &none, &mut events, false).ok().unwrap();
            // All of them from the core advanced to `t`; each alone from `m`, whose core may
            // have been left behind (a step inside the core's current step only records its end).
            let mut synced = m.clone();
            synced.sync().unwrap();
            let mut all = values.clone();
            synced.write_outputs(&mut all).unwrap();
            pending += usize::from(m.pending.is_some());
            for &i in &computed {
                let mut one = vec![f64::NAN; values.len()];
                m.write_some(&mut one, bit(i)).unwrap();
                same(&all, &one, i, t);
            }
            if all[var::in_contact] == 1.0 {
                riding += 1;
            } else {
                flying += 1;
            }
        }
        assert!(
            riding > 100 && flying > 100,
            "{riding} riding, {flying} in flight"
        );
        assert!(pending > 1000, "{pending} reads from a core left behind");
        // Model Exchange, internal and external plate, at a few states.
        for mode in [1.0, 2.0] {
            values[var::shaker_mode] = mode;
            values[var::z_in] = -0.01;
            values[var::zdot_in] = -0.02;
            let mut me = crate::me::Me::start(&values, 0.0).unwrap();
            for (t, x, v) in [(0.5, 0.3, -0.1), (1.0, -0.7, 0.4), (2.0, 0.5, 0.0)] {
                me.set_time(t).unwrap();
                me.set_states(&[x, v]).unwrap();
                let mut all = values.clone();
                me.write_outputs(&mut all);
                for &i in &computed {
                    let mut one = values.clone();
                    one[i] = f64::NAN;
                    me.write_some(&mut one, bit(i));
                    same(&all, &one, i, t);
                }
            }
        }
    }

    #[test]
    fn reads_ahead_give_the_values_of_a_read_without_them() {
        // Hosts reading x and v after every step, counting time as fmpy does (start + n dt),
        // by adding the step, or irregularly; every 7th read asks for every output. The values
        // must be those of a model that reads nothing ahead, bit for bit.
        type Clock = fn(f64, u32) -> (f64, f64);
        let hosts: [(&str, f64, Clock); 5] = [
            ("grid from 0", 0.0, |_, k| {
                (f64::from(k) * 0.01, f64::from(k + 1) * 0.01)
            }),
            ("grid from 0.3", 0.3, |_, k| {
                (0.3 + f64::from(k) * 0.007, 0.3 + f64::from(k + 1) * 0.007)
            }),
            ("sum", 0.0, |t, _| (t, t + 0.01)),
            ("sum from 0.1", 0.1, |t, _| (t, t + 0.013)),
            ("irregular", 0.0, |t, k| {
                (t, t + 0.004 + 0.003 * f64::from(k % 5))
            }),
        ];
        for (omega, v) in [(1.75, 0.07), (0.2, 0.05)] {
            for (name, start, clock) in hosts {
                let mut values = defaults();
                values[var::Omega] = omega;
                values[var::V] = v;
                let mut events = Vec::new();
                let none = [None; MAX_PLATE_ORDER + 1];
                let mut m = Model::start(&values, &none, start, &mut events).unwrap();
                let mut plain = m.clone();
                let (mut t, mut hits, mut reads) = (start, 0, 0);
                for k in 0..3000 {
                    let (tc, end) = clock(t, k);
                    let h = end - tc;
                    m.ahead.host_step(start, tc, h);
                    m.step(tc + h, &values, &none, &mut events, false)
                        .ok()
                        .unwrap();
                    plain
                        .step(tc + h, &values, &none, &mut events, false)
                        .ok()
                        .unwrap();
                    let at = m.pending.unwrap_or_else(|| m.sim.instant().to_f64());
                    hits += usize::from(m.ahead.clone().lookup(&m.sim, at).is_some());
                    reads += 1;
                    let want = if k % 7 == 0 { ALL } else { XV };
                    let (mut got, mut expected) = (values.clone(), values.clone());
                    m.write_some(&mut got, want).unwrap();
                    plain.write_outputs(&mut expected).unwrap();
                    for i in (0..VARS.len()).filter(|&i| want & bit(i) != 0) {
                        assert_eq!(
                            got[i].to_bits(),
                            expected[i].to_bits(),
                            "{name}, Omega {omega}: {} at t = {}",
                            VARS[i].name,
                            tc + h
                        );
                    }
                    t = tc + h;
                }
                // The patterns are read ahead at most points in flight (one read per Taylor
                // step evaluates the next ones); the irregular host's points only where a few
                // of them happen to lie on a grid (served and checked like the others).
                let expect_hits = name != "irregular";
                assert!(
                    if expect_hits {
                        hits * 2 > reads
                    } else {
                        hits * 100 < reads
                    },
                    "{name}, Omega {omega}: {hits} of {reads} reads ahead"
                );
            }
        }
    }
}
