//! `bistable_impact.sweep.basins`: the cells of a basin grid, classified by
//! `bistable_analysis::basins` exactly as `bistable basins` does, and the attractors they reach.

use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use bistable_analysis::basins::{
    classify_starts, count_uncertain, identify, plate_at, uncertainty_epsilons,
    uncertainty_exponent, uncertainty_samples, uncertainty_starts, Attractor, Cell, DecidedBy,
    Decision,
};
use bistable_analysis::recurrence::RecurrenceOptions;
use bistable_analysis::sensitivity::Outcome;
use bistable_analysis::sweep::interleaved;
use bistable_core::{ClassifyOptions, ResponseClass, SimError, Well};

use crate::common::{
    check_signals, invalid, invalid_text, lanes as lanes_arg, model, param_err, released, sim_err,
    threads as threads_arg,
};

fn cell_dict<'py>(py: Python<'py>, c: &Cell) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let o = &c.outcome;
    d.set_item("x0", c.x0)?;
    d.set_item("v0", c.v0)?;
    d.set_item("class", o.class.name())?;
    d.set_item("period", o.period)?;
    d.set_item("chaotic", o.chaotic)?;
    d.set_item("final_well", o.final_well.map(|w| w.number()))?;
    d.set_item("anchor_x", c.anchor.map(|a| a[0]))?;
    d.set_item("anchor_v", c.anchor.map(|a| a[1]))?;
    d.set_item("at_rest_in_second_well", c.at_rest)?;
    d.set_item("periods_simulated", c.periods_simulated)?;
    d.set_item("decided_by", c.decided_by.name())?;
    Ok(d)
}

/// Classifies the starts `(x0, v0)` at plate phase `phase` (cycles) on `threads` threads (0:
/// all cores) of `lanes` trajectories each in SIMD lanes (1, 4 or 8); one dict per start, in
/// order (the `bistable basins` CSV columns without the model's). By recurrence onto known
/// attractors (`bistable_analysis::recurrence`: `recurrence_hits` consecutive section points
/// near a periodic one, `aperiodic_hits` in the cells of an aperiodic one), the starts taken in rounds in the interleaved order of the list (as `bistable
/// basins` takes its grid); every start in full with `full_decision`. With `check_only` only the
/// arguments and the starts are checked (an empty list).
#[pyfunction]
#[pyo3(signature = (omega, velocity, phase, starts, zeta=0.02, restitution=0.85, tol=1e-16,
    chatter="accumulation", max_periods=2000.0, lyapunov_periods=300, threads=0, lanes=4,
    full_decision=false, recurrence_hits=2, aperiodic_hits=500, check_only=false))]
#[allow(clippy::too_many_arguments)]
pub fn basin_cells<'py>(
    py: Python<'py>,
    omega: f64,
    velocity: f64,
    phase: f64,
    starts: Vec<(f64, f64)>,
    zeta: f64,
    restitution: f64,
    tol: f64,
    chatter: &str,
    max_periods: f64,
    lyapunov_periods: u32,
    threads: usize,
    lanes: usize,
    full_decision: bool,
    recurrence_hits: u32,
    aperiodic_hits: u32,
    check_only: bool,
) -> PyResult<Bound<'py, PyList>> {
    let m = model(py, omega, velocity, zeta, restitution, tol, chatter)?;
    let (plate_x, _) = plate_at(&m, phase).map_err(|e| param_err(py, &e))?;
    for &(x0, _) in &starts {
        if x0.is_nan() || x0 < plate_x {
            return Err(invalid(
                py,
                "x0",
                x0,
                &format!("x0 must not be below the plate (z = {plate_x} at this phase)"),
            ));
        }
    }
    let co = ClassifyOptions {
        max_natural_periods: max_periods,
        lyapunov_periods,
        ..ClassifyOptions::default()
    }
    .check()
    .map_err(|e| param_err(py, &e))?;
    let ro = RecurrenceOptions {
        hits: recurrence_hits,
        aperiodic_hits,
        ..RecurrenceOptions::default()
    }
    .check()
    .map_err(|e| param_err(py, &e))?;
    let decision = if full_decision {
        Decision::Full
    } else {
        Decision::Recurrence(ro)
    };
    let threads = threads_arg(threads)?;
    let width = lanes_arg(lanes)?;
    if check_only {
        return Ok(PyList::empty(py));
    }
    // The rounds of a recurrence decision follow the list: spread them over the grid early.
    let order: Vec<usize> = interleaved(starts.len()).collect();
    let ordered: Vec<(f64, f64)> = order.iter().map(|&k| starts[k]).collect();
    let mut slots: Vec<Option<Result<Cell, SimError>>> = vec![None; starts.len()];
    released(
        py,
        || {
            classify_starts(&m, phase, co, decision, &ordered, threads, width, |i, r| {
                slots[order[i]] = Some(r);
                check_signals()
            })
            .map(|_| ())
        },
        |e| e.into_py(py),
    )?;
    let cells = slots
        .into_iter()
        .flatten()
        .collect::<Result<Vec<Cell>, SimError>>()
        .map_err(|e| sim_err(py, &e))?;
    let out = PyList::empty(py);
    for c in &cells {
        out.append(cell_dict(py, c)?)?;
    }
    Ok(out)
}

