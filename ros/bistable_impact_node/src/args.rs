//! Command line and environment: the ROS 2 conventions `--ros-args -p name:=value
//! --params-file FILE -r [node:]from:=to --log-level LEVEL` (remapping as in rcl, see
//! [`crate::names`]), and `ROS_DOMAIN_ID`.

use yaml_rust2::Yaml;

use crate::names::{Names, Remap};
use crate::params::{self, Settings};

/// The node's name in the code (before `__node` remapping).
pub const NODE_NAME: &str = "bistable_impact";

/// Largest DDS domain id whose RTPS ports fit in 16 bits (`7400 + 250·id + 11 < 65536`).
pub const MAX_DOMAIN_ID: u16 = 232;

/// ROS 2 log severities (values of `rcl_interfaces/Log` levels).
pub const LOG_LEVELS: [(&str, u8); 5] = [
    ("debug", 10),
    ("info", 20),
    ("warn", 30),
    ("error", 40),
    ("fatal", 50),
];

/// Everything the node needs to start.
#[derive(Debug, Clone, PartialEq)]
pub struct Config {
    /// Parameter values after defaults, parameter files and `-p` (in that order).
    pub settings: Settings,
    /// `use_sim_time` if given.
    pub use_sim_time: Option<bool>,
    /// Node name, namespace and remapping rules (default `/bistable_impact`, no rules).
    pub names: Names,
    /// DDS domain from `ROS_DOMAIN_ID` (default 0).
    pub domain_id: u16,
    /// Lowest severity logged.
    pub log_level: u8,
    /// Log to `/rosout`.
    pub rosout: bool,
    /// Log to standard error.
    pub stdout: bool,
    /// Things to warn about once the node is up (ignored parameters).
    pub warnings: Vec<String>,
}

/// What the command line asks for.
#[derive(Debug, Clone, PartialEq)]
pub enum Parsed {
    /// Run the node.
    Run(Box<Config>),
    /// Print the usage.
    Help,
}

/// Usage text.
pub const USAGE: &str = "\
usage: bistable_impact_node [--help] [--ros-args [-p NAME:=VALUE]... [--params-file FILE]...
                            [-r [NODE:]FROM:=TO]... [--log-level LEVEL]
                            [--disable-rosout-logs] [--disable-stdout-logs] [--]]
