//! `mrsim.Agent`: a robot of a running world (`planner = "external"`)
//! driven from Python over shared memory. Iterate it for observations,
//! answer each with `reply`; `close` it (or use it in a `with` block) to
//! leave the run.
//!
//! The agent's iceoryx2 ports may be used and dropped only on the thread
//! that opened them; a Python object, though, may be freed on any thread
//! (the garbage collector runs wherever it is triggered, for instance in
//! an in-process run's worker calling a Python planner). So the object
//! itself may travel and only its open agent is bound to its thread
//! ([`OnThread`]): a closed (or run-out) `Agent` is freed anywhere.

use crate::planner::{Kind, PyObservation, two_numbers};
use crate::run::params_dict;
use mrsim_agents::{LiveAgent, Next};
use pyo3::exceptions::{PyResourceWarning, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::mem::ManuallyDrop;
use std::thread::{self, ThreadId};
use std::time::Duration;

/// A value that is used and dropped only on the thread that made it: every
/// use checks the thread, and one dropped on another thread is leaked
/// (with a `ResourceWarning`) instead of dropped there.
struct OnThread<T> {
    owner: ThreadId,
    value: ManuallyDrop<T>,
}

// SAFETY: the value is reached only through `get`/`get_mut`, which check
// that the caller is on `owner`, and dropped only on `owner` (`Drop`);
// other threads move the wrapper (or free it, leaking the value) without
// touching it.
unsafe impl<T> Send for OnThread<T> {}
// SAFETY: as above: a shared reference reaches the value only on `owner`.
unsafe impl<T> Sync for OnThread<T> {}

impl<T> OnThread<T> {
    fn new(value: T) -> Self {
        Self {
            owner: thread::current().id(),
            value: ManuallyDrop::new(value),
        }
    }

    fn on_owner(&self) -> PyResult<()> {
        if thread::current().id() == self.owner {
            Ok(())
        } else {
            Err(PyRuntimeError::new_err(
                "an mrsim.Agent is used only on the thread that joined with it",
            ))
        }
    }

    fn get(&self) -> PyResult<&T> {
        self.on_owner().map(|()| &*self.value)
    }

    fn get_mut(&mut self) -> PyResult<&mut T> {
        self.on_owner()?;
        Ok(&mut self.value)
    }
}

impl<T> Drop for OnThread<T> {
    fn drop(&mut self) {
        if thread::current().id() == self.owner {
            // SAFETY: dropped once, here, on its own thread.
            unsafe { ManuallyDrop::drop(&mut self.value) };
        } else {
            Python::attach(|py| {
                let warned = PyErr::warn(
                    py,
                    &py.get_type::<PyResourceWarning>(),
                    c"an open mrsim.Agent was freed on another thread than its own and is \
                      leaked: close it (or use it in a `with` block) when done",
                    1,
                );
                if let Err(e) = warned {
                    e.write_unraisable(py, None);
                }
            });
        }
    }
}

/// A live agent: joins run `run_id` (the world's `--run`) as `robot`.
/// `for obs in agent: agent.reply((vx, vy))`: each observation is one tick
/// to answer (lockstep: the world waits; realtime: a late answer is a miss
/// and the robot brakes). The iteration ends when the run does; `close()`
/// (or the end of a `with` block) leaves the run earlier.
#[pyclass(weakref, module = "mrsim._mrsim")]
pub struct Agent {
    inner: Option<OnThread<LiveAgent>>,
    kind: Kind,
}

fn agent_error(e: mrsim_agents::AgentError) -> PyErr {
    PyRuntimeError::new_err(e.to_string())
}

#[pymethods]
impl Agent {
    /// `command`: "velocity" (default), "force" or "ackermann" (a car's
    /// speed and steering angle, rad), what `reply` sends; `timeout`:
    /// seconds to wait for the world and the join.
    #[new]
    #[pyo3(signature = (run_id, robot, command="velocity", timeout=30.0))]
    fn new(run_id: &str, robot: &str, command: &str, timeout: f64) -> PyResult<Self> {
        let kind = Kind::named(command)?;
        if !(timeout.is_finite() && timeout > 0.0) {
            return Err(PyValueError::new_err(
                "timeout must be a positive number of seconds",
            ));
        }
        let inner = LiveAgent::join(run_id, robot, Duration::from_secs_f64(timeout))
            .map_err(agent_error)?;
        Ok(Self {
            inner: Some(OnThread::new(inner)),
            kind,
        })
    }

    /// The robot's name ("" once closed).
    #[getter]
    fn robot(&self) -> PyResult<String> {
        match &self.inner {
            Some(a) => Ok(a.get()?.robot().to_string()),
            None => Ok(String::new()),
        }
    }

    /// The robot's planner params from its scenario entry.
    fn params<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let p = match &self.inner {
            Some(a) => a.get()?.params(),
            None => Default::default(),
        };
        params_dict(py, &p)
    }

    fn __iter__(slf: PyRef<'_, Self>) -> PyRef<'_, Self> {
        slf
    }

    fn __next__(&mut self, py: Python<'_>) -> PyResult<Option<PyObservation>> {
        let Some(agent) = self.inner.as_mut() else {
            return Ok(None);
        };
        let agent = agent.get_mut()?;
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

    /// Answers the last observation with two numbers (a velocity, a force
    /// or a car's speed and steering, as the constructor's `command` says).
    fn reply(&mut self, command: &Bound<'_, PyAny>) -> PyResult<()> {
        let v = two_numbers(command).map_err(PyValueError::new_err)?;
        if !(v[0].is_finite() && v[1].is_finite()) {
            return Err(PyValueError::new_err(format!("non-finite command {v:?}")));
        }
        let cmd = self.kind.command(v);
        let agent = self
            .inner
            .as_mut()
            .ok_or_else(|| PyRuntimeError::new_err("the run is over: nothing to answer"))?;
        agent.get_mut()?.reply(cmd).map_err(agent_error)
    }

    /// Leaves the run (also at the end of a `with` block, and when the
    /// object is freed); closing again does nothing.
    fn close(&mut self) -> PyResult<()> {
        if let Some(a) = &self.inner {
            a.on_owner()?;
        }
        self.inner = None;
        Ok(())
    }

    fn __enter__(slf: PyRef<'_, Self>) -> PyRef<'_, Self> {
        slf
    }

    /// Closes the agent; an exception in the block goes on.
    fn __exit__(
        &mut self,
        _exc_type: &Bound<'_, PyAny>,
        _exc: &Bound<'_, PyAny>,
        _traceback: &Bound<'_, PyAny>,
    ) -> PyResult<bool> {
        self.close()?;
        Ok(false)
    }
}
