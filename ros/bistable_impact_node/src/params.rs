//! The node's ROS 2 parameters: names, defaults, units, validation, and reading them from
//! `-p name:=value` and `--params-file` YAML.

use bistable_core::{MAX_VELOCITY, OMEGA_RANGE};
use ros2_client::ParameterValue;
use yaml_rust2::{Yaml, YamlLoader};

/// When a parameter may change.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Change {
    /// Settable while the node runs (through the parameter services).
    Runtime,
    /// Fixed once the node has started (command line or parameter file only).
    StartUp,
}

/// Description of one parameter.
#[derive(Debug, Clone, Copy)]
pub struct Spec {
    /// Parameter name.
    pub name: &'static str,
    /// Unit and meaning, for the documentation and error messages.
    pub doc: &'static str,
    /// Runtime or start-up only.
    pub change: Change,
}

/// Every parameter the node declares (besides the built-in `use_sim_time`).
pub const SPECS: [Spec; 12] = [
    Spec {
        name: "zeta",
        doc: "damping ratio ζ [-], >= 0",
        change: Change::Runtime,
    },
    Spec {
        name: "e",
        doc: "coefficient of restitution [-], in [0, 1]",
        change: Change::Runtime,
    },
    Spec {
        name: "omega0",
        doc: "linear natural frequency ω0 [rad/s], > 0",
        change: Change::StartUp,
    },
    Spec {
        name: "delta_x",
        doc: "distance between the wells Δx [m], > 0",
        change: Change::StartUp,
    },
    Spec {
        name: "Omega",
        doc: "initial shaker frequency ratio Ω = Ω̂/ω0 [-], in [1e-6, 1e6]",
        change: Change::StartUp,
    },
    Spec {
        name: "V",
        doc: "initial shaker velocity amplitude V = V̂/(ω0 Δx) [-], in [0, 1e6]",
        change: Change::StartUp,
    },
    Spec {
        name: "publish_rate",
        doc: "MassState and /clock rate [Hz of simulation time], in (0, 1e6]",
        change: Change::Runtime,
    },
    Spec {
        name: "real_time_factor",
        doc: "simulated seconds per wall-clock second [-], >= 0 (0: as fast as possible)",
        change: Change::Runtime,
    },
    Spec {
        name: "frame_id",
        doc: "header frame_id of MassState and ImpactEvent",
        change: Change::Runtime,
    },
    Spec {
        name: "history_depth",
        doc: "impacts a late-joining transient-local subscriber gets first [-], integer in \
              [1, 8192]",
        change: Change::StartUp,
    },
    Spec {
        name: "wait_for_impact_subscriptions",
        doc: "impact subscriptions the simulation waits for at t = 0 before it starts [-], \
              integer in [0, 1000] (0: start at once)",
        change: Change::StartUp,
    },
    Spec {
        name: "wait_for_impact_subscriptions_timeout",
        doc: "longest wait for those subscriptions [s of wall time], >= 0 (0: no limit); \
              the simulation then starts with those matched",
        change: Change::StartUp,
    },
];

/// Largest `history_depth`: RustDDS's writer keeps at most 8192 (+ 1) samples
/// (`DEFAULT_WRITER_MAX_SAMPLES`; ros2-client sets no resource limits).
pub const MAX_HISTORY_DEPTH: i64 = 8192;

/// Largest `wait_for_impact_subscriptions`.
pub const MAX_WAIT_FOR_SUBSCRIPTIONS: i64 = 1000;

/// The valid values of an integer parameter; `None` for the other parameters.
pub fn integer_range(name: &str) -> Option<std::ops::RangeInclusive<i64>> {
    match name {
        "history_depth" => Some(1..=MAX_HISTORY_DEPTH),
        "wait_for_impact_subscriptions" => Some(0..=MAX_WAIT_FOR_SUBSCRIPTIONS),
        _ => None,
    }
}

