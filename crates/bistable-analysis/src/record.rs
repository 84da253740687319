//! The record of one classified point: the keys and values that `bistable classify` prints as
//! JSON, `bistable map` writes as a CSV row and the Python package returns as a dict. The single
//! definition of those names, their order and their values; formatting is the callers' part.

use bistable_core::{Classification, Well};

use crate::period;
use crate::sensitivity::Sensitivity;
use crate::sweep::Classified;

/// Names of the [`Record`] fields, in order: the JSON keys and the map CSV columns.
pub const COLUMNS: [&str; 24] = [
    "omega",
    "velocity",
    "zeta",
    "restitution",
    "class",
    "period",
    "chaotic",
    "lyapunov",
    "snap_throughs",
    "final_well",
    "at_rest_in_second_well",
    "impacts_per_period",
    "sticking",
    "periods_simulated",
    "stopped_early",
    "wall_time_s",
    "sensitive",
    "runs",
    "majority_fraction",
    "outcomes",
    "sensitivity_trigger",
    "efoldings",
    "efoldings_threshold",
    "at_rest",
];

/// One value of a [`Record`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Value<'a> {
    /// A real number.
    F(f64),
    /// A count.
    I(u64),
    /// A flag.
    Bool(bool),
    /// A name.
    S(&'a str),
    /// No value (JSON `null`, an empty CSV field).
    Null,
    /// The outcomes of the sensitivity test: a list of objects in JSON and Python
    /// ([`OutcomeShare`]), their text form ([`outcomes_text`]) in a CSV field.
    Outcomes(&'a [OutcomeShare], &'a str),
}

/// One distinct outcome of a point's runs with its share (an entry of [`Record::outcomes`]):
/// the JSON object `{"class", "period", "chaotic", "final_well", "count", "fraction"}` of
/// `bistable classify` and the dict of the Python package.
#[derive(Debug, Clone, PartialEq)]
pub struct OutcomeShare {
    /// `intrawell`, `transient_interwell` or `continuous_interwell`.
    pub class: String,
    /// Steady-state period in shaker periods; `None` when aperiodic.
    pub period: Option<u32>,
    /// Aperiodic with a positive largest Lyapunov exponent.
    pub chaotic: bool,
    /// Final well (1 or 2); `None` for a continuous interwell response (it visits both).
    pub final_well: Option<u8>,
    /// Runs (verdicts) that reached this outcome.
    pub count: u32,
    /// `count / runs`.
    pub fraction: f64,
}

impl OutcomeShare {
    /// The names of the fields, in order (the JSON keys).
    pub const FIELDS: [&'static str; 6] = [
        "class",
        "period",
        "chaotic",
        "final_well",
        "count",
        "fraction",
    ];

    /// `class:period:well` (period `P-n`, `chaotic` or `aperiodic`; well `1`, `2` or `-`), the
    /// key of [`crate::sensitivity::Outcome::key`].
    pub fn key(&self) -> String {
        let period = period::label(self.period, self.chaotic);
        let well = self.final_well.map_or("-".to_string(), |w| w.to_string());
        format!("{}:{period}:{well}", self.class)
    }
}

/// The outcomes of a sensitivity test as data, most frequent first.
pub fn outcome_shares(s: &Sensitivity) -> Vec<OutcomeShare> {
    let n = f64::from(s.runs.max(1));
    s.outcomes
        .iter()
        .map(|(o, c)| OutcomeShare {
            class: o.class.name().to_string(),
            period: o.period,
            chaotic: o.chaotic,
            final_well: o.final_well.map(|w| w.number()),
            count: *c,
            fraction: f64::from(*c) / n,
        })
        .collect()
}

/// The CSV text of outcomes: `class:period:well=fraction` (fraction to 3 decimals) joined by
/// `;`, e.g. `transient_interwell:P-1:2=0.556;continuous_interwell:P-1:-=0.444`.
pub fn outcomes_text(shares: &[OutcomeShare]) -> String {
    shares
        .iter()
        .map(|o| format!("{}={:.3}", o.key(), o.fraction))
        .collect::<Vec<_>>()
        .join(";")
}

