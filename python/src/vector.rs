//! The engine of `mrsim.gym.NavVectorEnv`: N copies of one scenario, each
//! with one learner, stepped together in one call with the GIL released,
//! spread over a few threads, writing into numpy arrays the caller owns.
//!
//! Every per-environment rule of `mrsim.gym.NavEnv` (action scaling,
//! reward, termination, truncation) is computed here in the same order and
//! arithmetic, so an environment of the batch gives bit for bit the episode
//! a NavEnv gives for the same seed. Gymnasium's next-step autoreset: an
//! environment that ended at the last step is reset at this one (with the
//! seed the caller gives for it) and its action is ignored.

use crate::{engine_arrays, err};
use mrsim_runtime::sim::{Sim as Engine, observation_size};
use mrsim_runtime::{ScenarioSource, Validated};
use mrsim_world::Applied;
use numpy::{PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2, PyReadwriteArray1};
use numpy::{PyReadwriteArray2, PyUntypedArrayMethods};
use pyo3::exceptions::{PyIndexError, PyValueError};
use pyo3::prelude::*;

/// One environment of the batch and what it remembers between steps.
struct Env {
    engine: Engine,
    /// Distance to the goal after the last step (or reset).
    distance: f64,
    /// The goal was reached (held) at some step of this episode.
    reached: bool,
    /// The last step ended the episode: reset at the next.
    autoreset: bool,
    /// What the last step gave, copied out after the threads finish.
    out: StepOut,
}

/// One environment's results of a step, besides its observation.
#[derive(Debug, Clone, Copy, Default)]
struct StepOut {
    reward: f64,
    terminated: bool,
    truncated: bool,
    collisions: i64,
    distance: f64,
    at_goal: bool,
    reached: bool,
    tick: u64,
    time: f64,
}

/// The rules of an episode, the same for every environment.
#[derive(Debug, Clone, Copy)]
struct Rules {
    force: bool,
    /// The scale of a normalised action (max speed or max force).
    bound: f64,
    /// Ticks in an episode.
    horizon: u64,
    progress: f64,
    collision: f64,
    arrival: f64,
    k: usize,
}

impl Env {
    /// Starts an episode with `seed` and writes its first observation.
    fn reset(&mut self, seed: u64, rules: &Rules, obs: &mut [f32]) -> Result<(), String> {
        self.engine.reset(Some(seed)).map_err(|e| e.to_string())?;
        self.engine
            .observe_f32(rules.k, obs)
            .map_err(|e| e.to_string())?;
        let info = self.engine.info()[0];
        self.distance = info.distance_to_goal;
        self.reached = false;
        self.autoreset = false;
        self.out = StepOut {
            reward: 0.0,
            terminated: false,
            truncated: false,
            collisions: 0,
            distance: info.distance_to_goal,
            at_goal: info.at_goal,
            reached: false,
            tick: self.engine.world().tick(),
            time: self.engine.world().time(),
        };
        Ok(())
    }

    /// One step with normalised action `a` (already checked finite), or
    /// the autoreset with `seed` if the last step ended the episode.
    fn step(
        &mut self,
        a: [f64; 2],
        seed: u64,
        rules: &Rules,
        obs: &mut [f32],
    ) -> Result<(), String> {
        if self.autoreset {
            return self.reset(seed, rules, obs);
        }
        let v = [
            a[0].clamp(-1.0, 1.0) * rules.bound,
            a[1].clamp(-1.0, 1.0) * rules.bound,
        ];
        let command = if rules.force {
            Applied::Force(v)
        } else {
            Applied::Velocity(v)
        };
        let info = self.engine.step(&[command]).map_err(|e| e.to_string())?[0];
        self.engine
            .observe_f32(rules.k, obs)
            .map_err(|e| e.to_string())?;
        let d = info.distance_to_goal;
        let reached_now = info.reached && !self.reached;
        self.reached = info.reached;
        let collisions = i64::from(info.collisions);
        // NavEnv's Rewards, term by term in its order.
        let reward = rules.progress * (self.distance - d)
            + rules.collision * collisions as f64
            + rules.arrival * f64::from(u8::from(reached_now));
        self.distance = d;
        let terminated = self.reached || collisions > 0;
        let tick = self.engine.world().tick();
        let truncated = tick >= rules.horizon && !terminated;
        self.autoreset = terminated || truncated;
        self.out = StepOut {
            reward,
            terminated,
            truncated,
            collisions,
            distance: d,
            at_goal: info.at_goal,
            reached: self.reached,
            tick,
            time: self.engine.world().time(),
        };
        Ok(())
    }
}

/// N environments of one scenario stepped together (see the module
/// documentation).
#[pyclass(unsendable, module = "mrsim._mrsim")]
pub struct VecSim {
    envs: Vec<Env>,
    rules: Rules,
    threads: usize,
}

