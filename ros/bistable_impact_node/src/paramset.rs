//! Runtime parameter changes (the `set_parameters` and `set_parameters_atomically`
//! services), free of DDS: each change is checked ([`paramsrv::check_set`]), then applied to
//! the simulation, its publishing and its pacing; a refusal is logged and counted.

use ros2_client::parameters::Parameter;
use ros2_client::ParameterValue;

use crate::logging::{Log, LogLevel};
use crate::pacer::Pacer;
use crate::paramsrv::{self, USE_SIM_TIME};
use crate::state::LoopState;

/// What a set request changed: for the `/parameter_events` message and the loop's pacing.
#[derive(Debug, Default)]
pub struct Changes {
    /// The parameters set, in order (setting one to its current value counts too).
    pub changed: Vec<Parameter>,
    /// `real_time_factor` was set: the pacing schedule restarted.
    pub repaced: bool,
}

impl Changes {
    /// Checks and applies `p` ([`set_parameter`]) and records it if accepted.
    fn set<Id>(
        &mut self,
        st: &mut LoopState<Id>,
        p: Parameter,
        log: &impl Log,
    ) -> Result<(), String> {
        let r = set_parameter(st, &p.name, &p.value, log);
        if r.is_ok() {
            self.repaced |= p.name == "real_time_factor";
            self.changed.push(p);
        }
        r
    }
}

/// `set_parameters`: each parameter checked and applied on its own, in order; one result each.
pub fn set_each<Id>(
    st: &mut LoopState<Id>,
    params: impl IntoIterator<Item = Parameter>,
    log: &impl Log,
    changes: &mut Changes,
) -> Vec<Result<(), String>> {
    params
        .into_iter()
        .map(|p| changes.set(st, p, log))
        .collect()
}

/// `set_parameters_atomically`: all checked first, then applied in order, or none if one is
/// refused by the check (the reason, logged and counted once). A change the simulation cannot
/// take when applied stops there (the earlier ones stay).
pub fn set_atomically<Id>(
    st: &mut LoopState<Id>,
    params: Vec<Parameter>,
    log: &impl Log,
    changes: &mut Changes,
) -> Result<(), String> {
    let checked = params.iter().try_for_each(|p| {
        paramsrv::check_set(&st.settings, &p.name, &p.value)
            .map_err(|why| format!("parameter '{}': {why}", p.name))
    });
    if let Err(why) = checked {
        st.n.requests_refused += 1;
        st.log_throttled(log, LogLevel::Warn, &format!("refused parameters: {why}"));
        return Err(why);
    }
    params.into_iter().try_for_each(|p| changes.set(st, p, log))
}

/// Checks and applies a runtime parameter change; the reason if refused (logged, counted).
pub fn set_parameter<Id>(
    st: &mut LoopState<Id>,
    name: &str,
    value: &ParameterValue,
    log: &impl Log,
) -> Result<(), String> {
    let result = paramsrv::check_set(&st.settings, name, value)
        .and_then(|()| apply_parameter(st, name, value, log));
    if let Err(why) = &result {
        st.n.requests_refused += 1;
        st.log_throttled(
            log,
            LogLevel::Warn,
            &format!("refused parameter {name}: {why}"),
        );
    }
    result
}

