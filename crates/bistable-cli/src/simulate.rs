//! `bistable simulate`: one run from the paper's initial condition, with event files, a sampled
//! trace, plots and a summary.

use std::collections::VecDeque;
use std::ops::ControlFlow;
use std::path::{Path, PathBuf};
use std::time::Instant as WallClock;

use clap::{ArgGroup, Args};
use serde::Serialize;

use bistable_analysis::event_log::{
    mode_name, Cell, Closing, EventLog, Row, StickRow, IMPACT_COLUMNS, SNAP_COLUMNS,
    STICKING_COLUMNS,
};
use bistable_analysis::schedule::{earliest, Schedule};
use bistable_analysis::Model;
use bistable_core::{Event, Impact, Observer, SimError, State};

use crate::common::{positive, Chatter, CommonArgs};
use crate::error::CliError;
use crate::output::{num, print_json, print_text, sibling, CsvFile, Field};
use crate::plot::{self, PlotData, Sample};
use crate::progress::Progress;

const TAU: f64 = std::f64::consts::TAU;

/// Header of the trace file.
pub const TRACE_HEADER: &str = "t,x,v,z,zdot";

/// Most rows a trace may have.
const MAX_TRACE_ROWS: f64 = 1e9;

/// Long description shown by `bistable simulate --help`.
pub const LONG_ABOUT: &str = "\
Simulate the bistable oscillator from the paper's initial condition: the mass at
rest at x = 0 at τ = 0, where the plate z = (V/Ω)·sin(Ωτ) meets it moving up, so
impact number 0 happens at τ = 0 with rebound velocity (1+e)·V. The integration
is event driven (Taylor series; every impact, release and barrier crossing is
located as a polynomial root). Output samples are taken from the dense output
and never restart the integration.

Units (nondimensional, as in the paper): time τ = ω0·t, one linear natural
period is 2π; x and z in units of the well distance Δx (wells at 0 and 1,
barrier at 1/2); velocities in units of ω0·Δx; energies in units of k0·Δx².
Phases are shaker phases in cycles, φ/2π = frac(Ωτ/2π) ∈ [0, 1).

Prints a summary of the run: human-readable, or one JSON object with --json.";

/// Shown after the options by `bistable simulate -h`.
pub const AFTER_SHORT_HELP: &str =
    "See 'bistable simulate --help' for the units and the CSV formats.";

/// Shown after the options by `bistable simulate --help`.
pub const AFTER_LONG_HELP: &str = "\
CSV files: one header line, comma separated, numbers in shortest round-trip
form (full double precision).

  --impacts FILE.csv
      index,t,phase,x,v_before,v_after,delta_k
      One row per impact in time order; index 0 is the impact at τ = 0.
      t: impact time τ; phase: shaker phase in cycles, [0, 1); x: position of
      mass and plate; v_before, v_after: mass velocity just before and after,
      v_after = −e·v_before + (1+e)·ż; delta_k = ½(v_after² − v_before²), the
      kinetic energy change (Eq. 10).

  <stem>_sticking.csv, next to FILE.csv (e.g. out/imp.csv → out/imp_sticking.csv)
      start,end,x_start,x_end
      One row per sticking interval: the mass rides on the plate after a
      chatter sequence until the contact force turns negative. An interval
      still open at the end of the run has empty end and x_end.

  <stem>_snaps.csv, next to FILE.csv
      t,v,to_well
      One row per snap-through (crossing of the barrier x = 1/2): time,
      velocity, and the well entered (1: x < 1/2, 2: x > 1/2).

  --trace FILE.csv --dt H
      t,x,v,z,zdot            (with --trace-mode: t,x,v,z,zdot,mode,well)
      Samples at τ = k·H, k = 0, 1, 2, … while k·H ≤ T, from the dense output:
      mass position and velocity, plate position and velocity; mode is free or
      sticking, well is 1 or 2.

