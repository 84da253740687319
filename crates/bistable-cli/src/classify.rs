//! `bistable classify`: the response class at one point `(Ω, V)` (paper Sec. 3.4), and the
//! classification options and record shared with `bistable map`.

use clap::Args;
use serde::Serialize;

use bistable_analysis::sensitivity::SensitivityOptions;
use bistable_analysis::sweep::classify_point_with;
use bistable_core::ClassifyOptions;

use crate::common::CommonArgs;
use crate::error::CliError;
use crate::output::{print_json, Field};

/// Long description shown by `bistable classify --help`.
pub const LONG_ABOUT: &str = "\
Classify the response at one shaker point (Ω, V) from the paper's initial
condition (mass at rest at x = 0, impact 0 at τ = 0), as in the paper's Fig. 9:

  intrawell             never crosses the barrier x = 1/2
  transient_interwell   crosses only during the transient; the steady state
                        lies in one well (often at rest in well 2)
  continuous_interwell  the steady-state orbit itself crosses the barrier

and the steady-state period in shaker periods 2π/Ω (null when aperiodic).

The run is sampled once per shaker period (plate phase 0) and stops as soon as
the class is decided: the section points repeat with some period p <= 16 over
max(3p, 8) periods and keep converging, or the mass is at rest in well 2 below
the barrier and above the plate's reach. Otherwise it runs the full
--max-periods natural periods (paper: 20,000) and is aperiodic; the largest
Lyapunov exponent (per unit of τ, from the variational equations with saltation
matrices at impacts) over the next --lyapunov-periods shaker periods tells
whether it is chaotic (> 1e-3).

Sensitivity: in a chaotic transient, rounding errors of 1e-16 grow like e^(λτ)
and reach order one after a few hundred time units; which attractor such a run
ends on is then decided by rounding, and no double-precision run can decide it
(another tolerance, order or start 1e-12 away ends elsewhere). A run is repeated
when an infinitesimal perturbation grew by at least --efoldings e-foldings
before its class was decided (variational equations, over the first --horizon
natural periods), when it was decided later than that, or when it is still
aperiodic at the end: --repeats runs (tol x10, x100, and starts displaced by
--perturbation; those of an aperiodic run last --repeat-periods natural
periods), and for an aperiodic run --lyapunov-windows further Lyapunov windows,
the last stretches of the run itself (in its last quarter), each a verdict on
'chaotic'. The point is 'sensitive' when these do not all agree (class, period,
chaos, final well); the reported result is the most frequent outcome. Points
decided early stay a single run; a chaotic attractor that every run reaches and
keeps is 'chaotic', not sensitive. See docs/sensitivity.md.

Always prints one JSON object (--json is accepted and changes nothing):
  class, period, chaotic, lyapunov, snap_throughs, final_well (1 | 2),
  at_rest_in_second_well, impacts_per_period, sticking, periods_simulated
  (natural periods τ/2π), stopped_early, wall_time_s, the inputs omega,
  velocity, zeta, restitution; sensitive, runs (verdicts counted),
  majority_fraction, outcomes (every distinct outcome, most frequent first, as
  objects {class, period (null when aperiodic), chaotic, final_well (null for
  continuous interwell), count (runs that reached it), fraction (count/runs)};
  the map CSV writes them as text, class:period:well=fraction joined by ';'),
  sensitivity_trigger (none |
  growth | late | aperiodic), efoldings (transient growth, capped at the
  threshold) and efoldings_threshold; at_rest: the steady state is the mass at
  rest, at the second equilibrium (at_rest_in_second_well) or on the plate
  without ever leaving it (no flight, e.g. V = 0: class intrawell, period 1,
  no impacts, sticking). The same keys as the map CSV columns.";

/// Shown after the options by `bistable classify --help`.
pub const AFTER_HELP: &str = "\
Exit codes: 0 success; 2 invalid options; 1 the simulation failed.

Examples:
  bistable classify --omega 0.85 --velocity 0.11     # intrawell, period 4
  bistable classify --omega 0.85 --velocity 0.15     # at rest in well 2
  bistable classify --omega 0.85 --velocity 0        # at rest on the still plate
  bistable classify --omega 2.45 --velocity 0.07     # chaotic (not sensitive)
  bistable classify --omega 0.85 --velocity 0.13     # sensitive: rest in well 2
                                                     # or continuous interwell P-1
  bistable classify --omega 0.85 --velocity 0.11 --full --max-periods 5000";

/// How long and how carefully to classify (shared by `classify` and `map`).
#[derive(Debug, Clone, Args)]
#[command(next_help_heading = "Classification")]
pub struct ClassifyArgs {
    /// Longest run, in natural periods τ/2π (the paper: 20,000).
    #[arg(long, value_name = "N", default_value_t = 20_000.0)]
    pub max_periods: f64,

    /// Always run the full --max-periods (no early stop); the class is then decided on the
    /// final sections.
    #[arg(long)]
    pub full: bool,

