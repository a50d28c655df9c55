//! The native half of the `mrsim` Python package: the stepping engine of
//! `mrsim_runtime::sim` for the Gymnasium and PettingZoo environments,
//! arrays in and out as numpy. The Python half (python/mrsim/) holds the
//! environments themselves.
#![warn(missing_docs)]

mod live;
mod planner;
mod run;
mod sweep;
mod vector;

use mrsim_runtime::sim::{Sim as Engine, SimError, observation_size};
use mrsim_runtime::{ScenarioSource, Validated};
use mrsim_world::Applied;
use numpy::{PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2, PyReadwriteArray2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

fn err(e: SimError) -> PyErr {
    PyValueError::new_err(e.to_string())
}

/// A scenario stepped tick by tick: the robots named as learners take their
/// commands from `step`, the others follow their built-in planners.
#[pyclass(unsendable, module = "mrsim._mrsim")]
struct Sim {
    engine: Engine,
    k: usize,
    /// The learners' commands, reused each step.
    commands: Vec<Applied>,
}

impl Sim {
    fn learner_column(&self, f: impl Fn(&mrsim_scenario::RobotSpec) -> f64) -> Vec<f64> {
        let robots = &self.engine.scenario().robots;
        self.engine
            .learners()
            .iter()
            .map(|&i| f(&robots[i]))
            .collect()
    }
}

#[pymethods]
impl Sim {
    /// `scenario`: a scenario file (None: the built-in demo); `learners`:
    /// robot names (None: every robot); `set`: `KEY=VALUE` overrides as
    /// `mrsim run --set`; `k`: neighbours in an observation vector.
    #[new]
    #[pyo3(signature = (scenario=None, learners=None, set=Vec::new(), k=8))]
    fn new(
        scenario: Option<std::path::PathBuf>,
        learners: Option<Vec<String>>,
        set: Vec<String>,
        k: usize,
    ) -> PyResult<Self> {
        let validated = Validated::new(ScenarioSource {
            path: scenario,
            mode: None,
            set,
        })
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
        let learners = learners.unwrap_or_else(|| {
            validated
                .scenario()
                .robots
                .iter()
                .map(|r| r.name.clone())
                .collect()
        });
        let engine = Engine::new(validated, &learners).map_err(err)?;
        Ok(Self {
            commands: Vec::with_capacity(learners.len()),
            engine,
            k,
        })
    }

    /// Starts a new episode (with `seed`: the scenario loaded with
    /// `world.seed` set to it).
    #[pyo3(signature = (seed=None))]
    fn reset(&mut self, seed: Option<u64>) -> PyResult<()> {
        self.engine.reset(seed).map_err(err)
    }

    /// One tick. `actions`: (learners, 2) float64, forces if `force` else
    /// velocities; learners marked in `brake` (bool per learner) brake
    /// instead. Returns per learner: collisions started (int64), distance
    /// to goal, at goal now, goal reached (held).
    #[allow(clippy::type_complexity)]
    #[pyo3(signature = (actions, force, brake=None))]
    fn step<'py>(
        &mut self,
        py: Python<'py>,
        actions: PyReadonlyArray2<'py, f64>,
        force: bool,
        brake: Option<PyReadonlyArray1<'py, bool>>,
    ) -> PyResult<(
        Bound<'py, PyArray1<i64>>,
        Bound<'py, PyArray1<f64>>,
        Bound<'py, PyArray1<bool>>,
        Bound<'py, PyArray1<bool>>,
    )> {
        let a = actions.as_array();
        if a.ncols() != 2 {
            return Err(PyValueError::new_err(format!(
                "actions of shape {:?}, expected ({}, 2)",
                a.shape(),
                self.engine.learners().len()
            )));
        }
        let brake = brake.as_ref().map(|b| b.as_array());
        self.commands.clear();
        self.commands
            .extend(a.rows().into_iter().enumerate().map(|(j, r)| {
                let v = [r[0], r[1]];
                if brake.as_ref().and_then(|b| b.get(j)).copied() == Some(true) {
                    Applied::BRAKE
                } else if force {
                    Applied::Force(v)
                } else {
                    Applied::Velocity(v)
                }
            }));
        let info = self.engine.step(&self.commands).map_err(err)?;
        Ok((
            PyArray1::from_iter(py, info.iter().map(|i| i64::from(i.collisions))),
            PyArray1::from_iter(py, info.iter().map(|i| i.distance_to_goal)),
            PyArray1::from_iter(py, info.iter().map(|i| i.at_goal)),
            PyArray1::from_iter(py, info.iter().map(|i| i.reached)),
        ))
    }

    /// Fills `out` ((learners, obs_size) float32, C-contiguous) with every
    /// learner's observation vector.
    fn observe(&mut self, mut out: PyReadwriteArray2<'_, f32>) -> PyResult<()> {
        let slice = out
            .as_slice_mut()
            .map_err(|_| PyValueError::new_err("the observation buffer must be C-contiguous"))?;
        self.engine.observe_f32(self.k, slice).map_err(err)
    }

    /// Values in one learner's observation vector: 4 + 6 k.
    #[getter]
    fn obs_size(&self) -> usize {
        observation_size(self.k)
    }

    /// Ticks done in this episode.
    #[getter]
    fn tick(&self) -> u64 {
        self.engine.world().tick()
    }

    /// Simulated time, s.
    #[getter]
    fn time(&self) -> f64 {
        self.engine.world().time()
    }

    /// The control period, s.
    #[getter]
    fn dt(&self) -> f64 {
        self.engine.scenario().world.dt
    }

    /// The scenario's duration, s.
    #[getter]
    fn duration(&self) -> f64 {
        self.engine.scenario().world.duration
    }

    /// Every robot's name, by index.
    #[getter]
    fn robot_names(&self) -> Vec<String> {
        let s = self.engine.scenario();
        s.robots.iter().map(|r| r.name.clone()).collect()
    }

    /// The learners' names, in action order.
    #[getter]
    fn learner_names(&self) -> Vec<String> {
        let s = self.engine.scenario();
        let l = self.engine.learners();
        l.iter().map(|&i| s.robots[i].name.clone()).collect()
    }

    /// The learners' robot indices (rows of `positions()` etc.).
    #[getter]
    fn learner_indices(&self) -> Vec<usize> {
        self.engine.learners().to_vec()
    }

    /// The learners' top speeds.
    #[getter]
    fn max_speed<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_vec(py, self.learner_column(|r| r.max_speed))
    }

    /// The largest force that matters per learner: enough for its top
    /// acceleration against damping at top speed.
    #[getter]
    fn max_force<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let f = self.learner_column(|r| r.mass * r.max_accel + r.damping * r.max_speed);
        PyArray1::from_vec(py, f)
    }

    /// The learners' goals, (learners, 2).
    fn goals<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        engine_arrays::goals(py, &self.engine)
    }

    /// Every body's position, (bodies, 2): robots, then obstacles, then
    /// people.
    fn positions<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        engine_arrays::positions(py, &self.engine)
    }

    /// Every body's velocity, (bodies, 2).
    fn velocities<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        engine_arrays::velocities(py, &self.engine)
    }

    /// Every body's radius.
    fn radii<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        engine_arrays::radii(py, &self.engine)
    }

    /// Every body's kind: 0 robot, 1 obstacle, 2 person (`mrsim.KINDS`
    /// names them).
    fn kinds<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<u32>> {
        engine_arrays::kinds(py, &self.engine)
    }

    /// Every wall segment (the arena's included), (walls, 4): x0, y0, x1, y1.
    fn walls<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        engine_arrays::walls(py, &self.engine)
    }
}

