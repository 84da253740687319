//! The event log: the simulator's events turned into the three tables every front end shows,
//! one row at a time, with their rules in one place.
//!
//! - **Impacts** (`index, t, phase, x, v_before, v_after, delta_k`): one row per impact, in
//!   order, each with whether sticking followed it (`ended_in_sticking`, not a column). An impact
//!   is held back until that is known: until the next impact or stick start, or until the time
//!   has moved more than the log's lookahead past it, or until [`EventLog::finish`].
//! - **Sticking intervals** (`start, end, x_start, x_end`): one row when an interval closes: at
//!   the release ([`Event::StickEnd`]); at a second stick start without a release between, which
//!   closes the first where the next begins; or at the end of the run ([`EventLog::finish`]),
//!   which leaves `end` and `x_end` missing. A release seen without its start (a run that began
//!   sticking) gives a row with `start` and `x_start` missing.
//! - **Snap-throughs** (`t, v, to_well`): one row per barrier crossing.
//!
//! Rows wait in the log until [`EventLog::rows`] drains them, so a caller can write them as the
//! run goes (files of any length) or gather them (tables in memory). Formatting the cells is the
//! caller's part; [`Cell`] says which are integers, reals or missing.
//!
//! ```
//! use bistable_analysis::event_log::{EventLog, Row};
//! use bistable_core::{Event, Impact, StickCause};
//! let impact = Impact {
//!     index: 0, t: 0.0, phase: Some(0.0), x: 0.0, v_before: 0.0, v_after: 0.13, zdot: 0.07,
//!     delta_k: 0.008,
//! };
//! let mut log = EventLog::new();
//! log.record(&Event::Impact(impact));
//! log.record(&Event::StickStart { t: 1.0, x: 0.1, cause: StickCause::Accumulation, impacts: 1 });
//! log.finish();
//! let rows: Vec<Row> = log.rows().collect();
//! assert!(matches!(rows[0], Row::Impact(r) if r.ended_in_sticking));
//! assert!(matches!(rows[1], Row::Stick(s) if s.start == Some(1.0) && s.end.is_none()));
//! ```

use bistable_core::{ContactMode, Event, Impact, StickCause};

/// Column names of the impacts table, in order.
pub const IMPACT_COLUMNS: [&str; 7] =
    ["index", "t", "phase", "x", "v_before", "v_after", "delta_k"];
/// Column names of the sticking-intervals table, in order.
pub const STICKING_COLUMNS: [&str; 4] = ["start", "end", "x_start", "x_end"];
/// Column names of the snap-throughs table, in order.
pub const SNAP_COLUMNS: [&str; 3] = ["t", "v", "to_well"];
/// The integer columns (their cells are [`Cell::Int`]); all others are real.
pub const INTEGER_COLUMNS: [&str; 2] = ["index", "to_well"];

/// One cell of a row.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Cell {
    /// An integer column (`index`, `to_well`).
    Int(u64),
    /// A real column.
    Real(f64),
    /// A real column with no value here (an open interval's end, a phase without a sinusoid).
    Missing,
}

impl From<Option<f64>> for Cell {
    fn from(v: Option<f64>) -> Self {
        v.map_or(Cell::Missing, Cell::Real)
    }
}

/// A row of the impacts table.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImpactRow {
    /// The impact.
    pub impact: Impact,
    /// Whether the mass came to rest on the plate right after it (the next event was a stick
    /// start counting this impact as its last).
    pub ended_in_sticking: bool,
}

impl ImpactRow {
    /// The cells, in the order of [`IMPACT_COLUMNS`].
    pub fn cells(&self) -> [Cell; 7] {
        let i = &self.impact;
        [
            Cell::Int(i.index),
            Cell::Real(i.t),
            i.phase.into(),
            Cell::Real(i.x),
            Cell::Real(i.v_before),
            Cell::Real(i.v_after),
            Cell::Real(i.delta_k),
        ]
    }
}

/// What closed a sticking interval.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Closing {
    /// The mass left the plate ([`Event::StickEnd`]).
    Release,
    /// Another stick start came without a release between: the first closes where the next
    /// begins.
    NextStick,
    /// The run ended with the mass on the plate ([`EventLog::finish`]).
    EndOfRun,
}

/// A row of the sticking-intervals table.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StickRow {
    /// Start instant (missing when the log did not see the interval begin).
    pub start: Option<f64>,
    /// End instant (missing when the run ended first).
    pub end: Option<f64>,
    /// Position at the start.
    pub x_start: Option<f64>,
    /// Position at the end.
    pub x_end: Option<f64>,
    /// What closed the interval.
    pub closing: Closing,
}

