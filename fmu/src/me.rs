//! Model Exchange: the continuous states `x`, `v` integrated by the host, the event indicators
//! and the discrete part (impacts, sticking, release, snap-throughs) applied in event mode.
//!
//! The physics is the core's: free-flight acceleration, contact force and impact law come from
//! [`Params`], the chatter rule from [`ChatterRule`], and the end of a chatter sequence is run by
//! the core [`Simulator`] itself. Units as in `model/si.rs` (SI at the interface, nondimensional
//! inside).
//!
//! - **Modes.** Free flight: `x' = v`, `v' = −2ζv − U'(x)`. Sticking: `x' = ż`, `v' = z̈` (the
//!   host's states follow the plate up to its integration error).
//! - **Event indicators** (SI): 0 is the gap `x − z` in free flight and the contact force `N`
//!   (Eq. 9, per unit mass) while sticking; 1 is `x − Δx/2` (barrier).
//! - **Impact** (event mode, free flight): gap `≤ TOUCH` and approach speed `ż − v > GRAZE`;
//!   `v₊ = ż − e(v₋ − ż)` and `x := z`. A mass found below the plate without approaching is put
//!   back on it (`x := z`); one touching it with no relative speed while pushed (`N > 0`) sticks.
//! - **Chatter.** A host's integrator cannot resolve the unending impacts of a chatter sequence.
//!   When the core's accumulation rule with the horizon [`ME_HORIZON`] would end the sequence
//!   after an impact (predicted remaining chatter time `2w₊/(N(1−e)) ≤ ME_HORIZON`), the rest of
//!   the sequence is run by the core simulator (with the co-simulation's rule), from the state
//!   after that impact to its start of sticking. The mass rides the plate from the impact on;
//!   the sequence's impacts are logged at once and counted, with the start of sticking, at a
//!   time event at the core's sticking time (so counts match the co-simulation).
//! - **Release** (sticking): `N ≤ 0`: free flight from the plate (`x := z`, `v := ż`).
//! - **Plate.** Internal mode: the sinusoid from `Omega`, `V` (a tunable change, in event mode,
//!   keeps position and phase continuous). External mode: `z = z_in`, `ż = zdot_in`, `z̈ = 0`
//!   at the current time (Model Exchange has no input derivatives).

use std::ops::ControlFlow;

use bistable_core::law::{self, Contact};
use bistable_core::potential;
use bistable_core::{
    ChatterRule, ContactMode, Event, Impact, Instant, Observer, Params, PlateMotion, Simulator,
    Sinusoid, SolverOptions, StepView, StickCause, Well,
};

use crate::md::var;
use crate::model::checkpoint::{restore_phase_ref, save_phase_ref};
use crate::model::outputs::{Mass, Observed, Plate, VarSet, ALL};
use crate::model::plate::{
    origin_in_range, plate_inputs, plate_piece, PlateInputs, ShakerMode, MAX_CLOCK_SPAN,
    MAX_PLATE_ORDER,
};
use crate::model::setup::{below_plate, Setup};
use crate::model::si::{describe_event, describe_param, scale_of, Scale};
use crate::num::Num;

/// Horizon (time units) of the accumulation rule that hands a chatter sequence to the core: the
/// flights the host still resolves last at least `(1−e)·ME_HORIZON` (1.5e-3 at `e = 0.85`) and
/// rise about `N·((1−e)·ME_HORIZON)²/8` above the plate (7e-8 at `N = 0.25`), far above the
/// position error of an integrator at `rtol = 1e-10`.
pub const ME_HORIZON: f64 = 1e-2;

/// Gap (units of `Δx`, relative to `max(1, |z|)`) within which the mass touches the plate.
pub const TOUCH: f64 = 1e-10;

/// Relative speed (units of `ω0Δx`, relative to `max(1, |ż|)`) below which a contact is not an
/// impact: a host's integrator leaves errors far below it (1e-10 at `rtol = 1e-10`), which
/// would otherwise count as grazing impacts right after a release.
pub const GRAZE: f64 = 1e-8;