Plots (--plot DIR), sampled from the dense output (see --plot-samples); long
runs plot only their last part, as the titles say:
  waveform.png            x(τ) and the plate z(τ) against τ/2π, impacts marked
  phase_portrait.png      v against x, with the stroboscopic Poincaré section
                          (the state at plate phase 0, τ = k·2π/Ω) as dots
  energy_per_impact.png   ΔK/ΔK0 against the impact phase, ΔK0 = ½((1+e)V)²
                          (Eq. 11), with the line ΔK = 0
Text is drawn with DejaVu Sans (Debian package fonts-dejavu-core), or with the
TrueType file named by the environment variable BISTABLE_FONT.

Exit codes: 0 success; 2 missing, conflicting or invalid options or values;
1 a file could not be written or the simulation failed.

Examples:
  bistable simulate --omega 1.75 --velocity 0.07 --periods 100 --impacts out/impacts.csv
  bistable simulate --omega 0.2 --velocity 0.05 --t-end 60 --trace out/trace.csv --dt 0.01
  bistable simulate --omega 0.85 --velocity 0.11 --periods 200 --plot out/sim --json";

/// Options of `bistable simulate`.
#[derive(Debug, Clone, Args)]
#[command(group(ArgGroup::new("duration").required(true).args(["t_end", "periods"])))]
pub struct SimulateArgs {
    #[command(flatten)]
    pub common: CommonArgs,

    /// Simulate up to τ = T (time units; one natural period is 2π).
    #[arg(
        long,
        value_name = "T",
        allow_negative_numbers = true,
        help_heading = "Duration (one of)"
    )]
    pub t_end: Option<f64>,

    /// Simulate N natural periods, i.e. up to τ = 2π·N.
    #[arg(
        long,
        value_name = "N",
        allow_negative_numbers = true,
        help_heading = "Duration (one of)"
    )]
    pub periods: Option<f64>,

    /// Write one row per impact to FILE.csv, and sticking intervals and snap-throughs to
    /// <stem>_sticking.csv and <stem>_snaps.csv next to it (formats below).
    #[arg(long, value_name = "FILE.csv", help_heading = "Output")]
    pub impacts: Option<PathBuf>,

    /// Write samples t,x,v,z,zdot at τ = 0, H, 2H, … to FILE.csv (needs --dt).
    #[arg(
        long,
        value_name = "FILE.csv",
        requires = "dt",
        help_heading = "Output"
    )]
    pub trace: Option<PathBuf>,

    /// Sampling interval H of --trace (time units, > 0).
    #[arg(
        long,
        value_name = "H",
        requires = "trace",
        allow_negative_numbers = true,
        help_heading = "Output"
    )]
    pub dt: Option<f64>,

    /// Add the columns mode (free | sticking) and well (1 | 2) to --trace.
    #[arg(long, requires = "trace", help_heading = "Output")]
    pub trace_mode: bool,

    /// Write waveform.png, phase_portrait.png and energy_per_impact.png to DIR (created if
    /// missing).
    #[arg(long, value_name = "DIR", help_heading = "Output")]
    pub plot: Option<PathBuf>,

    /// Plot samples per shaker period, or per natural period if that is shorter (>= 10).
    #[arg(long, value_name = "N", default_value_t = 200, help_heading = "Output")]
    pub plot_samples: u32,

    /// Most samples in one plotted curve; longer runs plot only their last part (>= 1000).
    #[arg(
        long,
        value_name = "N",
        default_value_t = 200_000,
        help_heading = "Output"
    )]
    pub plot_max_points: u64,
}

/// What the plots need from the event stream.
struct PlotEvents {
    window_start: f64,
    /// Impacts in the plotted window: `(t, x, v_before, v_after)`.
    marks: Vec<(f64, f64, f64, f64)>,
    /// Sticking intervals ending in the window (or still open).
    sticking: Vec<(f64, Option<f64>)>,
    /// The last `cap` impacts: `(index, t, phase, ΔK/ΔK0)`.
    energy: VecDeque<(u64, f64, f64, f64)>,
    cap: usize,
    dk0: f64,
}

