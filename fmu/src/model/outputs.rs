//! The output variables, the state derivatives and the event indicators (SI) from a
//! nondimensional state, for both interfaces; sets of variables (`VarSet`).

use bistable_core::{potential, ContactMode, Impact, Params, Sinusoid, State, Well};

use super::si::{phase_of, Scale};
use crate::md::var;

/// Acceleration of the mass (nondimensional) in the state `st` with plate acceleration `zdd`:
/// the plate's while riding it, else free flight (Eq. 4).
pub fn mass_acceleration(params: &Params, st: &State, zdd: f64) -> f64 {
    match st.mode {
        ContactMode::Sticking => zdd,
        ContactMode::Free => params.flight_acceleration(st.x, st.v),
    }
}

/// A set of variables: bit `i` stands for `VARS[i]` (the model has fewer than 64).
pub(crate) type VarSet = u64;

/// The set holding only variable `i`.
pub(crate) const fn bit(i: usize) -> VarSet {
    1 << i
}

/// Every variable.
pub(crate) const ALL: VarSet = !0;

/// The mass's position and velocity.
pub(crate) const XV: VarSet = bit(var::x) | bit(var::v);

/// Mass position and velocity, contact mode and well now (nondimensional).
pub type Mass = (f64, f64, ContactMode, Well);

/// Plate position, velocity and acceleration now (nondimensional).
pub type Plate = (f64, f64, f64);

/// What the outputs are computed from (nondimensional), for both interfaces. The mass and the
/// plate are evaluated on demand, each at most once per [`Observed::write`]: a read of `x` and
/// `v` in free flight evaluates the step's series only, not the plate's sinusoid.
pub struct Observed<'a, M: Fn() -> Mass, P: Fn() -> Plate> {
    /// Model parameters.
    pub params: &'a Params,
    /// Time now (`τ`).
    pub tau: f64,
    /// The mass now.
    pub mass: M,
    /// The plate now.
    pub plate: P,
    /// Impacts so far.
    pub impacts: u64,
    /// Snap-throughs so far.
    pub snap_throughs: u64,
    /// The last impact.
    pub last_impact: Option<Impact>,
    /// Momentum per unit mass given to the plate (see [`Model::impulse`](super::Model::impulse)).
    pub impulse: f64,
}

/// `f()`, computed on the first call only.
fn once<T: Copy>(cache: &mut Option<T>, f: impl FnOnce() -> T) -> T {
    *cache.get_or_insert_with(f)
}