/// Parses the CSV text of [`outcomes_text`] back into outcomes of a point with `runs` runs
/// (`count` is the nearest whole number of runs to `fraction · runs`, `fraction` is then
/// `count / runs`: exact again for up to 1,000 runs).
pub fn parse_outcomes(text: &str, runs: u32) -> Result<Vec<OutcomeShare>, String> {
    let n = f64::from(runs.max(1));
    text.split(';')
        .map(|item| {
            let bad = || format!("bad outcome '{item}'");
            let (key, share) = item.split_once('=').ok_or_else(bad)?;
            let mut parts = key.split(':');
            let (Some(class), Some(period), Some(well), None) =
                (parts.next(), parts.next(), parts.next(), parts.next())
            else {
                return Err(bad());
            };
            if !CLASSES.contains(&class) {
                return Err(bad());
            }
            let (period, chaotic) = period::parse_label(period).ok_or_else(bad)?;
            let final_well = match well {
                "-" => None,
                "1" => Some(1),
                "2" => Some(2),
                _ => return Err(bad()),
            };
            let share: f64 = share.parse().map_err(|_| bad())?;
            if !(0.0..=1.0).contains(&share) {
                return Err(bad());
            }
            let count = (share * n).round() as u32;
            Ok(OutcomeShare {
                class: class.to_string(),
                period,
                chaotic,
                final_well,
                count,
                fraction: f64::from(count) / n,
            })
        })
        .collect()
}

/// One classified point (see [`COLUMNS`]); units are the model's (nondimensional).
#[derive(Debug, Clone, PartialEq)]
pub struct Record {
    /// `Ω`.
    pub omega: f64,
    /// `V`.
    pub velocity: f64,
    /// `ζ`.
    pub zeta: f64,
    /// `e`.
    pub restitution: f64,
    /// `intrawell`, `transient_interwell` or `continuous_interwell`.
    pub class: String,
    /// Steady-state period in shaker periods; `None` when aperiodic.
    pub period: Option<u32>,
    /// Aperiodic with a positive largest Lyapunov exponent.
    pub chaotic: bool,
    /// Largest Lyapunov exponent (per unit of τ) of an aperiodic response.
    pub lyapunov: Option<f64>,
    /// Barrier crossings over the whole run.
    pub snap_throughs: u64,
    /// 1 or 2.
    pub final_well: u8,
    /// Converged to rest at the second equilibrium.
    pub at_rest_in_second_well: bool,
    /// Impacts per steady-state period.
    pub impacts_per_period: Option<u64>,
    /// The steady state includes sticking.
    pub sticking: bool,
    /// Natural periods simulated.
    pub periods_simulated: f64,
    /// Stopped before the full length.
    pub stopped_early: bool,
    /// Wall-clock time of this point, all its runs (s).
    pub wall_time_s: f64,
    /// The runs from perturbed starts did not all reach the same outcome
    /// ([`crate::sensitivity`]).
    pub sensitive: bool,
    /// Verdicts counted: 1, or 1 + the repeats of a suspect point (+ the further Lyapunov
    /// windows of an aperiodic one).
    pub runs: u32,
    /// Share of the runs that reached the reported outcome.
    pub majority_fraction: f64,
    /// Every distinct outcome with its share, most frequent first ([`OutcomeShare`]; in a CSV
    /// field as [`Record::outcomes_text`]).
    pub outcomes: Vec<OutcomeShare>,
    /// The CSV text of `outcomes` ([`outcomes_text`]): `class:period:well=share` joined by `;`
    /// (period `P-n`, `chaotic` or `aperiodic`; well `-` for continuous interwell), e.g.
    /// `transient_interwell:P-1:2=0.556;continuous_interwell:P-1:-=0.444`.
    pub outcomes_text: String,
    /// Why the point was repeated: `none`, `growth`, `late` or `aperiodic`
    /// ([`crate::sensitivity::Trigger`]).
    pub sensitivity_trigger: String,
    /// Transient growth of the run from the paper's initial condition (e-foldings, capped at
    /// the threshold); `None` without the test.
    pub efoldings: Option<f64>,
    /// The growth from which a decided run is repeated; `None` without the test.
    pub efoldings_threshold: Option<f64>,
    /// The steady state is the mass at rest: at the second equilibrium
    /// (`at_rest_in_second_well`), or on the plate without ever leaving it (no flight: see
    /// [`never_leaves_the_plate`]). Such a state counts as period 1 with no impacts.
    pub at_rest: bool,
}

/// Whether a classification in well 1 is the mass riding on the plate without any flight in
/// the steady state (the paper's start with `V = 0`: the plate never moves and the mass, at
/// rest on it at `x = 0`, never leaves it). The classifier sees a period-1 state without
/// impacts or barrier crossings in well 1; with damping (`ζ > 0`) or a still plate that can
/// only be the mass on the plate (a free mass in well 1 settles at `x = 0`, where a moving
/// plate hits it). It is then reported at rest, with sticking.
pub fn never_leaves_the_plate(c: &Classification, zeta: f64, velocity: f64) -> bool {
    c.period == Some(1)
        && c.impacts_per_period == Some(0)
        && c.snap_throughs == 0
        && c.final_well == Well::One
        && !c.at_rest_in_second_well
        && (zeta > 0.0 || velocity == 0.0)
}