/// A stepping engine's state as numpy arrays, for [`Sim`] and
/// [`vector::VecSim`].
mod engine_arrays {
    use super::Engine;
    use numpy::{PyArray1, PyArray2, PyArrayMethods};
    use pyo3::prelude::*;

    /// The learners' goals, (learners, 2).
    pub fn goals<'py>(py: Python<'py>, e: &Engine) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let s = e.scenario();
        let rows: Vec<Vec<f64>> = (e.learners().iter())
            .map(|&i| s.robots[i].goal.to_vec())
            .collect();
        Ok(PyArray2::from_vec2(py, &rows)?)
    }

    /// Every body's position, (bodies, 2): robots, then obstacles, then
    /// people.
    pub fn positions<'py>(py: Python<'py>, e: &Engine) -> Bound<'py, PyArray2<f64>> {
        let s = e.world().states();
        let flat: Vec<f64> = s.iter().flat_map(|b| b.position).collect();
        reshape(py, flat, s.len(), 2)
    }

    /// Every body's velocity, (bodies, 2).
    pub fn velocities<'py>(py: Python<'py>, e: &Engine) -> Bound<'py, PyArray2<f64>> {
        let s = e.world().states();
        let flat: Vec<f64> = s.iter().flat_map(|b| b.velocity).collect();
        reshape(py, flat, s.len(), 2)
    }

    /// Every body's radius.
    pub fn radii<'py>(py: Python<'py>, e: &Engine) -> Bound<'py, PyArray1<f64>> {
        let s = e.world().states();
        PyArray1::from_iter(py, s.iter().map(|b| b.radius))
    }

    /// Every body's kind: 0 robot, 1 obstacle, 2 person (`mrsim.KINDS`
    /// names them).
    pub fn kinds<'py>(py: Python<'py>, e: &Engine) -> Bound<'py, PyArray1<u32>> {
        let s = e.world().states();
        PyArray1::from_iter(py, s.iter().map(|b| b.kind))
    }

    /// Every wall segment (the arena's included), (walls, 4): x0, y0, x1, y1.
    pub fn walls<'py>(py: Python<'py>, e: &Engine) -> Bound<'py, PyArray2<f64>> {
        let w = e.world().walls();
        let flat: Vec<f64> = w
            .iter()
            .flat_map(|s| [s[0][0], s[0][1], s[1][0], s[1][1]])
            .collect();
        reshape(py, flat, w.len(), 4)
    }

    /// A (rows, cols) array of `flat`, row by row.
    fn reshape(
        py: Python<'_>,
        flat: Vec<f64>,
        rows: usize,
        cols: usize,
    ) -> Bound<'_, PyArray2<f64>> {
        let a = PyArray1::from_vec(py, flat);
        match a.reshape([rows, cols]) {
            Ok(a) => a,
            // Cannot happen: `flat` has rows × cols values by construction.
            Err(_) => PyArray2::zeros(py, [rows, cols], false),
        }
    }
}

