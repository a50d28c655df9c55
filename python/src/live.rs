//! `mrsim.Agent`: a robot of a running world (`planner = "external"`)
//! driven from Python over shared memory. Iterate it for observations,
//! answer each with `reply`.

use crate::planner::{Kind, PyObservation, two_numbers};
use crate::run::params_dict;
use mrsim_agents::{LiveAgent, Next};
use mrsim_planners::{Command, Vec2};
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::time::Duration;

/// A live agent: joins run `run_id` (the world's `--run`) as `robot`.
/// `for obs in agent: agent.reply((vx, vy))`: each observation is one tick
/// to answer (lockstep: the world waits; realtime: a late answer is a miss
/// and the robot brakes). The iteration ends when the run does.
#[pyclass(unsendable, module = "mrsim._mrsim")]
pub struct Agent {
    inner: Option<LiveAgent>,
    kind: Kind,
}

fn agent_error(e: mrsim_agents::AgentError) -> PyErr {
    PyRuntimeError::new_err(e.to_string())
}

#[pymethods]
impl Agent {
    /// `command`: "velocity" (default) or "force", what `reply` sends;
    /// `timeout`: seconds to wait for the world and the join.
    #[new]
    #[pyo3(signature = (run_id, robot, command="velocity", timeout=30.0))]
    fn new(run_id: &str, robot: &str, command: &str, timeout: f64) -> PyResult<Self> {
        let kind = match command {
            "velocity" => Kind::Velocity,
            "force" => Kind::Force,
            other => {
                return Err(PyValueError::new_err(format!(
                    "command is \"velocity\" or \"force\", not {other:?}"
                )));
            }
        };
        if !(timeout.is_finite() && timeout > 0.0) {
            return Err(PyValueError::new_err(
                "timeout must be a positive number of seconds",
            ));
        }
        let inner = LiveAgent::join(run_id, robot, Duration::from_secs_f64(timeout))
            .map_err(agent_error)?;
        Ok(Self {
            inner: Some(inner),
            kind,
        })
    }

    /// The robot's name.
    #[getter]
    fn robot(&self) -> String {
        self.inner
            .as_ref()
            .map_or(String::new(), |a| a.robot().to_string())
    }

    /// The robot's planner params from its scenario entry.
    fn params<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let p = self
            .inner
            .as_ref()
            .map(LiveAgent::params)
            .unwrap_or_default();
        params_dict(py, &p)
    }

    fn __iter__(slf: PyRef<'_, Self>) -> PyRef<'_, Self> {
        slf
    }

    fn __next__(&mut self, py: Python<'_>) -> PyResult<Option<PyObservation>> {
        let Some(agent) = self.inner.as_mut() else {
            return Ok(None);
        };
        loop {
            match agent
                .next(Duration::from_millis(100))
                .map_err(agent_error)?
            {
                Next::Observation(o) => return PyObservation::new(py, &o.view()).map(Some),
                // Ctrl-C in the Python program is heard between waits.
                Next::Idle => py.check_signals()?,
                Next::Finished | Next::Interrupted => {
                    self.inner = None;
                    return Ok(None);
                }
                Next::WorldGone => {
                    self.inner = None;
                    return Err(PyRuntimeError::new_err(
                        "the world is gone (its process died or left without ending the run)",
                    ));
                }
            }
        }
    }

    /// Answers the last observation with two numbers (a velocity or a force,
    /// as the constructor's `command` says).
    fn reply(&mut self, command: &Bound<'_, PyAny>) -> PyResult<()> {
        let v = two_numbers(command).map_err(PyValueError::new_err)?;
        if !(v[0].is_finite() && v[1].is_finite()) {
            return Err(PyValueError::new_err(format!("non-finite command {v:?}")));
        }
        let v = Vec2::new(v[0], v[1]);
        let cmd = match self.kind {
            Kind::Force => Command::Force(v),
            Kind::Velocity => Command::Velocity(v),
        };
        let agent = self
            .inner
            .as_mut()
            .ok_or_else(|| PyRuntimeError::new_err("the run is over: nothing to answer"))?;
        agent.reply(cmd).map_err(agent_error)
    }

    /// Leaves the run (also when the object is dropped).
    fn close(&mut self) {
        self.inner = None;
    }
}