/// A numpy array's data as a slice, or why not.
fn contiguous<'a, T>(
    what: &str,
    s: Result<&'a mut [T], numpy::NotContiguousError>,
) -> PyResult<&'a mut [T]> {
    s.map_err(|_| PyValueError::new_err(format!("the {what} buffer must be C-contiguous")))
}

/// Checks that `len` is `expected`, naming the buffer.
fn check_len(what: &str, len: usize, expected: usize) -> PyResult<()> {
    if len == expected {
        Ok(())
    } else {
        Err(PyValueError::new_err(format!(
            "the {what} buffer holds {len} values, {expected} needed"
        )))
    }
}

/// What [`for_each_env`] does to one environment: its action, its seed,
/// its observation row.
type PerEnv<'a> = dyn Fn(&mut Env, [f64; 2], u64, &mut [f32]) -> Result<(), String> + Sync + 'a;

/// Runs `f` on every environment with its observation row, its action and
/// its seed, the environments split over `threads` threads (the calling
/// one included). Returns the first error, naming the environment.
fn for_each_env(
    envs: &mut [Env],
    obs: &mut [f32],
    actions: &[f64],
    seeds: &[u64],
    size: usize,
    threads: usize,
    f: &PerEnv<'_>,
) -> Result<(), String> {
    let n = envs.len();
    if n == 0 {
        return Ok(());
    }
    let per = n.div_ceil(threads.clamp(1, n));
    let run = |first: usize, envs: &mut [Env], obs: &mut [f32], actions: &[f64], seeds: &[u64]| {
        for (j, (env, row)) in envs.iter_mut().zip(obs.chunks_exact_mut(size)).enumerate() {
            let a = [actions[2 * j], actions[2 * j + 1]];
            f(env, a, seeds[j], row).map_err(|e| format!("environment {}: {e}", first + j))?;
        }
        Ok::<(), String>(())
    };
    let mut results: Vec<Result<(), String>> = Vec::new();
    std::thread::scope(|s| {
        let mut chunks = envs
            .chunks_mut(per)
            .zip(obs.chunks_mut(per * size))
            .zip(actions.chunks(per * 2))
            .zip(seeds.chunks(per))
            .enumerate();
        // The first chunk runs on the calling thread, the rest on their own.
        let first = chunks.next();
        let handles: Vec<_> = chunks
            .map(|(c, (((e, o), a), sd))| s.spawn(move || run(c * per, e, o, a, sd)))
            .collect();
        if let Some((_, (((e, o), a), sd))) = first {
            results.push(run(0, e, o, a, sd));
        }
        for h in handles {
            results.push(
                h.join()
                    .unwrap_or_else(|_| Err("a stepping thread panicked".into())),
            );
        }
    });
    results.into_iter().collect()
}

impl VecSim {
    fn env(&self, i: usize) -> PyResult<&Engine> {
        self.envs.get(i).map(|e| &e.engine).ok_or_else(|| {
            PyIndexError::new_err(format!("no environment {i} of {}", self.envs.len()))
        })
    }

    /// Copies the environments' step results into the caller's arrays.
    fn write_out(&self, mut out: Outputs<'_>) -> PyResult<()> {
        let n = self.envs.len();
        let rewards = contiguous("rewards", out.rewards.as_slice_mut())?;
        let terminated = contiguous("terminations", out.terminated.as_slice_mut())?;
        let truncated = contiguous("truncations", out.truncated.as_slice_mut())?;
        let collisions = contiguous("collisions", out.collisions.as_slice_mut())?;
        let distance = contiguous("distance", out.distance.as_slice_mut())?;
        let at_goal = contiguous("at_goal", out.at_goal.as_slice_mut())?;
        let reached = contiguous("reached", out.reached.as_slice_mut())?;
        let tick = contiguous("tick", out.tick.as_slice_mut())?;
        let time = contiguous("time", out.time.as_slice_mut())?;
        for (what, len) in [
            ("rewards", rewards.len()),
            ("terminations", terminated.len()),
            ("truncations", truncated.len()),
            ("collisions", collisions.len()),
            ("distance", distance.len()),
            ("at_goal", at_goal.len()),
            ("reached", reached.len()),
            ("tick", tick.len()),
            ("time", time.len()),
        ] {
            check_len(what, len, n)?;
        }
        for (i, e) in self.envs.iter().enumerate() {
            let o = &e.out;
            rewards[i] = o.reward;
            terminated[i] = o.terminated;
            truncated[i] = o.truncated;
            collisions[i] = o.collisions;
            distance[i] = o.distance;
            at_goal[i] = o.at_goal;
            reached[i] = o.reached;
            tick[i] = o.tick;
            time[i] = o.time;
        }
        Ok(())
    }
}

