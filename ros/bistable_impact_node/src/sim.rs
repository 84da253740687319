//! The simulation side of the node, free of DDS: advances the core simulator from one publish
//! tick to the next, turns its events into [`ImpactEvent`]s at their located times, schedules
//! shaker commands, and converts everything to SI units (`model.md` Sec. 6:
//! `x̂ = Δx·x`, `t̂ = τ/ω0`, velocities `ω0·Δx·v`, specific energies `(ω0·Δx)²·E`).
//!
//! Shaker commands take effect at `max(stamp, now, end of the queued commands)` (SI seconds of
//! simulation time, a zero stamp meaning "now"), where "now" is the time of the last published
//! state: the node applies commands between publish ticks. A sinusoid set-point starts a
//! [`SetpointRamp`] of [`RAMP_CYCLES`] periods of the new frequency: plate position and
//! velocity stay continuous and the plate ends on `(V/Ω) sin(·)` about the initial sinusoid's
//! centre, whatever came before. An external sample `(z, ż)` at time
//! `t1` makes the plate follow the cubic Hermite curve from its position and velocity at the
//! start of the piece to `(z, ż)` at `t1`; the simulation then waits at `t1` for the next
//! sample or command. Plate position is therefore always continuous.

use std::collections::VecDeque;

use bistable_analysis::event_log::{EventLog, Row};
use bistable_core::units::Scale;
use bistable_core::{
    ChatterRule, ContactMode, Event, Impact, Instant, Params, PlateMotion, PolyPiece, SetpointRamp,
    SimError, Simulator, Sinusoid, SolverOptions, MAX_VELOCITY, OMEGA_RANGE,
};

use crate::inbox::num;
use crate::msg::{Header, ImpactEvent, MassState, ShakerCommand, Time};
use crate::params::Settings;

/// Most shaker commands waiting for their instant.
pub const MAX_QUEUED_COMMANDS: usize = 1024;
/// Length of a set-point ramp [periods of the new shaker frequency].
pub const RAMP_CYCLES: f64 = 2.0;
/// Largest accepted nondimensional plate position, velocity or displacement amplitude `V/Ω` in a
/// command, and mass position or velocity in a reset (the model is meaningful for values of
/// order one; far larger ones only overflow the integrator). `Ω` and `V` have the core's ranges
/// ([`OMEGA_RANGE`], [`MAX_VELOCITY`]).
pub const MAX_NONDIMENSIONAL: f64 = 1e6;

/// The rule for the fields a mode does not use: they must be zero (so that a command meant
/// for the other mode, or a field set by mistake, is refused rather than half applied).
fn unused_zero(fields: &[(&str, f64)], mode: &str) -> Result<(), String> {
    match fields.iter().find(|(_, v)| *v != 0.0) {
        Some((name, v)) => Err(format!(
            "{name} = {} is not used by {mode} and must be 0",
            num(*v)
        )),
        None => Ok(()),
    }
}

/// A command waiting for its instant (times in SI seconds, values nondimensional).
#[derive(Debug, Clone, Copy, PartialEq)]
enum Scheduled {
    /// Switch to the sinusoid `Ω`, `V` at `at`.
    Sinusoid { at: f64, omega: f64, v: f64 },
    /// From `start`, follow a Hermite cubic to `(z, zd)` at `end`.
    Sample {
        start: f64,
        end: f64,
        z: f64,
        zd: f64,
    },
}

impl Scheduled {
    fn start(&self) -> f64 {
        match *self {
            Scheduled::Sinusoid { at, .. } => at,
            Scheduled::Sample { start, .. } => start,
        }
    }

    fn end(&self) -> f64 {
        match *self {
            Scheduled::Sinusoid { at, .. } => at,
            Scheduled::Sample { end, .. } => end,
        }
    }
}

/// What one call of [`Runner::advance`] did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Outcome {
    /// Reached a publish tick: publish the state and the clock.
    Tick,
    /// Stopped at the instant of a queued command (applied by the next call) or at the end of
    /// a piece of a set-point ramp.
    Command,
    /// The plate follows external samples and the last one is reached: waiting for more.
    Blocked,
    /// The simulation stopped on an error (see [`Runner::halted`]).
    Halted,
}

