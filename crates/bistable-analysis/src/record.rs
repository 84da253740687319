//! The record of one classified point: the keys and values that `bistable classify` prints as
//! JSON, `bistable map` writes as a CSV row and the Python package returns as a dict. The single
//! definition of those names, their order and their values; formatting is the callers' part.

use crate::sweep::Classified;

/// Names of the [`Record`] fields, in order: the JSON keys and the map CSV columns.
pub const COLUMNS: [&str; 23] = [
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
    /// Every distinct outcome with its share, most frequent first: `class:period:well=share`
    /// joined by `;` (period `P-n`, `chaotic` or `aperiodic`; well `-` for continuous
    /// interwell), e.g. `transient_interwell:P-1:2=0.556;continuous_interwell:P-1:-=0.444`.
    pub outcomes: String,
    /// Why the point was repeated: `none`, `growth`, `late` or `aperiodic`
    /// ([`crate::sensitivity::Trigger`]).
    pub sensitivity_trigger: String,
    /// Transient growth of the run from the paper's initial condition (e-foldings, capped at
    /// the threshold); `None` without the test.
    pub efoldings: Option<f64>,
    /// The growth from which a decided run is repeated; `None` without the test.
    pub efoldings_threshold: Option<f64>,
}

/// The three class names a [`Record`] may hold.
pub const CLASSES: [&str; 3] = ["intrawell", "transient_interwell", "continuous_interwell"];

impl Record {
    /// The record of a classified point.
    pub fn new(point: &Classified) -> Self {
        let (m, c) = (&point.model, &point.classification);
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
            sticking: c.sticking,
            periods_simulated: c.periods_simulated,
            stopped_early: c.stopped_early,
            wall_time_s: point.wall_time_s,
            sensitive: point.sensitivity.sensitive,
            runs: point.sensitivity.runs,
            majority_fraction: point.sensitivity.majority_fraction(),
            outcomes: point.sensitivity.fractions(),
            sensitivity_trigger: point.sensitivity.trigger.name().to_string(),
            efoldings: point.sensitivity.efoldings,
            efoldings_threshold: point.sensitivity.threshold,
        }
    }

    /// The values in the order of [`COLUMNS`].
    pub fn values(&self) -> [Value<'_>; 23] {
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
            Value::S(&self.outcomes),
            Value::S(&self.sensitivity_trigger),
            self.efoldings.map_or(Value::Null, Value::F),
            self.efoldings_threshold.map_or(Value::Null, Value::F),
        ]
    }

    /// `(name, value)` pairs in order.
    pub fn pairs(&self) -> impl Iterator<Item = (&'static str, Value<'_>)> {
        COLUMNS.into_iter().zip(self.values())
    }
}