/// Parameter values (see [`SPECS`] for units).
#[derive(Debug, Clone, PartialEq)]
pub struct Settings {
    /// ζ [-].
    pub zeta: f64,
    /// e [-].
    pub e: f64,
    /// ω0 \[rad/s\].
    pub omega0: f64,
    /// Δx \[m\].
    pub delta_x: f64,
    /// Initial Ω [-].
    pub omega: f64,
    /// Initial V [-].
    pub v: f64,
    /// State and clock rate [Hz of simulation time].
    pub publish_rate: f64,
    /// Simulated seconds per wall second (0: as fast as possible).
    pub real_time_factor: f64,
    /// Frame of the published headers.
    pub frame_id: String,
    /// Impacts kept for late-joining subscribers (the impact writer's KEEP_LAST depth).
    pub history_depth: i64,
    /// Impact subscriptions to wait for at t = 0 before the simulation starts (0: none).
    pub wait_for_impact_subscriptions: i64,
    /// Longest such wait [s of wall time] (0: no limit).
    pub wait_for_impact_subscriptions_timeout: f64,
}

impl Default for Settings {
    /// The paper's baseline (ζ = 0.02, e = 0.85, Ω = 1.75, V = 0.07) in nondimensional units
    /// (ω0 = 1 rad/s, Δx = 1 m), 100 Hz, real time, a history of 1000 impacts, started at
    /// once.
    fn default() -> Self {
        Self {
            zeta: 0.02,
            e: 0.85,
            omega0: 1.0,
            delta_x: 1.0,
            omega: 1.75,
            v: 0.07,
            publish_rate: 100.0,
            real_time_factor: 1.0,
            frame_id: "shaker_base".to_owned(),
            history_depth: 1000,
            wait_for_impact_subscriptions: 0,
            wait_for_impact_subscriptions_timeout: 0.0,
        }
    }
}

/// Largest accepted `publish_rate` \[Hz\].
pub const MAX_PUBLISH_RATE: f64 = 1e6;

impl Settings {
    /// Every parameter with its current value, in [`SPECS`] order.
    pub fn values(&self) -> Vec<(&'static str, ParameterValue)> {
        SPECS
            .iter()
            .map(|s| (s.name, self.get(s.name).unwrap_or(ParameterValue::NotSet)))
            .collect()
    }

    /// Value of the parameter `name`.
    pub fn get(&self, name: &str) -> Option<ParameterValue> {
        let d = ParameterValue::Double;
        Some(match name {
            "zeta" => d(self.zeta),
            "e" => d(self.e),
            "omega0" => d(self.omega0),
            "delta_x" => d(self.delta_x),
            "Omega" => d(self.omega),
            "V" => d(self.v),
            "publish_rate" => d(self.publish_rate),
            "real_time_factor" => d(self.real_time_factor),
            "frame_id" => ParameterValue::String(self.frame_id.clone()),
            "history_depth" => ParameterValue::Integer(self.history_depth),
            "wait_for_impact_subscriptions" => {
                ParameterValue::Integer(self.wait_for_impact_subscriptions)
            }
            "wait_for_impact_subscriptions_timeout" => {
                d(self.wait_for_impact_subscriptions_timeout)
            }
            _ => return None,
        })
    }

    /// Checks `value` for `name` and stores it.
    pub fn set(&mut self, name: &str, value: &ParameterValue) -> Result<(), String> {
        check(name, value)?;
        match (name, value) {
            ("frame_id", ParameterValue::String(s)) => self.frame_id = s.clone(),
            ("history_depth", ParameterValue::Integer(i)) => self.history_depth = *i,
            ("wait_for_impact_subscriptions", ParameterValue::Integer(i)) => {
                self.wait_for_impact_subscriptions = *i
            }
            (_, ParameterValue::Double(x)) => {
                let slot = match name {
                    "zeta" => &mut self.zeta,
                    "e" => &mut self.e,
                    "omega0" => &mut self.omega0,
                    "delta_x" => &mut self.delta_x,
                    "Omega" => &mut self.omega,
                    "V" => &mut self.v,
                    "publish_rate" => &mut self.publish_rate,
                    "wait_for_impact_subscriptions_timeout" => {
                        &mut self.wait_for_impact_subscriptions_timeout
                    }
                    _ => &mut self.real_time_factor,
                };
                *slot = *x;
            }
            _ => return Err(format!("parameter '{name}' cannot take {value:?}")),
        }
        Ok(())
    }

    /// Checks a runtime change from the current settings: the value must be valid, and
    /// start-up parameters may only be "set" to their current value.
    pub fn check_runtime(&self, name: &str, value: &ParameterValue) -> Result<(), String> {
        check(name, value)?;
        let spec = spec(name).ok_or_else(|| format!("unknown parameter '{name}'"))?;
        if spec.change == Change::StartUp && self.get(name).as_ref() != Some(value) {
            return Err(format!(
                "parameter '{name}' ({}) is fixed at start-up: restart the node with \
                 -p {name}:=VALUE{}",
                spec.doc,
                if matches!(name, "Omega" | "V") {
                    ", or change the shaker with /bistable/shaker_command"
                } else {
                    ""
                }
            ));
        }
        Ok(())
    }
}