impl StickRow {
    /// The cells, in the order of [`STICKING_COLUMNS`].
    pub fn cells(&self) -> [Cell; 4] {
        [
            self.start.into(),
            self.end.into(),
            self.x_start.into(),
            self.x_end.into(),
        ]
    }
}

/// A row of the snap-throughs table.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SnapRow {
    /// Instant of the crossing.
    pub t: f64,
    /// Velocity at the crossing.
    pub v: f64,
    /// The well entered, 1 or 2.
    pub to_well: u8,
}

impl SnapRow {
    /// The cells, in the order of [`SNAP_COLUMNS`].
    pub fn cells(&self) -> [Cell; 3] {
        [
            Cell::Real(self.t),
            Cell::Real(self.v),
            Cell::Int(u64::from(self.to_well)),
        ]
    }
}

/// A row of one of the three tables.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Row {
    /// An impact, once it is known whether sticking followed it.
    Impact(ImpactRow),
    /// A closed (or, at the end of the run, open) sticking interval.
    Stick(StickRow),
    /// A snap-through.
    Snap(SnapRow),
}

/// Turns events into rows of the impacts, sticking and snap-through tables; see the module
/// documentation for the rules.
#[derive(Debug, Clone)]
pub struct EventLog {
    lookahead: f64,
    /// The last impact, held until it is known whether sticking follows it.
    pending: Option<Impact>,
    /// Start `(t, x)` of the sticking interval in progress.
    open_stick: Option<(f64, f64)>,
    rows: Vec<Row>,
    impacts: u64,
    sticks: u64,
    snaps: u64,
    last_impact: Option<Impact>,
}

impl Default for EventLog {
    fn default() -> Self {
        Self::new()
    }
}

impl EventLog {
    /// A log that holds each impact until the next impact or stick start (or the end of the
    /// run) tells whether sticking followed it.
    pub fn new() -> Self {
        Self::with_lookahead(f64::INFINITY)
    }

    /// A log that also lets an impact go, as not followed by sticking, once the time has
    /// moved more than `lookahead` past it ([`EventLog::settle`] or a later event): for
    /// callers that publish impacts as the run goes and know how soon sticking can follow.
    pub fn with_lookahead(lookahead: f64) -> Self {
        Self {
            lookahead,
            pending: None,
            open_stick: None,
            rows: Vec::new(),
            impacts: 0,
            sticks: 0,
            snaps: 0,
            last_impact: None,
        }
    }

    /// Takes one event (in time order).
    pub fn record(&mut self, event: &Event) {
        self.settle(event.t());
        match *event {
            Event::Impact(i) => {
                self.impacts += 1;
                self.last_impact = Some(i);
                if let Some(p) = self.pending.replace(i) {
                    self.impact_row(p, false);
                }
            }
            Event::StickStart { t, x, impacts, .. } => {
                self.sticks += 1;
                if let Some(p) = self.pending.take() {
                    self.impact_row(p, impacts == p.index + 1);
                }
                if let Some((t0, x0)) = self.open_stick.replace((t, x)) {
                    self.stick_row(Some((t0, x0)), Some((t, x)), Closing::NextStick);
                }
            }
            Event::StickEnd { t, x, .. } => {
                let start = self.open_stick.take();
                self.stick_row(start, Some((t, x)), Closing::Release);
            }
            Event::SnapThrough { t, v, to } => {
                self.snaps += 1;
                self.rows.push(Row::Snap(SnapRow {
                    t,
                    v,
                    to_well: to.number(),
                }));
            }
        }
    }

    /// Lets the held impact go, as not followed by sticking, if `now` is more than the
    /// lookahead past it.
    pub fn settle(&mut self, now: f64) {
        if let Some(p) = self.pending {
            if now - p.t > self.lookahead {
                self.pending = None;
                self.impact_row(p, false);
            }
        }
    }

    /// Ends the run: the held impact goes as not followed by sticking, and a sticking interval
    /// still open gets its row with the end missing. The log can then take a new run (the
    /// counts go on).
    pub fn finish(&mut self) {
        if let Some(p) = self.pending.take() {
            self.impact_row(p, false);
        }
        if let Some(start) = self.open_stick.take() {
            self.stick_row(Some(start), None, Closing::EndOfRun);
        }
    }

