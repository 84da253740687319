//! `bistable coexistence`: which attractors coexist at every point of an `Ω × V` grid (or
//! along one parameter) and how likely each is from a box of starts, decided by recurrence;
//! the attractors matched from point to point into branches; a resumable CSV, a JSON summary
//! and a picture (the map by number of coexisting attractors, or the basin fractions along the
//! line as stacked areas over the orbit branches).

use std::collections::BTreeMap;
use std::path::Path;
use std::time::Instant as WallClock;

use clap::{ArgGroup, Args};
use plotters::prelude::*;
use serde::Serialize;

use bistable_analysis::basins::{Cell, DecidedBy, Steady};
use bistable_analysis::branches::Branches;
use bistable_analysis::coexistence::{
    coexistence, match_branches, orbit_branches, row as row_values, steady_class,
    CoexistenceOptions, Coexisting, PointCoexistence, Sampling, StartBox, Starts, TableSettings,
    COLUMNS, FIRST_ROUND,
};
use bistable_analysis::sensitivity::Outcome;
use bistable_analysis::Model;
use bistable_core::{ClassifyOptions, ParamError, ResponseClass, Well};

use crate::common::ModelArgs;
use crate::decision::DecisionArgs;
use crate::error::CliError;
use crate::grid::{self, grid_help, GridArgs, GridFile, GridRun, GridSummary, Rows};
use crate::output::{print_json, print_text, Field};
use crate::plot::{self, header, Mark, FONT};
use crate::progress::StageBars;
use crate::ranges::Range;

/// Long description shown by `bistable coexistence --help`.
pub const LONG_ABOUT: &str = "\
Which responses coexist, and how likely each is: at every point of an Ω × V grid
(or along one parameter, with one value of the other) the starts of a box are
each classified as 'bistable basins' classifies a start, and the attractors they
reach are listed with their basin fraction (the share of the starts that reach
each) and its standard error. Attractors are matched from point to point into
branches, as Attractors.jl's global continuation does (same steady state, nearest
anchor within --match-distance), so one branch keeps one id across the grid.

Starts: --starts NXxNV (a grid with the box's corners, default 20x20) or
random:K[:SEED] (K seeded uniform starts) in --box X0:X1,V0:V1 (default
0:1.2,-0.6:0.6; x0 from the plate, at z = 0 at phase 0, to beyond the second
well), all at τ = 0 with the plate at phase 0. The same starts serve every
point. The paper's own start (at rest at x = 0, the start of 'bistable map') is
classified too, in full and with the sensitivity test of 'bistable map' (so its
outcome is the one the map reports), and marked (paper_start); it is not one of
the K.

Fraction f = n/K of an attractor reached by n of the K starts; standard error
sqrt(f(1 − f)/K) (binomial: exact for random starts, an upper bound in practice
for a grid). An attractor only the paper's start reaches is listed with n = 0.

Decision by recurrence (as for 'bistable basins', see its --help): a start stops
once it is known to be on an attractor already found at this point (2
consecutive section points within the probed capture radius of a periodic one,
or 500 in the cells of an aperiodic one that do not close in on a cycle). Each
point takes its starts in rounds (16, then doubling), so its result does not
depend on --threads, --lanes or the other points. With a few hundred starts,
periodic attractors are mostly not probed (probing costs more than it saves):
their starts run in full, and the recurrence saves its time on chaotic
attractors, whose starts would otherwise run the full --max-periods.

Resuming: each point's rows are appended and flushed when the point is done (in
an interleaved order over the grid); run the same command again to compute only
the missing points. Rows written with another ζ, e, box, starts or decision, or
for points not on this grid, are refused. When every point is done the file is
rewritten in grid order (Ω inner, V outer) with the branch ids filled in.";

