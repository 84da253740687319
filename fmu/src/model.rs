//! The adapter between FMU variables (SI units) and the nondimensional core.
//!
//! Units (`model.md` Sec. 6): time `t = τ/ω0` (s), lengths `x̂ = Δx·x` (m), velocities
//! `ω0Δx·v` (m/s), accelerations `ω0²Δx·a` (m/s²), energies `m·ω0²Δx²·E` (J). With `omega0 = 1`,
//! `delta_x = 1` and `mass = 1` every conversion is a multiplication by 1: the FMU is the
//! nondimensional model bit for bit.

use bistable_core::{
    potential, ChatterRule, Checkpoint, ContactMode, Event, Instant, ParamError, Params,
    PlateMotion, PolyPiece, SimError, Simulator, Sinusoid, SolverOptions,
};

use crate::md::var;

/// Highest plate derivative that an external piece carries (degree of `PolyPiece`).
pub const MAX_PLATE_ORDER: usize = bistable_core::shaker::MAX_POLY_DEGREE;

/// Chatter rule of the FMU (the core's default, as the CLI uses).
fn chatter_rule() -> ChatterRule {
    SolverOptions::default().chatter()
}

/// What moves the plate (`shaker_mode`, an Enumeration in the model description).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ShakerMode {
    /// `ż = V cos(Ωτ)` from the parameters.
    Internal = 1,
    /// From the inputs `z_in`, `zdot_in` and their derivatives.
    External = 2,
}

impl ShakerMode {
    /// From the variable's value (range-checked at the boundary).
    pub fn of(value: f64) -> Option<Self> {
        match value {
            1.0 => Some(Self::Internal),
            2.0 => Some(Self::External),
            _ => None,
        }
    }
}

/// Conversions between SI and the core's units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Scale {
    /// `ω0` (rad/s).
    pub omega0: f64,
    /// `Δx` (m).
    pub dx: f64,
    /// Mass (kg), for energies only.
    pub mass: f64,
}

impl Scale {
    /// From the parameter values.
    pub fn of(values: &[f64]) -> Self {
        Self {
            omega0: values[var::omega0],
            dx: values[var::delta_x],
            mass: values[var::mass],
        }
    }

    /// `τ` of the SI time `t` (s).
    pub fn tau(&self, t: f64) -> f64 {
        t * self.omega0
    }

    /// SI time (s) of `τ`.
    pub fn time(&self, tau: f64) -> f64 {
        tau / self.omega0
    }

    /// Length (m).
    pub fn length(&self, x: f64) -> f64 {
        x * self.dx
    }

    /// Velocity (m/s).
    pub fn velocity(&self, v: f64) -> f64 {
        v * (self.omega0 * self.dx)
    }

    /// Acceleration (m/s²).
    pub fn acceleration(&self, a: f64) -> f64 {
        a * (self.omega0 * self.omega0 * self.dx)
    }

    /// Energy (J).
    pub fn energy(&self, e: f64) -> f64 {
        e * (self.mass * self.omega0 * self.omega0 * self.dx * self.dx)
    }

    /// Nondimensional Taylor coefficient `z_k` of the SI plate derivative `d^k ẑ/dt^k`.
    pub fn plate_coefficient(&self, k: usize, d: f64) -> f64 {
        let mut c = d / self.dx;
        for j in 1..=k {
            c /= self.omega0 * j as f64;
        }
        c
    }
}

/// Plate derivatives for the next step (SI, order 0..=5); `None`: not given (zero above order 1).
pub type PlateInputs = [Option<f64>; MAX_PLATE_ORDER + 1];

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
}

/// Why a step stopped short.
pub enum StepFailure {
    /// The model cannot go on (Zeno sequence, overflow): report `fmi2Discard` and terminate.
    Stopped(String),
    /// A refused request (bad plate data, time mismatch): report `fmi2Error`.
    Refused(String),
}

/// Renames the core's parameter names to the FMU's variable names.
fn fmu_name(core: &str) -> &str {
    match core {
        "restitution" => "e",
        "omega" => "Omega",
        "velocity" => "V",
        other => other,
    }
}