/// Applies a checked runtime parameter change (logged); the reason if the simulation cannot
/// take it (nothing changes then). Setting a parameter to its current value does nothing.
pub fn apply_parameter<Id>(
    st: &mut LoopState<Id>,
    name: &str,
    value: &ParameterValue,
    log: &impl Log,
) -> Result<(), String> {
    if name == USE_SIM_TIME {
        return Ok(());
    }
    let LoopState {
        settings,
        runner,
        pacer,
        ..
    } = st;
    let before = settings.get(name);
    if before.as_ref() == Some(value) {
        return Ok(());
    }
    let mut next = settings.clone();
    next.set(name, value).and_then(|()| match name {
        "zeta" | "e" => runner.set_params(next.zeta, next.e),
        "publish_rate" => {
            runner.set_rate(next.publish_rate);
            Ok(())
        }
        "real_time_factor" => {
            *pacer = Pacer::new(next.real_time_factor, runner.now());
            Ok(())
        }
        "frame_id" => {
            runner.set_frame_id(&next.frame_id);
            Ok(())
        }
        _ => Ok(()),
    })?;
    *settings = next;
    log.log(
        LogLevel::Info,
        &format!(
            "parameter {name} changed from {before:?} to {value:?} at t = {} s",
            runner.now()
        ),
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::logging::Recorder;
    use crate::params::Settings;
    use crate::sim::{Outcome, Runner};
    use ParameterValue::{Boolean, Double, Integer, String as Str};

    fn state() -> LoopState<()> {
        let settings = Settings::default();
        LoopState::new(Runner::new(&settings).unwrap(), settings)
    }

    fn p(name: &str, value: ParameterValue) -> Parameter {
        Parameter {
            name: name.to_owned(),
            value,
        }
    }

    #[test]
    fn runtime_parameters_reach_the_simulation() {
        let mut st = state();
        let log = Recorder::default();
        set_parameter(&mut st, "frame_id", &Str("plate".into()), &log).unwrap();
        assert_eq!(st.settings.frame_id, "plate");
        assert_eq!(st.runner.state().header.frame_id, "plate");
        set_parameter(&mut st, "zeta", &Double(0.05), &log).unwrap();
        assert_eq!(st.settings.zeta, 0.05);
        set_parameter(&mut st, "publish_rate", &Double(10.0), &log).unwrap();
        let mut impacts = Vec::new();
        while st.runner.advance(&mut impacts) != Outcome::Tick {}
        assert!((st.runner.now() - 0.1).abs() < 1e-9, "{}", st.runner.now());
        assert_eq!(log.at(LogLevel::Info).len(), 3);
        assert!(log.at(LogLevel::Info)[1]
            .starts_with("parameter zeta changed from Some(Double(0.02)) to Double(0.05)"));
        assert_eq!(st.n.requests_refused, 0);
    }

    #[test]
    fn real_time_factor_restarts_the_pacing() {
        let mut st = state();
        let log = Recorder::default();
        let mut changes = Changes::default();
        let r = set_each(
            &mut st,
            [p("real_time_factor", Double(0.0))],
            &log,
            &mut changes,
        );
        assert_eq!(r, [Ok(())]);
        assert!(changes.repaced);
        assert_eq!(st.pacer.rtf(), 0.0);
        assert_eq!(st.pacer.due(1.0), None);
    }

    #[test]
    fn refusals_are_counted_and_change_nothing() {
        let mut st = state();
        let log = Recorder::default();
        let before = st.settings.clone();
        for (name, value) in [
            ("zeta", Double(-1.0)),
            ("zeta", Integer(1)),
            ("omega0", Double(2.0)),
            ("no_such", Double(1.0)),
            ("use_sim_time", Boolean(true)),
        ] {
            assert!(
                set_parameter(&mut st, name, &value, &log).is_err(),
                "{name}"
            );
        }
        assert_eq!(st.settings, before);
        assert_eq!(st.n.requests_refused, 5);
        assert_eq!(log.at(LogLevel::Warn).len(), 5);
        assert!(log.at(LogLevel::Info).is_empty());
    }

    #[test]
    fn current_values_and_use_sim_time_false_are_accepted_silently() {
        let mut st = state();
        let log = Recorder::default();
        let mut changes = Changes::default();
        let r = set_each(
            &mut st,
            [p("omega0", Double(1.0)), p("use_sim_time", Boolean(false))],
            &log,
            &mut changes,
        );
        assert_eq!(r, [Ok(()), Ok(())]);
        assert_eq!(changes.changed.len(), 2);
        assert!(!changes.repaced);
        assert!(log.0.borrow().is_empty());
    }

    #[test]
    fn set_each_applies_the_valid_ones() {
        let mut st = state();
        let log = Recorder::default();
        let mut changes = Changes::default();
        let r = set_each(
            &mut st,
            [
                p("e", Double(0.5)),
                p("e", Double(2.0)),
                p("zeta", Double(0.1)),
            ],
            &log,
            &mut changes,
        );
        assert!(r[0].is_ok() && r[1].is_err() && r[2].is_ok(), "{r:?}");
        assert_eq!((st.settings.e, st.settings.zeta), (0.5, 0.1));
        let names: Vec<_> = changes.changed.iter().map(|p| p.name.as_str()).collect();
        assert_eq!(names, ["e", "zeta"]);
        assert_eq!(st.n.requests_refused, 1);
    }

    #[test]
    fn set_atomically_is_all_or_nothing() {
        let mut st = state();
        let log = Recorder::default();
        let mut changes = Changes::default();
        let bad = vec![p("e", Double(0.5)), p("zeta", Double(-0.1))];
        let why = set_atomically(&mut st, bad, &log, &mut changes).unwrap_err();
        assert!(why.starts_with("parameter 'zeta': "), "{why}");
        assert_eq!(st.settings.e, 0.85);
        assert!(changes.changed.is_empty());
        assert_eq!(st.n.requests_refused, 1);
        let good = vec![p("e", Double(0.5)), p("real_time_factor", Double(4.0))];
        set_atomically(&mut st, good, &log, &mut changes).unwrap();
        assert_eq!((st.settings.e, st.settings.real_time_factor), (0.5, 4.0));
        assert_eq!(changes.changed.len(), 2);
        assert!(changes.repaced);
        assert_eq!(st.n.requests_refused, 1);
    }
}