    /// Largest steady-state period looked for, in shaker periods (1..=64; longer periods
    /// count as aperiodic).
    #[arg(long, value_name = "P", default_value_t = 16)]
    pub max_period: u32,

    /// Relative agreement of section points p periods apart that counts as periodic
    /// (in (0, 1e-3]).
    #[arg(long, value_name = "TOL", default_value = "1e-8")]
    pub period_tol: f64,

    /// Shaker periods averaged for the Lyapunov exponent of an aperiodic response
    /// [default: 2000 for classify, 300 for map (throughput)].
    #[arg(long, value_name = "N")]
    pub lyapunov_periods: Option<u32>,

    /// Sensitivity test: perturbed repeats of a suspect run (0..=64; 0 turns the test off).
    #[arg(long, value_name = "K", default_value_t = SensitivityOptions::default().repeats)]
    pub repeats: u32,

    /// Sensitivity test: transient growth, in e-foldings of an infinitesimal perturbation,
    /// from which a decided run is suspect and repeated (in (0, 700]).
    #[arg(long, value_name = "N", default_value_t = SensitivityOptions::default().efoldings)]
    pub efoldings: f64,

    /// Sensitivity test: displacement of the repeats' initial state (x0, x0') from (0, 0)
    /// (in (0, 1e-3]).
    #[arg(long, value_name = "D", default_value = "1e-12")]
    pub perturbation: f64,

    /// Sensitivity test: natural periods over which the transient growth is tracked; a run
    /// decided later is repeated too (in [1, 1e8]).
    #[arg(long, value_name = "N", default_value_t = SensitivityOptions::default().horizon)]
    pub horizon: f64,

    /// Sensitivity test: length of the repeats of an aperiodic run, in natural periods (in
    /// [1, 1e8]).
    #[arg(long, value_name = "N", default_value_t = SensitivityOptions::default().repeat_periods)]
    pub repeat_periods: f64,

    /// Sensitivity test: further Lyapunov windows of an aperiodic run, each a verdict on
    /// 'chaotic': the last stretches of the run itself, as many as fit in its last quarter
    /// (0..=1024).
    #[arg(long, value_name = "N", default_value_t = SensitivityOptions::default().windows)]
    pub lyapunov_windows: u32,
}

impl ClassifyArgs {
    /// Validated core options; `lyapunov_default` applies when `--lyapunov-periods` is absent.
    pub fn options(&self, lyapunov_default: u32) -> Result<ClassifyOptions, CliError> {
        Ok(ClassifyOptions {
            max_natural_periods: self.max_periods,
            full_length: self.full,
            max_period: self.max_period,
            period_tol: self.period_tol,
            lyapunov_periods: self.lyapunov_periods.unwrap_or(lyapunov_default),
        }
        .check()?)
    }

    /// Validated settings of the sensitivity test.
    pub fn sensitivity(&self) -> Result<SensitivityOptions, CliError> {
        let so = SensitivityOptions {
            repeats: self.repeats,
            efoldings: self.efoldings,
            perturbation: self.perturbation,
            horizon: self.horizon,
            repeat_periods: self.repeat_periods,
            windows: self.lyapunov_windows,
        };
        Ok(so.check()?)
    }
}

/// Options of `bistable classify`.
#[derive(Debug, Clone, Args)]
pub struct ClassifyCmdArgs {
    #[command(flatten)]
    pub common: CommonArgs,

    #[command(flatten)]
    pub classify: ClassifyArgs,
}

use bistable_analysis::record::{parse_outcomes, OutcomeShare, Value, CLASSES};
pub use bistable_analysis::record::{Record, COLUMNS as CSV_COLUMNS};

/// A [`Record`] as the JSON object `classify` prints (keys and order of [`CSV_COLUMNS`]).
pub struct Json<'a>(pub &'a Record);

impl Serialize for Json<'_> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut m = s.serialize_map(Some(CSV_COLUMNS.len()))?;
        for (k, v) in self.0.pairs() {
            match v {
                Value::F(x) => m.serialize_entry(k, &x)?,
                Value::I(n) => m.serialize_entry(k, &n)?,
                Value::Bool(b) => m.serialize_entry(k, &b)?,
                Value::S(t) => m.serialize_entry(k, t)?,
                Value::Null => m.serialize_entry(k, &None::<u8>)?,
                Value::Outcomes(list, _) => {
                    let list: Vec<OutcomeJson<'_>> = list.iter().map(OutcomeJson).collect();
                    m.serialize_entry(k, &list)?
                }
            }
        }
        m.end()
    }
}

/// An [`OutcomeShare`] as a JSON object (keys of [`OutcomeShare::FIELDS`]).
struct OutcomeJson<'a>(&'a OutcomeShare);

