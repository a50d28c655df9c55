//! The run folder: what a run (or a bench, or a sweep) leaves on disk.
//!
//! One crate owns it so that the writer and every reader agree: the file
//! names are the constants below, and the JSON files have one typed schema
//! each ([`metrics::RunMetrics`] for `metrics.json`, [`usage::Usage`] for
//! `usage.json`, [`bench::BenchDoc`] for `bench.json`), with `Serialize` for
//! the process that writes them and `Deserialize` for everything that reads
//! them. The world writes `metrics.json` with [`write_metrics`]; the report,
//! the summary table, sweeps and the bench read it with [`read_metrics`].
//!
//! Reading is tolerant (a missing field takes its default, an unknown one
//! is ignored) so that a folder written by an older world, or a hand-made
//! one in a test, still reads; writing is exact (every field, in the order
//! declared, `null` for an absent value).
//!
//! The trajectory is `trajectory.csv` ([`csv`] reads its rows),
//! `trajectory.parquet` ([`trajectory`] has its schema, a writer and a
//! reader) or absent, as the scenario's `[output]` says. What timing decided per planner call is `timing.csv`
//! ([`timing`]); encounters.csv and scan.csv have their readers in
//! [`encounters`] and [`scan`].
//!
//! The files written while the run goes on are written in whole rows and
//! flushed on one clock ([`stream`]); every reader here accepts a torn last
//! row of a cut run, leaves it out and says so ([`stream::Cut`]), and
//! refuses any other bad line with the file and line.
#![warn(missing_docs)]

pub mod bench;
pub mod csv;
pub mod encounters;
pub mod metrics;
mod parquet_out;
pub mod scan;
pub mod stream;
pub mod sweep;
pub mod timing;
pub mod trajectory;
pub mod usage;

pub use metrics::{Percentiles, RobotMetrics, RunMetrics, TimingMetrics};

use std::path::{Path, PathBuf};

/// The resolved scenario, as the world ran it.
pub const SCENARIO_FILE: &str = "scenario.json";
/// Every body's state at every recorded tick (`[output] trajectory = "csv"`,
/// the default): `tick,time,body,kind,x,y,vx,vy`, numbers to six decimals.
pub const TRAJECTORY_FILE: &str = "trajectory.csv";
/// The same rows as [`TRAJECTORY_FILE`], typed, as Parquet (`[output]
/// trajectory = "parquet"`; schema in [`trajectory`]).
pub const TRAJECTORY_PARQUET_FILE: &str = "trajectory.parquet";
/// [`TRAJECTORY_PARQUET_FILE`]'s rows in [`TRAJECTORY_FILE`]'s format while
/// the run lives, removed once the Parquet footer is written: what a cut
/// run's trajectory is read from.
pub const TRAJECTORY_JOURNAL_FILE: &str = "trajectory.journal.csv";
/// The laser scans of the robots that record theirs ([`scan`]).
pub const SCAN_FILE: &str = "scan.csv";
/// `mrsim ros2`'s message counts per robot.
pub const ROS2_STATS_FILE: &str = "ros2.json";
/// The run as an MCAP file for Foxglove (`mrsim export`).
pub const MCAP_FILE: &str = "run.mcap";
/// One JSON object per line: joins, losses, contacts, goals, rejections.
pub const EVENTS_FILE: &str = "events.jsonl";
/// How the run's scenario was given ([`SourceDoc`]): what `mrsim rerun`
/// loads it from again.
pub const SOURCE_FILE: &str = "source.json";
/// Every time two bodies came within `[output] encounter_gap` of each
/// other: one row each ([`metrics::ENCOUNTERS_HEADER`]).
pub const ENCOUNTERS_FILE: &str = "encounters.csv";
/// The run's metrics ([`metrics::RunMetrics`]).
pub const METRICS_FILE: &str = "metrics.json";
/// The planners' per-tick diagnostics (only when some planner reported any).
pub const DIAGNOSTICS_FILE: &str = "diagnostics.csv";
/// [`DIAGNOSTICS_FILE`]'s header.
pub const DIAGNOSTICS_HEADER: &str = "tick,time,robot,name,value";
/// The routes of the robots with `route = "shortest"`, as planned at the
/// start: `robot,seq,x,y`, one row a point, start to goal.
pub const ROUTES_FILE: &str = "routes.csv";
/// The static plot, vector.
pub const PLOT_SVG_FILE: &str = "plot.svg";
/// The static plot, bitmap.
pub const PLOT_PNG_FILE: &str = "plot.png";
/// The self-contained replay page.
pub const REPLAY_FILE: &str = "replay.html";
/// What the agents used while the run ticked ([`usage::Usage`]).
pub const USAGE_FILE: &str = "usage.json";
/// `mrsim bench`'s rows ([`bench::BenchDoc`]).
pub const BENCH_FILE: &str = "bench.json";
/// `mrsim bench`'s rows flattened to CSV.
pub const BENCH_CSV_FILE: &str = "bench.csv";
/// `mrsim bench`'s plot.
pub const BENCH_SVG_FILE: &str = "bench.svg";
/// `mrsim bench --stress`: round trip and misses against the load, vector.
pub const STRESS_SVG_FILE: &str = "stress.svg";
/// `mrsim bench --stress`: the same figure, bitmap.
pub const STRESS_PNG_FILE: &str = "stress.png";
/// `mrsim sweep`: every metric against a swept number, vector.
pub const SWEEP_SVG_FILE: &str = "sweep.svg";
/// `mrsim sweep`: the same figure, bitmap.
pub const SWEEP_PNG_FILE: &str = "sweep.png";
/// `mrsim sweep`: one row per run.
pub const SWEEP_FILE: &str = "sweep.csv";
/// `mrsim sweep`: means and confidence intervals per setting.
pub const SUMMARY_FILE: &str = "summary.csv";
/// `mrsim sweep --allowable`: the largest allowable value per seed.
pub const ALLOWABLE_FILE: &str = "allowable.csv";