/// Shown after the options by `bistable coexistence --help`.
pub const AFTER_HELP: &str = "\
CSV (--out): header and one row per point and attractor:
  omega,velocity,zeta,restitution,box,starts,decision,attractors,attractor,
  branch,label,class,period,chaotic,final_well,at_rest,anchor_x,anchor_v,count,
  fraction,fraction_se,decided_by_recurrence,periods_simulated,paper_start,
  paper_class,paper_period,paper_chaotic,paper_final_well,paper_sensitive
  (box X0:X1;V0:V1; starts as given to --starts; decision recurrence or full;
  attractors: how many coexist at the point; attractor: its number there,
  largest basin first, from 1; branch: its id across the grid, from 1, empty
  until every point is done; class of the steady state: continuous_interwell,
  intrawell or rest (rest in well 2); empty period: aperiodic; anchor: the
  cycle's section point with the smallest x, the mean section point of an
  aperiodic attractor; count: starts that reach it; decided_by_recurrence: how
  many of those stopped by recurrence; periods_simulated: natural periods those
  starts simulated together; paper_start: the paper's start reaches it; the
  paper_* columns: that start's own class (with its transient), period, chaos
  and final well, and whether rounding decides them, as 'bistable map' reports
  them with its sensitivity test).

PNG (--plot): over a grid, the map coloured by the number of coexisting
attractors, with a ring where the paper's start reaches a minority basin (less
than half of the starts). Along one parameter: the basin fractions as stacked
areas, one colour per branch, and below them the periodic orbits continued from
the attractors found (maximum x of each cycle; stable thick, unstable dashed).

Exit codes: 0 success; 2 invalid options or a --out file that does not fit;
1 a file could not be written, or some points failed (listed on stderr; the
others are saved).

Examples:
  bistable coexistence --omega-range 0.2:3.5:60 --velocity-range 0.005:0.2:40 \\
      --out out/coexistence.csv --plot out/coexistence.png
  bistable coexistence --omega-range 1.2:1.8:61 --velocity-range 0.05:0.05:1 \\
      --starts random:1000:1 --plot out/fractions_v005.png";

/// Options of `bistable coexistence`.
#[derive(Debug, Clone, Args)]
#[command(group(ArgGroup::new("output").required(true).multiple(true).args(["out", "plot"])))]
#[command(mut_args(grid_help(
    "Append each point's rows to FILE.csv, skipping points already in it (see below)",
    "Draw the map, or the fractions along one parameter, to FILE.png"
)))]
pub struct CoexistenceArgs {
    /// Ω values A:B:N (N evenly spaced values from A to B, ends included; Ω > 0).
    #[arg(
        long,
        value_name = "A:B:N",
        default_value = "0.2:3.5:60",
        allow_hyphen_values = true
    )]
    pub omega_range: Range,

    /// V values A:B:N (V >= 0).
    #[arg(
        long,
        value_name = "A:B:N",
        default_value = "0.005:0.2:40",
        allow_hyphen_values = true
    )]
    pub velocity_range: Range,

    /// The box of starts X0:X1,V0:V1: x0 from X0 (>= 0, the plate) to X1, x0' from V0 to V1.
    #[arg(
        long = "box",
        value_name = "X0:X1,V0:V1",
        default_value = "0:1.2,-0.6:0.6",
        allow_hyphen_values = true
    )]
    pub start_box: String,

    /// The starts: `NXxNV` (a grid over the box) or `random:K[:SEED]` (K uniform random starts,
    /// seed 1 unless given); at most 1e6.
    #[arg(long, value_name = "SPEC", default_value = "20x20")]
    pub starts: String,

    /// Most natural periods a start runs (the paper's limit for aperiodic motion).
    #[arg(long, value_name = "N", default_value_t = 20_000.0)]
    pub max_periods: f64,

    /// Shaker periods over which the Lyapunov exponent of an aperiodic start is averaged (as
    /// 'bistable map').
    #[arg(long, value_name = "N", default_value_t = 300)]
    pub lyapunov_periods: u32,

    /// Largest distance (max-norm in the section plane, units Δx and ω0·Δx) between the
    /// anchors of two attractors of neighbouring points that are matched into one branch.
    #[arg(
        long,
        value_name = "D",
        default_value_t = 0.2,
        allow_negative_numbers = true
    )]
    pub match_distance: f64,

    #[command(flatten)]
    pub decision: DecisionArgs,

    #[command(flatten)]
    pub grid: GridArgs,

    #[command(flatten)]
    pub model: ModelArgs,
}

/// The rows of one point read back from the file (some may be missing).
#[derive(Debug, Clone)]
struct PointRows {
    point: PointCoexistence,
    present: Vec<bool>,
}

const FILE: GridFile<PointRows> = GridFile {
    columns: &COLUMNS,
    kind: "coexistence",
    axes: ["Ω", "V"],
    point: |r| (r.point.omega, r.point.velocity),
    rows: Rows::Group {
        merge: merge_rows,
        complete: |r| r.present.iter().all(|&p| p) && r.point.paper_attractor < r.present.len(),
    },
};