/// The end of a chatter sequence, run by the core and applied at its start of sticking.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tail {
    /// Start of sticking (`τ`).
    pub until: f64,
    /// Why the core stuck.
    pub cause: StickCause,
    /// Impacts of the sequence after the one that handed it over.
    pub impacts: u64,
    /// The last of them.
    pub last: Option<Impact>,
    /// Momentum per unit mass they give the plate.
    pub impulse: f64,
}

/// The discrete and continuous state of a Model Exchange run (nondimensional).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SavedMe {
    /// Phase reference (see `model::checkpoint::SavedModel::phase_ref`).
    pub phase_ref: (f64, f64, f64, f64, f64, f64),
    /// `(Ω, V)` in force.
    pub applied: (f64, f64),
    /// Current time `τ`.
    pub tau: f64,
    /// Time `τ` of the last event mode: the time may not be set before it.
    pub event_tau: f64,
    /// Mass position (continuous state).
    pub x: f64,
    /// Mass velocity (continuous state).
    pub v: f64,
    /// Free flight or sticking.
    pub contact: ContactMode,
    /// Well of the mass.
    pub well: Well,
    /// Impacts counted so far.
    pub impacts: u64,
    /// Snap-throughs so far.
    pub snap_throughs: u64,
    /// The last impact counted.
    pub last_impact: Option<Impact>,
    /// Momentum per unit mass given to the plate in the last event mode.
    pub impulse: f64,
    /// A chatter sequence handed to the core, not yet applied.
    pub tail: Option<Tail>,
}

/// A Model Exchange run: [`SavedMe`] plus what the parameters give.
#[derive(Debug, Clone)]
pub struct Me {
    /// Unit conversions.
    pub scale: Scale,
    mode: ShakerMode,
    params: Params,
    opts: SolverOptions,
    phase_ref: Sinusoid,
    /// The state.
    pub s: SavedMe,
}

/// What an event-mode update did.
#[derive(Debug, Clone, Copy, Default)]
pub struct Update {
    /// The continuous states changed.
    pub states_changed: bool,
}

impl Me {
    /// A run at `t_start` (s) from the parameters; the events at the start instant are left to
    /// the first event-mode update.
    pub fn start(values: &[f64], t_start: f64) -> Result<Self, String> {
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
        let tau = origin.to_f64();
        let me = Self {
            scale,
            mode,
            params,
            opts,
            phase_ref,
            s: SavedMe {
                phase_ref: save_phase_ref(&phase_ref),
                applied: (phase_ref.omega(), phase_ref.velocity()),
                tau,
                event_tau: tau,
                x: x0,
                v: v0,
                contact: ContactMode::Free,
                well: Well::of(x0),
                impacts: 0,
                snap_throughs: 0,
                last_impact: None,
                impulse: 0.0,
                tail: None,
            },
        };
        if !(x0.is_finite() && v0.is_finite()) {
            return Err("x0 and v0 must be finite".into());
        }
        let z = me.plate(values).0;
        if !z.is_finite() {
            return Err("the plate position is not finite at the start time".into());
        }
        if x0 < z {
            return Err(below_plate(values, scale.length(z)));
        }
        Ok(me)
    }