/// The description of `name`, if the node has such a parameter.
pub fn spec(name: &str) -> Option<&'static Spec> {
    SPECS.iter().find(|s| s.name == name)
}

/// Checks that `value` is valid for the parameter `name` (type and range), with the reason
/// if it is not.
pub fn check(name: &str, value: &ParameterValue) -> Result<(), String> {
    let spec = spec(name).ok_or_else(|| format!("unknown parameter '{name}'"))?;
    if name == "frame_id" {
        return match value {
            ParameterValue::String(_) => Ok(()),
            other => Err(format!(
                "parameter 'frame_id' must be a string, got {other:?}"
            )),
        };
    }
    if let Some(range) = integer_range(name) {
        return match value {
            ParameterValue::Integer(i) if range.contains(i) => Ok(()),
            other => Err(format!("invalid {name} = {other:?}: {}", spec.doc)),
        };
    }
    let x = match value {
        ParameterValue::Double(x) => *x,
        other => {
            return Err(format!(
                "parameter '{name}' ({}) must be a double, got {other:?}",
                spec.doc
            ))
        }
    };
    let ok = x.is_finite()
        && match name {
            "zeta" | "real_time_factor" | "wait_for_impact_subscriptions_timeout" => x >= 0.0,
            "e" => (0.0..=1.0).contains(&x),
            "Omega" => OMEGA_RANGE.contains(&x),
            "V" => (0.0..=MAX_VELOCITY).contains(&x),
            "publish_rate" => x > 0.0 && x <= MAX_PUBLISH_RATE,
            _ => x > 0.0,
        };
    if ok {
        Ok(())
    } else {
        Err(format!("invalid {name} = {x}: {}", spec.doc))
    }
}

/// Converts a YAML value (from `-p` or a parameter file) to a parameter value, for the
/// parameter `name`: integers are accepted for doubles, any scalar for a string.
pub fn from_yaml(name: &str, y: &Yaml) -> Result<ParameterValue, String> {
    let is_string = name == "frame_id";
    let v = match y {
        Yaml::Integer(i) if integer_range(name).is_some() => ParameterValue::Integer(*i),
        Yaml::Real(s) => match y.as_f64() {
            Some(x) if !is_string => ParameterValue::Double(x),
            _ => ParameterValue::String(s.clone()),
        },
        Yaml::Integer(i) if !is_string => ParameterValue::Double(*i as f64),
        Yaml::Integer(i) => ParameterValue::String(i.to_string()),
        Yaml::String(s) => ParameterValue::String(s.clone()),
        Yaml::Boolean(b) if is_string => ParameterValue::String(b.to_string()),
        Yaml::Boolean(b) => ParameterValue::Boolean(*b),
        other => return Err(format!("parameter '{name}': unsupported value {other:?}")),
    };
    Ok(v)
}

/// Parses `name:=value` (the value is YAML, as in ROS 2).
pub fn parse_assignment(arg: &str) -> Result<(String, Yaml), String> {
    let (name, value) = arg
        .split_once(":=")
        .ok_or_else(|| format!("'{arg}' is not of the form name:=value"))?;
    if name.is_empty() {
        return Err(format!("'{arg}': empty parameter name"));
    }
    let docs = YamlLoader::load_from_str(value)
        .map_err(|e| format!("'{arg}': value is not valid YAML: {e}"))?;
    let y = docs.into_iter().next().unwrap_or(Yaml::Null);
    Ok((name.to_owned(), y))
}