/// The three class names a [`Record`] may hold.
pub const CLASSES: [&str; 3] = ["intrawell", "transient_interwell", "continuous_interwell"];

impl Record {
    /// The record of a classified point.
    pub fn new(point: &Classified) -> Self {
        let (m, c) = (&point.model, &point.classification);
        let outcomes = outcome_shares(&point.sensitivity);
        let on_plate = never_leaves_the_plate(c, m.params.zeta(), m.velocity());
        Self {
            omega: m.omega(),
            velocity: m.velocity(),
            zeta: m.params.zeta(),
            restitution: m.restitution(),
            class: c.class.name().to_string(),
            period: c.period,
            chaotic: c.chaotic,
            lyapunov: c.lyapunov,
            snap_throughs: c.snap_throughs,
            final_well: c.final_well.number(),
            at_rest_in_second_well: c.at_rest_in_second_well,
            impacts_per_period: c.impacts_per_period,
            sticking: c.sticking || on_plate,
            periods_simulated: c.periods_simulated,
            stopped_early: c.stopped_early,
            wall_time_s: point.wall_time_s,
            sensitive: point.sensitivity.sensitive,
            runs: point.sensitivity.runs,
            majority_fraction: point.sensitivity.majority_fraction(),
            outcomes_text: outcomes_text(&outcomes),
            outcomes,
            sensitivity_trigger: point.sensitivity.trigger.name().to_string(),
            efoldings: point.sensitivity.efoldings,
            efoldings_threshold: point.sensitivity.threshold,
            at_rest: c.at_rest_in_second_well || on_plate,
        }
    }

    /// The values in the order of [`COLUMNS`].
    pub fn values(&self) -> [Value<'_>; 24] {
        let opt_i = |v: Option<u64>| v.map_or(Value::Null, Value::I);
        [
            Value::F(self.omega),
            Value::F(self.velocity),
            Value::F(self.zeta),
            Value::F(self.restitution),
            Value::S(&self.class),
            opt_i(self.period.map(u64::from)),
            Value::Bool(self.chaotic),
            self.lyapunov.map_or(Value::Null, Value::F),
            Value::I(self.snap_throughs),
            Value::I(u64::from(self.final_well)),
            Value::Bool(self.at_rest_in_second_well),
            opt_i(self.impacts_per_period),
            Value::Bool(self.sticking),
            Value::F(self.periods_simulated),
            Value::Bool(self.stopped_early),
            Value::F(self.wall_time_s),
            Value::Bool(self.sensitive),
            Value::I(u64::from(self.runs)),
            Value::F(self.majority_fraction),
            Value::Outcomes(&self.outcomes, &self.outcomes_text),
            Value::S(&self.sensitivity_trigger),
            self.efoldings.map_or(Value::Null, Value::F),
            self.efoldings_threshold.map_or(Value::Null, Value::F),
            Value::Bool(self.at_rest),
        ]
    }

    /// `(name, value)` pairs in order.
    pub fn pairs(&self) -> impl Iterator<Item = (&'static str, Value<'_>)> {
        COLUMNS.into_iter().zip(self.values())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn outcomes_text_round_trips_and_bad_text_is_refused() {
        let shares = vec![
            OutcomeShare {
                class: "transient_interwell".into(),
                period: Some(1),
                chaotic: false,
                final_well: Some(2),
                count: 5,
                fraction: 5.0 / 9.0,
            },
            OutcomeShare {
                class: "continuous_interwell".into(),
                period: None,
                chaotic: true,
                final_well: None,
                count: 4,
                fraction: 4.0 / 9.0,
            },
        ];
        let text = outcomes_text(&shares);
        assert_eq!(
            text,
            "transient_interwell:P-1:2=0.556;continuous_interwell:chaotic:-=0.444"
        );
        assert_eq!(parse_outcomes(&text, 9).unwrap(), shares);
        for bad in [
            "",
            "intrawell:P-1:1",
            "sideways:P-1:1=1.000",
            "intrawell:P-x:1=1.000",
            "intrawell:P-1:3=1.000",
            "intrawell:P-1=1.000",
            "intrawell:P-1:1=2",
        ] {
            assert!(parse_outcomes(bad, 1).is_err(), "{bad}");
        }
    }
}