/// The simulation with its publish schedule and command queue.
pub struct Runner {
    sim: Simulator,
    /// `omega0` and `delta_x`; energies are published per unit mass (no mass: NaN).
    scale: Scale,
    frame_id: String,
    rate: f64,
    tick_origin: f64,
    tick_k: u64,
    queue: VecDeque<Scheduled>,
    /// SI end of the external piece the plate follows now.
    piece_end: Option<f64>,
    /// The set-point ramp the plate follows now.
    ramp: Option<SetpointRamp>,
    /// Centre of the shaker's sinusoids (the initial one's), nondimensional.
    centre: f64,
    /// Turns events into impacts, each held until it is known whether sticking follows it
    /// (for as long after it as sticking can start).
    log: EventLog,
    events: Vec<Event>,
    notes: Vec<String>,
    halted: Option<String>,
    /// Accepted commands the core could not apply when they became due.
    dropped: u64,
}

impl Runner {
    /// The paper's initial condition (mass at rest at `x = 0`, impact 0 at `t = 0`) with the
    /// shaker `Ω`, `V` of `settings`.
    pub fn new(settings: &Settings) -> Result<Self, String> {
        let params = Params::new(settings.zeta, settings.e).map_err(|e| e.to_string())?;
        let plate = Sinusoid::new(settings.omega, settings.v).map_err(|e| e.to_string())?;
        let opts = SolverOptions::default();
        let lookahead = match opts.chatter() {
            ChatterRule::Accumulation { horizon } => 2.0 * horizon,
            ChatterRule::FixedGap { .. } => 0.0,
        };
        let sim = Simulator::new(params, plate.into(), opts).map_err(|e| e.to_string())?;
        Ok(Self {
            sim,
            scale: Scale {
                omega0: settings.omega0,
                dx: settings.delta_x,
                mass: f64::NAN,
            },
            frame_id: settings.frame_id.clone(),
            rate: settings.publish_rate,
            tick_origin: 0.0,
            tick_k: 0,
            queue: VecDeque::new(),
            piece_end: None,
            ramp: None,
            centre: plate.origin().2,
            log: EventLog::with_lookahead(lookahead),
            events: Vec::new(),
            notes: Vec::new(),
            halted: None,
            dropped: 0,
        })
    }

    /// Restarts the simulation at time 0 with the mass at `x` \[m\] moving at `v` \[m/s\] (the
    /// paper's initial condition, `x = v = 0`, when `state` is `None`), the initial shaker
    /// sinusoid (`Omega`, `V` of `settings`) and the current `zeta`, `e`: impact indices restart
    /// at 0, queued commands and any ramp or external motion are discarded, ticks restart at 0.
    /// The last impact of the run before, if held back to learn whether sticking follows it, is
    /// appended to `impacts` first (its run ended without sticking). Refused, with nothing
    /// changed, for a non-finite or out-of-range value or a mass below the plate.
    pub fn reset(
        &mut self,
        settings: &Settings,
        state: Option<(f64, f64)>,
        impacts: &mut Vec<ImpactEvent>,
    ) -> Result<String, String> {
        let (x, v) = state.unwrap_or((0.0, 0.0));
        for (name, value) in [("x", x), ("v", v)] {
            if !value.is_finite() {
                return Err(format!("{name} = {} is not finite", num(value)));
            }
        }
        let (xn, vn) = (self.scale.of_length(x), self.scale.of_velocity(v));
        if xn.abs() > MAX_NONDIMENSIONAL || vn.abs() > MAX_NONDIMENSIONAL {
            return Err(format!(
                "x = {} m or v = {} m/s is out of range (at most {MAX_NONDIMENSIONAL:e} delta_x \
                 and omega0·delta_x)",
                num(x),
                num(v)
            ));
        }
        let params = Params::new(settings.zeta, settings.e).map_err(|e| e.to_string())?;
        let plate = Sinusoid::new(settings.omega, settings.v).map_err(|e| e.to_string())?;
        let motion: PlateMotion = plate.into();
        let z0 = motion.motion(Instant::new(0.0)).0;
        if xn < z0 {
            return Err(format!(
                "x = {} m is below the plate, which is at z = {} m at time 0",
                num(x),
                num(self.scale.length(z0))
            ));
        }
        let sim = Simulator::with_state(params, motion, SolverOptions::default(), 0.0, xn, vn)
            .map_err(|e| e.to_string())?;
        self.log.finish();
        self.collect_rows(impacts);
        self.sim = sim;
        self.tick_origin = 0.0;
        self.tick_k = 0;
        self.queue.clear();
        self.piece_end = None;
        self.ramp = None;
        self.centre = plate.origin().2;
        self.events.clear();
        self.halted = None;
        Ok(format!(
            "simulation reset to t = 0 s, x = {} m, v = {} m/s (shaker Omega = {}, V = {}; \
             impact indices restart at 0)",
            num(x),
            num(v),
            num(settings.omega),
            num(settings.v)
        ))
    }

