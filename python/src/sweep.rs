//! The native half of `mrsim.sweep`: the runs of a sweep as `mrsim sweep`
//! lists them (`mrsim_runtime::sweep::check`), and one run of it in this
//! process returning its row of sweep.csv's metrics. Spreading the runs
//! (an executor, a Dask cluster) is the Python half's.

use mrsim_runtime::Refusal;
use mrsim_runtime::sweep::{METRICS, SweepMode, SweepPlan, check, run_in_process, sets};
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::path::PathBuf;

/// The runs of a sweep of `scenario` over `set` (`KEY=V1,V2,...` each)
/// with seeds 1..=`seeds`, in lockstep: a dict with `name`, `axes` (the
/// keys), `files` (the maps the runs read) and `jobs`, one
/// `(values, seed, folder, overrides)` per run in sweep.csv's order.
#[pyfunction]
pub fn sweep_jobs<'py>(
    py: Python<'py>,
    scenario: PathBuf,
    set: Vec<String>,
    seeds: u64,
) -> PyResult<Bound<'py, PyDict>> {
    let plan = SweepPlan {
        scenario,
        set,
        seeds,
        out: None,
        jobs: None,
        allowable: None,
        mode: SweepMode::Lockstep,
        x: None,
        metrics: Vec::new(),
        sched: Default::default(),
        resume: false,
    };
    let checked = check(&plan).map_err(|e| match e.refused() {
        Some(i) => PyValueError::new_err(i.to_string()),
        None => PyRuntimeError::new_err(e.to_string()),
    })?;
    let d = PyDict::new(py);
    d.set_item("name", &checked.name)?;
    let keys: Vec<&str> = checked.axes.iter().map(|(k, _)| k.as_str()).collect();
    d.set_item("axes", keys)?;
    let values: Vec<&Vec<String>> = checked.axes.iter().map(|(_, v)| v).collect();
    d.set_item("values", values)?;
    let files: Vec<String> = checked
        .files
        .iter()
        .map(|f| f.to_string_lossy().into_owned())
        .collect();
    d.set_item("files", files)?;
    let jobs = PyList::empty(py);
    for job in &checked.jobs {
        let combo = &checked.combos[job.combo];
        jobs.append((
            job.combo,
            job.seed,
            &job.folder,
            sets(&checked.axes, combo, job.seed),
        ))?;
    }
    d.set_item("jobs", jobs)?;
    Ok(d)
}

/// Runs `scenario` with the overrides `set` in this process, in lockstep,
/// into the folder `out`, and returns sweep.csv's metrics of the run as
/// `(name, value or None)` pairs in the file's column order. The GIL is
/// released while it runs.
#[pyfunction]
pub fn sweep_run(
    py: Python<'_>,
    scenario: PathBuf,
    set: Vec<String>,
    out: PathBuf,
) -> PyResult<Vec<(&'static str, Option<f64>)>> {
    let metrics = py
        .detach(|| run_in_process(&scenario, set, &out))
        .map_err(PyRuntimeError::new_err)?;
    Ok(METRICS.iter().map(|(n, f)| (*n, f(&metrics))).collect())
}
