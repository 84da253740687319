//! Which attractors coexist over a grid of shaker points (`bistable_analysis::coexistence`,
//! `bistable coexistence`): each point's attractors as plain Python data (so that Dask can
//! carry them), and the table of the CLI's CSV built from all of them.

use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use bistable_analysis::basins::{Cell, DecidedBy, Decision, Steady};
use bistable_analysis::coexistence::{
    coexistence, match_branches, row, CoexistenceOptions, Coexisting, PointCoexistence, Sampling,
    StartBox, Starts, TableSettings, COLUMNS, FIRST_ROUND,
};
use bistable_analysis::recurrence::RecurrenceOptions;
use bistable_analysis::sensitivity::Outcome;
use bistable_analysis::Model;
use bistable_core::{ClassifyOptions, ResponseClass, Sinusoid, Well};

use crate::common::{
    check_signals, invalid_text, lanes as lanes_arg, model, param_err, released,
    threads as threads_arg, values_dict, Stop,
};

/// The sweep's model (damping, restitution, solver) and options, checked; the errors name
/// the Python arguments.
#[allow(clippy::too_many_arguments)]
fn setting(
    py: Python<'_>,
    start_box: (f64, f64, f64, f64),
    grid: Option<(usize, usize)>,
    random: Option<(usize, u64)>,
    (zeta, restitution, tol, chatter): (f64, f64, f64, &str),
    (max_periods, lyapunov_periods): (f64, u32),
    (full_decision, recurrence_hits, aperiodic_hits): (bool, u32, u32),
) -> PyResult<(Model, CoexistenceOptions)> {
    let m = model(py, 1.0, 0.1, zeta, restitution, tol, chatter)?;
    let sampling = match (grid, random) {
        (Some((nx, nv)), None) => Sampling::Grid { nx, nv },
        (None, Some((n, seed))) => Sampling::Random { n, seed },
        _ => {
            return Err(invalid_text(
                "starts",
                "",
                "give a grid (nx, nv) or a count",
            ))
        }
    };
    let (x0, x1, v0, v1) = start_box;
    let starts = Starts {
        bounds: StartBox {
            x: [x0, x1],
            v: [v0, v1],
        },
        sampling,
    }
    .check()
    .map_err(|e| {
        let name = if e.name == "start_box" {
            "box"
        } else {
            "starts"
        };
        invalid_text(name, e.value, e.rule)
    })?;
    let classify = ClassifyOptions {
        max_natural_periods: max_periods,
        lyapunov_periods,
        ..ClassifyOptions::default()
    }
    .check()
    .map_err(|e| param_err(py, &e))?;
    let decision = if full_decision {
        Decision::Full
    } else {
        Decision::Recurrence(
            RecurrenceOptions {
                hits: recurrence_hits,
                aperiodic_hits,
                first_round: FIRST_ROUND,
                ..RecurrenceOptions::default()
            }
            .check()
            .map_err(|e| param_err(py, &e))?,
        )
    };
    Ok((
        m,
        CoexistenceOptions {
            starts,
            classify,
            decision,
            ..CoexistenceOptions::default()
        },
    ))
}

/// Decides the starts (a grid `(nx, nv)` or `random` seeded ones) of the box `(x0 from, x0
/// to, x0' from, x0' to)` at every `(omega, velocity)` of `points`, on `threads` threads (0:
/// all cores) of `lanes` trajectories each, as `bistable coexistence` does; one dict per point
/// (see `_point_dict`) in the order of `points`. After each point Python's signal handlers
/// run (Ctrl-C stops the sweep) and `progress(done, total)` is called if given. With
/// `check_only` only the arguments are checked (an empty list).
#[pyfunction]
#[pyo3(signature = (points, start_box=(0.0, 1.2, -0.6, 0.6), grid=None, random=None, zeta=0.02,
    restitution=0.85, tol=1e-16, chatter="accumulation", max_periods=20000.0,
    lyapunov_periods=300, full_decision=false, recurrence_hits=2, aperiodic_hits=500,
    threads=0, lanes=4, progress=None, check_only=false))]
