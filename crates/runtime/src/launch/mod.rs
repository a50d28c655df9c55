//! A whole run (`mrsim run`): the world and one agent per robot, as
//! processes over iceoryx2 or in this process ([`crate::inproc`]), then
//! [`crate::finish`].
//!
//! [`prepare`] claims everything the run needs before anything starts (the
//! output folder, the run id's namespace, the scheduling, the termination
//! signals) so that a refusal comes before any process; [`Prepared::start`]
//! runs it. Each process is described by a [`ProcessSpec`] in this crate's
//! request types and started with the command its caller's [`Starter`]
//! builds for it (the `mrsim` executable's `world` and `agent`
//! subcommands); a termination signal to the launcher is forwarded to the
//! world, which writes what it has and tells its agents the run is over.
//!
//! One role per file: `embed` the embedding API ([`run_in_process`]),
//! `prepare` what is claimed before anything starts, `in_process` the
//! in-process path, `processes` starting and supervising the processes,
//! `zenoh` where a Zenoh world listens and its agents connect, `spec`
//! the processes' specs.

mod embed;
mod in_process;
mod prepare;
mod processes;
mod spec;
mod zenoh;

pub(crate) use embed::run_validated_in_process;
pub use embed::{InProcess, InProcessError, RunResult, run_in_process};
pub use prepare::{Prepared, prepare};
pub use spec::{ProcessSpec, Starter};

use crate::error::{Invalid, Refusal};
use crate::finish::FinishError;
use crate::sched::Sched;
use mrsim_transport::zenoh::ZenohOptions;
use std::path::PathBuf;
use std::process::ExitStatus;
use std::time::Duration;

/// How often `--restart-agents` restarts one robot's agent at most.
pub const MAX_RESTARTS: u32 = 10;

pub use crate::transport::Transport;

/// How to carry a run out, beyond its scenario.
#[derive(Debug, Clone, Default)]
pub struct RunRequest {
    /// The run id (iceoryx2 namespace); `None`: a fresh one.
    pub run_id: Option<String>,
    /// The output folder; `None`: a fresh folder under `runs/`.
    pub out: Option<PathBuf>,
    /// The transport between world and agents.
    pub transport: Transport,
    /// CPU affinity and SCHED_FIFO.
    pub sched: Sched,
    /// Draw plot.svg/png and replay.html at the end.
    pub render: bool,
    /// Restart an agent process that dies while the world runs (at most
    /// [`MAX_RESTARTS`] times per robot).
    pub restart_agents: bool,
    /// With [`Transport::Zenoh`]: where the world listens (`None`: a free
    /// loopback port) and the Zenoh config file, if any.
    pub zenoh: ZenohOptions,
    /// With [`Transport::Inproc`] in lockstep: the longest one robot's
    /// answer (observe, plan, send) may take before the run stops with
    /// [`InProcessError::Planner`] naming the robot and the tick, the
    /// outputs so far written. `None`: no limit (a planner that never returns holds
    /// the run).
    pub plan_timeout: Option<Duration>,
    /// Robots with planner `ros2`: how the ROS 2 agent reaches ROS 2.
    pub ros2: Ros2Side,
}

/// Where the ROS 2 agent (`mrsim ros2`) that `mrsim run` starts for the
/// robots with planner `ros2` finds the ROS 2 nodes.
#[derive(Debug, Clone, Default)]
pub struct Ros2Side {
    /// The Zenoh router of the ROS 2 side (`None`: tcp/localhost:7447).
    pub connect: Option<String>,
    /// The ROS domain id.
    pub domain: u32,
}

/// What happens while a run goes on, for a caller that shows it.
#[derive(Debug)]
pub enum Event<'a> {
    /// The launcher is waiting for its world (about every 20 ms): a moment
    /// to show progress.
    Waiting,
    /// The same for an in-process run, with an observer of its live
    /// statistics (a world process is observed over iceoryx2 instead).
    WaitingInproc(Observing<'a>),
    /// The world process has ended.
    WorldEnded,
    /// An agent process died and was started again.
    AgentRestarted {
        /// Its robot.
        robot: &'a str,
        /// The process that died.
        pid: u32,
        /// How it ended.
        how: String,
        /// This robot's restarts so far, this one included.
        restart: u32,
    },
}

/// An observer of a running in-process world.
pub struct Observing<'a>(pub &'a mut dyn mrsim_transport::ObserverTransport);

impl std::fmt::Debug for Observing<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Observing(..)")
    }
}

/// Why a run failed.
#[derive(Debug, thiserror::Error)]
pub enum LaunchError {
    /// Refused before anything started: the output folder, the run id, the
    /// CPU list.
    #[error(transparent)]
    Invalid(#[from] Invalid),
    /// The world process could not be started.
    #[error("cannot start the world process")]
    SpawnWorld(#[source] std::io::Error),
    /// An agent process could not be started.
    #[error("cannot start the agent process for {robot}")]
    SpawnAgent {
        /// Its robot.
        robot: String,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// Waiting for the world process failed.
    #[error("waiting for the world")]
    Wait(#[source] std::io::Error),
    /// The run in this process failed (`--transport inproc`): refused, a
    /// planner that failed in lockstep, the run itself, or its ending
    /// ([`InProcessError`]'s variants).
    #[error(transparent)]
    InProcess(#[from] InProcessError),
    /// The run's processes ended but the run could not be finished.
    #[error(transparent)]
    Finish(#[from] FinishError),
}

impl Refusal for LaunchError {
    fn refused(&self) -> Option<&Invalid> {
        match self {
            LaunchError::Invalid(i) => Some(i),
            LaunchError::InProcess(e) => e.refused(),
            _ => None,
        }
    }
}

/// How a child process ended, in words.
pub fn describe(status: ExitStatus) -> String {
    use std::os::unix::process::ExitStatusExt;
    match (status.code(), status.signal()) {
        (Some(c), _) => format!("exited with status {c}"),
        (None, Some(s)) => format!("was killed by signal {s} ({})", mrsim_sys::signal::name(s)),
        _ => "ended".to_string(),
    }
}