/// scenarios/crowdnav/circle-crossing.toml: CrowdNav's test scene, with
/// test case 0's people.
const CROWDNAV_SCENE: &str = include_str!("../../scenarios/crowdnav/circle-crossing.toml");

/// The line after which the CrowdNav scene lists its people.
const CROWDNAV_PEOPLE: &str = "# The people of test case ";

/// The text of CrowdNav's test case `case`: the shipped circle-crossing
/// scene with `world.seed` 1000 + `case` and that case's five people as
/// CrowdNav places them (`mrsim_scenario::crowdnav::CircleCrossing`), who
/// see the robot if `visible`. Case 0, invisible, is the shipped file.
#[pyfunction]
#[pyo3(signature = (case, visible=false))]
fn crowdnav_scene(case: u64, visible: bool) -> PyResult<String> {
    use mrsim_scenario::crowdnav::{CircleCrossing, TEST_SEED_OFFSET};
    let seed = u32::try_from(case)
        .ok()
        .and_then(|k| k.checked_add(TEST_SEED_OFFSET))
        .ok_or_else(|| {
            PyValueError::new_err(format!(
                "CrowdNav case {case}: cases run from 0 to {} (seed 1000 + case, a 32-bit seed)",
                u32::MAX - TEST_SEED_OFFSET
            ))
        })?;
    let (head, _) = CROWDNAV_SCENE.split_once(CROWDNAV_PEOPLE).ok_or_else(|| {
        PyValueError::new_err("the shipped CrowdNav scene lost its people's marker")
    })?;
    let mut s = head.replace("seed = 1000\n", &format!("seed = {seed}\n"));
    s.push_str(&format!(
        "{CROWDNAV_PEOPLE}{case} (seed {seed}), as mrsim_scenario::crowdnav::CircleCrossing places them.\n"
    ));
    let motion = "{ model = \"orca\", neighbor_dist = 10.0, max_neighbors = 10, \
                  time_horizon = 5.0, time_horizon_obst = 5.0, radius_margin = 0.01 }";
    let blocks: Vec<String> = CircleCrossing::default()
        .people(seed)
        .iter()
        .enumerate()
        .map(|(i, p)| {
            format!(
                "[[person]]\nname = \"h{i}\"\nstart = [{:?}, {:?}]\ngoal = [{:?}, {:?}]\n\
                 radius = 0.3\npreferred_speed = 1.0\nsees_robots = {visible}\nmotion = {motion}\n",
                p.start[0], p.start[1], p.goal[0], p.goal[1]
            )
        })
        .collect();
    s.push_str(&blocks.join("\n"));
    Ok(s)
}