    /// Current simulation time \[s\].
    pub fn now(&self) -> f64 {
        self.scale.time(self.sim.time())
    }

    /// Impacts located so far.
    pub fn impact_count(&self) -> u64 {
        self.sim.stats().impacts
    }

    /// Accepted commands dropped when they became due, because the core could not continue
    /// the plate motion with them (logged as notes).
    pub fn commands_dropped(&self) -> u64 {
        self.dropped
    }

    /// The error that stopped the simulation, if any.
    pub fn halted(&self) -> Option<&str> {
        self.halted.as_deref()
    }

    /// Messages about applied or dropped commands since the last call, for the log.
    pub fn take_notes(&mut self) -> Vec<String> {
        std::mem::take(&mut self.notes)
    }

    /// Publish rate [Hz of simulation time]; ticks restart from the current time.
    pub fn set_rate(&mut self, rate: f64) {
        self.rate = rate;
        self.tick_origin = self.now();
        self.tick_k = 0;
    }

    /// Frame of the published headers.
    pub fn set_frame_id(&mut self, frame_id: &str) {
        frame_id.clone_into(&mut self.frame_id);
    }

    /// Changes `ζ` and `e` from the current time on (the integration restarts here).
    pub fn set_params(&mut self, zeta: f64, e: f64) -> Result<(), String> {
        Params::new(zeta, e).map_err(|err| err.to_string())?;
        let plate = *self.sim.plate();
        let mut sim = self.sim.clone();
        sim.set_plate(plate).map_err(|err| err.to_string())?;
        let mut c = sim.checkpoint();
        c.zeta = zeta;
        c.restitution = e;
        self.sim = Simulator::from_checkpoint(&c).map_err(|err| err.to_string())?;
        self.halted = None;
        Ok(())
    }

    /// Validates a shaker command and queues it; returns what was scheduled, or why the
    /// command is refused (then nothing changes).
    pub fn command(&mut self, cmd: &ShakerCommand) -> Result<String, String> {
        let stamp = cmd.header.stamp;
        if stamp.sec < 0 || stamp.nanosec >= 1_000_000_000 {
            return Err(format!(
                "invalid stamp {}.{:09}: sec must be >= 0 and nanosec < 1e9",
                stamp.sec, stamp.nanosec
            ));
        }
        for (name, value) in [
            ("omega", cmd.omega),
            ("velocity", cmd.velocity),
            ("z", cmd.z),
            ("zdot", cmd.zdot),
        ] {
            if !value.is_finite() {
                return Err(format!("{name} = {} is not finite", num(value)));
            }
        }
        if self.queue.len() >= MAX_QUEUED_COMMANDS {
            return Err(format!(
                "{MAX_QUEUED_COMMANDS} commands are already waiting for their instant"
            ));
        }
        let (frontier, external) = self.frontier();
        let item = match cmd.mode {
            ShakerCommand::MODE_SINUSOID => {
                unused_zero(&[("z", cmd.z), ("zdot", cmd.zdot)], "MODE_SINUSOID")?;
                let omega = self.scale.of_frequency(cmd.omega);
                let v = self.scale.of_velocity(cmd.velocity);
                // The core's ranges (`Sinusoid::new`), refused here, before the command waits.
                if !OMEGA_RANGE.contains(&omega) {
                    return Err(format!(
                        "omega = {} rad/s must be in [{:e}, {:e}]·omega0",
                        num(cmd.omega),
                        OMEGA_RANGE.start(),
                        OMEGA_RANGE.end()
                    ));
                }
                // The sign of the value sent: a tiny negative one may scale to −0.
                if !(cmd.velocity >= 0.0 && v <= MAX_VELOCITY) {
                    return Err(format!(
                        "velocity = {} m/s must be >= 0 and at most {MAX_VELOCITY:e}·omega0·delta_x",
                        num(cmd.velocity)
                    ));
                }
                // The plate's displacement amplitude V/Ω (an overflow for a tiny Ω) must be in
                // range too, or the plate position could not be continued.
                if v / omega > MAX_NONDIMENSIONAL {
                    return Err(format!(
                        "velocity/omega = {} m (the plate's displacement amplitude) must be at \
                         most {MAX_NONDIMENSIONAL:e}·delta_x",
                        num(cmd.velocity / cmd.omega)
                    ));
                }
                // After external motion the sinusoid takes over where the samples end, so that
                // the plate motion stays defined.
                let at = if external || stamp.is_zero() {
                    frontier
                } else {
                    stamp.to_seconds().max(frontier)
                };
                Scheduled::Sinusoid { at, omega, v }
            }
            ShakerCommand::MODE_EXTERNAL => {
                unused_zero(
                    &[("omega", cmd.omega), ("velocity", cmd.velocity)],
                    "MODE_EXTERNAL",
                )?;
                let z = self.scale.of_length(cmd.z);
                let zd = self.scale.of_velocity(cmd.zdot);
                if z.abs() > MAX_NONDIMENSIONAL || zd.abs() > MAX_NONDIMENSIONAL {
                    return Err(format!(
                        "z = {} m or zdot = {} m/s is out of range (at most {MAX_NONDIMENSIONAL:e} \
                         delta_x and omega0·delta_x)",
                        num(cmd.z),
                        num(cmd.zdot)
                    ));
                }
                let end = if stamp.is_zero() {
                    frontier + 1.0 / self.rate
                } else {
                    stamp.to_seconds()
                };
                if self.scale.tau(end) <= self.scale.tau(frontier) {
                    return Err(format!(
                        "sample time {end} s is not after {frontier} s (the current simulation \
                         time or the end of the queued commands)"
                    ));
                }
                Scheduled::Sample {
                    start: frontier,
                    end,
                    z,
                    zd,
                }
            }
            other => {
                return Err(format!(
                    "unknown mode {other} (MODE_SINUSOID = 0, MODE_EXTERNAL = 1)"
                ))
            }
        };
        self.queue.push_back(item);
        // A command due now takes effect at once (as the next `advance` would do first), so
        // that commands for "now" never fill the queue, however many arrive between steps.
        self.apply_due();
        Ok(match item {
            Scheduled::Sinusoid { at, .. } => format!(
                "shaker sinusoid omega = {} rad/s, velocity = {} m/s from t = {at} s",
                num(cmd.omega),
                num(cmd.velocity)
            ),
            Scheduled::Sample { start, end, .. } => format!(
                "external plate sample z = {} m, zdot = {} m/s at t = {end} s (from t = {start} s)",
                num(cmd.z),
                num(cmd.zdot)
            ),
        })
    }

