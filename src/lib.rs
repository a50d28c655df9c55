//! mrsim, a multi-robot simulator: one rapier2d world, each robot driven by
//! its own agent running a planner. This crate is what a program depends
//! on to bring its own planner or to run scenarios from a program; the
//! `mrsim` command line (src/bin/mrsim/) is built on it.
//!
//! # Your own planner
//!
//! Implement [`Planner`]: the same trait the built-in planners implement.
//! Each tick it gets the robot's [`Observation`] (its own state, its goal,
//! the bodies it senses, with the scenario's sensing range, field of view
//! and noise already applied, the walls) and returns a [`Command`], a force
//! or a velocity. It must be a pure function of the observation and its
//! own state: no clock, no I/O, so lockstep runs repeat to the byte.
//!
//! Then either
//!
//! - **run a scenario in this process** with the planner registered under
//!   a name ([`Registry::register`]) that the scenario's robots use as
//!   their `planner`: [`run_in_process`] runs it headless and gives back
//!   the run folder and its [`RunMetrics`]; or
//! - **join a live run** as one robot's agent, exactly as `mrsim agent`
//!   does ([`LiveAgent`]): give the robot `planner = "external"` in the
//!   scenario, start the world (`mrsim run` or `mrsim world`, which start no
//!   agent for it and wait for yours), and join with the run id and the
//!   robot's name. `examples/my_agent.rs` is a whole one.
//!
//! In-process, a planner that panics or returns a non-finite command stops
//! a lockstep run at that tick with an error naming the robot and the tick
//! ([`RunError::Planner`]); the outputs so far are written.
//!
//! ```
//! use mrsim::{Command, InProcess, Observation, Planner, Registry, ScenarioSource};
//! use std::sync::Arc;
//!
//! /// Straight at the goal, as fast as it can still stop there.
//! struct Straight;
//!
//! impl Planner for Straight {
//!     fn plan(&mut self, obs: &Observation) -> Command {
//!         let to_goal = obs.goal - obs.me.position;
//!         let d = to_goal.norm();
//!         let speed = (obs.me.max_speed)
//!             .min((2.0 * obs.me.max_accel * d).sqrt())
//!             .min(d / obs.dt);
//!         Command::Velocity(to_goal.try_normalize(1e-12).unwrap_or_default() * speed)
//!     }
//! }
//!
//! let dir = std::env::temp_dir().join(format!("mrsim-doc-{}", std::process::id()));
//! std::fs::create_dir_all(&dir)?;
//! let scenario = dir.join("straight.toml");
//! std::fs::write(&scenario, r#"
//!     name = "straight"
//!     [world]
//!     dt = 0.1
//!     duration = 10.0
//!     [[robot]]
//!     name = "r0"
//!     start = [0.0, 0.0]
//!     goal = [3.0, 4.0]
//!     planner = "straight"
//!     max_speed = 2.0
//!     goal_tolerance = 0.1
//! "#)?;
//!
//! let mut registry = Registry::builtin();
//! registry.register_simple("straight", "straight at the goal", || Straight)?;
//! let run = mrsim::run_in_process(&InProcess {
//!     scenario: ScenarioSource { path: Some(scenario), ..Default::default() },
//!     registry: Arc::new(registry),
//!     out: Some(dir.join("run")),
//!     render: false,
//!     plan_timeout: None,
//! })?;
//! let r0 = &run.metrics.robots["r0"];
//! assert!(r0.reached_goal);
//! assert!((5.0..5.5).contains(&r0.path_length)); // a little overshoot while braking
//! assert!(run.dir.join("trajectory.csv").is_file());
//! # std::fs::remove_dir_all(&dir)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! Joining a live run (a test runs `examples/my_agent.rs` against a real
//! world; here it would wait for one):
//!
//! ```no_run
//! use mrsim::{AgentExit, Command, LiveAgent, Next};
//! use std::time::Duration;
//!
//! let mut agent = LiveAgent::join("lab1", "me", Duration::from_secs(30))?;
//! loop {
//!     match agent.next(Duration::from_millis(100))? {
//!         Next::Observation(obs) => {
//!             let to_goal = obs.goal - obs.me.position;
//!             agent.reply(Command::Velocity(to_goal.cap_magnitude(obs.me.max_speed)))?;
//!         }
//!         Next::Idle => {}
//!         Next::Finished | Next::Interrupted => break,
//!         Next::WorldGone => return Err("the world is gone".into()),
//!     }
//! }
//! // Or, with a `Planner`: `agent.drive(&mut my_planner)?`, the loop of `mrsim agent`.
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![warn(missing_docs)]

pub use mrsim_agents::{
    AgentError, AgentExit, LiveAgent, Next, OwnedObservation, PlanFailure, PlanFault,
};
pub use mrsim_planners::{
    BodyKind, BuildError, Command, DesignatedPath, Diagnostic, EXTERNAL, Observation, ParamError,
    ParamReader, ParamValue, Params, Placed, Planner, Polygon, Pose, RegisterError, Registry,
    Segment, SelfState, Sensed, Shape, Vec2,
};
pub use mrsim_runfolder::{FileError, RobotMetrics, RunMetrics};
/// Why [`run_in_process`] failed: refused before anything ran
/// ([`RunError::Invalid`]), a planner that failed in lockstep
/// ([`RunError::Planner`]), the run or its ending ([`RunError::Run`],
/// [`RunError::Finish`]). A run in this process starts no process, so no
/// variant speaks of one.
pub use mrsim_runtime::InProcessError as RunError;
pub use mrsim_runtime::InprocError;
/// Why the world of a run in this process could not carry it out (its
/// output files), as [`InprocError::Run`] holds it.
pub use mrsim_runtime::WorldRunError;
pub use mrsim_runtime::{AgentFailure, FinishError};
pub use mrsim_runtime::{InProcess, RunResult, run_in_process};
pub use mrsim_runtime::{Invalid, ScenarioSource};
pub use mrsim_scenario::Mode;