Remapping as in rcl: -r __node:=NAME, -r __ns:=/NAMESPACE, -r bistable/impacts:=hits,
-r /clock:=clock (relative names resolve in the node's namespace, ~ is the node).
Environment: ROS_DOMAIN_ID (0..=232, default 0).
Parameters (units; start-up only ones are fixed once the node runs):";

/// Parses the arguments (without the program name); `domain_env` is `ROS_DOMAIN_ID`,
/// `read_file` reads a parameter file.
pub fn parse(
    args: &[String],
    domain_env: Option<&str>,
    read_file: impl Fn(&str) -> Result<String, String>,
) -> Result<Parsed, String> {
    let mut rules = Vec::new();
    let mut files = Vec::new();
    let mut assigns = Vec::new();
    let mut log_level = 20;
    let (mut rosout, mut stdout) = (true, true);
    let mut ros = false;
    let mut it = args.iter();
    while let Some(arg) = it.next() {
        let arg = arg.as_str();
        if !ros {
            match arg {
                "--ros-args" => ros = true,
                "-h" | "--help" => return Ok(Parsed::Help),
                _ => return Err(format!("unexpected argument '{arg}' (see --help)")),
            }
            continue;
        }
        let mut value = |what: &str| {
            it.next()
                .cloned()
                .ok_or_else(|| format!("{arg} needs {what}"))
        };
        match arg {
            "--" => ros = false,
            "--ros-args" => {}
            "-p" | "--param" => assigns.push(params::parse_assignment(&value("NAME:=VALUE")?)?),
            "--params-file" => files.push(value("a file name")?),
            "-r" | "--remap" => rules.push(Remap::parse(&value("a remapping rule")?)?),
            "--log-level" => {
                let level = value("a level")?;
                let name = level.rsplit(":=").next().unwrap_or(&level).to_lowercase();
                log_level = LOG_LEVELS
                    .iter()
                    .find(|(n, _)| *n == name)
                    .map(|&(_, l)| l)
                    .ok_or_else(|| format!("unknown log level '{level}'"))?;
            }
            "--disable-rosout-logs" => rosout = false,
            "--enable-rosout-logs" => rosout = true,
            "--disable-stdout-logs" => stdout = false,
            "--enable-stdout-logs" => stdout = true,
            "--disable-external-lib-logs" | "--enable-external-lib-logs" => {}
            other => return Err(format!("unsupported ROS argument '{other}'")),
        }
    }
    let names = Names::new(NODE_NAME, "/", rules)?;
    let fully_qualified = names.fully_qualified();
    let mut sources: Vec<(String, String, Yaml)> = Vec::new();
    for f in &files {
        let text = read_file(f).map_err(|e| format!("--params-file {f}: {e}"))?;
        for (n, y) in params::from_params_file(&text, &fully_qualified)
            .map_err(|e| format!("--params-file {f}: {e}"))?
        {
            sources.push((format!("--params-file {f}"), n, y));
        }
    }
    sources.extend(assigns.into_iter().map(|(n, y)| ("-p".to_owned(), n, y)));
    let mut settings = Settings::default();
    let mut use_sim_time = None;
    let mut warnings = Vec::new();
    for (source, name, y) in sources {
        if name == "use_sim_time" {
            match y {
                Yaml::Boolean(b) => use_sim_time = Some(b),
                other => {
                    return Err(format!(
                        "{source}: use_sim_time must be a bool, got {other:?}"
                    ))
                }
            }
            continue;
        }
        if params::spec(&name).is_none() {
            warnings.push(format!("{source}: ignoring unknown parameter '{name}'"));
            continue;
        }
        let v = params::from_yaml(&name, &y).map_err(|e| format!("{source}: {e}"))?;
        settings
            .set(&name, &v)
            .map_err(|e| format!("{source}: {e}"))?;
    }
    let domain_id = match domain_env.map(str::trim) {
        None | Some("") => 0,
        Some(s) => s
            .parse::<u16>()
            .ok()
            .filter(|&d| d <= MAX_DOMAIN_ID)
            .ok_or_else(|| {
                format!("ROS_DOMAIN_ID='{s}' must be an integer in 0..={MAX_DOMAIN_ID}")
            })?,
    };
    Ok(Parsed::Run(Box::new(Config {
        settings,
        use_sim_time,
        names,
        domain_id,
        log_level,
        rosout,
        stdout,
        warnings,
    })))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(args: &[&str], domain: Option<&str>) -> Result<Config, String> {
        let args: Vec<String> = args.iter().map(|s| s.to_string()).collect();
        let files = |name: &str| match name {
            "p.yaml" => Ok(
                "/**:\n  ros__parameters:\n    zeta: 0.03\n    e: 0.7\n    typo: 1\n".to_owned(),
            ),
            _ => Err("no such file".to_owned()),
        };
        match parse(&args, domain, files)? {
            Parsed::Run(c) => Ok(*c),
            Parsed::Help => Err("help".to_owned()),
        }
    }

    #[test]
    fn defaults_files_then_overrides() {
        let c = run(&[], None).unwrap();
        assert_eq!(
            (c.settings, c.domain_id, c.names.fully_qualified().as_str()),
            (Settings::default(), 0, "/bistable_impact")
        );
        let c = run(
            &[
                "--ros-args",
                "--params-file",
                "p.yaml",
                "-p",
                "e:=0.9",
                "-p",
                "use_sim_time:=true",
                "-r",
                "__node:=shaker1",
                "--remap",
                "__ns:=/lab",
                "-r",
                "bistable/impacts:=~/hits",
                "--log-level",
                "WARN",
            ],
            Some("42"),
        )
        .unwrap();
        assert_eq!((c.settings.zeta, c.settings.e), (0.03, 0.9));
        assert_eq!(c.use_sim_time, Some(true));
        assert_eq!(c.names.fully_qualified(), "/lab/shaker1");
        assert_eq!(
            c.names
                .resolve("bistable/impacts", crate::names::Kind::Topic)
                .unwrap(),
            "/lab/shaker1/hits"
        );
        assert_eq!((c.domain_id, c.log_level), (42, 30));
        assert_eq!(c.warnings.len(), 1, "{:?}", c.warnings);
        assert!(c.warnings[0].contains("typo"));
    }

    #[test]
    fn refuses_bad_input_with_reasons() {
        for (args, domain, needle) in [
            (&["-p", "zeta:=1"][..], None, "unexpected argument"),
            (&["--ros-args", "-p", "zeta:=-1"][..], None, "invalid zeta"),
            (&["--ros-args", "-p", "e:=.nan"][..], None, "invalid e"),
            (
                &["--ros-args", "-p", "publish_rate:=abc"][..],
                None,
                "must be a double",
            ),
            (&["--ros-args", "-p"][..], None, "needs"),
            (
                &["--ros-args", "--params-file", "missing.yaml"][..],
                None,
                "no such file",
            ),
            (
                &["--ros-args", "-r", "/bistable/impacts:=/x y"][..],
                None,
                "invalid remapping rule '/bistable/impacts:=/x y'",
            ),
            (
                &["--ros-args", "-r", "__ns:=lab"][..],
                None,
                "must be absolute",
            ),
            (&["--ros-args", "-r"][..], None, "needs a remapping rule"),
            (
                &["--ros-args", "--log-level", "loud"][..],
                None,
                "unknown log level",
            ),
            (
                &["--ros-args", "--enclave", "x"][..],
                None,
                "unsupported ROS argument",
            ),
            (&[][..], Some("233"), "ROS_DOMAIN_ID"),
            (&[][..], Some("-1"), "ROS_DOMAIN_ID"),
            (&[][..], Some("seven"), "ROS_DOMAIN_ID"),
        ] {
            let err = run(args, domain).unwrap_err();
            assert!(err.contains(needle), "{args:?}: {err}");
        }
        assert_eq!(run(&["--help"], None).unwrap_err(), "help");
        assert_eq!(
            run(&["--ros-args", "--", "--help"], None).unwrap_err(),
            "help"
        );
    }
}

/// How far DDS discovery reaches, from `ROS_AUTOMATIC_DISCOVERY_RANGE` (and the older
/// `ROS_LOCALHOST_ONLY`), as rmw reads them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DiscoveryRange {
    /// The DDS implementation's own default (RustDDS: every interface).
    SystemDefault,
    /// Every interface of the subnet (rmw's default).
    Subnet,
    /// Loopback only: the participant uses and announces only 127.0.0.1.
    Localhost,
}