    /// The instant from which a new command can act \[s\], and whether the plate follows
    /// external samples there.
    fn frontier(&self) -> (f64, bool) {
        let mut frontier = self.now();
        let mut external = false;
        if let Some(end) = self.piece_end {
            frontier = frontier.max(end);
            external = true;
        }
        if let Some(last) = self.queue.back() {
            frontier = frontier.max(last.end());
            external = matches!(last, Scheduled::Sample { .. });
        }
        (frontier, external)
    }

    /// Applies the queued commands whose instant has come.
    fn apply_due(&mut self) {
        while let Some(&item) = self.queue.front() {
            if self.scale.tau(item.start()) > self.sim.time() {
                break;
            }
            self.queue.pop_front();
            let t = self.now();
            let result = match item {
                Scheduled::Sinusoid { omega, v, .. } => {
                    SetpointRamp::start(&mut self.sim, self.centre, omega, v, RAMP_CYCLES).map(
                        |ramp| {
                            self.piece_end = None;
                            self.ramp = Some(ramp);
                            format!(
                                "shaker sinusoid ramp from t = {t} s to t = {} s",
                                self.scale.time(ramp.end().to_f64())
                            )
                        },
                    )
                }
                Scheduled::Sample { end, z, zd, .. } => self.follow_sample(end, z, zd).map(|()| {
                    self.piece_end = Some(end);
                    self.ramp = None;
                    format!("external plate motion to t = {end} s applied at t = {t} s")
                }),
            };
            match result {
                Ok(note) => {
                    self.halted = None;
                    self.notes.push(note);
                }
                Err(e) => {
                    self.dropped += 1;
                    self.notes
                        .push(format!("shaker command dropped at t = {t} s: {e}"));
                }
            }
        }
    }

    fn follow_sample(&mut self, end: f64, z: f64, zd: f64) -> Result<(), SimError> {
        let now = self.sim.state();
        let piece = PolyPiece::hermite(
            self.sim.instant(),
            Instant::new(self.scale.tau(end)),
            (now.z, now.zdot),
            (z, zd),
        )?;
        self.sim.set_plate(piece.into())
    }

    fn next_tick(&self) -> f64 {
        self.tick_origin + (self.tick_k + 1) as f64 / self.rate
    }