#[allow(clippy::too_many_arguments)]
pub fn coexistence_points<'py>(
    py: Python<'py>,
    points: Vec<(f64, f64)>,
    start_box: (f64, f64, f64, f64),
    grid: Option<(usize, usize)>,
    random: Option<(usize, u64)>,
    zeta: f64,
    restitution: f64,
    tol: f64,
    chatter: &str,
    max_periods: f64,
    lyapunov_periods: u32,
    full_decision: bool,
    recurrence_hits: u32,
    aperiodic_hits: u32,
    threads: usize,
    lanes: usize,
    progress: Option<Py<PyAny>>,
    check_only: bool,
) -> PyResult<Bound<'py, PyList>> {
    let (m, options) = setting(
        py,
        start_box,
        grid,
        random,
        (zeta, restitution, tol, chatter),
        (max_periods, lyapunov_periods),
        (full_decision, recurrence_hits, aperiodic_hits),
    )?;
    for &(w, v) in &points {
        Sinusoid::new(w, v).map_err(|e| param_err(py, &e))?;
    }
    let threads = threads_arg(threads)?;
    let width = lanes_arg(lanes)?;
    if check_only {
        return Ok(PyList::empty(py));
    }
    let mut out: Vec<Option<PointCoexistence>> = vec![None; points.len()];
    let (mut done, total) = (0usize, points.len());
    released(
        py,
        || {
            coexistence(&m, &points, options, threads, width, |i, r| {
                out[i] = Some(r?);
                done += 1;
                check_signals()?;
                if let Some(f) = &progress {
                    Python::with_gil(|py| f.call1(py, (done, total)).map(|_| ()))
                        .map_err(Stop::Py)?;
                }
                Ok::<(), Stop>(())
            })
        },
        |e| e.into_py(py),
    )?;
    let list = PyList::empty(py);
    for p in out.iter().flatten() {
        list.append(point_dict(py, p)?)?;
    }
    Ok(list)
}

/// The table of `bistable coexistence`'s CSV (one dict per point and attractor, keys
/// `COEXISTENCE_COLUMNS`) for the grid `omegas × velocities` (Ω inner, V outer) from the point
/// dicts of [`coexistence_points`] (every grid point once, any order), with the branches
/// matched within `match_distance`; the other arguments as given to [`coexistence_points`].
#[pyfunction]
#[pyo3(signature = (points, omegas, velocities, match_distance=0.2,
    start_box=(0.0, 1.2, -0.6, 0.6), grid=None, random=None, zeta=0.02, restitution=0.85,
    tol=1e-16, chatter="accumulation", max_periods=20000.0, lyapunov_periods=300,
    full_decision=false, recurrence_hits=2, aperiodic_hits=500))]
#[allow(clippy::too_many_arguments)]
pub fn coexistence_table<'py>(
    py: Python<'py>,
    points: Vec<Bound<'py, PyDict>>,
    omegas: Vec<f64>,
    velocities: Vec<f64>,
    match_distance: f64,
    start_box: (f64, f64, f64, f64),
    grid: Option<(usize, usize)>,
    random: Option<(usize, u64)>,
    zeta: f64,
    restitution: f64,
    tol: f64,
    chatter: &str,
    max_periods: f64,
    lyapunov_periods: u32,
    full_decision: bool,
    recurrence_hits: u32,
    aperiodic_hits: u32,
) -> PyResult<Bound<'py, PyList>> {
    let (m, options) = setting(
        py,
        start_box,
        grid,
        random,
        (zeta, restitution, tol, chatter),
        (max_periods, lyapunov_periods),
        (full_decision, recurrence_hits, aperiodic_hits),
    )?;
    if !(match_distance.is_finite() && match_distance >= 0.0) {
        return Err(invalid_text(
            "match_distance",
            match_distance,
            "must be finite and >= 0",
        ));
    }
    let parsed: Vec<PointCoexistence> = points
        .iter()
        .enumerate()
        .map(|(i, d)| point_from(d).map_err(|e| invalid_text("points", i, &e)))
        .collect::<PyResult<_>>()?;
    let key = |w: f64, v: f64| (w.to_bits(), v.to_bits());
    let by_key: std::collections::HashMap<(u64, u64), &PointCoexistence> = parsed
        .iter()
        .map(|p| (key(p.omega, p.velocity), p))
        .collect();
    let grid_points: Vec<Option<&PointCoexistence>> = velocities
        .iter()
        .flat_map(|&v| omegas.iter().map(move |&w| (w, v)))
        .map(|(w, v)| by_key.get(&key(w, v)).copied())
        .collect();
    if let Some(k) = grid_points.iter().position(Option::is_none) {
        let (w, v) = (omegas[k % omegas.len()], velocities[k / omegas.len()]);
        return Err(invalid_text(
            "points",
            format!("(Ω = {w}, V = {v})"),
            "has no result for this grid point",
        ));
    }
    let (ids, _) = match_branches(omegas.len(), &grid_points, match_distance);
    let settings = TableSettings::new(&m, &options);
    let out = PyList::empty(py);
    for (p, ids) in grid_points.iter().flatten().zip(&ids) {
        for (k, (a, &id)) in p.attractors.iter().zip(ids).enumerate() {
            let label = a.steady.label();
            let values = row(p, k, Some(id), &settings, &label);
            out.append(values_dict(py, &mut COLUMNS.into_iter().zip(values))?)?;
        }
    }
    Ok(out)
}

