//! `bistable_impact._native`: the Python adapter over `bistable-core` and `bistable-analysis`.
//!
//! No numerics here: arguments are validated by the core's and the analyses' own checks where
//! they have them, and otherwise with the CLI's rules and messages (errors become `ValueError`
//! naming the argument, simulation failures `RuntimeError`); runs are delegated to the core and
//! the analyses with the GIL released, and results are handed to Python as plain objects
//! (dicts, bytes of little-endian columns that the Python layer views as numpy arrays). The
//! Python package `bistable_impact` (in `python/`) wraps these functions.
//!
//! One module per area of the API, each registered in `_native` below: `simulate`
//! (`simulate`, `Simulator`), `classify` (`classify`, the point lists of `sweep.map`,
//! `thresholds`), `orbit` (`orbit`, `continue_omega`, `atlas`), `bifurcation`, `energy` (`energy_map`),
//! `spectrum`, `basins` (the cells and attractors of `sweep.basins`); `common` holds the argument
//! checks, the model, the tables and the Ctrl-C check shared by them. A new area is a new module
//! with its `#[pyfunction]`s, one `add_function` line here and its wrapper in
//! `python/bistable_impact/`.

use pyo3::prelude::*;

mod basins;
mod bifurcation;
mod classify;
mod coexistence;
mod common;
mod energy;
mod orbit;
mod simulate;
mod spectrum;

/// `n` evenly spaced values from `start` to `end`, both included exactly (the CLI's `A:B:N`,
/// with its limits: finite ends, `1 <= n <= MAX_POINTS`).
#[pyfunction]
fn linspace(py: Python<'_>, start: f64, end: f64, n: usize) -> PyResult<Vec<f64>> {
    use bistable_analysis::grid::MAX_POINTS;
    for (name, v) in [("start", start), ("end", end)] {
        if !v.is_finite() {
            return Err(common::invalid(py, name, v, "must be finite"));
        }
    }
    if !(1..=MAX_POINTS).contains(&n) {
        return Err(common::invalid_text("n", n, "must be in [1, 10000000]"));
    }
    Ok(bistable_analysis::grid::linspace(start, end, n))
}

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    // A refused BISTABLE_SIMD (unknown value, or a path the CPU lacks) fails the import.
    bistable_core::simd::check()
        .map_err(|e| pyo3::exceptions::PyImportError::new_err(e.to_string()))?;
    m.add_function(wrap_pyfunction!(simulate::simulate, m)?)?;
    m.add_function(wrap_pyfunction!(orbit::kind_names, m)?)?;
    m.add_class::<simulate::PySimulator>()?;
    m.add_function(wrap_pyfunction!(classify::classify, m)?)?;
    m.add_function(wrap_pyfunction!(classify::classify_many, m)?)?;
    m.add_function(wrap_pyfunction!(coexistence::coexistence_points, m)?)?;
    m.add_function(wrap_pyfunction!(coexistence::coexistence_table, m)?)?;
    m.add_function(wrap_pyfunction!(classify::thresholds_of, m)?)?;
    m.add_function(wrap_pyfunction!(classify::outcomes_text, m)?)?;
    m.add_function(wrap_pyfunction!(classify::outcomes_from_text, m)?)?;
    m.add_function(wrap_pyfunction!(orbit::orbit, m)?)?;
    m.add_function(wrap_pyfunction!(orbit::continue_omega, m)?)?;
    m.add_function(wrap_pyfunction!(orbit::atlas, m)?)?;
    m.add_function(wrap_pyfunction!(bifurcation::bifurcation, m)?)?;
    m.add_function(wrap_pyfunction!(energy::energy_map, m)?)?;
    m.add_function(wrap_pyfunction!(spectrum::spectrum, m)?)?;
    m.add_function(wrap_pyfunction!(basins::basin_cells, m)?)?;
    m.add_function(wrap_pyfunction!(basins::basin_attractors, m)?)?;
    m.add_function(wrap_pyfunction!(basins::basin_uncertainty_starts, m)?)?;
    m.add_function(wrap_pyfunction!(basins::basin_uncertainty, m)?)?;
    m.add_function(wrap_pyfunction!(linspace, m)?)?;
    // The classify record's keys in order: the map CSV's columns (one definition, in Rust).
    m.add("COLUMNS", bistable_analysis::record::COLUMNS.to_vec())?;
    m.add(
        "COEXISTENCE_COLUMNS",
        bistable_analysis::coexistence::COLUMNS.to_vec(),
    )?;
    // Most values of one grid (the CLI's cap on a range's points).
    m.add("MAX_POINTS", bistable_analysis::grid::MAX_POINTS)?;
    // Most worker threads of a `threads` argument.
    m.add("MAX_THREADS", common::MAX_THREADS)?;
    // The sensitivity test's default settings (one definition, in Rust).
    m.add(
        "SENSITIVITY_DEFAULTS",
        classify::sensitivity_defaults(m.py())?,
    )?;
    Ok(())
}
