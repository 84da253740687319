//! The node's answers to the `rcl_interfaces` parameter services (`list_parameters`,
//! `get_parameters`, `get_parameter_types`, `describe_parameters`, `set_parameters`,
//! `set_parameters_atomically`), free of DDS. The node serves them itself (not through
//! ros2-client's spinner) so that the descriptors are complete (description with unit,
//! floating-point and integer ranges, `read_only` for start-up parameters) and so that
//! `use_sim_time` can be refused: this node publishes `/clock` and never follows it.

use bistable_core::{MAX_VELOCITY, OMEGA_RANGE};
use ros2_client::parameters::raw;
use ros2_client::rcl_interfaces::ListParametersResult;
use ros2_client::ParameterValue;

use crate::params::{self, Change, Settings, MAX_PUBLISH_RATE, SPECS};

/// The built-in parameter every ROS 2 node has.
pub const USE_SIM_TIME: &str = "use_sim_time";

/// Why `use_sim_time` stays false.
pub const USE_SIM_TIME_REFUSED: &str = "use_sim_time must stay false: this node owns the \
     simulation clock (it publishes /clock from its own simulation time and never follows one)";

/// Smallest positive double: the inclusive lower end of a range that means `> 0`.
const ABOVE_ZERO: f64 = 5e-324;

/// Every parameter name the node has, sorted (as rclcpp lists them).
pub fn names() -> Vec<String> {
    let mut names: Vec<String> = SPECS.iter().map(|s| s.name.to_owned()).collect();
    names.push(USE_SIM_TIME.to_owned());
    names.sort();
    names
}

/// The value of `name` (`NotSet` for an unknown name).
pub fn get(settings: &Settings, name: &str) -> ParameterValue {
    if name == USE_SIM_TIME {
        return ParameterValue::Boolean(false);
    }
    settings.get(name).unwrap_or(ParameterValue::NotSet)
}

/// `list_parameters` with rclcpp's semantics: with no prefixes, the names with fewer than
/// `depth` dots (0: any); otherwise the names equal to a prefix or under `prefix.`. The node's
/// names have no dots, so `prefixes` of the result is always empty.
pub fn list(prefixes: &[String], depth: u64) -> ListParametersResult {
    let within = |s: &str| depth == 0 || (s.matches('.').count() as u64) < depth;
    let names = names()
        .into_iter()
        .filter(|n| {
            (prefixes.is_empty() && within(n))
                || prefixes.iter().any(|p| {
                    n == p
                        || n.strip_prefix(p.as_str())
                            .and_then(|r| r.strip_prefix('.'))
                            .is_some_and(|r| within(&format!(".{r}")))
                })
        })
        .collect();
    ListParametersResult {
        names,
        prefixes: Vec::new(),
    }
}

/// The full descriptor of `name`: type, description with unit, the range of valid values,
/// `read_only` for start-up parameters. For an unknown name, an empty descriptor of type
/// `NOT_SET` (as rclcpp answers).
pub fn describe(name: &str) -> raw::ParameterDescriptor {
    let mut d = raw::ParameterDescriptor {
        name: name.to_owned(),
        r#type: raw::ParameterType::NOT_SET,
        description: String::new(),
        additional_constraints: String::new(),
        read_only: false,
        dynamic_typing: false,
        floating_point_range: Vec::new(),
        integer_range: Vec::new(),
    };
    if name == USE_SIM_TIME {
        d.r#type = raw::ParameterType::BOOL;
        d.description = "use simulation time from /clock: always false here, this node \
                         publishes /clock (its own simulation time)"
            .to_owned();
        d.additional_constraints = "only false; setting true is refused".to_owned();
        return d;
    }
    let Some(spec) = params::spec(name) else {
        return d;
    };
    d.description = spec.doc.to_owned();
    d.read_only = spec.change == Change::StartUp;
    let float = |from: f64, to: f64| {
        vec![raw::FloatingPointRange {
            from_value: from,
            to_value: to,
            step: 0.0,
        }]
    };
    match (name, params::integer_range(name)) {
        ("frame_id", _) => d.r#type = raw::ParameterType::STRING,
        (_, Some(range)) => {
            d.r#type = raw::ParameterType::INTEGER;
            d.integer_range = vec![raw::IntegerRange {
                from_value: *range.start(),
                to_value: *range.end(),
                step: 1,
            }];
        }
        _ => {
            d.r#type = raw::ParameterType::DOUBLE;
            let (range, constraint) = match name {
                "e" => (float(0.0, 1.0), "finite"),
                "zeta" | "real_time_factor" | "wait_for_impact_subscriptions_timeout" => {
                    (float(0.0, f64::MAX), "finite, >= 0")
                }
                "Omega" => (float(*OMEGA_RANGE.start(), *OMEGA_RANGE.end()), "finite"),
                "V" => (float(0.0, MAX_VELOCITY), "finite"),
                "publish_rate" => (float(ABOVE_ZERO, MAX_PUBLISH_RATE), "> 0"),
                _ => (float(ABOVE_ZERO, f64::MAX), "finite, > 0"),
            };
            d.floating_point_range = range;
            d.additional_constraints = constraint.to_owned();
        }
    }
    if d.read_only {
        d.additional_constraints = if d.additional_constraints.is_empty() {
            "read-only: set at start-up (-p or --params-file)".to_owned()
        } else {
            format!(
                "{}; read-only: set at start-up (-p or --params-file)",
                d.additional_constraints
            )
        };
    }
    d
}