/// The native module.
#[pymodule]
fn _mrsim(m: &Bound<'_, PyModule>) -> PyResult<()> {
    planner::quiet_planner_panics();
    m.add_class::<Sim>()?;
    m.add_class::<vector::VecSim>()?;
    m.add_function(wrap_pyfunction!(sweep::sweep_jobs, m)?)?;
    m.add_function(wrap_pyfunction!(sweep::sweep_run, m)?)?;
    m.add_class::<planner::PyObservation>()?;
    m.add_class::<live::Agent>()?;
    m.add_function(wrap_pyfunction!(run::run_inproc, m)?)?;
    m.add_function(wrap_pyfunction!(run::rerun_inproc, m)?)?;
    m.add_function(wrap_pyfunction!(crowdnav_scene, m)?)?;
    m.add("PlannerError", m.py().get_type::<run::PlannerError>())?;
    m.add("FILES", files(m.py())?)?;
    Ok(())
}

/// The run folder's file names by what they hold, from the one crate that
/// names them (`mrsim_runfolder`): Python code names a file through it.
fn files(py: Python<'_>) -> PyResult<Bound<'_, pyo3::types::PyDict>> {
    use mrsim_runfolder as f;
    let d = pyo3::types::PyDict::new(py);
    for (what, name) in [
        ("scenario", f::SCENARIO_FILE),
        ("source", f::SOURCE_FILE),
        ("trajectory", f::TRAJECTORY_FILE),
        ("trajectory_parquet", f::TRAJECTORY_PARQUET_FILE),
        ("trajectory_journal", f::TRAJECTORY_JOURNAL_FILE),
        ("timing", f::timing::TIMING_FILE),
        ("timing_parquet", f::timing::TIMING_PARQUET_FILE),
        ("timing_journal", f::timing::TIMING_JOURNAL_FILE),
        ("events", f::EVENTS_FILE),
        ("encounters", f::ENCOUNTERS_FILE),
        ("scan", f::SCAN_FILE),
        ("diagnostics", f::DIAGNOSTICS_FILE),
        ("routes", f::ROUTES_FILE),
        ("metrics", f::METRICS_FILE),
        ("usage", f::USAGE_FILE),
        ("ros2_stats", f::ROS2_STATS_FILE),
        ("mcap", f::MCAP_FILE),
        ("replay", f::REPLAY_FILE),
        ("plot_svg", f::PLOT_SVG_FILE),
        ("plot_png", f::PLOT_PNG_FILE),
        ("sweep", f::SWEEP_FILE),
        ("summary", f::SUMMARY_FILE),
        ("allowable", f::ALLOWABLE_FILE),
    ] {
        d.set_item(what, name)?;
    }
    Ok(d)
}