/// The `ros__parameters` of a ROS 2 parameter file that apply to the node
/// `fully_qualified` (e.g. `/bistable_impact`): entries under `/**`, `**`, the node's base
/// name (when in the root namespace), its fully qualified name with or without the leading
/// slash, or `/**/base_name`. Later entries win. Nested maps flatten to `a.b` names.
pub fn from_params_file(text: &str, fully_qualified: &str) -> Result<Vec<(String, Yaml)>, String> {
    let docs = YamlLoader::load_from_str(text).map_err(|e| format!("not valid YAML: {e}"))?;
    let base = fully_qualified
        .rsplit('/')
        .next()
        .unwrap_or(fully_qualified);
    let in_root = fully_qualified.trim_start_matches('/') == base;
    let mut out = Vec::new();
    for doc in &docs {
        let Yaml::Hash(nodes) = doc else {
            return Err("top level must be a map of node names".to_owned());
        };
        for (key, body) in nodes {
            let Some(key) = key.as_str() else {
                return Err(format!("node name {key:?} is not a string"));
            };
            let k = key.trim_start_matches('/');
            let applies = k == "**"
                || k == fully_qualified.trim_start_matches('/')
                || (in_root && k == base)
                || k.strip_prefix("**/") == Some(base);
            if !applies {
                continue;
            }
            let params = match body {
                Yaml::Hash(h) => h.get(&Yaml::String("ros__parameters".to_owned())),
                _ => None,
            };
            match params {
                Some(p) => flatten("", p, &mut out)?,
                None => return Err(format!("'{key}' has no ros__parameters map")),
            }
        }
    }
    Ok(out)
}