/// Adds the attractors of `more` (one row) to `into` (rows of the same point).
fn merge_rows(into: &mut PointRows, more: PointRows) {
    if more.present.len() != into.present.len() {
        // Rows of an interrupted write and of a later run disagree: the later one counts.
        *into = more;
        return;
    }
    for (k, present) in more.present.iter().enumerate() {
        if *present {
            into.point.attractors[k] = more.point.attractors[k];
            into.present[k] = true;
        }
    }
    if more.point.paper_attractor != usize::MAX {
        into.point.paper_attractor = more.point.paper_attractor;
    }
}

/// The `--box` and `--starts` options, checked.
fn starts_of(args: &CoexistenceArgs) -> Result<Starts, CliError> {
    let bad_box = |rule: &str| CliError::invalid_text("--box", &args.start_box, rule);
    let pair = |s: &str| -> Option<[f64; 2]> {
        let (a, b) = s.split_once(':')?;
        Some([a.trim().parse().ok()?, b.trim().parse().ok()?])
    };
    let (x, v) = args
        .start_box
        .split_once(',')
        .and_then(|(x, v)| Some((pair(x)?, pair(v)?)))
        .ok_or_else(|| bad_box("must be X0:X1,V0:V1 (numbers)"))?;
    let bad_starts = |rule: &str| CliError::invalid_text("--starts", &args.starts, rule);
    let sampling = if let Some(rest) = args.starts.strip_prefix("random:") {
        let mut parts = rest.split(':');
        let n = parts.next().and_then(|n| n.parse::<usize>().ok());
        let seed = match parts.next() {
            None => Some(1),
            Some(s) => s.parse::<u64>().ok(),
        };
        match (n, seed, parts.next()) {
            (Some(n), Some(seed), None) => Sampling::Random { n, seed },
            _ => return Err(bad_starts("must be NXxNV or random:K[:SEED]")),
        }
    } else {
        let (nx, nv) = args
            .starts
            .split_once('x')
            .and_then(|(a, b)| Some((a.parse().ok()?, b.parse().ok()?)))
            .ok_or_else(|| bad_starts("must be NXxNV or random:K[:SEED]"))?;
        Sampling::Grid { nx, nv }
    };
    Starts {
        bounds: StartBox { x, v },
        sampling,
    }
    .check()
    .map_err(|e: ParamError| match e.name {
        "start_box" => bad_box(e.rule),
        _ => bad_starts(e.rule),
    })
}