impl<M: Fn() -> Mass, P: Fn() -> Plate> Observed<'_, M, P> {
    /// Writes the variables of `want` among the outputs, the state derivatives `der_x`,
    /// `der_v`, the event indicators and `time` (SI); the others are left as they are.
    pub fn write(&self, s: &Scale, phase_ref: &Sinusoid, values: &mut [f64], want: VarSet) {
        let (mut mass_now, mut plate_now) = (None, None);
        let mut mass = || once(&mut mass_now, &self.mass);
        let mut plate = || once(&mut plate_now, &self.plate);
        let wants = |i: usize| want & bit(i) != 0;
        let count = |n: u64| n.min(i32::MAX as u64) as f64;
        if wants(var::time) {
            values[var::time] = s.time(self.tau);
        }
        if wants(var::x) {
            values[var::x] = s.length(mass().0);
        }
        if wants(var::v) {
            values[var::v] = s.velocity(mass().1);
        }
        if wants(var::der_x) {
            let riding = mass().2 == ContactMode::Sticking;
            values[var::der_x] = s.velocity(if riding { plate().1 } else { mass().1 });
        }
        if wants(var::der_v) {
            let (x, v, mode, _) = mass();
            let a = match mode {
                ContactMode::Sticking => plate().2,
                ContactMode::Free => self.params.flight_acceleration(x, v),
            };
            values[var::der_v] = s.acceleration(a);
        }
        if wants(var::z) {
            values[var::z] = s.length(plate().0);
        }
        if wants(var::zdot) {
            values[var::zdot] = s.velocity(plate().1);
        }
        if wants(var::kinetic_energy) {
            values[var::kinetic_energy] = s.energy(potential::kinetic(mass().1));
        }
        if wants(var::potential_energy) {
            values[var::potential_energy] = s.energy(potential::energy(mass().0));
        }
        if wants(var::impact_count) {
            values[var::impact_count] = count(self.impacts);
        }
        if wants(var::snap_through_count) {
            values[var::snap_through_count] = count(self.snap_throughs);
        }
        if wants(var::well) {
            values[var::well] = f64::from(mass().3.number());
        }
        if wants(var::in_contact) {
            values[var::in_contact] = f64::from(u8::from(mass().2 == ContactMode::Sticking));
        }
        const IMPACT: VarSet = bit(var::last_impact_time)
            | bit(var::last_impact_phase)
            | bit(var::last_impact_v_before)
            | bit(var::last_impact_v_after)
            | bit(var::last_impact_delta_k);
        if want & IMPACT != 0 {
            let (t, phase, vb, va, dk) = match &self.last_impact {
                Some(i) => (
                    s.time(i.t),
                    if wants(var::last_impact_phase) {
                        phase_of(phase_ref, i)
                    } else {
                        0.0
                    },
                    s.velocity(i.v_before),
                    s.velocity(i.v_after),
                    s.energy(i.delta_k),
                ),
                None => (0.0, 0.0, 0.0, 0.0, 0.0),
            };
            for (i, value) in [
                (var::last_impact_time, t),
                (var::last_impact_phase, phase),
                (var::last_impact_v_before, vb),
                (var::last_impact_v_after, va),
                (var::last_impact_delta_k, dk),
            ] {
                if wants(i) {
                    values[i] = value;
                }
            }
        }
        if wants(var::plate_impulse) {
            values[var::plate_impulse] = s.mass * s.velocity(self.impulse);
        }
        if wants(var::contact_indicator) {
            values[var::contact_indicator] = contact_indicator(self.params, s, mass(), plate());
        }
        if wants(var::barrier_indicator) {
            values[var::barrier_indicator] = s.length(mass().0 - potential::BARRIER);
        }
    }

    /// The event indicators (SI): the gap `x − z` (m) in free flight or the contact force per
    /// unit mass (m/s², Eq. 9) while sticking, and `x − Δx/2` (m).
    pub fn indicators(&self, s: &Scale) -> [f64; 2] {
        let mass = (self.mass)();
        [
            contact_indicator(self.params, s, mass, (self.plate)()),
            s.length(mass.0 - potential::BARRIER),
        ]
    }
}

/// The contact indicator (SI) of the mass and the plate: the gap `x − z` (m) in free flight or
/// the contact force per unit mass (m/s², Eq. 9) while sticking.
fn contact_indicator(params: &Params, s: &Scale, mass: Mass, (z, zdot, zddot): Plate) -> f64 {
    match mass.2 {
        ContactMode::Free => s.length(mass.0 - z),
        ContactMode::Sticking => s.acceleration(params.contact_force(z, zdot, zddot)),
    }
}

/// The largest nondimensional position, velocity and acceleration (of the mass and the plate)
/// for which a step without the state check (`Model::fly_over`) is sure to give finite outputs:
/// the outputs are at most quartic in them (the potential energy) times a unit factor.
pub(crate) fn fly_limit(scale: &Scale) -> f64 {
    let factor = [
        scale.length(1.0),
        scale.velocity(1.0),
        scale.acceleration(1.0),
        scale.energy(1.0),
        scale.specific_energy(1.0),
        1.0,
    ]
    .iter()
    .fold(0.0_f64, |m, f| m.max(f.abs()));
    (1e280 / factor).sqrt().sqrt().min(1e50)
}