/// Checks a runtime set of `name` to `value` against the current `settings`: the reason if it
/// is refused. Setting a start-up parameter to its current value, or `use_sim_time` to false,
/// changes nothing and is accepted.
pub fn check_set(settings: &Settings, name: &str, value: &ParameterValue) -> Result<(), String> {
    if name == USE_SIM_TIME {
        return match value {
            ParameterValue::Boolean(false) => Ok(()),
            ParameterValue::Boolean(true) => Err(USE_SIM_TIME_REFUSED.to_owned()),
            other => Err(format!("use_sim_time must be a bool, got {other:?}")),
        };
    }
    if params::spec(name).is_none() {
        return Err(format!(
            "parameter '{name}' is not declared by this node (undeclared parameters are not \
             allowed)"
        ));
    }
    let current = get(settings, name);
    if std::mem::discriminant(&current) != std::mem::discriminant(value) {
        return Err(format!(
            "wrong type for parameter '{name}': it is {:?}, got {value:?}",
            current.to_parameter_type()
        ));
    }
    settings.check_runtime(name, value)
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::params::{MAX_HISTORY_DEPTH, MAX_WAIT_FOR_SUBSCRIPTIONS};

    #[test]
    fn descriptors_have_units_ranges_and_read_only() {
        for name in names() {
            let d = describe(&name);
            assert!(!d.description.is_empty(), "{name}");
            assert_ne!(d.r#type, raw::ParameterType::NOT_SET, "{name}");
            let value = get(&Settings::default(), &name);
            assert_eq!(
                d.r#type,
                ParameterValue::to_parameter_type_raw(&value),
                "{name}"
            );
            if d.r#type == raw::ParameterType::DOUBLE {
                assert_eq!(d.floating_point_range.len(), 1, "{name}");
                let r = &d.floating_point_range[0];
                let ParameterValue::Double(x) = value else {
                    unreachable!()
                };
                assert!(r.from_value <= x && x <= r.to_value, "{name}");
                // The ends of the range agree with the check.
                assert!(params::check(&name, &ParameterValue::Double(r.from_value)).is_ok());
                assert!(params::check(&name, &ParameterValue::Double(r.to_value)).is_ok());
                let below = r.from_value - r.from_value.abs().max(5e-324);
                assert!(
                    params::check(&name, &ParameterValue::Double(below)).is_err(),
                    "{name}"
                );
            }
        }
        let d = describe("omega0");
        assert!(d.read_only && d.description.contains("rad/s"));
        assert!(!describe("zeta").read_only);
        for (name, from, to) in [
            ("history_depth", 1, MAX_HISTORY_DEPTH),
            (
                "wait_for_impact_subscriptions",
                0,
                MAX_WAIT_FOR_SUBSCRIPTIONS,
            ),
        ] {
            let d = describe(name);
            let r = &d.integer_range[0];
            assert_eq!((d.read_only, r.from_value, r.to_value), (true, from, to));
        }
        let t = describe("wait_for_impact_subscriptions_timeout");
        assert!(t.read_only && t.description.contains("wall time"));
        assert_eq!(t.floating_point_range[0].from_value, 0.0);
        let r = &describe("publish_rate").floating_point_range[0];
        assert_eq!(r.to_value, MAX_PUBLISH_RATE);
        assert!(params::check("publish_rate", &ParameterValue::Double(0.0)).is_err());
        assert_eq!(describe("nope").r#type, raw::ParameterType::NOT_SET);
    }

    #[test]
    fn use_sim_time_cannot_be_set_true() {
        let s = Settings::default();
        let why = check_set(&s, USE_SIM_TIME, &ParameterValue::Boolean(true)).unwrap_err();
        assert!(why.contains("owns the simulation clock"), "{why}");
        assert!(check_set(&s, USE_SIM_TIME, &ParameterValue::Boolean(false)).is_ok());
        assert!(check_set(&s, USE_SIM_TIME, &ParameterValue::Integer(1)).is_err());
        assert!(check_set(&s, "nope", &ParameterValue::Double(1.0))
            .unwrap_err()
            .contains("not declared"));
        assert!(check_set(&s, "zeta", &ParameterValue::Double(0.1)).is_ok());
        assert!(check_set(&s, "zeta", &ParameterValue::String("abc".into()))
            .unwrap_err()
            .contains("wrong type"));
        assert_eq!(get(&s, USE_SIM_TIME), ParameterValue::Boolean(false));
    }

    #[test]
    fn list_follows_rclcpp() {
        let all = list(&[], 0).names;
        assert_eq!(all.len(), SPECS.len() + 1);
        assert!(all.windows(2).all(|w| w[0] < w[1]));
        assert_eq!(list(&["zeta".to_owned()], 0).names, vec!["zeta".to_owned()]);
        assert!(list(&["zet".to_owned()], 0).names.is_empty());
        assert_eq!(list(&[], 1).names.len(), all.len());
    }
}