/// Runs `bistable coexistence`.
pub fn run(args: &CoexistenceArgs) -> Result<(), CliError> {
    let omegas = args.omega_range.omegas("--omega-range")?;
    let vs = args.velocity_range.velocities("--velocity-range")?;
    grid::check_size(omegas, vs, "--omega-range")?;
    let model = args.model.model(omegas.start, vs.start)?;
    let starts = starts_of(args)?;
    let classify = ClassifyOptions {
        max_natural_periods: args.max_periods,
        lyapunov_periods: args.lyapunov_periods,
        ..ClassifyOptions::default()
    }
    .check()?;
    let decision = args.decision.decision(FIRST_ROUND)?;
    if !(args.match_distance.is_finite() && args.match_distance >= 0.0) {
        return Err(CliError::invalid(
            "--match-distance",
            args.match_distance,
            "must be finite and >= 0",
        ));
    }
    let (threads, width) = args.grid.parallel()?;
    let options = CoexistenceOptions {
        starts,
        classify,
        decision,
        ..CoexistenceOptions::default()
    };
    let settings = TableSettings::new(&model, &options);
    let on_grid = |w: f64, v: f64| {
        (0..omegas.n).any(|i| omegas.value(i) == w) && (0..vs.n).any(|j| vs.value(j) == v)
    };

    let mut run = GridRun::open(
        &FILE,
        args.grid.out.as_deref(),
        (omegas, vs),
        |text, row| {
            let r = parse_row(text, &settings, starts.count())
                .map_err(|e| format!("has a bad row {row}: {e}"))?;
            if !on_grid(r.point.omega, r.point.velocity) {
                return Err(format!(
                    "holds Ω = {}, V = {} (row {row}), not a point of --omega-range {omegas} × \
                 --velocity-range {vs}; use another file",
                    r.point.omega, r.point.velocity
                ));
            }
            Ok(r)
        },
    )?;

    let start = WallClock::now();
    let done = run.compute(
        format!(
            "coexistence: {} points × {} starts",
            run.todo.len(),
            starts.count()
        ),
        |c, r| {
            for (k, a) in r.point.attractors.iter().enumerate() {
                c.row(&row(&r.point, k, None, &settings, &a.steady.label()))?;
            }
            Ok(())
        },
        |todo, done| {
            coexistence(&model, todo, options, threads, width, |i, r| {
                done(
                    i,
                    r.map(|point| PointRows {
                        present: vec![true; point.attractors.len()],
                        point,
                    })
                    .map_err(CliError::from),
                )
            })
        },
    )?;
    let wall = start.elapsed().as_secs_f64();

    // Every point in grid order (Ω inner, V outer), and the branches across the grid.
    let by_grid: Vec<Option<&PointCoexistence>> = (0..omegas.n * vs.n)
        .map(|k| {
            run.get((omegas.value(k % omegas.n), vs.value(k / omegas.n)))
                .map(|r| &r.point)
        })
        .collect();
    let (branch_ids, branches) = match_branches(omegas.n, &by_grid, args.match_distance);
    if by_grid.iter().all(Option::is_some) {
        run.rewrite(|c| {
            for (p, ids) in by_grid.iter().flatten().zip(&branch_ids) {
                for (k, (&id, a)) in ids.iter().zip(&p.attractors).enumerate() {
                    c.row(&row(p, k, Some(id), &settings, &a.steady.label()))?;
                }
            }
            Ok(())
        })?;
    }

    let points: Vec<(&PointCoexistence, &[usize])> = by_grid
        .iter()
        .zip(&branch_ids)
        .filter_map(|(p, ids)| p.map(|p| (p, ids.as_slice())))
        .collect();
    let summary = Summary::new(
        args,
        (omegas, vs),
        &settings,
        run.summary(&done, (threads, width), wall),
        &points,
        branches,
    );
    if let Some(path) = &args.grid.plot {
        if omegas.n > 1 && vs.n > 1 {
            draw_map(path, &summary, (omegas, vs), &points)?;
        } else {
            let line = if vs.n == 1 { omegas } else { vs };
            let models: Vec<Model> = points
                .iter()
                .map(|(p, _)| model.at(p.omega, p.velocity))
                .collect::<Result<_, _>>()?;
            let on_line: Vec<&PointCoexistence> = points.iter().map(|(p, _)| *p).collect();
            let mut bars = StageBars::new("orbit branches: ");
            let orbits = orbit_branches(&models, &on_line, threads, &mut |p| bars.report(p))?;
            draw_line(path, &summary, line, vs.n == 1, &points, &orbits)?;
        }
    }
    if args.model.json {
        print_json(&summary)?;
    } else {
        print_text(&human(&summary))?;
    }
    run.check(&done, "points")
}

/// The CSV row of attractor `k` of `p` (see [`row_values`]).
fn row<'a>(
    p: &PointCoexistence,
    k: usize,
    branch: Option<usize>,
    t: &'a TableSettings,
    label: &'a str,
) -> [Field<'a>; 29] {
    row_values(p, k, branch, t, label).map(Field::from)
}

