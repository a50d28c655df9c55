//! What a run is given and what it returns.

use crate::metrics::RunMetrics;
use mrsim_transport::TransportError;
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
}

/// What a finished run returns.
#[derive(Debug, Clone)]
pub struct RunOutcome {
    /// Everything written to metrics.json.
    pub metrics: RunMetrics,
}

/// Why a run could not be carried out.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
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
) -> impl FnOnce(std::io::Error) -> RunError + use<> {
    let dir = dir.display().to_string();
    move |source| RunError::Output { what, dir, source }
}