    /// Rebuilds a run from its saved state, checking it against the parameter values.
    pub fn restore(values: &[f64], saved: &SavedMe) -> Result<Self, String> {
        let setup = Setup::of(values, 0.0)?;
        let s = *saved;
        let finite = [s.tau, s.event_tau, s.x, s.v, s.impulse]
            .iter()
            .all(|v| v.is_finite());
        if !finite || s.event_tau > s.tau {
            return Err(
                "the FMU state's time, states or impulse are not finite or inconsistent".into(),
            );
        }
        let now = Instant::new(s.tau);
        let phase_ref = restore_phase_ref(&setup.scale, s.phase_ref, s.applied, now)?;
        let limit = 1u64 << 53;
        let tail_ok = s.tail.is_none_or(|t| {
            s.contact == ContactMode::Sticking
                && t.until.is_finite()
                && t.until >= s.event_tau
                && t.until - s.event_tau <= 2.0 * ME_HORIZON
                && t.impulse.is_finite()
                && t.impacts <= limit
                && t.last.is_some() == (t.impacts > 0)
        });
        let last_ok = s.last_impact.is_none_or(|i| {
            i.t <= s.tau
                && i.index.checked_add(1) == Some(s.impacts)
                && i.phase.is_none_or(|p| (0.0..1.0).contains(&p))
        }) && (s.last_impact.is_some() || s.impacts == 0);
        if !tail_ok || !last_ok || s.snap_throughs > limit || s.impacts > limit {
            return Err(
                "the FMU state's counters, last impact or chatter tail are inconsistent".into(),
            );
        }
        // The well may differ from the side of the barrier the mass is on: the host sets the
        // states, and the snap-through is applied at its next event update (the barrier
        // indicator has changed sign), so a state saved in between is a state of the run.
        let me = Self {
            scale: setup.scale,
            mode: setup.mode,
            params: setup.params,
            opts: setup.opts,
            phase_ref,
            s,
        };
        let mut out = values.to_vec();
        me.write_outputs(&mut out);
        if let Some(k) = out.iter().position(|v| !v.is_finite()) {
            return Err(format!(
                "the FMU state gives the non-finite output {} = {}",
                crate::md::VARS[k].name,
                out[k]
            ));
        }
        Ok(me)
    }

    /// The plate `(z, ż, z̈)` now (nondimensional).
    fn plate(&self, values: &[f64]) -> (f64, f64, f64) {
        self.plate_of([values[var::z_in], values[var::zdot_in]])
    }

    /// Whether the computed values depend on the value of variable `i` (the inputs `z_in`,
    /// `zdot_in` of the external plate; parameters act at the next event update).
    pub fn reads_input(&self, i: usize) -> bool {
        self.mode == ShakerMode::External && (i == var::z_in || i == var::zdot_in)
    }

    /// [`Me::plate`] with the inputs `z_in`, `zdot_in`.
    fn plate_of(&self, [z_in, zdot_in]: [f64; 2]) -> (f64, f64, f64) {
        match self.mode {
            ShakerMode::Internal => {
                PlateMotion::from(self.phase_ref).motion(Instant::new(self.s.tau))
            }
            ShakerMode::External => {
                let sc = &self.scale;
                (
                    sc.plate_coefficient(0, z_in),
                    sc.plate_coefficient(1, zdot_in),
                    0.0,
                )
            }
        }
    }

    /// Current time (s).
    pub fn time(&self) -> f64 {
        self.scale.time(self.s.tau)
    }

    /// `fmi2SetTime`: `t` (s) must be finite, not before the last event and within the clock
    /// range of the shaker. A time at or after the time event announced by
    /// [`Me::next_event_time`] puts `τ` at or after the event (see `Me::tail_due`).
    pub fn set_time(&mut self, t: f64) -> Result<(), String> {
        let tau = self.scale.tau(t);
        // Rounding allowance as for co-simulation communication points: 1e-9 relative, in s.
        let event = self.scale.time(self.s.event_tau);
        if !tau.is_finite() || t < event - 1e-9 * event.abs().max(1.0) {
            return Err(format!(
                "time = {t} s must be finite and not before the last event at {} s",
                self.scale.time(self.s.event_tau)
            ));
        }
        let origin = self.phase_ref.origin().0;
        let omega = self.phase_ref.omega();
        if !origin_in_range(omega, origin, Instant::new(tau.max(self.s.event_tau))) {
            return Err(format!(
                "time = {t} s is {:e} shaker radians (time units when Omega < 1) from the shaker's origin: beyond the FMU's clock range of {MAX_CLOCK_SPAN:e}",
                omega.max(1.0) * (tau - origin.to_f64())
            ));
        }
        // A time at or after the announced time event reaches it, whatever `t·ω0` rounds to.
        let announced = self.s.tail.map_or(f64::INFINITY, |tail| tail.until);
        let tau = if t >= self.scale.time(announced) {
            tau.max(announced)
        } else {
            tau
        };
        self.s.tau = tau.max(self.s.event_tau);
        Ok(())
    }