    /// The rows complete so far, in the order they completed (each table's rows in time
    /// order); they leave the log.
    pub fn rows(&mut self) -> std::vec::Drain<'_, Row> {
        self.rows.drain(..)
    }

    /// Impacts recorded.
    pub fn impacts(&self) -> u64 {
        self.impacts
    }

    /// Stick starts recorded.
    pub fn sticks(&self) -> u64 {
        self.sticks
    }

    /// Snap-throughs recorded.
    pub fn snaps(&self) -> u64 {
        self.snaps
    }

    /// The last impact recorded.
    pub fn last_impact(&self) -> Option<Impact> {
        self.last_impact
    }

    /// Start `(t, x)` of the sticking interval in progress, if any.
    pub fn open_stick(&self) -> Option<(f64, f64)> {
        self.open_stick
    }

    fn impact_row(&mut self, impact: Impact, ended_in_sticking: bool) {
        self.rows.push(Row::Impact(ImpactRow {
            impact,
            ended_in_sticking,
        }));
    }

    fn stick_row(&mut self, start: Option<(f64, f64)>, end: Option<(f64, f64)>, closing: Closing) {
        let (start, x_start) = start.unzip();
        let (end, x_end) = end.unzip();
        self.rows.push(Row::Stick(StickRow {
            start,
            end,
            x_start,
            x_end,
            closing,
        }));
    }
}

/// Name of a contact mode: `free` or `sticking`.
pub fn mode_name(mode: ContactMode) -> &'static str {
    match mode {
        ContactMode::Free => "free",
        ContactMode::Sticking => "sticking",
    }
}