/// Receives the simulator's events and writes the rows of its event log out.
struct Recorder {
    log: EventLog,
    impacts_csv: Option<CsvFile>,
    sticking_csv: Option<CsvFile>,
    snaps_csv: Option<CsvFile>,
    plot: Option<PlotEvents>,
    error: Option<CliError>,
}

/// A cell of the event log as a CSV field.
fn field(c: Cell) -> Field<'static> {
    match c {
        Cell::Int(i) => Field::I(i),
        Cell::Real(v) => Field::F(v),
        Cell::Missing => Field::Empty,
    }
}

impl Recorder {
    /// Writes the rows the log has completed.
    fn write_rows(&mut self) -> Result<(), CliError> {
        for row in self.log.rows() {
            match row {
                Row::Impact(r) => {
                    if let Some(csv) = &mut self.impacts_csv {
                        csv.row(&r.cells().map(field))?;
                    }
                    if let Some(p) = &mut self.plot {
                        p.impact(&r.impact);
                    }
                }
                Row::Stick(r) => {
                    if let Some(csv) = &mut self.sticking_csv {
                        csv.row(&r.cells().map(field))?;
                    }
                    if let Some(p) = &mut self.plot {
                        p.stick(&r);
                    }
                }
                Row::Snap(r) => {
                    if let Some(csv) = &mut self.snaps_csv {
                        csv.row(&r.cells().map(field))?;
                    }
                }
            }
        }
        Ok(())
    }

    /// Closes the log at the end of the run and writes its last rows.
    fn finish(&mut self) -> Result<(), CliError> {
        self.log.finish();
        self.write_rows()
    }

    /// `reached`, after writing the rows the log still holds when the run failed (the impacts
    /// up to the failure are all in the files).
    fn written_if_failed<T>(&mut self, reached: Result<T, SimError>) -> Result<T, CliError> {
        if reached.is_err() {
            self.finish()?;
        }
        Ok(reached?)
    }

    /// The first error met while recording, if any.
    fn check(&mut self) -> Result<(), CliError> {
        self.error.take().map_or(Ok(()), Err)
    }
}

impl PlotEvents {
    fn impact(&mut self, imp: &Impact) {
        if imp.t >= self.window_start {
            self.marks.push((imp.t, imp.x, imp.v_before, imp.v_after));
        }
        if self.energy.len() == self.cap {
            self.energy.pop_front();
        }
        self.energy.push_back((
            imp.index,
            imp.t,
            imp.phase.unwrap_or(f64::NAN),
            imp.delta_k / self.dk0,
        ));
    }

    /// Intervals that ended in a release in the window, and the one still open at the end.
    fn stick(&mut self, r: &StickRow) {
        match (r.closing, r.start, r.end) {
            (Closing::Release, Some(t0), Some(t)) if t >= self.window_start => {
                self.sticking.push((t0, Some(t)));
            }
            (Closing::EndOfRun, Some(t0), _) => self.sticking.push((t0, None)),
            _ => {}
        }
    }
}

impl Observer for Recorder {
    fn event(&mut self, event: &Event) -> ControlFlow<()> {
        self.log.record(event);
        match self.write_rows() {
            Ok(()) => ControlFlow::Continue(()),
            Err(e) => {
                self.error = Some(e);
                ControlFlow::Break(())
            }
        }
    }
}

/// The JSON summary.
#[derive(Debug, Serialize)]
struct Summary {
    command: &'static str,
    omega: f64,
    velocity: f64,
    zeta: f64,
    restitution: f64,
    tol: f64,
    chatter: Chatter,
    /// End of the run (time units).
    t_end: f64,
    /// `t_end / 2π`.
    natural_periods: f64,
    /// `t_end / (2π/Ω)`.
    shaker_periods: f64,
    impacts: u64,
    sticking_intervals: u64,
    snap_throughs: u64,
    final_well: u8,
    final_state: FinalState,
    last_impact: Option<ImpactJson>,
    /// Simulation, sampling and CSV writing (not plotting).
    wall_time_s: f64,
    /// Drawing the PNG files.
    plot_time_s: f64,
    steps: u64,
    files: Files,
}