fn flatten(prefix: &str, y: &Yaml, out: &mut Vec<(String, Yaml)>) -> Result<(), String> {
    let Yaml::Hash(h) = y else {
        return Err(format!("ros__parameters{prefix} must be a map"));
    };
    for (k, v) in h {
        let k = match k {
            Yaml::String(s) => s.clone(),
            other => return Err(format!("parameter name {other:?} is not a string")),
        };
        let name = if prefix.is_empty() {
            k
        } else {
            format!("{prefix}.{k}")
        };
        match v {
            Yaml::Hash(_) => flatten(&name, v, out)?,
            _ => out.push((name, v.clone())),
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refuses_bad_values_with_reasons() {
        let mut s = Settings::default();
        for (name, bad) in [
            ("zeta", -0.1),
            ("zeta", f64::NAN),
            ("e", 1.5),
            ("e", f64::INFINITY),
            ("omega0", 0.0),
            ("delta_x", -1.0),
            ("Omega", f64::NEG_INFINITY),
            ("V", -0.07),
            ("publish_rate", 0.0),
            ("publish_rate", 2e6),
            ("real_time_factor", -1.0),
        ] {
            let err = s.set(name, &ParameterValue::Double(bad)).unwrap_err();
            assert!(err.contains(name), "{err}");
        }
        assert_eq!(s, Settings::default(), "refused values must not be stored");
        assert!(check("zeta", &ParameterValue::Integer(1))
            .unwrap_err()
            .contains("double"));
        assert!(check("frame_id", &ParameterValue::Double(1.0)).is_err());
        assert!(check("nope", &ParameterValue::Double(1.0))
            .unwrap_err()
            .contains("unknown"));
        assert!(check("zeta", &ParameterValue::NotSet).is_err());
        for bad in [
            ParameterValue::Integer(0),
            ParameterValue::Integer(MAX_HISTORY_DEPTH + 1),
            ParameterValue::Double(1000.0),
        ] {
            let err = s.set("history_depth", &bad).unwrap_err();
            assert!(err.contains("invalid history_depth"), "{err}");
        }
        s.set("history_depth", &ParameterValue::Integer(1500))
            .unwrap();
        assert_eq!(s.history_depth, 1500);
        for bad in [
            ParameterValue::Integer(-1),
            ParameterValue::Integer(MAX_WAIT_FOR_SUBSCRIPTIONS + 1),
            ParameterValue::Double(2.0),
        ] {
            let err = s.set("wait_for_impact_subscriptions", &bad).unwrap_err();
            assert!(
                err.contains("invalid wait_for_impact_subscriptions"),
                "{err}"
            );
        }
        s.set("wait_for_impact_subscriptions", &ParameterValue::Integer(3))
            .unwrap();
        for bad in [-1.0, f64::NAN, f64::INFINITY] {
            let err = s
                .set(
                    "wait_for_impact_subscriptions_timeout",
                    &ParameterValue::Double(bad),
                )
                .unwrap_err();
            assert!(
                err.contains("wait_for_impact_subscriptions_timeout"),
                "{err}"
            );
        }
        s.set(
            "wait_for_impact_subscriptions_timeout",
            &ParameterValue::Double(12.5),
        )
        .unwrap();
        assert_eq!(
            (
                s.wait_for_impact_subscriptions,
                s.wait_for_impact_subscriptions_timeout
            ),
            (3, 12.5)
        );
        assert!(s
            .check_runtime("wait_for_impact_subscriptions", &ParameterValue::Integer(0))
            .unwrap_err()
            .contains("fixed at start-up"));
        assert!(s
            .check_runtime("history_depth", &ParameterValue::Integer(1000))
            .unwrap_err()
            .contains("fixed at start-up"));
        s.set("e", &ParameterValue::Double(1.0)).unwrap();
        s.set("frame_id", &ParameterValue::String("lab".into()))
            .unwrap();
        assert_eq!((s.e, s.frame_id.as_str()), (1.0, "lab"));
    }

    #[test]
    fn start_up_parameters_are_fixed_at_runtime() {
        let s = Settings::default();
        let err = s
            .check_runtime("Omega", &ParameterValue::Double(2.0))
            .unwrap_err();
        assert!(
            err.contains("fixed at start-up") && err.contains("shaker_command"),
            "{err}"
        );
        assert!(s
            .check_runtime("Omega", &ParameterValue::Double(1.75))
            .is_ok());
        assert!(s
            .check_runtime("zeta", &ParameterValue::Double(0.05))
            .is_ok());
        assert!(s
            .check_runtime("zeta", &ParameterValue::Double(f64::NAN))
            .is_err());
    }

    #[test]
    fn assignments_and_yaml_types() {
        let (n, y) = parse_assignment("zeta:=0.05").unwrap();
        assert_eq!(from_yaml(&n, &y).unwrap(), ParameterValue::Double(0.05));
        let (n, y) = parse_assignment("publish_rate:=50").unwrap();
        assert_eq!(from_yaml(&n, &y).unwrap(), ParameterValue::Double(50.0));
        let (n, y) = parse_assignment("history_depth:=2000").unwrap();
        assert_eq!(from_yaml(&n, &y).unwrap(), ParameterValue::Integer(2000));
        let (n, y) = parse_assignment("wait_for_impact_subscriptions:=2").unwrap();
        assert_eq!(from_yaml(&n, &y).unwrap(), ParameterValue::Integer(2));
        let (n, y) = parse_assignment("wait_for_impact_subscriptions_timeout:=30").unwrap();
        assert_eq!(from_yaml(&n, &y).unwrap(), ParameterValue::Double(30.0));
        let (n, y) = parse_assignment("frame_id:=123").unwrap();
        assert_eq!(
            from_yaml(&n, &y).unwrap(),
            ParameterValue::String("123".into())
        );
        let (n, y) = parse_assignment("zeta:=.nan").unwrap();
        let v = from_yaml(&n, &y).unwrap();
        assert!(matches!(v, ParameterValue::Double(x) if x.is_nan()));
        assert!(check(&n, &v).unwrap_err().contains("invalid zeta"));
        assert!(parse_assignment("zeta=1").is_err());
        assert!(parse_assignment(":=1").is_err());
        assert!(parse_assignment("zeta:=[1, 2").is_err());
        let (n, y) = parse_assignment("zeta:=[1, 2]").unwrap();
        assert!(from_yaml(&n, &y).is_err());
    }

    #[test]
    fn params_file_selects_this_node() {
        let text = "
/**:
  ros__parameters:
    zeta: 0.01
    publish_rate: 10
other_node:
  ros__parameters:
    zeta: 0.5
bistable_impact:
  ros__parameters:
    e: 0.7
    nested:
      a: 1
";
        let got = from_params_file(text, "/bistable_impact").unwrap();
        let names: Vec<&str> = got.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, ["zeta", "publish_rate", "e", "nested.a"]);
        assert_eq!(got[0].1, Yaml::Real("0.01".into()));
        // In a namespace the bare base name does not apply, the qualified name does.
        let got = from_params_file(text, "/lab/bistable_impact").unwrap();
        assert_eq!(got.len(), 2);
        let got = from_params_file(
            "/lab/bistable_impact:\n  ros__parameters:\n    e: 0.5\n",
            "/lab/bistable_impact",
        )
        .unwrap();
        assert_eq!(got.len(), 1);
        assert!(from_params_file("- 1\n", "/bistable_impact").is_err());
        assert!(from_params_file("bistable_impact: 3\n", "/bistable_impact").is_err());
        assert!(from_params_file("a: [", "/bistable_impact").is_err());
    }
}
