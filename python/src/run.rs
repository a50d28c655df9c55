//! `mrsim.run`: an in-process lockstep run in which robots may be driven by
//! planners written in Python, registered under names of their own beside
//! the built-in ones.

use crate::planner::{PyPlanner, describe};
use mrsim_planners::{BuildError, ParamValue, Params, Registry};
use mrsim_runtime::ScenarioSource;
use mrsim_runtime::{InProcess, InProcessError as RunError};
use mrsim_scenario::Mode;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

pyo3::create_exception!(
    _mrsim,
    PlannerError,
    PyRuntimeError,
    "A planner failed (raised, returned NaN or not two numbers, or took too long) at one robot and tick; the run stopped there. Attributes: robot, tick, dir (the run folder with the outputs so far)."
);

/// A robot's params as a Python dict.
pub fn params_dict<'py>(py: Python<'py>, params: &Params) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    for (k, v) in params {
        match v {
            ParamValue::Number(x) => d.set_item(k, x)?,
            ParamValue::Text(s) => d.set_item(k, s)?,
            ParamValue::Bool(b) => d.set_item(k, b)?,
            ParamValue::Numbers(xs) => d.set_item(k, PyList::new(py, xs)?)?,
            ParamValue::Points(ps) => {
                let rows: Vec<Vec<f64>> = ps.iter().map(|p| p.to_vec()).collect();
                d.set_item(k, rows)?
            }
        }
    }
    Ok(d)
}

/// The built-in planners plus `planners` (name -> a factory called with
/// the robot's params dict, returning an object with `plan(observation)`).
fn registry(planners: Option<&Bound<'_, PyDict>>) -> PyResult<Registry> {
    let mut registry = Registry::builtin();
    let Some(planners) = planners else {
        return Ok(registry);
    };
    for (name, factory) in planners.iter() {
        let name: String = name.extract()?;
        if !factory.is_callable() {
            return Err(PyValueError::new_err(format!(
                "planners[{name:?}] is not callable: give a class or a function taking the robot's params"
            )));
        }
        let summary = factory
            .getattr("__doc__")
            .ok()
            .and_then(|d| d.extract::<String>().ok())
            .and_then(|d| {
                d.lines()
                    .map(str::trim)
                    .find(|l| !l.is_empty())
                    .map(String::from)
            })
            .unwrap_or_else(|| "a planner written in Python".into());
        let factory: Py<PyAny> = factory.unbind();
        registry
            .register(&name, &summary, move |params: &Params| {
                Python::attach(|py| {
                    let made = params_dict(py, params)
                        .and_then(|d| factory.bind(py).call1((d,)))
                        .and_then(PyPlanner::new);
                    match made {
                        Ok(p) => Ok(Box::new(p) as Box<dyn mrsim_planners::Planner>),
                        Err(e) => Err(BuildError::Other(format!(
                            "the Python planner could not be made: {}",
                            describe(py, &e)
                        ))),
                    }
                })
            })
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
    }
    Ok(registry)
}

/// Runs `scenario` in this process in lockstep and returns the run folder.
#[pyfunction]
#[pyo3(signature = (scenario=None, planners=None, out=None, set=Vec::new(), render=false, plan_timeout=None))]
pub fn run_inproc(
    py: Python<'_>,
    scenario: Option<PathBuf>,
    planners: Option<Bound<'_, PyDict>>,
    out: Option<PathBuf>,
    set: Vec<String>,
    render: bool,
    plan_timeout: Option<f64>,
) -> PyResult<String> {
    let limit = match plan_timeout {
        None => None,
        Some(t) if t.is_finite() && t > 0.0 => Some(Duration::from_secs_f64(t)),
        Some(t) => {
            return Err(PyValueError::new_err(format!(
                "plan_timeout must be a positive number of seconds, got {t}"
            )));
        }
    };
    let req = InProcess {
        scenario: ScenarioSource {
            path: scenario,
            mode: Some(Mode::Lockstep),
            set,
        },
        registry: Arc::new(registry(planners.as_ref())?),
        out,
        render,
        // The run's watchdog: a call still running after the limit stops
        // the run, whether or not it ever returns.
        plan_timeout: limit,
    };
    // The GIL is released for the run: its worker threads take it to call
    // the Python planners.
    let result = py
        .detach(|| mrsim_runtime::run_in_process(&req))
        .map_err(|e| run_error(py, e))?;
    Ok(result.dir.to_string_lossy().into_owned())
}

/// What `rerun_inproc` returns to Python: the rerun's folder, the robots
/// (name, planner) not known to be deterministic, and where a cut run's
/// rerun stopped.
type RerunDone = (String, Vec<(String, String)>, Option<String>);

/// Reruns the recorded run folder `run` in this process in lockstep with
/// the timing it recorded (`mrsim rerun`); returns the rerun's folder and
/// the robots (name, planner) whose planner is not built in: not known to
/// be deterministic, the reason a replay may differ; and, for a run that
/// was cut, where the rerun stopped and why (`None` for a run that ended).
#[pyfunction]
#[pyo3(signature = (run, out=None, set=Vec::new(), planners=None, render=false))]
pub fn rerun_inproc(
    py: Python<'_>,
    run: PathBuf,
    out: Option<PathBuf>,
    set: Vec<String>,
    planners: Option<Bound<'_, PyDict>>,
    render: bool,
) -> PyResult<RerunDone> {
    let req = mrsim_runtime::rerun::Rerun {
        run,
        out,
        set,
        registry: Arc::new(registry(planners.as_ref())?),
        render,
    };
    let done = py
        .detach(|| mrsim_runtime::rerun::rerun(&req))
        .map_err(|e| match e {
            mrsim_runtime::rerun::RerunError::Invalid(i) => PyValueError::new_err(i.to_string()),
            mrsim_runtime::rerun::RerunError::Run(e) => run_error(py, e),
        })?;
    let cut = done.cut.map(|c| {
        let mut text = format!("the run was cut: rerun up to tick {}", c.tick);
        for f in &c.files {
            text.push_str(&format!("; {f}"));
        }
        text
    });
    Ok((
        done.result.dir.to_string_lossy().into_owned(),
        done.not_deterministic,
        cut,
    ))
}

/// The Python exception for a failed run.
fn run_error(py: Python<'_>, e: RunError) -> PyErr {
    match e {
        RunError::Planner { failure, dir } => {
            let text = format!(
                "{failure}; the run stopped there, outputs so far are in {}",
                dir.display()
            );
            let err = PlannerError::new_err(text);
            let v = err.value(py);
            let _ = v.setattr("robot", &failure.robot);
            let _ = v.setattr("tick", failure.tick);
            let _ = v.setattr("dir", dir.to_string_lossy().into_owned());
            err
        }
        RunError::Invalid(i) => PyValueError::new_err(i.to_string()),
        other => PyRuntimeError::new_err(mrsim_runtime::in_words(&other)),
    }
}