    /// Advances to the next publish tick, or to the instant of the next queued command, or to
    /// the end of the external plate motion, whichever comes first; appends the impacts that
    /// are complete (their sticking flag known) to `impacts`, in order.
    pub fn advance(&mut self, impacts: &mut Vec<ImpactEvent>) -> Outcome {
        self.apply_due();
        if let Some(ramp) = self.ramp {
            match ramp.follow(&mut self.sim) {
                Ok(true) => {}
                Ok(false) => self.ramp = None,
                Err(e) => self.halt(&e),
            }
        }
        if self.halted.is_some() {
            return Outcome::Halted;
        }
        let now = self.sim.time();
        let mut target = self.scale.tau(self.next_tick());
        let mut outcome = Outcome::Tick;
        if let Some(item) = self.queue.front() {
            let start = self.scale.tau(item.start());
            if start < target {
                target = start;
                outcome = Outcome::Command;
            }
        }
        if let Some(h) = self.sim.plate().horizon() {
            let h = h.to_f64();
            if h < target {
                target = h;
                outcome = if self.ramp.is_some() {
                    Outcome::Command
                } else {
                    Outcome::Blocked
                };
            }
        }
        if outcome == Outcome::Blocked && target <= now {
            return Outcome::Blocked;
        }
        let events = &mut self.events;
        let result = self
            .sim
            .advance_to(target, &mut |e: &Event| events.push(*e));
        self.collect(impacts);
        if let Err(e) = result {
            self.halt(&e);
            return Outcome::Halted;
        }
        if outcome == Outcome::Tick {
            self.tick_k += 1;
        }
        outcome
    }

    fn halt(&mut self, e: &SimError) {
        self.halted = Some(format!(
            "simulation stopped at t = {} s: {e}; it resumes after a parameter change or shaker \
             command that lets it go on",
            self.now()
        ));
    }

    /// Turns the collected events into complete impacts.
    fn collect(&mut self, out: &mut Vec<ImpactEvent>) {
        for mut e in std::mem::take(&mut self.events).drain(..) {
            // On a ramp's pieces the shaker phase is the ramp's.
            if let (Event::Impact(i), Some(ramp)) = (&mut e, &self.ramp) {
                i.phase = ramp.impact_phase(i);
            }
            self.log.record(&e);
        }
        self.log.settle(self.sim.time());
        self.collect_rows(out);
    }

    /// Appends the impacts the log has completed.
    fn collect_rows(&mut self, out: &mut Vec<ImpactEvent>) {
        let rows: Vec<Row> = self.log.rows().collect();
        for row in rows {
            if let Row::Impact(r) = row {
                out.push(self.impact_msg(&r.impact, r.ended_in_sticking));
            }
        }
    }

    fn header(&self, t: f64) -> Header {
        Header {
            stamp: Time::from_seconds(t),
            frame_id: self.frame_id.clone(),
        }
    }

    fn impact_msg(&self, i: &Impact, ended_in_sticking: bool) -> ImpactEvent {
        let sc = self.scale;
        let t = sc.time(i.t);
        ImpactEvent {
            header: self.header(t),
            index: i.index,
            t,
            phase: i.phase.unwrap_or(f64::NAN),
            x: sc.length(i.x),
            v_before: sc.velocity(i.v_before),
            v_after: sc.velocity(i.v_after),
            zdot: sc.velocity(i.zdot),
            delta_k: sc.specific_energy(i.delta_k),
            ended_in_sticking,
        }
    }

    /// The state at the current time, in SI units.
    pub fn state(&self) -> MassState {
        let sc = self.scale;
        let s = self.sim.state();
        let t = sc.time(s.t);
        // During a ramp: its target set-point.
        let sinusoid = match (self.sim.plate(), &self.ramp) {
            (PlateMotion::Sinusoid(p), _) => Some(*p),
            (PlateMotion::Poly(_), Some(ramp)) => Some(ramp.target()),
            (PlateMotion::Poly(_), None) => None,
        };
        let (mode, omega, velocity) = match sinusoid {
            Some(p) => (
                ShakerCommand::MODE_SINUSOID,
                sc.frequency(p.omega()),
                // The amplitude as it always was, `(V·ω0)·Δx` (not `V·(ω0Δx)`).
                p.velocity() * sc.omega0 * sc.dx,
            ),
            None => (ShakerCommand::MODE_EXTERNAL, f64::NAN, f64::NAN),
        };
        MassState {
            header: self.header(t),
            t,
            x: sc.length(s.x),
            v: sc.velocity(s.v),
            z: sc.length(s.z),
            zdot: sc.velocity(s.zdot),
            kinetic_energy: sc.specific_energy(s.kinetic_energy()),
            potential_energy: sc.specific_energy(s.potential_energy()),
            well: s.well.number(),
            in_contact: s.mode == ContactMode::Sticking,
            impact_count: self.sim.stats().impacts,
            shaker_mode: mode,
            shaker_omega: omega,
            shaker_velocity: velocity,
        }
    }
}