/// One row read back: its point with only this row's attractor present (`count`: the run's
/// number of starts, which the row's `starts` matches).
fn parse_row(text: &str, s: &TableSettings, count: usize) -> Result<PointRows, String> {
    let f: Vec<&str> = text.split(',').collect();
    if f.len() != COLUMNS.len() {
        return Err(format!("{} fields, expected {}", f.len(), COLUMNS.len()));
    }
    let col = |name: &str| COLUMNS.iter().position(|c| *c == name).expect("a column");
    let get = |name: &str| f[col(name)];
    let num = |name: &str| -> Result<f64, String> {
        get(name)
            .parse::<f64>()
            .map_err(|_| format!("bad {name} '{}'", get(name)))
    };
    let int = |name: &str| -> Result<usize, String> {
        get(name)
            .parse::<usize>()
            .map_err(|_| format!("bad {name} '{}'", get(name)))
    };
    let opt_int = |name: &str| -> Result<Option<u32>, String> {
        match get(name) {
            "" => Ok(None),
            t => t
                .parse::<u32>()
                .map(Some)
                .map_err(|_| format!("bad {name} '{t}'")),
        }
    };
    let flag = |name: &str| -> Result<bool, String> {
        match get(name) {
            "true" => Ok(true),
            "false" => Ok(false),
            t => Err(format!("bad {name} '{t}'")),
        }
    };
    let well = |name: &str| -> Result<Option<Well>, String> {
        match get(name) {
            "" => Ok(None),
            "1" => Ok(Some(Well::One)),
            "2" => Ok(Some(Well::Two)),
            t => Err(format!("bad {name} '{t}'")),
        }
    };
    let recorded: [(&str, String, String); 5] = [
        ("zeta", num("zeta")?.to_string(), s.zeta.to_string()),
        (
            "restitution",
            num("restitution")?.to_string(),
            s.restitution.to_string(),
        ),
        ("box", get("box").to_string(), s.start_box.clone()),
        ("starts", get("starts").to_string(), s.starts.clone()),
        (
            "decision",
            get("decision").to_string(),
            s.decision.to_string(),
        ),
    ];
    for (name, got, want) in recorded {
        if got != want {
            return Err(format!(
                "it holds {name} = {got}, this run has {want}; use another file"
            ));
        }
    }
    let n = int("attractors")?;
    let k = int("attractor")?;
    if k == 0 || k > n {
        return Err(format!("bad attractor {k} of {n}"));
    }
    let class = get("class");
    let at_rest = flag("at_rest")?;
    let steady = Steady {
        across: class == ResponseClass::ContinuousInterwell.name(),
        period: opt_int("period")?,
        chaotic: flag("chaotic")?,
        well: well("final_well")?,
        at_rest,
    };
    if steady_class(&steady) != class {
        return Err(format!("bad class '{class}'"));
    }
    let anchor = match (get("anchor_x"), get("anchor_v")) {
        ("", "") => None,
        _ => Some([num("anchor_x")?, num("anchor_v")?]),
    };
    let attractor = Coexisting {
        steady,
        anchor,
        count: int("count")?,
        by_recurrence: int("decided_by_recurrence")?,
        periods_simulated: num("periods_simulated")?,
    };
    let paper_class = [
        ResponseClass::Intrawell,
        ResponseClass::TransientInterwell,
        ResponseClass::ContinuousInterwell,
    ]
    .into_iter()
    .find(|c| c.name() == get("paper_class"))
    .ok_or_else(|| format!("bad paper_class '{}'", get("paper_class")))?;
    let paper = Cell {
        x0: 0.0,
        v0: 0.0,
        outcome: Outcome {
            class: paper_class,
            period: opt_int("paper_period")?,
            chaotic: flag("paper_chaotic")?,
            final_well: well("paper_final_well")?,
        },
        anchor: None,
        at_rest: false,
        periods_simulated: 0.0,
        decided_by: DecidedBy::Full,
    };
    let mut attractors = vec![attractor; n];
    let mut present = vec![false; n];
    present[k - 1] = true;
    attractors[k - 1] = attractor;
    Ok(PointRows {
        point: PointCoexistence {
            omega: num("omega")?,
            velocity: num("velocity")?,
            starts: count,
            attractors,
            paper,
            paper_sensitive: flag("paper_sensitive")?,
            paper_attractor: if flag("paper_start")? {
                k - 1
            } else {
                usize::MAX
            },
        },
        present,
    })
}

#[derive(Debug, Serialize)]
struct AttractorJson {
    attractor: usize,
    branch: usize,
    label: String,
    class: &'static str,
    period: Option<u32>,
    chaotic: bool,
    final_well: Option<u8>,
    at_rest: bool,
    anchor: Option<[f64; 2]>,
    count: usize,
    fraction: f64,
    fraction_se: f64,
    decided_by_recurrence: usize,
}

#[derive(Debug, Serialize)]
struct PointJson {
    omega: f64,
    velocity: f64,
    /// The number of the attractor the paper's start reaches.
    paper_attractor: usize,
    paper_in_minority: bool,
    /// Rounding decides the paper start's outcome ('bistable map''s `sensitive`).
    paper_sensitive: bool,
    attractors: Vec<AttractorJson>,
}

#[derive(Debug, Serialize)]
struct BranchJson {
    branch: usize,
    label: String,
    points: usize,
    mean_fraction: f64,
    max_fraction: f64,
}

#[derive(Debug, Serialize)]
struct CountJson {
    attractors: usize,
    points: usize,
}