impl Serialize for OutcomeJson<'_> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let o = self.0;
        let [class, period, chaotic, final_well, count, fraction] = OutcomeShare::FIELDS;
        let mut m = s.serialize_map(Some(OutcomeShare::FIELDS.len()))?;
        m.serialize_entry(class, &o.class)?;
        m.serialize_entry(period, &o.period)?;
        m.serialize_entry(chaotic, &o.chaotic)?;
        m.serialize_entry(final_well, &o.final_well)?;
        m.serialize_entry(count, &o.count)?;
        m.serialize_entry(fraction, &o.fraction)?;
        m.end()
    }
}

/// The CSV form of a [`Record`] (one row of `bistable map`).
pub trait RecordCsv: Sized {
    /// The CSV fields, in the order of [`CSV_COLUMNS`].
    fn fields(&self) -> [Field<'_>; 24];
    /// Parses a CSV row written with [`RecordCsv::fields`] (columns as in [`CSV_COLUMNS`]).
    fn from_csv(cells: &[&str]) -> Result<Self, String>;
}

impl RecordCsv for Record {
    fn fields(&self) -> [Field<'_>; 24] {
        self.values().map(Field::from)
    }

    fn from_csv(cells: &[&str]) -> Result<Self, String> {
        if cells.len() != CSV_COLUMNS.len() {
            return Err(format!(
                "{} fields, expected {}",
                cells.len(),
                CSV_COLUMNS.len()
            ));
        }
        fn parse<T: std::str::FromStr>(cells: &[&str], i: usize) -> Result<T, String> {
            cells[i]
                .parse()
                .map_err(|_| format!("bad {} '{}'", CSV_COLUMNS[i], cells[i]))
        }
        fn opt<T: std::str::FromStr>(cells: &[&str], i: usize) -> Result<Option<T>, String> {
            if cells[i].is_empty() {
                Ok(None)
            } else {
                parse(cells, i).map(Some)
            }
        }
        let class = cells[4];
        if !CLASSES.contains(&class) {
            return Err(format!("bad class '{class}'"));
        }
        Ok(Self {
            omega: parse(cells, 0)?,
            velocity: parse(cells, 1)?,
            zeta: parse(cells, 2)?,
            restitution: parse(cells, 3)?,
            class: class.to_string(),
            period: opt(cells, 5)?,
            chaotic: parse(cells, 6)?,
            lyapunov: opt(cells, 7)?,
            snap_throughs: parse(cells, 8)?,
            final_well: parse(cells, 9)?,
            at_rest_in_second_well: parse(cells, 10)?,
            impacts_per_period: opt(cells, 11)?,
            sticking: parse(cells, 12)?,
            periods_simulated: parse(cells, 13)?,
            stopped_early: parse(cells, 14)?,
            wall_time_s: parse(cells, 15)?,
            sensitive: parse(cells, 16)?,
            runs: parse(cells, 17)?,
            majority_fraction: parse(cells, 18)?,
            outcomes: parse_outcomes(cells[19], parse(cells, 17)?)?,
            outcomes_text: cells[19].to_string(),
            sensitivity_trigger: cells[20].to_string(),
            efoldings: opt(cells, 21)?,
            efoldings_threshold: opt(cells, 22)?,
            at_rest: parse(cells, 23)?,
        })
    }
}

/// Runs `bistable classify`.
pub fn run(args: &ClassifyCmdArgs) -> Result<(), CliError> {
    let model = args.common.model()?;
    let co = args
        .classify
        .options(ClassifyOptions::default().lyapunov_periods)?;
    let so = args.classify.sensitivity()?;
    print_json(&Json(&Record::new(&classify_point_with(&model, co, so)?)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::push_fields;

    #[test]
    fn csv_row_round_trips() {
        let r = Record {
            omega: 0.85,
            velocity: 1.0 / 3.0,
            zeta: 0.02,
            restitution: 0.7,
            class: "transient_interwell".into(),
            period: None,
            chaotic: true,
            lyapunov: Some(0.0123),
            snap_throughs: 17,
            final_well: 2,
            at_rest_in_second_well: false,
            impacts_per_period: None,
            sticking: false,
            periods_simulated: 20000.5,
            stopped_early: false,
            wall_time_s: 1.5e-3,
            sensitive: true,
            runs: 9,
            majority_fraction: 7.0 / 9.0,
            outcomes: parse_outcomes(
                "transient_interwell:P-1:2=0.778;continuous_interwell:P-1:-=0.222",
                9,
            )
            .unwrap(),
            outcomes_text: "transient_interwell:P-1:2=0.778;continuous_interwell:P-1:-=0.222"
                .into(),
            sensitivity_trigger: "growth".into(),
            efoldings: Some(20.0),
            efoldings_threshold: Some(20.0),
            at_rest: false,
        };
        let mut line = String::new();
        push_fields(&mut line, &r.fields());
        let cells: Vec<&str> = line.split(',').collect();
        assert_eq!(Record::from_csv(&cells).unwrap(), r);
        assert!(Record::from_csv(&cells[1..]).is_err());
        let mut bad = cells.clone();
        bad[4] = "sideways";
        assert!(Record::from_csv(&bad).is_err());
    }
}