/// A core parameter error in the FMU's words.
pub fn describe_param(e: &ParamError) -> String {
    format!("invalid {} = {}: {}", fmu_name(e.name), e.value, e.rule)
}

/// A core error in the FMU's words (SI times).
fn describe(e: &SimError, scale: &Scale) -> String {
    match e {
        SimError::Param(p) => describe_param(p),
        SimError::Zeno { t, impacts } => format!(
            "chatter did not end after {impacts} impacts at t = {} s and the contact force pulls the mass off the plate (Zeno guard)",
            scale.time(*t)
        ),
        SimError::NonFinite { t } => format!(
            "the solution is no longer finite at t = {} s: parameters outside the model's scope",
            scale.time(*t)
        ),
        other => other.to_string(),
    }
}

impl Model {
    /// Builds the model at `t_start` (s) from the variable values and processes the events at
    /// the start instant (with the paper's initial condition: impact 0), reporting them to
    /// `events`.
    pub fn start(
        values: &[f64],
        inputs: &PlateInputs,
        t_start: f64,
        events: &mut Vec<Event>,
    ) -> Result<Self, String> {
        let scale = Scale::of(values);
        let mode = ShakerMode::of(values[var::shaker_mode])
            .ok_or_else(|| format!("invalid shaker_mode = {}", values[var::shaker_mode]))?;
        let params =
            Params::new(values[var::zeta], values[var::e]).map_err(|e| describe_param(&e))?;
        let opts =
            SolverOptions::new(values[var::tol], chatter_rule()).map_err(|e| describe_param(&e))?;
        let (omega, v) = (values[var::Omega], values[var::V]);
        let tau0 = scale.tau(t_start);
        if !tau0.is_finite() {
            return Err(format!("start time {t_start} s times omega0 is not finite"));
        }
        let origin = Instant::new(tau0);
        let phase_ref = Sinusoid::new(omega, v)
            .and_then(|s| s.with_origin(origin, 0.0, 0.0))
            .map_err(|e| describe_param(&e))?;
        let plate: PlateMotion = match mode {
            ShakerMode::Internal => phase_ref.into(),
            // Only its start matters: every step replaces it with a piece over the step.
            ShakerMode::External => plate_piece(&scale, origin, tau0 + 1.0, inputs, None)?.into(),
        };
        let x0 = values[var::x0] / scale.dx;
        let v0 = values[var::v0] / (scale.omega0 * scale.dx);
        let mut sim = Simulator::with_state(params, plate, opts, tau0, x0, v0).map_err(|e| match e {
            SimError::Param(p) if p.name == "x0" => format!(
                "x0 = {} m is below the plate position z = {} m at the start time: the mass must start on or above the plate",
                values[var::x0],
                scale.length(plate.motion(origin).0)
            ),
            other => describe(&other, &scale),
        })?;
        sim.advance_to(tau0, &mut |e: &Event| events.push(*e))
            .map_err(|e| describe(&e, &scale))?;
        Ok(Self {
            sim,
            scale,
            mode,
            phase_ref,
            applied: (omega, v),
            time: t_start,
        })
    }

    /// Rebuilds a model from its saved parts (see `state.rs`).
    pub fn restore(values: &[f64], saved: &SavedModel) -> Result<Self, String> {
        let scale = Scale::of(values);
        let sim =
            Simulator::from_checkpoint(&saved.checkpoint).map_err(|e| describe(&e, &scale))?;
        let (omega, v, hi, lo, phase0, offset) = saved.phase_ref;
        let origin = Instant::from_parts(hi, lo).ok_or("invalid phase origin in the FMU state")?;
        let phase_ref = Sinusoid::new(omega, v)
            .and_then(|s| s.with_origin(origin, phase0, offset))
            .map_err(|e| describe_param(&e))?;
        let mode = ShakerMode::of(values[var::shaker_mode])
            .ok_or("invalid shaker_mode in the FMU state")?;
        if !saved.time.is_finite() {
            return Err("invalid time in the FMU state".into());
        }
        Ok(Self {
            sim,
            scale,
            mode,
            phase_ref,
            applied: saved.applied,
            time: saved.time,
        })
    }