/// What `coexistence` prints at the end.
#[derive(Debug, Serialize)]
struct Summary {
    omega_range: String,
    velocity_range: String,
    zeta: f64,
    restitution: f64,
    start_box: String,
    starts: String,
    starts_per_point: usize,
    decision: &'static str,
    match_distance: f64,
    #[serde(flatten)]
    grid: GridSummary,
    /// Starts of the points in hand that were decided by recurrence, and all their starts.
    decided_by_recurrence: usize,
    starts_decided: usize,
    /// Points by the number of attractors that coexist there.
    coexisting: Vec<CountJson>,
    /// Points where the paper's start reaches a minority basin.
    paper_in_minority: usize,
    branches: Vec<BranchJson>,
    results: Vec<PointJson>,
    out: Option<std::path::PathBuf>,
    plot: Option<std::path::PathBuf>,
}

impl Summary {
    fn new(
        args: &CoexistenceArgs,
        (omegas, vs): (Range, Range),
        s: &TableSettings,
        grid: GridSummary,
        points: &[(&PointCoexistence, &[usize])],
        branches: usize,
    ) -> Self {
        let mut counts: BTreeMap<usize, usize> = BTreeMap::new();
        let mut per_branch: Vec<(String, usize, f64, f64)> =
            vec![(String::new(), 0, 0.0, 0.0); branches];
        for (p, ids) in points {
            *counts.entry(p.attractors.len()).or_default() += 1;
            for (a, &id) in p.attractors.iter().zip(*ids) {
                let b = &mut per_branch[id];
                if b.1 == 0 {
                    b.0 = a.steady.label();
                }
                let f = a.fraction(p.starts);
                b.1 += 1;
                b.2 += f;
                b.3 = b.3.max(f);
            }
        }
        let attractor_json =
            |p: &PointCoexistence, k: usize, a: &Coexisting, id: usize| AttractorJson {
                attractor: k + 1,
                branch: id + 1,
                label: a.steady.label(),
                class: steady_class(&a.steady),
                period: a.steady.period,
                chaotic: a.steady.chaotic,
                final_well: a.steady.well.map(|w| w.number()),
                at_rest: a.steady.at_rest,
                anchor: a.anchor,
                count: a.count,
                fraction: a.fraction(p.starts),
                fraction_se: a.standard_error(p.starts),
                decided_by_recurrence: a.by_recurrence,
            };
        Self {
            omega_range: omegas.to_string(),
            velocity_range: vs.to_string(),
            zeta: s.zeta,
            restitution: s.restitution,
            start_box: s.start_box.clone(),
            starts: s.starts.clone(),
            starts_per_point: points.first().map_or(0, |(p, _)| p.starts),
            decision: s.decision,
            match_distance: args.match_distance,
            grid,
            decided_by_recurrence: points
                .iter()
                .flat_map(|(p, _)| &p.attractors)
                .map(|a| a.by_recurrence)
                .sum(),
            starts_decided: points.iter().map(|(p, _)| p.starts).sum(),
            coexisting: counts
                .into_iter()
                .map(|(attractors, points)| CountJson { attractors, points })
                .collect(),
            paper_in_minority: points.iter().filter(|(p, _)| p.paper_in_minority()).count(),
            branches: per_branch
                .into_iter()
                .enumerate()
                .map(|(id, (label, n, sum, max))| BranchJson {
                    branch: id + 1,
                    label,
                    points: n,
                    mean_fraction: sum / n.max(1) as f64,
                    max_fraction: max,
                })
                .collect(),
            results: points
                .iter()
                .map(|(p, ids)| PointJson {
                    omega: p.omega,
                    velocity: p.velocity,
                    paper_attractor: p.paper_attractor + 1,
                    paper_in_minority: p.paper_in_minority(),
                    paper_sensitive: p.paper_sensitive,
                    attractors: p
                        .attractors
                        .iter()
                        .zip(*ids)
                        .enumerate()
                        .map(|(k, (a, &id))| attractor_json(p, k, a, id))
                        .collect(),
                })
                .collect(),
            out: args.grid.out.clone(),
            plot: args.grid.plot.clone(),
        }
    }
}