/// The arrays a step or reset fills besides the observations.
struct Outputs<'py> {
    rewards: PyReadwriteArray1<'py, f64>,
    terminated: PyReadwriteArray1<'py, bool>,
    truncated: PyReadwriteArray1<'py, bool>,
    collisions: PyReadwriteArray1<'py, i64>,
    distance: PyReadwriteArray1<'py, f64>,
    at_goal: PyReadwriteArray1<'py, bool>,
    reached: PyReadwriteArray1<'py, bool>,
    tick: PyReadwriteArray1<'py, u64>,
    time: PyReadwriteArray1<'py, f64>,
}

#[pymethods]
impl VecSim {
    /// `num_envs` copies of `scenario` (a path; None: the built-in demo)
    /// with `set` overrides, robot `learner` taking the actions; `k`
    /// neighbours per observation; `force`: actions are forces, else
    /// velocities, scaled by `bound`; episodes truncated after `horizon`
    /// ticks; rewards per metre of progress, collision started and
    /// arrival; `threads` threads step the batch.
    #[new]
    #[allow(clippy::too_many_arguments)]
    #[pyo3(signature = (scenario, learner, set, k, num_envs, force, bound, horizon, progress, collision, arrival, threads))]
    fn new(
        scenario: Option<std::path::PathBuf>,
        learner: String,
        set: Vec<String>,
        k: usize,
        num_envs: usize,
        force: bool,
        bound: f64,
        horizon: u64,
        progress: f64,
        collision: f64,
        arrival: f64,
        threads: usize,
    ) -> PyResult<Self> {
        if num_envs == 0 {
            return Err(PyValueError::new_err("num_envs must be at least 1"));
        }
        if threads == 0 {
            return Err(PyValueError::new_err("num_threads must be at least 1"));
        }
        let mut envs = Vec::with_capacity(num_envs);
        for _ in 0..num_envs {
            let validated = Validated::new(ScenarioSource {
                path: scenario.clone(),
                mode: None,
                set: set.clone(),
            })
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
            let engine = Engine::new(validated, std::slice::from_ref(&learner)).map_err(err)?;
            envs.push(Env {
                engine,
                distance: 0.0,
                reached: false,
                autoreset: false,
                out: StepOut::default(),
            });
        }
        Ok(Self {
            envs,
            rules: Rules {
                force,
                bound,
                horizon,
                progress,
                collision,
                arrival,
                k,
            },
            threads,
        })
    }