    /// `fmi2SetContinuousStates` (SI: m, m/s).
    pub fn set_states(&mut self, x: &[f64]) -> Result<(), String> {
        let [xs, vs] = x else {
            return Err(format!(
                "nx = {}: the model has 2 continuous states (x, v)",
                x.len()
            ));
        };
        if !(xs.is_finite() && vs.is_finite()) {
            return Err(format!(
                "continuous states x = {} m, v = {} m/s must be finite",
                Num(*xs),
                Num(*vs)
            ));
        }
        let sc = &self.scale;
        let (xn, vn) = (xs / sc.dx, vs / (sc.omega0 * sc.dx));
        // The energies (outputs, and part of an FMU state) must stay finite.
        let energies = sc.energy(potential::energy(xn)) + sc.energy(potential::kinetic(vn));
        if !(xn.is_finite() && vn.is_finite() && energies.is_finite()) {
            return Err(format!(
                "continuous states x = {} m, v = {} m/s give non-finite energies",
                Num(*xs),
                Num(*vs)
            ));
        }
        self.s.x = xn;
        self.s.v = vn;
        Ok(())
    }

    /// The continuous states (SI).
    pub fn states(&self) -> [f64; 2] {
        [self.scale.length(self.s.x), self.scale.velocity(self.s.v)]
    }

    /// Nominal magnitudes of the continuous states (SI): `Δx`, `ω0Δx`.
    pub fn nominals(values: &[f64]) -> [f64; 2] {
        let sc = scale_of(values);
        [sc.dx, sc.velocity(1.0)]
    }