/// The cells of `list` (dicts of [`basin_cells`]); a bad one raises `ValueError` naming
/// `name` and the row.
fn cells_from(name: &str, list: &[Bound<'_, PyDict>]) -> PyResult<Vec<Cell>> {
    list.iter()
        .enumerate()
        .map(|(i, d)| {
            cell_from(d).map_err(|e| {
                let why = e.value(d.py()).to_string();
                invalid_text(
                    name,
                    format!("row {i}"),
                    &format!("not a basin cell: {why}"),
                )
            })
        })
        .collect()
}

fn cell_from(d: &Bound<'_, PyDict>) -> PyResult<Cell> {
    let get = |k: &str| -> PyResult<Bound<'_, PyAny>> {
        d.get_item(k)?
            .ok_or_else(|| pyo3::exceptions::PyKeyError::new_err(k.to_string()))
    };
    let class = match get("class")?.extract::<String>()?.as_str() {
        "intrawell" => ResponseClass::Intrawell,
        "transient_interwell" => ResponseClass::TransientInterwell,
        "continuous_interwell" => ResponseClass::ContinuousInterwell,
        other => {
            return Err(pyo3::exceptions::PyValueError::new_err(format!(
                "bad class {other:?}"
            )))
        }
    };
    let well: Option<u8> = get("final_well")?.extract()?;
    let ax: Option<f64> = get("anchor_x")?.extract()?;
    let av: Option<f64> = get("anchor_v")?.extract()?;
    Ok(Cell {
        x0: get("x0")?.extract()?,
        v0: get("v0")?.extract()?,
        outcome: Outcome {
            class,
            period: get("period")?.extract()?,
            chaotic: get("chaotic")?.extract()?,
            final_well: well.map(|w| if w == 2 { Well::Two } else { Well::One }),
        },
        anchor: ax.zip(av).map(|(a, b)| [a, b]),
        at_rest: get("at_rest_in_second_well")?.extract()?,
        periods_simulated: get("periods_simulated")?.extract()?,
        // How the cell was decided, not what it reached: `full` when not given.
        decided_by: match d.get_item("decided_by")? {
            None => DecidedBy::Full,
            Some(v) => match v.extract::<String>()?.as_str() {
                "full" => DecidedBy::Full,
                "recurrence" => DecidedBy::Recurrence,
                other => {
                    return Err(pyo3::exceptions::PyValueError::new_err(format!(
                        "bad decided_by {other:?}"
                    )))
                }
            },
        },
    })
}

/// The attractors reached by `cells` (dicts of [`basin_cells`]), largest basin first, as
/// dicts (`number`, `label`, `across_barrier`, `at_rest_in_second_well`, `period`, `chaotic`,
/// `final_well`, `anchor`, `cells`, `fraction`), and each cell's attractor number (from 1).
#[pyfunction]
pub fn basin_attractors<'py>(
    py: Python<'py>,
    cells: Vec<Bound<'py, PyDict>>,
) -> PyResult<(Bound<'py, PyList>, Vec<usize>)> {
    let cells = cells_from("cells", &cells)?;
    let (attractors, index) = identify(&cells);
    let total = cells.len().max(1) as f64;
    let out = PyList::empty(py);
    for (i, a) in attractors.iter().enumerate() {
        let d = PyDict::new(py);
        let mut label = a.steady.label();
        if let Some(x) = a.anchor {
            label.push_str(&format!(" (x = {:.4}, x' = {:.4})", x[0], x[1]));
        }
        d.set_item("number", i + 1)?;
        d.set_item("label", label)?;
        d.set_item("across_barrier", a.steady.across)?;
        d.set_item("at_rest_in_second_well", a.steady.at_rest)?;
        d.set_item("period", a.steady.period)?;
        d.set_item("chaotic", a.steady.chaotic)?;
        d.set_item("final_well", a.steady.well.map(|w| w.number()))?;
        d.set_item("anchor", a.anchor.map(|x| x.to_vec()))?;
        d.set_item("cells", a.cells)?;
        d.set_item("fraction", a.cells as f64 / total)?;
        out.append(d)?;
    }
    Ok((out, index.into_iter().map(|i| i + 1).collect()))
}

