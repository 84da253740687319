//! SI units and the FMU's words (`model.md` Sec. 6): time `t = τ/ω0` (s), lengths `x̂ = Δx·x`
//! (m), velocities `ω0Δx·v` (m/s), accelerations `ω0²Δx·a` (m/s²), energies `m·ω0²Δx²·E` (J).
//! With `omega0 = 1`, `delta_x = 1` and `mass = 1` every conversion is a multiplication by 1:
//! the FMU is the nondimensional model bit for bit. Core errors and events are described here
//! with the FMU's variable names and in SI units.

use bistable_core::{Event, Impact, Instant, ParamError, SimError, Sinusoid};

use crate::md::var;

pub use bistable_core::units::Scale;

/// The SI scales of the parameter values.
pub fn scale_of(values: &[f64]) -> Scale {
    Scale {
        omega0: values[var::omega0],
        dx: values[var::delta_x],
        mass: values[var::mass],
    }
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
pub(crate) fn describe(e: &SimError, scale: &Scale) -> String {
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

/// Impact phase in cycles: the core's (internal mode), else from the reference sinusoid.
pub fn phase_of(phase_ref: &Sinusoid, i: &Impact) -> f64 {
    i.phase
        .unwrap_or_else(|| phase_ref.phase_cycles(Instant::new(i.t)))
}

/// A line for the `logEvents` category (SI units, full precision), for both interfaces.
pub fn describe_event(s: &Scale, phase_ref: &Sinusoid, e: &Event) -> String {
    match *e {
        Event::Impact(i) => format!(
            "impact {} at t={:.17e} s phase={:.17e} x={:.17e} m v_before={:.17e} m/s v_after={:.17e} m/s",
            i.index,
            s.time(i.t),
            phase_of(phase_ref, &i),
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

#[cfg(test)]
mod tests {
    use super::*;
    use bistable_core::Params;

    #[test]
    fn core_parameter_errors_use_the_fmu_names() {
        let e = Params::new(0.1, 7.0).unwrap_err();
        assert!(describe_param(&e).starts_with("invalid e = 7"));
    }
}