fn human(s: &Summary) -> String {
    let mut t = format!(
        "coexistence over Ω {} × V {} (ζ = {}, e = {}): {} starts per point ({} in box {}), \
         decided by {}\n{}; {:.1} s on {} threads\n",
        s.omega_range,
        s.velocity_range,
        s.zeta,
        s.restitution,
        s.starts_per_point,
        s.starts,
        s.start_box,
        s.decision,
        s.grid.counts("points", "resumed"),
        s.grid.wall_time_s,
        s.grid.threads
    );
    if s.starts_decided > 0 {
        t.push_str(&format!(
            "  decided by recurrence: {} of {} starts ({:.1}%)\n",
            s.decided_by_recurrence,
            s.starts_decided,
            100.0 * s.decided_by_recurrence as f64 / s.starts_decided as f64
        ));
    }
    for c in &s.coexisting {
        t.push_str(&format!(
            "  {} point(s) with {} coexisting attractor(s)\n",
            c.points, c.attractors
        ));
    }
    t.push_str(&format!(
        "  the paper's start reaches a minority basin at {} point(s)\n  {} branches; the largest:\n",
        s.paper_in_minority,
        s.branches.len()
    ));
    let mut order: Vec<&BranchJson> = s.branches.iter().collect();
    order.sort_by(|a, b| b.points.cmp(&a.points).then(a.branch.cmp(&b.branch)));
    for b in order.iter().take(12) {
        t.push_str(&format!(
            "    #{:<4} {:<40} at {:>5} points, mean fraction {:.3}\n",
            b.branch, b.label, b.points, b.mean_fraction
        ));
    }
    if let Some(p) = &s.out {
        t.push_str(&format!("  rows: {}\n", p.display()));
    }
    if let Some(p) = &s.plot {
        t.push_str(&format!("  plot: {}\n", p.display()));
    }
    t
}

/// Fill of a map cell with `n` coexisting attractors (5 and more share the last).
fn count_colour(n: usize) -> RGBColor {
    const SHADES: [RGBColor; 5] = [
        RGBColor(232, 238, 246),
        RGBColor(150, 190, 230),
        RGBColor(60, 130, 200),
        RGBColor(20, 70, 150),
        RGBColor(60, 20, 90),
    ];
    SHADES[n.clamp(1, 5) - 1]
}

/// The ring at points where the paper's start reaches a minority basin.
const MINORITY: RGBColor = RGBColor(230, 90, 20);

fn draw_map(
    path: &Path,
    s: &Summary,
    (omegas, vs): (Range, Range),
    points: &[(&PointCoexistence, &[usize])],
) -> Result<(), CliError> {
    let subtitle = format!(
        "{} × {} points, {} starts each in x0, x0' box {} at plate phase 0; decided by {}",
        omegas.n, vs.n, s.starts_per_point, s.start_box, s.decision
    );
    let legend = vec![(
        Mark::Ring(MINORITY, 5, 2),
        "the paper's start (rest at x = 0) reaches a minority basin (< 50 % of the starts)"
            .to_string(),
    )];
    plot::png(path, crate::map::MAP_SIZE, |root| {
        let area = header(
            root,
            &format!(
                "Coexisting attractors — ζ = {}, e = {}",
                s.zeta, s.restitution
            ),
            &subtitle,
            &legend,
        )?;
        plot::grid_figure(
            &area,
            330,
            (omegas, vs),
            (
                "shaker frequency ratio Ω (units of ω0)",
                "shaker velocity amplitude V (units of ω0·Δx)",
            ),
            |chart, right, [(_, hw), (_, hv)]| {
                chart.draw_series(points.iter().map(|(p, _)| {
                    plot::cell(
                        (p.omega, p.velocity),
                        (hw, hv),
                        count_colour(p.attractors.len()),
                    )
                }))?;
                for (p, _) in points.iter().filter(|(p, _)| p.paper_in_minority()) {
                    plot::draw_point(chart, (p.omega, p.velocity), Mark::Ring(MINORITY, 5, 2))?;
                }
                let text = |size| (FONT, size).into_font().color(&BLACK);
                right.draw(&Text::new(
                    "coexisting attractors",
                    (14, 30),
                    plot::left(text(17)),
                ))?;
                for n in 1..=5 {
                    let count = points
                        .iter()
                        .filter(|(p, _)| p.attractors.len().min(5) == n)
                        .count();
                    let label = if n == 5 {
                        "5 or more".to_string()
                    } else {
                        n.to_string()
                    };
                    plot::swatch(
                        right,
                        40 + 50 * n as i32,
                        count_colour(n),
                        label,
                        (format!("{count} points"), 13, RGBColor(90, 90, 90)),
                    )?;
                }
                Ok(())
            },
        )
    })
}