#[derive(Debug, Serialize)]
struct FinalState {
    t: f64,
    x: f64,
    v: f64,
    z: f64,
    zdot: f64,
    mode: &'static str,
    well: u8,
    kinetic_energy: f64,
    potential_energy: f64,
}

#[derive(Debug, Serialize)]
struct ImpactJson {
    index: u64,
    t: f64,
    phase: Option<f64>,
    x: f64,
    v_before: f64,
    v_after: f64,
    delta_k: f64,
}

#[derive(Debug, Default, Serialize)]
struct Files {
    impacts: Option<PathBuf>,
    sticking: Option<PathBuf>,
    snaps: Option<PathBuf>,
    trace: Option<PathBuf>,
    plots: Vec<PathBuf>,
}

/// Validated options of a run.
struct Plan {
    model: Model,
    t_end: f64,
    trace_dt: Option<f64>,
    plot_dt: f64,
    plot_window_start: f64,
}

impl Plan {
    fn new(args: &SimulateArgs) -> Result<Self, CliError> {
        let model = args.common.model()?;
        let t_end = match (args.t_end, args.periods) {
            (Some(t), _) => positive("--t-end", t)?,
            (None, Some(n)) => positive("--periods", n)? * TAU,
            // clap's group makes one of them required.
            (None, None) => return Err(CliError::invalid_text("--t-end", "", "required")),
        };
        if !t_end.is_finite() {
            return Err(CliError::invalid(
                "--periods",
                args.periods.unwrap_or(t_end),
                "too large (2π·N overflows)",
            ));
        }
        let trace_dt = match args.dt {
            Some(h) => {
                let h = positive("--dt", h)?;
                let rows = t_end / h;
                if rows > MAX_TRACE_ROWS {
                    return Err(CliError::invalid(
                        "--dt",
                        h,
                        format!(
                            "too small for a run up to τ = {}: {:.3e} rows (at most {MAX_TRACE_ROWS:e})",
                            num(t_end),
                            rows
                        ),
                    ));
                }
                Some(h)
            }
            None => None,
        };
        CliError::at_least("--plot-samples", args.plot_samples, 10)?;
        CliError::at_least("--plot-max-points", args.plot_max_points, 1000)?;
        let plot_dt = model.shaker_period().min(TAU) / f64::from(args.plot_samples);
        let span = plot_dt * (args.plot_max_points - 1) as f64;
        let plot_window_start = if t_end > span {
            // Start on a shaker period boundary, so the window shows whole cycles.
            let ts = model.shaker_period();
            let start = ((t_end - span) / ts).ceil() * ts;
            if start < t_end {
                start
            } else {
                t_end - span
            }
        } else {
            0.0
        };
        Ok(Self {
            model,
            t_end,
            trace_dt,
            plot_dt,
            plot_window_start,
        })
    }
}

