//! What a run is given and what it returns.

use crate::metrics::RunMetrics;
use mrsim_transport::TransportError;
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::Duration;

/// How a run is carried out.
#[derive(Debug, Clone)]
pub struct RunOptions {
    /// Folder for the outputs (must exist).
    pub out_dir: PathBuf,
    /// The run id, written into metrics.json.
    pub run_id: String,
    /// Transport name for metrics.json (`shm` or `inproc`).
    pub transport: String,
    /// How long to wait for every agent to join; None = forever.
    pub start_timeout: Option<Duration>,
    /// Print progress lines (joins, losses) to stderr.
    pub verbose: bool,
    /// The routes of the robots with `route = "shortest"`, by name, as
    /// their agents compute them: written to routes.csv, and each one's
    /// length is the shortest path the robot's `spl` is measured against
    /// (the straight start-goal distance for the others).
    pub routes: BTreeMap<String, Route>,
    /// The most robots one agent process may join as: what the transport's
    /// buffer for one process's commands holds (a join that says more is
    /// refused). `None`: no such limit.
    pub group_room: Option<usize>,
}

/// The route a robot was given at the start: the shortest way its disc
/// fits through the run's walls and static obstacles.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Route {
    /// Its points, from the start to the goal.
    pub points: Vec<[f64; 2]>,
    /// Its length along the points.
    pub length: f64,
}

/// What a finished run returns.
#[derive(Debug, Clone)]
pub struct RunOutcome {
    /// Everything written to metrics.json.
    pub metrics: RunMetrics,
}

/// Why a run could not be carried out.
#[derive(Debug, thiserror::Error)]
pub enum WorldRunError {
    /// The transport failed.
    #[error(transparent)]
    Transport(#[from] TransportError),
    /// An output could not be written.
    #[error("cannot write {what} in {dir}: {source}")]
    Output {
        /// Which file.
        what: &'static str,
        /// The output folder.
        dir: String,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The scenario's cores cannot be modelled (`[world.cpus]` with no
    /// core, or `deadline` with a cpu robot without a reservation).
    #[error(transparent)]
    Cores(#[from] mrsim_scenario::cores::CoresError),
    /// Not every agent joined in time.
    #[error("agents for {missing} did not join within {secs:.0} s")]
    StartTimeout {
        /// The first few robot names, comma-separated, and how many more.
        missing: String,
        /// The timeout.
        secs: f64,
    },
}

/// The error of writing `what` into `dir`.
pub(super) fn out_err(
    dir: &std::path::Path,
    what: &'static str,
) -> impl FnOnce(std::io::Error) -> WorldRunError + use<> {
    let dir = dir.display().to_string();
    move |source| WorldRunError::Output { what, dir, source }
}
