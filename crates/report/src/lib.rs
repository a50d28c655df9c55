//! Seeing a run: reads a finished run's folder and draws it.
//!
//! [`RunData::load`] reads `scenario.json`, the trajectory (`trajectory.csv`,
//! `trajectory.parquet`, or none), `events.jsonl`,
//! `metrics.json` and the optional `diagnostics.csv`; [`write_plots`] draws
//! `plot.svg` and `plot.png` (map with trajectories, speeds, diagnostics);
//! [`write_replay`] writes `replay.html`, one self-contained page that
//! animates the run; [`export_mcap`] writes `run.mcap` for Foxglove.
//! [`render_all`] draws the first three; `mrsim run` calls it at the end of
//! a run and `mrsim report DIR` on a folder. [`sweep_plot`] and
//! [`bench_plot`] draw a sweep's and a bench's figures.
#![warn(missing_docs)]

pub mod bench_plot;
mod foxglove;
mod geometry;
mod load;
mod palette;
mod plot;
mod records;
mod replay;
mod run;
mod sensing;
pub mod sweep_plot;

pub use foxglove::{MCAP_FILE, McapWritten, export_mcap, write_mcap};
pub use geometry::BodyLook;
pub use palette::{COLLISION, PALETTE, PERSON, hex, robot_color};
pub use plot::{MAX_PLOT_POINTS, PLOT_WIDTH, plot_every, plot_size, write_plots};
pub use records::{BodyKind, BodyTrack, DiagnosticSample, Event, EventKind, Sample, Trajectory};
pub use replay::{
    MAP_HEIGHT, MAP_WIDTH, MAX_REPLAY_POSITIONS, ReplayView, STRIP_HEIGHT, replay_every,
    write_replay,
};
pub use run::{
    DIAGNOSTICS_FILE, EVENTS_FILE, METRICS_FILE, Metrics, Percentiles, RobotMetrics, RunData,
    SCENARIO_FILE, TRAJECTORY_FILE,
};

use std::path::{Path, PathBuf};

/// Why a run folder could not be read or drawn.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// The path given is not a folder.
    #[error("{path}: not a run folder (not a directory)")]
    NotADirectory {
        /// The path.
        path: PathBuf,
    },
    /// A required file is missing.
    #[error(
        "{path}: missing (a run folder needs scenario.json, events.jsonl and the trajectory its [output] names)"
    )]
    Missing {
        /// The file that should be there.
        path: PathBuf,
    },
    /// A file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// A line of a CSV or JSONL file (a row of a Parquet file) is
    /// malformed.
    #[error("{path}:{line}: {reason}")]
    Parse {
        /// The file.
        path: PathBuf,
        /// 1-based line number (the header is line 1); in a Parquet file,
        /// the 1-based row.
        line: usize,
        /// What is wrong with it.
        reason: String,
    },
    /// A JSON file is malformed (the message gives line and column).
    #[error("{path}: {source}")]
    Json {
        /// The file.
        path: PathBuf,
        /// serde_json's error.
        source: serde_json::Error,
    },
    /// `trajectory.parquet` is not a readable trajectory.
    #[error(transparent)]
    Parquet(mrsim_runfolder::trajectory::TrajectoryError),
    /// plotters failed to draw.
    #[error("{path}: drawing failed: {reason}")]
    Plot {
        /// The file being drawn.
        path: PathBuf,
        /// plotters' message.
        reason: String,
    },
    /// The MCAP writer failed.
    #[error("{path}: writing MCAP failed: {reason}")]
    Mcap {
        /// The file being written.
        path: PathBuf,
        /// The mcap crate's message.
        reason: String,
    },
    /// The PNG encoder failed.
    #[error("{path}: {source}")]
    Png {
        /// The file.
        path: PathBuf,
        /// png's error.
        source: png::EncodingError,
    },
}

/// Reads the run folder `dir` and writes `plot.svg`, `plot.png` and
/// `replay.html` into it; gives back where the run was cut, if it was
/// ([`RunData::cut`]: empty for a run that ended).
pub fn render_all(dir: &Path) -> Result<Vec<mrsim_runfolder::stream::Cut>, RenderError> {
    let run = RunData::load(dir)?;
    write_plots(&run, dir)?;
    write_replay(&run, dir)?;
    Ok(run.cut)
}

pub(crate) fn write_file(path: &Path, bytes: &[u8]) -> Result<(), RenderError> {
    std::fs::write(path, bytes).map_err(|source| RenderError::Io {
        path: path.to_path_buf(),
        source,
    })
}