/// Runs `bistable simulate`.
pub fn run(args: &SimulateArgs) -> Result<(), CliError> {
    let plan = Plan::new(args)?;
    let model = plan.model;
    let t_end = plan.t_end;
    let clock = WallClock::now();

    let mut files = Files::default();
    let mut rec = Recorder {
        log: EventLog::new(),
        impacts_csv: None,
        sticking_csv: None,
        snaps_csv: None,
        plot: None,
        error: None,
    };
    if let Some(path) = &args.impacts {
        rec.impacts_csv = Some(CsvFile::create(path, &IMPACT_COLUMNS.join(","))?);
        rec.sticking_csv = Some(CsvFile::create(
            &sibling(path, "_sticking.csv"),
            &STICKING_COLUMNS.join(","),
        )?);
        rec.snaps_csv = Some(CsvFile::create(
            &sibling(path, "_snaps.csv"),
            &SNAP_COLUMNS.join(","),
        )?);
    }
    let mut trace = match &args.trace {
        Some(path) => {
            let header = if args.trace_mode {
                format!("{TRACE_HEADER},mode,well")
            } else {
                TRACE_HEADER.to_string()
            };
            Some(CsvFile::create(path, &header)?)
        }
        None => None,
    };
    if let Some(dir) = &args.plot {
        crate::output::create_dir(dir)?;
        rec.plot = Some(PlotEvents {
            window_start: plan.plot_window_start,
            marks: Vec::new(),
            sticking: Vec::new(),
            energy: VecDeque::new(),
            cap: args.plot_max_points as usize,
            dk0: model.delta_k0(),
        });
    }

    let mut sim = model.simulator()?;
    let mut trace_times = match plan.trace_dt {
        Some(h) => Schedule::new(h, 0.0, t_end),
        None => Schedule::none(),
    };
    let (mut plot_times, mut poincare_times) = if args.plot.is_some() {
        (
            Schedule::new(plan.plot_dt, plan.plot_window_start, t_end),
            Schedule::new(model.shaker_period(), plan.plot_window_start, t_end),
        )
    } else {
        (Schedule::none(), Schedule::none())
    };
    let mut chunks = Schedule::new(t_end / 1000.0, 0.0, t_end);
    let mut samples: Vec<Sample> = Vec::new();
    let mut poincare: Vec<(f64, f64)> = Vec::new();
    let mut progress = Progress::new(t_end, "simulating");

    while let Some(next) = earliest(&[&trace_times, &plot_times, &poincare_times, &chunks]) {
        let reached = sim.advance(next, &mut rec);
        rec.check()?;
        rec.written_if_failed(reached)?;
        let st = sim.state();
        if trace_times.take(next) {
            if let Some(csv) = &mut trace {
                write_trace_row(csv, &st, args.trace_mode)?;
            }
        }
        if plot_times.take(next) {
            samples.push(Sample::from_state(&st));
        }
        if poincare_times.take(next) {
            poincare.push((st.x, st.v));
        }
        if chunks.take(next) {
            progress.set(next);
        }
    }
    let reached = sim.advance(t_end, &mut rec);
    rec.check()?;
    rec.written_if_failed(reached)?;
    progress.finish();
    let fin = sim.state();
    if let Some(p) = &rec.plot {
        if samples.last().is_none_or(|s| s.t < fin.t) && fin.t >= p.window_start {
            samples.push(Sample::from_state(&fin));
        }
    }

    // Close the files.
    rec.finish()?;
    if let Some(csv) = rec.impacts_csv.take() {
        files.impacts = Some(csv.finish()?);
    }
    if let Some(csv) = rec.sticking_csv.take() {
        files.sticking = Some(csv.finish()?);
    }
    if let Some(csv) = rec.snaps_csv.take() {
        files.snaps = Some(csv.finish()?);
    }
    if let Some(csv) = trace.take() {
        files.trace = Some(csv.finish()?);
    }
    let wall_time_s = clock.elapsed().as_secs_f64();

    let plot_clock = WallClock::now();
    if let (Some(dir), Some(events)) = (&args.plot, rec.plot.take()) {
        let data = PlotData {
            model,
            t_end,
            window_start: plan.plot_window_start,
            samples,
            impacts: events.marks,
            sticking: events.sticking,
            poincare,
            energy: events.energy.into_iter().collect(),
            total_impacts: rec.log.impacts(),
        };
        files.plots = plot::draw_all(dir, &data)?;
    }
    let plot_time_s = plot_clock.elapsed().as_secs_f64();

    let summary = Summary {
        command: "simulate",
        omega: model.omega(),
        velocity: model.velocity(),
        zeta: model.params.zeta(),
        restitution: model.restitution(),
        tol: model.opts.tol(),
        chatter: args.common.model.chatter,
        t_end,
        natural_periods: t_end / TAU,
        shaker_periods: t_end / model.shaker_period(),
        impacts: rec.log.impacts(),
        sticking_intervals: rec.log.sticks(),
        snap_throughs: rec.log.snaps(),
        final_well: fin.well.number(),
        final_state: FinalState {
            t: fin.t,
            x: fin.x,
            v: fin.v,
            z: fin.z,
            zdot: fin.zdot,
            mode: mode_name(fin.mode),
            well: fin.well.number(),
            kinetic_energy: fin.kinetic_energy(),
            potential_energy: fin.potential_energy(),
        },
        last_impact: rec.log.last_impact().map(|i| ImpactJson {
            index: i.index,
            t: i.t,
            phase: i.phase,
            x: i.x,
            v_before: i.v_before,
            v_after: i.v_after,
            delta_k: i.delta_k,
        }),
        wall_time_s,
        plot_time_s,
        steps: sim.stats().steps,
        files,
    };
    if args.common.json() {
        print_json(&summary)
    } else {
        print_text(&human(&summary))
    }
}