/// Prefix of an agent's diagnostics part file (merged into
/// [`DIAGNOSTICS_FILE`] when the run ends).
pub const DIAGNOSTICS_PART_PREFIX: &str = "diagnostics-";
/// Suffix of an agent's diagnostics part file.
pub const DIAGNOSTICS_PART_SUFFIX: &str = ".part";

/// Name of the diagnostics part file written by process `pid` (one per
/// process, so an agent that restarts does not overwrite its predecessor's
/// values). Each of its lines is a row of [`DIAGNOSTICS_FILE`] preceded by
/// the robot's id (`id,tick,time,robot,name,value`).
pub fn diagnostics_part_file(pid: u32) -> String {
    format!("{DIAGNOSTICS_PART_PREFIX}{pid}{DIAGNOSTICS_PART_SUFFIX}")
}

/// The process id of a diagnostics part file's name, or `None` for any
/// other file.
pub fn diagnostics_part_pid(name: &str) -> Option<u32> {
    name.strip_prefix(DIAGNOSTICS_PART_PREFIX)?
        .strip_suffix(DIAGNOSTICS_PART_SUFFIX)?
        .parse()
        .ok()
}

/// Name of the file in which the agent of `robot` leaves its usage for the
/// launcher (hidden; the launcher sums them into [`USAGE_FILE`] and removes
/// them).
pub fn agent_usage_file(robot: &str) -> String {
    format!(".usage-{robot}.json")
}

/// `source.json`: the scenario file and overrides a run was started with.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct SourceDoc {
    /// The scenario file, absolute; `None` for the built-in demo.
    pub file: Option<PathBuf>,
    /// The `--set KEY=VALUE` overrides, in order.
    pub set: Vec<String>,
    /// The `--mode` override (`lockstep` or `realtime`), if any.
    pub mode: Option<String>,
}

/// Writes `dir/source.json`.
pub fn write_source(dir: &Path, doc: &SourceDoc) -> Result<(), FileError> {
    let path = dir.join(SOURCE_FILE);
    let text = serde_json::to_string_pretty(doc).map_err(|source| FileError::Json {
        path: path.clone(),
        source,
    })?;
    std::fs::write(&path, text).map_err(|source| FileError::Io { path, source })
}

/// Why a run folder's file could not be read or written.
#[derive(Debug, thiserror::Error)]
pub enum FileError {
    /// The file could not be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The file is not what its schema says.
    #[error("{}: {source}", path.display())]
    Json {
        /// The file.
        path: PathBuf,
        /// The parse (or encoding) error.
        source: serde_json::Error,
    },
}

/// Why a streamed CSV file of the run folder (encounters.csv, scan.csv)
/// could not be read.
#[derive(Debug, thiserror::Error)]
pub enum RowsError {
    /// The file could not be read.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// A line is not a row of the file's schema (a torn last row of a cut
    /// run is not this: it is left out and reported).
    #[error("{}:{line}: {reason}", path.display())]
    Row {
        /// The file.
        path: PathBuf,
        /// 1-based line (the header is line 1).
        line: usize,
        /// What is wrong with it.
        reason: String,
    },
}

impl FileError {
    /// The file concerned.
    pub fn path(&self) -> &Path {
        match self {
            Self::Io { path, .. } | Self::Json { path, .. } => path,
        }
    }
}

/// Reads `dir/name` as JSON of type `T`.
pub fn read_json<T: serde::de::DeserializeOwned>(dir: &Path, name: &str) -> Result<T, FileError> {
    let path = dir.join(name);
    let text = std::fs::read_to_string(&path).map_err(|source| FileError::Io {
        path: path.clone(),
        source,
    })?;
    serde_json::from_str(&text).map_err(|source| FileError::Json { path, source })
}

/// Reads `dir/metrics.json`.
pub fn read_metrics(dir: &Path) -> Result<RunMetrics, FileError> {
    read_json(dir, METRICS_FILE)
}

/// Writes `dir/metrics.json` (pretty-printed, fields in declared order).
pub fn write_metrics(dir: &Path, metrics: &RunMetrics) -> Result<(), FileError> {
    let path = dir.join(METRICS_FILE);
    let text = serde_json::to_string_pretty(metrics).map_err(|source| FileError::Json {
        path: path.clone(),
        source,
    })?;
    std::fs::write(&path, text).map_err(|source| FileError::Io { path, source })
}