/// The discovery range for the environment values of `ROS_AUTOMATIC_DISCOVERY_RANGE` and
/// `ROS_LOCALHOST_ONLY` (rmw's rules: the range wins when set; `ROS_LOCALHOST_ONLY=1` means
/// `LOCALHOST` otherwise; unset or empty means `SUBNET`). `OFF` (no discovery at all) cannot be
/// done with RustDDS and is refused with the reason, as are unknown values.
pub fn discovery_range(
    automatic: Option<&str>,
    localhost_only: Option<&str>,
) -> Result<DiscoveryRange, String> {
    match automatic.map(str::trim).filter(|s| !s.is_empty()) {
        Some("SUBNET") => Ok(DiscoveryRange::Subnet),
        Some("LOCALHOST") => Ok(DiscoveryRange::Localhost),
        Some("SYSTEM_DEFAULT") => Ok(DiscoveryRange::SystemDefault),
        Some("OFF") => Err(
            "ROS_AUTOMATIC_DISCOVERY_RANGE=OFF (no discovery) is not supported: RustDDS always \
             announces the participant; use LOCALHOST to keep it on this machine"
                .to_owned(),
        ),
        Some(other) => Err(format!(
            "ROS_AUTOMATIC_DISCOVERY_RANGE='{other}' must be SUBNET, LOCALHOST, SYSTEM_DEFAULT or OFF"
        )),
        None => match localhost_only.map(str::trim) {
            Some("1") => Ok(DiscoveryRange::Localhost),
            _ => Ok(DiscoveryRange::Subnet),
        },
    }
}

#[cfg(test)]
mod discovery_tests {
    use super::*;

    #[test]
    fn discovery_range_as_rmw_reads_it() {
        use DiscoveryRange::*;
        for (auto, local, want) in [
            (None, None, Subnet),
            (Some(""), None, Subnet),
            (None, Some("1"), Localhost),
            (None, Some("0"), Subnet),
            (Some("LOCALHOST"), None, Localhost),
            (Some("SUBNET"), Some("1"), Subnet),
            (Some("SYSTEM_DEFAULT"), None, SystemDefault),
            (Some(""), Some("1"), Localhost),
        ] {
            assert_eq!(discovery_range(auto, local), Ok(want), "{auto:?} {local:?}");
        }
        assert!(discovery_range(Some("OFF"), None)
            .unwrap_err()
            .contains("not supported"));
        assert!(discovery_range(Some("lan"), None)
            .unwrap_err()
            .contains("must be"));
    }
}