/// A point's result as plain data: `omega`, `velocity`, `starts`, `paper` (class, period,
/// chaotic, final_well of the paper's start), `paper_sensitive`, `paper_attractor` (index) and
/// `attractors`
/// (dicts of `across`, `period`, `chaotic`, `well`, `at_rest`, `anchor`, `count`,
/// `by_recurrence`, `periods_simulated`).
fn point_dict<'py>(py: Python<'py>, p: &PointCoexistence) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("omega", p.omega)?;
    d.set_item("velocity", p.velocity)?;
    d.set_item("starts", p.starts)?;
    let o = &p.paper.outcome;
    d.set_item(
        "paper",
        (
            o.class.name(),
            o.period,
            o.chaotic,
            o.final_well.map(|w| w.number()),
        ),
    )?;
    d.set_item("paper_attractor", p.paper_attractor)?;
    d.set_item("paper_sensitive", p.paper_sensitive)?;
    let list = PyList::empty(py);
    for a in &p.attractors {
        let s = &a.steady;
        let e = PyDict::new(py);
        e.set_item("across", s.across)?;
        e.set_item("period", s.period)?;
        e.set_item("chaotic", s.chaotic)?;
        e.set_item("well", s.well.map(|w| w.number()))?;
        e.set_item("at_rest", s.at_rest)?;
        e.set_item("anchor", a.anchor.map(|x| (x[0], x[1])))?;
        e.set_item("count", a.count)?;
        e.set_item("by_recurrence", a.by_recurrence)?;
        e.set_item("periods_simulated", a.periods_simulated)?;
        list.append(e)?;
    }
    d.set_item("attractors", list)?;
    Ok(d)
}

/// The inverse of [`point_dict`]; `Err` says what is wrong.
fn point_from(d: &Bound<'_, PyDict>) -> Result<PointCoexistence, String> {
    fn get<'py, T: FromPyObject<'py>>(d: &Bound<'py, PyDict>, k: &str) -> Result<T, String> {
        d.get_item(k)
            .map_err(|e| e.to_string())?
            .ok_or_else(|| format!("has no '{k}'"))?
            .extract()
            .map_err(|e| format!("bad '{k}': {e}"))
    }
    let well = |n: Option<u8>| match n {
        None => Ok(None),
        Some(1) => Ok(Some(Well::One)),
        Some(2) => Ok(Some(Well::Two)),
        Some(n) => Err(format!("bad well {n}")),
    };
    let (class, period, chaotic, final_well): (String, Option<u32>, bool, Option<u8>) =
        get(d, "paper")?;
    let class = [
        ResponseClass::Intrawell,
        ResponseClass::TransientInterwell,
        ResponseClass::ContinuousInterwell,
    ]
    .into_iter()
    .find(|c| c.name() == class)
    .ok_or_else(|| format!("bad paper class '{class}'"))?;
    let mut attractors = Vec::new();
    for e in get::<Vec<Bound<'_, PyDict>>>(d, "attractors")? {
        let anchor: Option<(f64, f64)> = get(&e, "anchor")?;
        attractors.push(Coexisting {
            steady: Steady {
                across: get(&e, "across")?,
                period: get(&e, "period")?,
                chaotic: get(&e, "chaotic")?,
                well: well(get(&e, "well")?)?,
                at_rest: get(&e, "at_rest")?,
            },
            anchor: anchor.map(|(x, v)| [x, v]),
            count: get(&e, "count")?,
            by_recurrence: get(&e, "by_recurrence")?,
            periods_simulated: get(&e, "periods_simulated")?,
        });
    }
    let paper_attractor: usize = get(d, "paper_attractor")?;
    if paper_attractor >= attractors.len() {
        return Err(format!("bad paper_attractor {paper_attractor}"));
    }
    Ok(PointCoexistence {
        omega: get(d, "omega")?,
        velocity: get(d, "velocity")?,
        starts: get(d, "starts")?,
        attractors,
        paper: Cell {
            x0: 0.0,
            v0: 0.0,
            outcome: Outcome {
                class,
                period,
                chaotic,
                final_well: well(final_well)?,
            },
            anchor: None,
            at_rest: false,
            periods_simulated: 0.0,
            decided_by: DecidedBy::Full,
        },
        paper_sensitive: get(d, "paper_sensitive")?,
        paper_attractor,
    })
}