/// Name of a stick cause: `accumulation`, `fixed_gap`, `plastic` or `zeno_guard`.
pub fn cause_name(cause: StickCause) -> &'static str {
    match cause {
        StickCause::Accumulation => "accumulation",
        StickCause::FixedGap => "fixed_gap",
        StickCause::Plastic => "plastic",
        StickCause::ZenoGuard => "zeno_guard",
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use bistable_core::Well;

    fn impact(index: u64, t: f64) -> Impact {
        Impact {
            index,
            t,
            phase: Some(0.25),
            x: 0.1 * t,
            v_before: -0.5,
            v_after: 0.4,
            zdot: 0.02,
            delta_k: 0.5 * (0.4f64.powi(2) - 0.5f64.powi(2)),
        }
    }

    fn start(t: f64, x: f64, impacts: u64) -> Event {
        Event::StickStart {
            t,
            x,
            cause: StickCause::Accumulation,
            impacts,
        }
    }

    fn end(t: f64, x: f64) -> Event {
        Event::StickEnd { t, x, v: 0.0 }
    }

    fn run(log: &mut EventLog, events: &[Event]) -> Vec<Row> {
        for e in events {
            log.record(e);
        }
        log.finish();
        log.rows().collect()
    }

    fn sticks(rows: &[Row]) -> Vec<StickRow> {
        rows.iter()
            .filter_map(|r| match r {
                Row::Stick(s) => Some(*s),
                _ => None,
            })
            .collect()
    }

    #[test]
    fn a_second_stick_start_closes_the_first() {
        let mut log = EventLog::new();
        let rows = run(
            &mut log,
            &[start(1.0, 0.1, 0), start(2.0, 0.2, 0), end(3.0, 0.3)],
        );
        let s = sticks(&rows);
        assert_eq!(s.len(), 2);
        assert_eq!(
            s[0],
            StickRow {
                start: Some(1.0),
                end: Some(2.0),
                x_start: Some(0.1),
                x_end: Some(0.2),
                closing: Closing::NextStick,
            }
        );
        assert_eq!(
            s[1].cells(),
            [
                Cell::Real(2.0),
                Cell::Real(3.0),
                Cell::Real(0.2),
                Cell::Real(0.3)
            ]
        );
        assert_eq!(s[1].closing, Closing::Release);
        assert_eq!(log.sticks(), 2);
        assert_eq!(log.open_stick(), None);
    }

    #[test]
    fn an_open_stick_is_closed_at_the_end() {
        let mut log = EventLog::new();
        log.record(&start(1.5, 0.4, 0));
        assert_eq!(log.open_stick(), Some((1.5, 0.4)));
        assert_eq!(log.rows().count(), 0, "an open interval has no row yet");
        log.finish();
        let rows: Vec<Row> = log.rows().collect();
        let s = sticks(&rows);
        assert_eq!(s.len(), 1);
        assert_eq!(s[0].closing, Closing::EndOfRun);
        assert_eq!(
            s[0].cells(),
            [
                Cell::Real(1.5),
                Cell::Missing,
                Cell::Real(0.4),
                Cell::Missing
            ]
        );
        assert_eq!(log.open_stick(), None);
    }

    #[test]
    fn a_release_without_its_start_has_the_start_missing() {
        let rows = run(&mut EventLog::new(), &[end(2.0, 0.3)]);
        assert_eq!(
            sticks(&rows)[0].cells(),
            [
                Cell::Missing,
                Cell::Real(2.0),
                Cell::Missing,
                Cell::Real(0.3)
            ]
        );
    }

    #[test]
    fn impacts_and_snaps_are_recorded_with_their_fields() {
        let mut log = EventLog::new();
        let mut i1 = impact(1, 0.5);
        i1.phase = None;
        let snap = Event::SnapThrough {
            t: 0.7,
            v: 0.3,
            to: Well::Two,
        };
        let rows = run(
            &mut log,
            &[Event::Impact(impact(0, 0.0)), Event::Impact(i1), snap],
        );
        let i0 = impact(0, 0.0);
        assert_eq!(
            rows,
            vec![
                Row::Impact(ImpactRow {
                    impact: i0,
                    ended_in_sticking: false
                }),
                Row::Snap(SnapRow {
                    t: 0.7,
                    v: 0.3,
                    to_well: 2
                }),
                Row::Impact(ImpactRow {
                    impact: i1,
                    ended_in_sticking: false
                }),
            ]
        );
        let Row::Impact(r) = rows[0] else {
            unreachable!()
        };
        assert_eq!(
            r.cells(),
            [
                Cell::Int(0),
                Cell::Real(0.0),
                Cell::Real(0.25),
                Cell::Real(0.0),
                Cell::Real(-0.5),
                Cell::Real(0.4),
                Cell::Real(i0.delta_k),
            ]
        );
        let Row::Impact(r) = rows[2] else {
            unreachable!()
        };
        assert_eq!(r.cells()[2], Cell::Missing, "no phase without a sinusoid");
        let Row::Snap(s) = rows[1] else {
            unreachable!()
        };
        assert_eq!(s.cells(), [Cell::Real(0.7), Cell::Real(0.3), Cell::Int(2)]);
        assert_eq!((log.impacts(), log.snaps(), log.sticks()), (2, 1, 0));
        assert_eq!(log.last_impact(), Some(i1));
    }

    #[test]
    fn an_impact_ends_in_sticking_when_the_stick_start_counts_it_last() {
        let rows = run(
            &mut EventLog::new(),
            &[
                Event::Impact(impact(0, 0.0)),
                Event::Impact(impact(1, 1.0)),
                start(1.2, 0.12, 2),
                end(2.0, 0.2),
                Event::Impact(impact(2, 3.0)),
                // A stick start that does not count impact 2 as its last.
                start(3.5, 0.35, 7),
            ],
        );
        let flags: Vec<(u64, bool)> = rows
            .iter()
            .filter_map(|r| match r {
                Row::Impact(i) => Some((i.impact.index, i.ended_in_sticking)),
                _ => None,
            })
            .collect();
        assert_eq!(flags, [(0, false), (1, true), (2, false)]);
    }

    #[test]
    fn the_lookahead_lets_a_held_impact_go() {
        let mut log = EventLog::with_lookahead(0.5);
        log.record(&Event::Impact(impact(0, 1.0)));
        log.settle(1.5);
        assert_eq!(log.rows().count(), 0, "held up to the lookahead");
        log.settle(1.6);
        let rows: Vec<Row> = log.rows().collect();
        assert!(matches!(rows[..], [Row::Impact(r)] if !r.ended_in_sticking));
        // A later stick start no longer marks it.
        log.record(&Event::Impact(impact(1, 2.0)));
        log.record(&start(2.6, 0.3, 2));
        let rows: Vec<Row> = log.rows().collect();
        assert!(matches!(rows[..], [Row::Impact(r)] if !r.ended_in_sticking));
        // Without a lookahead the impact waits for the stick start.
        let mut log = EventLog::new();
        log.record(&Event::Impact(impact(0, 1.0)));
        log.settle(1e12);
        log.record(&start(1e12, 0.3, 1));
        let rows: Vec<Row> = log.rows().collect();
        assert!(matches!(rows[0], Row::Impact(r) if r.ended_in_sticking));
    }

    #[test]
    fn names() {
        assert_eq!(mode_name(ContactMode::Free), "free");
        assert_eq!(mode_name(ContactMode::Sticking), "sticking");
        assert_eq!(cause_name(StickCause::FixedGap), "fixed_gap");
        assert_eq!(cause_name(StickCause::ZenoGuard), "zeno_guard");
    }
}