    /// The parts to save (pointer-free).
    pub fn save(&self) -> SavedModel {
        let (origin, phase0, offset) = self.phase_ref.origin();
        let (hi, lo) = origin.parts();
        SavedModel {
            checkpoint: self.sim.checkpoint(),
            phase_ref: (
                self.phase_ref.omega(),
                self.phase_ref.velocity(),
                hi,
                lo,
                phase0,
                offset,
            ),
            applied: self.applied,
            time: self.time,
        }
    }

    /// Integrates from the current time to exactly `t_end` (s), continuing the trajectory (no
    /// restart) unless the plate changes: a tunable `Omega`/`V` change, or, in external mode, the
    /// piece built from the inputs. Events go to `events`.
    pub fn step(
        &mut self,
        t_end: f64,
        values: &[f64],
        inputs: &PlateInputs,
        events: &mut Vec<Event>,
    ) -> Result<(), StepFailure> {
        let tau_end = self.scale.tau(t_end);
        let now = self.sim.instant();
        let refuse = |e: &SimError, s: &Scale| StepFailure::Refused(describe(e, s));
        let wanted = (values[var::Omega], values[var::V]);
        if wanted != self.applied {
            let (omega, v) = wanted;
            self.phase_ref = PlateMotion::from(self.phase_ref)
                .continued_by_sinusoid(now, omega, v)
                .map_err(|e| StepFailure::Refused(describe_param(&e)))?;
            if self.mode == ShakerMode::Internal {
                self.sim
                    .set_sinusoid(omega, v)
                    .map_err(|e| refuse(&e, &self.scale))?;
            }
            self.applied = wanted;
        }
        if self.mode == ShakerMode::External {
            let z_now = self.sim.state().z;
            let piece = plate_piece(&self.scale, now, tau_end, inputs, Some(z_now))
                .map_err(StepFailure::Refused)?;
            self.sim
                .set_plate(piece.into())
                .map_err(|e| refuse(&e, &self.scale))?;
        }
        let result = self
            .sim
            .advance_to(tau_end, &mut |e: &Event| events.push(*e));
        match result {
            Ok(()) => {
                self.time = t_end;
                Ok(())
            }
            Err(e @ (SimError::Zeno { .. } | SimError::NonFinite { .. })) => {
                self.time = self.scale.time(self.sim.time());
                Err(StepFailure::Stopped(describe(&e, &self.scale)))
            }
            Err(e) => Err(refuse(&e, &self.scale)),
        }
    }

    /// Impact phase in cycles: the core's in internal mode, else from the reference sinusoid.
    pub fn phase_of(&self, t: f64, core_phase: Option<f64>) -> f64 {
        core_phase.unwrap_or_else(|| self.phase_ref.phase_cycles(Instant::new(t)))
    }

    /// Writes every output variable into `values`.
    pub fn write_outputs(&self, values: &mut [f64]) {
        let s = &self.scale;
        let st = self.sim.state();
        let stats = self.sim.stats();
        let count = |n: u64| n.min(i32::MAX as u64) as f64;
        values[var::x] = s.length(st.x);
        values[var::v] = s.velocity(st.v);
        values[var::z] = s.length(st.z);
        values[var::zdot] = s.velocity(st.zdot);
        values[var::kinetic_energy] = s.energy(st.kinetic_energy());
        values[var::potential_energy] = s.energy(st.potential_energy());
        values[var::impact_count] = count(stats.impacts);
        values[var::snap_through_count] = count(stats.snap_throughs);
        values[var::well] = f64::from(st.well.number());
        values[var::in_contact] = f64::from(u8::from(st.mode == ContactMode::Sticking));
        let (t, phase, vb, va, dk) = match self.sim.last_impact() {
            Some(i) => (
                s.time(i.t),
                self.phase_of(i.t, i.phase),
                s.velocity(i.v_before),
                s.velocity(i.v_after),
                s.energy(i.delta_k),
            ),
            None => (0.0, 0.0, 0.0, 0.0, 0.0),
        };
        values[var::last_impact_time] = t;
        values[var::last_impact_phase] = phase;
        values[var::last_impact_v_before] = vb;
        values[var::last_impact_v_after] = va;
        values[var::last_impact_delta_k] = dk;
    }