/// A basin grid as the uncertainty measurement sees it, a dict from Python: the shaker point,
/// the phase and model options given to [`basin_cells`], its cells (dicts of [`basin_cells`],
/// in grid order), the start positions' range (`x_first` to `x_last` in `nx` values) and the
/// number of cells to sample.
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
pub struct Grid<'py> {
    omega: f64,
    velocity: f64,
    phase: f64,
    zeta: f64,
    restitution: f64,
    tol: f64,
    chatter: String,
    cells: Vec<Bound<'py, PyDict>>,
    samples: usize,
    x_first: f64,
    x_last: f64,
    nx: usize,
}

/// What the measurement is made of, as `bistable basins` chooses it: the attractors of the
/// cells, the sampled cells, the displacements and the neighbour starts.
struct Plan {
    attractors: Vec<Attractor>,
    samples: Vec<(Cell, usize)>,
    epsilons: Vec<f64>,
    starts: Vec<(usize, usize, f64)>,
}

fn plan(py: Python<'_>, g: &Grid<'_>) -> PyResult<Plan> {
    let m = model(
        py,
        g.omega,
        g.velocity,
        g.zeta,
        g.restitution,
        g.tol,
        &g.chatter,
    )?;
    let (plate_x, _) = plate_at(&m, g.phase).map_err(|e| param_err(py, &e))?;
    if g.nx == 0 {
        return Err(invalid(py, "x0", 0.0, "needs at least one value"));
    }
    for x in [g.x_first, g.x_last] {
        if !x.is_finite() {
            return Err(invalid(py, "x0", x, "must be finite"));
        }
    }
    let cells = cells_from("cells", &g.cells)?;
    let (attractors, index) = identify(&cells);
    let samples = uncertainty_samples(&cells, &index, g.samples);
    let epsilons = uncertainty_epsilons(g.x_first, g.x_last, g.nx);
    let starts = uncertainty_starts(&samples, &epsilons, plate_x);
    Ok(Plan {
        attractors,
        samples,
        epsilons,
        starts,
    })
}

/// The neighbour starts `(x0, v0)` of the uncertainty measurement of `grid` ([`Grid`]): its
/// sampled cells spread over the grid, each displaced by `±ε` in `x0` (see
/// `bistable_analysis::basins`).
#[pyfunction]
pub fn basin_uncertainty_starts(py: Python<'_>, grid: Grid<'_>) -> PyResult<Vec<(f64, f64)>> {
    let p = plan(py, &grid)?;
    Ok(p.starts
        .iter()
        .map(|&(_, i, x0)| (x0, p.samples[i].0.v0))
        .collect())
}

/// The uncertainty fractions (dicts `epsilon`, `samples`, `uncertain`, `fraction`, largest
/// `ε` first; none without samples) and exponent (`None` with fewer than two fractions above
/// zero) of `grid`, from `reached`: the cells (dicts of [`basin_cells`]) of the starts of
/// [`basin_uncertainty_starts`], in its order.
#[pyfunction]
pub fn basin_uncertainty<'py>(
    py: Python<'py>,
    grid: Grid<'py>,
    reached: Vec<Bound<'py, PyDict>>,
) -> PyResult<(Bound<'py, PyList>, Option<f64>)> {
    let p = plan(py, &grid)?;
    if reached.len() != p.starts.len() {
        return Err(invalid_text(
            "reached",
            reached.len(),
            &format!("must hold one cell per start ({})", p.starts.len()),
        ));
    }
    let reached = cells_from("reached", &reached)?;
    let unc = count_uncertain(&p.attractors, &p.samples, &p.epsilons, &p.starts, &reached);
    let out = PyList::empty(py);
    for u in &unc {
        let d = PyDict::new(py);
        d.set_item("epsilon", u.epsilon)?;
        d.set_item("samples", u.samples)?;
        d.set_item("uncertain", u.uncertain)?;
        d.set_item("fraction", u.fraction())?;
        out.append(d)?;
    }
    Ok((out, uncertainty_exponent(&unc)))
}