fn write_trace_row(csv: &mut CsvFile, st: &State, mode: bool) -> Result<(), CliError> {
    let base = [
        Field::F(st.t),
        Field::F(st.x),
        Field::F(st.v),
        Field::F(st.z),
        Field::F(st.zdot),
    ];
    if mode {
        let well = u64::from(st.well.number());
        let mut row = base.to_vec();
        row.push(Field::S(mode_name(st.mode)));
        row.push(Field::I(well));
        csv.row(&row)
    } else {
        csv.row(&base)
    }
}

fn show(path: &Path) -> String {
    path.display().to_string()
}

fn human(s: &Summary) -> String {
    use std::fmt::Write as _;
    let mut o = String::new();
    let _ = writeln!(
        o,
        "bistable simulate: Ω = {}, V = {}, ζ = {}, e = {}, tol = {:e}, chatter rule: {}",
        s.omega,
        s.velocity,
        s.zeta,
        s.restitution,
        s.tol,
        match s.chatter {
            Chatter::Accumulation => "accumulation",
            Chatter::Paper => "paper (1e-9 gap)",
        }
    );
    let _ = writeln!(
        o,
        "  simulated τ ∈ [0, {}]: {:.6} natural periods, {:.6} shaker periods",
        num(s.t_end),
        s.natural_periods,
        s.shaker_periods
    );
    let _ = match &s.last_impact {
        Some(i) => writeln!(
        o,
            "  impacts:            {} (last: #{} at τ = {:.10}, phase {:.6} cycles, v {:.6} → {:.6})",
            s.impacts,
            i.index,
            i.t,
            i.phase.unwrap_or(f64::NAN),
            i.v_before,
            i.v_after
        ),
        None => writeln!(o, "  impacts:            0"),
    };
    let _ = writeln!(o, "  sticking intervals: {}", s.sticking_intervals);
    let _ = writeln!(o, "  snap-throughs:      {}", s.snap_throughs);
    let f = &s.final_state;
    let _ = writeln!(
        o,
        "  final state:        τ = {:.10}, x = {:.10}, v = {:.10}, z = {:.10}, ż = {:.10}, {}, well {}",
        f.t,
        f.x,
        f.v,
        f.z,
        f.zdot,
        if f.mode == "free" {
            "free flight"
        } else {
            "sticking to the plate"
        },
        f.well
    );
    let _ = writeln!(
        o,
        "  energy:             K = {:.6e}, U = {:.6e} (barrier U(1/2) = 1/32)",
        f.kinetic_energy, f.potential_energy
    );
    let _ = writeln!(
        o,
        "  work:               {} Taylor steps, {:.3} s{}",
        s.steps,
        s.wall_time_s,
        if s.files.plots.is_empty() {
            String::new()
        } else {
            format!(" (+ {:.3} s plotting)", s.plot_time_s)
        }
    );
    let mut wrote: Vec<String> = [
        &s.files.impacts,
        &s.files.sticking,
        &s.files.snaps,
        &s.files.trace,
    ]
    .into_iter()
    .flatten()
    .map(|p| show(p))
    .collect();
    wrote.extend(s.files.plots.iter().map(|p| show(p)));
    for (i, w) in wrote.iter().enumerate() {
        if i == 0 {
            let _ = writeln!(o, "  wrote:              {w}");
        } else {
            let _ = writeln!(o, "                      {w}");
        }
    }
    o
}