    /// What the outputs are computed from, with the inputs `z_in`, `zdot_in` (the plate is
    /// evaluated only when asked).
    fn observed(
        &self,
        inputs: [f64; 2],
    ) -> Observed<'_, impl Fn() -> Mass + '_, impl Fn() -> Plate + '_> {
        Observed {
            params: &self.params,
            tau: self.s.tau,
            mass: || (self.s.x, self.s.v, self.s.contact, self.s.well),
            plate: move || self.plate_of(inputs),
            impacts: self.s.impacts,
            snap_throughs: self.s.snap_throughs,
            last_impact: self.s.last_impact,
            impulse: self.s.impulse,
        }
    }

    /// Writes the outputs and the state derivatives into `values` (which holds the inputs).
    pub fn write_outputs(&self, values: &mut [f64]) {
        self.write_some(values, ALL);
    }

    /// Writes the variables of `want` (see [`Observed::write`]) into `values` (which holds the
    /// inputs), evaluating only what they need.
    pub fn write_some(&self, values: &mut [f64], want: VarSet) {
        let inputs = [values[var::z_in], values[var::zdot_in]];
        self.observed(inputs)
            .write(&self.scale, &self.phase_ref, values, want);
    }

    /// `fmi2GetEventIndicators` (SI): gap (m) or contact force (m/s²), and `x − Δx/2` (m).
    pub fn indicators(&self, values: &[f64]) -> [f64; 2] {
        self.observed([values[var::z_in], values[var::zdot_in]])
            .indicators(&self.scale)
    }

    /// Whether the states have moved where event mode must act (`fmi2CompletedIntegratorStep`
    /// and hosts that step over an indicator's sign change): a time event due, the mass below the
    /// plate, a negative contact force while sticking, or the mass on the other side of the
    /// barrier than its well.
    pub fn needs_event(&self, values: &[f64]) -> bool {
        let (z, zd, zdd) = self.plate(values);
        let s = &self.s;
        let due = self.tail_due();
        let contact = match s.contact {
            ContactMode::Free => s.x - z < -TOUCH * z.abs().max(1.0),
            ContactMode::Sticking => self.params.contact_force(z, zd, zdd) < 0.0,
        };
        due || contact || Well::of(s.x) != s.well
    }

    /// Time (s) of the next time event (the start of sticking of a handed-over chatter tail).
    pub fn next_event_time(&self) -> Option<f64> {
        self.s.tail.map(|t| self.scale.time(t.until))
    }

    /// Whether the handed-over chatter tail is due: the time has reached its start of sticking
    /// `until`, in `τ` or as the time in s that [`Me::next_event_time`] reported. A host sets
    /// the time to that report, `until/ω0` rounded, and `τ = t·ω0` may come back an ulp before
    /// `until` (e.g. `ω0 = 1.2314973701554512`, `until = 0.7510390451270431`: `t =
    /// 0.6098584238407588` s gives `τ = 0.751039045127043`). Comparing in `τ` alone would leave
    /// such a tail never due at the time of its own time event: every event update would
    /// announce the same time again, and a host honouring it would loop without progress.
    fn tail_due(&self) -> bool {
        self.s.tail.is_some_and(|t| {
            self.s.tau >= t.until || self.scale.time(self.s.tau) >= self.scale.time(t.until)
        })
    }

    /// Start of an event mode: the time becomes the earliest one allowed and the impulse is reset.
    pub fn enter_event_mode(&mut self) {
        self.s.event_tau = self.s.tau;
        self.s.impulse = 0.0;
    }

    /// One `fmi2NewDiscreteStates`: applies what happens at the current time (tunable shaker
    /// change, due chatter tail, impact, sticking, release, snap-through), reporting events.
    /// One call settles the instant: a second one would change nothing.
    pub fn update(&mut self, values: &[f64], events: &mut Vec<Event>) -> Result<Update, String> {
        let now = Instant::new(self.s.tau);
        let wanted = (values[var::Omega], values[var::V]);
        if wanted != self.s.applied {
            let next = PlateMotion::from(self.phase_ref)
                .continued_by_sinusoid(now, wanted.0, wanted.1)
                .map_err(|e| describe_param(&e))?;
            self.phase_ref = next;
            self.s.phase_ref = save_phase_ref(&next);
            self.s.applied = wanted;
        }
        self.s.event_tau = self.s.tau;
        let mut up = Update::default();
        if self.tail_due() {
            self.apply_tail(events);
        }
        let (z, zd, zdd) = self.plate(values);
        let force = self.params.contact_force(z, zd, zdd);
        let s = &mut self.s;
        match s.contact {
            ContactMode::Free => {
                let (gap, w) = (s.x - z, s.v - zd);
                let touch = TOUCH * z.abs().max(1.0);
                let graze = GRAZE * zd.abs().max(1.0);
                if gap <= touch && w < -graze {
                    self.impact(values, events)?;
                    up.states_changed = true;
                } else if gap <= touch && w <= graze && force > 0.0 {
                    (s.x, s.v) = (z, zd);
                    self.stick(self.s.tau, StickCause::Plastic, events);
                    up.states_changed = true;
                } else if gap < -touch {
                    s.x = z;
                    s.v = s.v.max(zd);
                    up.states_changed = true;
                }
            }
            ContactMode::Sticking if force <= 0.0 => {
                self.apply_tail(events);
                let s = &mut self.s;
                (s.contact, s.x, s.v) = (ContactMode::Free, z, zd);
                events.push(law::release(s.tau, z, zd));
                up.states_changed = true;
            }
            ContactMode::Sticking => {}
        }
        let s = &mut self.s;
        let well = Well::of(s.x);
        if well != s.well {
            s.well = well;
            s.snap_throughs += 1;
            events.push(law::snap_through(s.tau, s.v, well));
        }
        Ok(up)
    }

    /// Applies the impact law now (free flight, mass at or below the plate, approaching).
    fn impact(&mut self, values: &[f64], events: &mut Vec<Event>) -> Result<(), String> {
        let (z, zd, zdd) = self.plate(values);
        let now = Instant::new(self.s.tau);
        let v_before = self.s.v;
        let (imp, w_plus) = law::impact_law(
            &self.params,
            &Contact {
                index: self.s.impacts,
                t: self.s.tau,
                phase: (self.mode == ShakerMode::Internal)
                    .then(|| self.phase_ref.phase_cycles(now)),
                z,
                zdot: zd,
                w_minus: v_before - zd,
                v_before,
            },
        );
        let v_after = imp.v_after;
        let s = &mut self.s;
        s.impacts += 1;
        s.last_impact = Some(imp);
        s.impulse += v_before - v_after;
        (s.x, s.v) = (z, v_after);
        events.push(Event::Impact(imp));
        let e = self.params.restitution();
        let force = self.params.contact_force(z, zd, zdd);
        let hand_over = ChatterRule::Accumulation {
            horizon: ME_HORIZON,
        }
        .stick_delay(e, w_plus, force, None)
        .is_some();
        if hand_over {
            if let Some(tail) = self.run_tail(values, z, v_after, events) {
                self.s.contact = ContactMode::Sticking;
                self.s.v = zd;
                self.s.tail = Some(tail);
                if self.tail_due() {
                    self.apply_tail(events);
                }
            }
        }
        Ok(())
    }

    /// Runs the rest of a chatter sequence with the core from the mass at `x` (on the plate)
    /// with velocity `v` now, up to its start of sticking; its impacts go to `events` (logged
    /// now, counted when the tail is applied). `None` if the core does not stick within twice
    /// the horizon (the host then resolves the flights).
    fn run_tail(&self, values: &[f64], x: f64, v: f64, events: &mut Vec<Event>) -> Option<Tail> {
        let tau = self.s.tau;
        let end = tau + 2.0 * ME_HORIZON;
        let plate: PlateMotion = match self.mode {
            ShakerMode::Internal => self.phase_ref.into(),
            ShakerMode::External => {
                let none: PlateInputs = [None; MAX_PLATE_ORDER + 1];
                let inputs = plate_inputs(values, &none);
                plate_piece(&self.scale, Instant::new(tau), end, &inputs, None)
                    .ok()?
                    .into()
            }
        };
        let mut sim = Simulator::with_state(self.params, plate, self.opts, tau, x, v).ok()?;
        let mut obs = TailObserver {
            first: self.s.impacts,
            found: Vec::new(),
            stick: None,
            steps: 0,
        };
        let _ = sim.advance(end, &mut obs);
        let (until, cause) = obs.stick?;
        let found = obs.found;
        events.extend(found.iter().copied().map(Event::Impact));
        Some(Tail {
            until,
            cause,
            impacts: found.len() as u64,
            last: found.last().copied(),
            impulse: found
                .iter()
                .map(|i| i.v_before - i.v_after)
                .fold(0.0, |a, b| a + b),
        })
    }

    /// Counts a handed-over chatter tail and reports its start of sticking.
    fn apply_tail(&mut self, events: &mut Vec<Event>) {
        let Some(t) = self.s.tail.take() else { return };
        let s = &mut self.s;
        s.impacts += t.impacts;
        s.last_impact = t.last.or(s.last_impact);
        s.impulse += t.impulse;
        self.stick(t.until, t.cause, events);
    }

    /// Puts the mass on the plate (mode only: the caller sets the states) and reports it.
    fn stick(&mut self, t: f64, cause: StickCause, events: &mut Vec<Event>) {
        self.s.contact = ContactMode::Sticking;
        events.push(law::stick_start(t, self.s.x, cause, self.s.impacts));
    }

    /// A line for the `logEvents` category.
    pub fn describe_event(&self, e: &Event) -> String {
        describe_event(&self.scale, &self.phase_ref, e)
    }

    /// The state to save.
    pub fn save(&self) -> SavedMe {
        self.s
    }
}

/// Most core steps a chatter tail may take (a sequence takes about 2 per impact, and the core's
/// Zeno guard ends one after 100,000 impacts).
const TAIL_STEPS: u64 = 1_000_000;

/// Collects a chatter tail's impacts (renumbered after `first`) up to the start of sticking.
struct TailObserver {
    first: u64,
    found: Vec<Impact>,
    stick: Option<(f64, StickCause)>,
    steps: u64,
}

impl Observer for TailObserver {
    fn event(&mut self, e: &Event) -> ControlFlow<()> {
        match *e {
            Event::Impact(i) => self.found.push(Impact {
                index: self.first + self.found.len() as u64,
                ..i
            }),
            Event::StickStart { t, cause, .. } => {
                self.stick = Some((t, cause));
                return ControlFlow::Break(());
            }
            _ => {}
        }
        if self.steps > TAIL_STEPS {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    }

    fn step(&mut self, _: &StepView<'_>) {
        self.steps += 1;
    }
}