    /// First time derivative (SI) of the output `index`, for `x`, `v`, `z`, `zdot`.
    pub fn output_derivative(&self, index: usize) -> Option<f64> {
        let s = &self.scale;
        let st = self.sim.state();
        let zdd = self.sim.plate().motion(self.sim.instant()).2;
        let a = match st.mode {
            ContactMode::Sticking => zdd,
            ContactMode::Free => -2.0 * self.sim.params().zeta() * st.v - potential::force(st.x),
        };
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
        let s = &self.scale;
        match *e {
            Event::Impact(i) => format!(
                "impact {} at t={:.17e} s phase={:.17e} x={:.17e} m v_before={:.17e} m/s v_after={:.17e} m/s",
                i.index,
                s.time(i.t),
                self.phase_of(i.t, i.phase),
                s.length(i.x),
                s.velocity(i.v_before),
                s.velocity(i.v_after)
            ),
            Event::StickStart { t, x, cause, .. } => format!(
                "stick start at t={:.17e} s x={:.17e} m ({cause:?})",
                s.time(t),
                s.length(x)
            ),
            Event::StickEnd { t, x, .. } => format!(
                "stick end at t={:.17e} s x={:.17e} m",
                s.time(t),
                s.length(x)
            ),
            Event::SnapThrough { t, to, .. } => format!(
                "snap-through to well {} at t={:.17e} s",
                to.number(),
                s.time(t)
            ),
        }
    }
}

/// The parts of a [`Model`] an FMU state keeps (plain numbers).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SavedModel {
    /// Core checkpoint.
    pub checkpoint: Checkpoint,
    /// Phase reference: `Ω`, `V`, origin `(hi, lo)`, phase at origin (rad), offset.
    pub phase_ref: (f64, f64, f64, f64, f64, f64),
    /// `(Ω, V)` in force.
    pub applied: (f64, f64),
    /// Communication time (s).
    pub time: f64,
}

/// The plate over `[start, end]` (τ) from the inputs: their Taylor polynomial at the step start
/// (`canInterpolateInputs`), plus a blend `δ(1 − 3σ² + 2σ³)`, `σ = (τ − start)/(end − start)`,
/// that removes the difference `δ = z_now − z_in` between where the plate is and where the
/// inputs put it. The plate position stays continuous (the core refuses jumps) and reaches the
/// inputs' extrapolation by the end of the step; `δ` is zero for inputs that extrapolate exactly.
/// `z_now = None`: the plate starts at `z_in` (initialization).
fn plate_piece(
    scale: &Scale,
    start: Instant,
    end: f64,
    inputs: &PlateInputs,
    z_now: Option<f64>,
) -> Result<PolyPiece, String> {
    let mut c = [0.0; MAX_PLATE_ORDER + 1];
    for (k, (ck, d)) in c.iter_mut().zip(inputs).enumerate() {
        *ck = scale.plate_coefficient(k, d.unwrap_or(0.0));
    }
    let len = Instant::new(end).since(start);
    if len.is_nan() || len <= 0.0 {
        return Err(format!(
            "the step must end after t = {} s",
            scale.time(start.to_f64())
        ));
    }
    let delta = z_now.map_or(0.0, |z| z - c[0]);
    if delta != 0.0 {
        c[0] += delta;
        c[2] -= 3.0 * delta / (len * len);
        c[3] += 2.0 * delta / (len * len * len);
    }
    if let Some(k) = c.iter().position(|v| !v.is_finite()) {
        return Err(format!(
            "the plate polynomial from the inputs is not finite (coefficient of order {k}); inputs z_in, zdot_in and their derivatives must be finite and moderate"
        ));
    }
    PolyPiece::new(start, Instant::new(end), &c).map_err(|e| describe_param(&e))
}