    /// Resets the environments marked in `mask` with their `seeds`, writing
    /// their first observations into `obs` and their info into the other
    /// arrays (rows of unmarked environments are left as they are).
    #[allow(clippy::too_many_arguments)]
    fn reset<'py>(
        &mut self,
        py: Python<'py>,
        seeds: PyReadonlyArray1<'py, u64>,
        mask: PyReadonlyArray1<'py, bool>,
        mut obs: PyReadwriteArray2<'py, f32>,
        rewards: PyReadwriteArray1<'py, f64>,
        terminated: PyReadwriteArray1<'py, bool>,
        truncated: PyReadwriteArray1<'py, bool>,
        collisions: PyReadwriteArray1<'py, i64>,
        distance: PyReadwriteArray1<'py, f64>,
        at_goal: PyReadwriteArray1<'py, bool>,
        reached: PyReadwriteArray1<'py, bool>,
        tick: PyReadwriteArray1<'py, u64>,
        time: PyReadwriteArray1<'py, f64>,
    ) -> PyResult<()> {
        let n = self.envs.len();
        let size = observation_size(self.rules.k);
        let seeds = seeds
            .as_slice()
            .map_err(|_| PyValueError::new_err("seeds must be contiguous"))?;
        let mask = mask
            .as_slice()
            .map_err(|_| PyValueError::new_err("the mask must be contiguous"))?;
        check_len("seeds", seeds.len(), n)?;
        check_len("mask", mask.len(), n)?;
        let o = contiguous("observation", obs.as_slice_mut())?;
        check_len("observation", o.len(), n * size)?;
        let rules = self.rules;
        let threads = self.threads;
        let envs = &mut self.envs;
        // The action slot carries the mask: 1 resets, 0 leaves the env be.
        let flags: Vec<f64> = mask
            .iter()
            .flat_map(|&m| [f64::from(u8::from(m)); 2])
            .collect();
        py.detach(|| {
            for_each_env(
                envs,
                o,
                &flags,
                seeds,
                size,
                threads,
                &|env, a, seed, row| {
                    if a[0] != 0.0 {
                        env.reset(seed, &rules, row)
                    } else {
                        Ok(())
                    }
                },
            )
        })
        .map_err(PyValueError::new_err)?;
        self.write_out(Outputs {
            rewards,
            terminated,
            truncated,
            collisions,
            distance,
            at_goal,
            reached,
            tick,
            time,
        })
    }

    /// One step of every environment: `actions` (N, 2) float64 normalised
    /// actions (clipped to [-1, 1]); an environment whose last step ended
    /// its episode is reset instead with its entry of `seeds`. Writes the
    /// observations, rewards, terminations, truncations and info arrays.
    #[allow(clippy::too_many_arguments)]
    fn step<'py>(
        &mut self,
        py: Python<'py>,
        actions: PyReadonlyArray2<'py, f64>,
        seeds: PyReadonlyArray1<'py, u64>,
        mut obs: PyReadwriteArray2<'py, f32>,
        rewards: PyReadwriteArray1<'py, f64>,
        terminated: PyReadwriteArray1<'py, bool>,
        truncated: PyReadwriteArray1<'py, bool>,
        collisions: PyReadwriteArray1<'py, i64>,
        distance: PyReadwriteArray1<'py, f64>,
        at_goal: PyReadwriteArray1<'py, bool>,
        reached: PyReadwriteArray1<'py, bool>,
        tick: PyReadwriteArray1<'py, u64>,
        time: PyReadwriteArray1<'py, f64>,
    ) -> PyResult<()> {
        let n = self.envs.len();
        let size = observation_size(self.rules.k);
        if actions.shape() != [n, 2] {
            return Err(PyValueError::new_err(format!(
                "actions of shape {:?}, expected ({n}, 2): one row of two numbers per environment",
                actions.shape()
            )));
        }
        let a = actions
            .as_slice()
            .map_err(|_| PyValueError::new_err("the actions must be C-contiguous"))?;
        for (i, e) in self.envs.iter().enumerate() {
            let row = [a[2 * i], a[2 * i + 1]];
            if !e.autoreset && !row.iter().all(|x| x.is_finite()) {
                return Err(PyValueError::new_err(format!(
                    "environment {i}: non-finite action {row:?}"
                )));
            }
        }
        let seeds = seeds
            .as_slice()
            .map_err(|_| PyValueError::new_err("seeds must be contiguous"))?;
        check_len("seeds", seeds.len(), n)?;
        let o = contiguous("observation", obs.as_slice_mut())?;
        check_len("observation", o.len(), n * size)?;
        let rules = self.rules;
        let threads = self.threads;
        let envs = &mut self.envs;
        py.detach(|| {
            for_each_env(envs, o, a, seeds, size, threads, &|env, a, seed, row| {
                env.step(a, seed, &rules, row)
            })
        })
        .map_err(PyValueError::new_err)?;
        self.write_out(Outputs {
            rewards,
            terminated,
            truncated,
            collisions,
            distance,
            at_goal,
            reached,
            tick,
            time,
        })
    }

    /// Which environments will be reset at the next step (their last step
    /// ended an episode).
    fn autoreset<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<bool>> {
        PyArray1::from_iter(py, self.envs.iter().map(|e| e.autoreset))
    }

    /// Environments in the batch.
    #[getter]
    fn num_envs(&self) -> usize {
        self.envs.len()
    }

    /// Environment `i`'s body positions, (bodies, 2).
    fn positions<'py>(&self, py: Python<'py>, i: usize) -> PyResult<Bound<'py, PyArray2<f64>>> {
        Ok(engine_arrays::positions(py, self.env(i)?))
    }

    /// Environment `i`'s body velocities, (bodies, 2).
    fn velocities<'py>(&self, py: Python<'py>, i: usize) -> PyResult<Bound<'py, PyArray2<f64>>> {
        Ok(engine_arrays::velocities(py, self.env(i)?))
    }

    /// Environment `i`'s body radii.
    fn radii<'py>(&self, py: Python<'py>, i: usize) -> PyResult<Bound<'py, PyArray1<f64>>> {
        Ok(engine_arrays::radii(py, self.env(i)?))
    }

    /// Environment `i`'s body kinds: 0 robot, 1 obstacle, 2 person.
    fn kinds<'py>(&self, py: Python<'py>, i: usize) -> PyResult<Bound<'py, PyArray1<u32>>> {
        Ok(engine_arrays::kinds(py, self.env(i)?))
    }

    /// Environment `i`'s walls, (walls, 4).
    fn walls<'py>(&self, py: Python<'py>, i: usize) -> PyResult<Bound<'py, PyArray2<f64>>> {
        Ok(engine_arrays::walls(py, self.env(i)?))
    }

    /// Environment `i`'s learner goal, (1, 2).
    fn goals<'py>(&self, py: Python<'py>, i: usize) -> PyResult<Bound<'py, PyArray2<f64>>> {
        engine_arrays::goals(py, self.env(i)?)
    }

    /// The learner's robot index in every environment.
    #[getter]
    fn learner_indices(&self) -> PyResult<Vec<usize>> {
        Ok(self.env(0)?.learners().to_vec())
    }
}