fn draw_line(
    path: &Path,
    s: &Summary,
    line: Range,
    along_omega: bool,
    points: &[(&PointCoexistence, &[usize])],
    orbits: &[Branches],
) -> Result<(), CliError> {
    let x_of = |p: &PointCoexistence| if along_omega { p.omega } else { p.velocity };
    let (x_desc, fixed) = if along_omega {
        (
            "shaker frequency ratio Ω (units of ω0)",
            format!("V = {}", s.velocity_range.split(':').next().unwrap_or("")),
        )
    } else {
        (
            "shaker velocity amplitude V (units of ω0·Δx)",
            format!("Ω = {}", s.omega_range.split(':').next().unwrap_or("")),
        )
    };
    // Branches in the order of their ids, with the fraction at each point (0 where absent).
    let mut ids: Vec<usize> = points
        .iter()
        .flat_map(|(_, ids)| ids.iter().copied())
        .collect();
    ids.sort_unstable();
    ids.dedup();
    let share = |p: &PointCoexistence, pids: &[usize], id: usize| {
        pids.iter()
            .position(|&b| b == id)
            .map_or(0.0, |k| p.attractors[k].fraction(p.starts))
    };
    let legend: Vec<(Mark, String)> = ids
        .iter()
        .enumerate()
        .take(20)
        .map(|(k, &id)| {
            let label = s
                .branches
                .get(id)
                .map_or(String::new(), |b| b.label.clone());
            (
                Mark::Square(plot::category_colour(k)),
                format!("#{} {label}", id + 1),
            )
        })
        .collect();
    let (lo, hi) = line.bounds();
    let (lo, hi) = if lo < hi {
        (lo, hi)
    } else {
        (lo - 0.5, hi + 0.5)
    };
    plot::png(path, (1500, 1150), |root| {
        let area = header(
            root,
            &format!(
                "Basin fractions along {} — {fixed}, ζ = {}, e = {}",
                if along_omega { "Ω" } else { "V" },
                s.zeta,
                s.restitution
            ),
            &format!(
                "{} starts per point in x0, x0' box {} at plate phase 0; branches matched \
                 within {}",
                s.starts_per_point, s.start_box, s.match_distance
            ),
            &legend,
        )?;
        let (_, h) = area.dim_in_pixel();
        let (top, bottom) = area.split_vertically(h * 11 / 20);
        let mut chart = plot::chart(&top, (lo, hi), (0.0, 1.0), x_desc, "basin fraction", None)?;
        let mut below = vec![0.0; points.len()];
        for (k, &id) in ids.iter().enumerate() {
            let above: Vec<f64> = points
                .iter()
                .zip(&below)
                .map(|((p, pids), b)| b + share(p, pids, id))
                .collect();
            let mut poly: Vec<(f64, f64)> = points
                .iter()
                .zip(&above)
                .map(|((p, _), &y)| (x_of(p), y))
                .collect();
            poly.extend(
                points
                    .iter()
                    .zip(&below)
                    .rev()
                    .map(|((p, _), &y)| (x_of(p), y)),
            );
            chart.draw_series([Polygon::new(poly, plot::category_colour(k).filled())])?;
            below = above;
        }
        let ys: Vec<f64> = orbits
            .iter()
            .flat_map(|b| b.slots.iter().flatten())
            .flat_map(|o| o.cycle_max.iter().copied())
            .collect();
        let (ylo, yhi) = if ys.is_empty() {
            (0.0, 1.0)
        } else {
            plot::range(ys.iter().copied(), 0.05)
        };
        let mut lower = plot::chart(
            &bottom,
            (lo, hi),
            (ylo, yhi),
            x_desc,
            "periodic orbits: max x per cycle",
            Some(
                "orbits continued from the attractors found — P-1 red, P-2 green, P-4 blue, \
                 P-8 orange, other periods purple; stable thick, unstable dashed",
            ),
        )?;
        let xs: Vec<f64> = points.iter().map(|(p, _)| x_of(p)).collect();
        for b in orbits {
            crate::branches::draw(&mut lower, b, &xs, crate::diagram::period_colour(b.period))?;
        }
        Ok(())
    })
}
