//! The end of a run, one function for every path (agent processes, the
//! in-process pool, a world started by hand): the agents' diagnostics merged
//! into diagnostics.csv, usage.json written, metrics.json taken from the
//! world that ran in this process or read from the folder, the plots and
//! replay drawn, and all of it handed back as an [`Outcome`] for the caller
//! to present.

use crate::usage::AgentUsage;
use mrsim_agents::diagnostics::MergeSummary;
use mrsim_report::RenderError;
use mrsim_runfolder::{FileError, RunMetrics};
use std::path::{Path, PathBuf};

/// How a run ended, for its caller to present.
#[derive(Debug)]
pub struct Outcome {
    /// The run folder.
    pub dir: PathBuf,
    /// Merging the agents' diagnostics into diagnostics.csv: what was
    /// merged (and left out), or why it could not be.
    pub diagnostics: Result<MergeSummary, std::io::Error>,
    /// The world process failed: nothing further was done (the outputs so
    /// far are in [`Outcome::dir`]).
    pub world_failure: Option<WorldFailure>,
    /// Agents that ended badly while the world ran to its end (the run's
    /// events.jsonl says what the world saw).
    pub agent_failures: Vec<AgentFailure>,
    /// metrics.json (absent when the world failed).
    pub metrics: Option<RunMetrics>,
    /// Drawing plot.svg/png and replay.html, or writing run.mcap (when
    /// `[output] mcap = true`), failed (the run itself did not).
    pub render_error: Option<RenderError>,
}

impl Outcome {
    /// True if the run was cut short by a signal (and wrote what it had).
    pub fn interrupted(&self) -> bool {
        self.metrics.as_ref().is_some_and(|m| m.interrupted)
    }
}

/// A world process that did not end well.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct WorldFailure {
    /// Its process id.
    pub pid: u32,
    /// How it ended (`exited with status 1`, `was killed by signal 9
    /// (SIGKILL)`).
    pub how: String,
}

/// An agent that did not end well.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct AgentFailure {
    /// Its robot.
    pub robot: String,
    /// What happened (`exited with status 1`, `failed: the world is gone`).
    pub what: String,
}

impl std::fmt::Display for AgentFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "agent for {} {}", self.robot, self.what)
    }
}

/// Why finishing a run failed.
#[derive(Debug, thiserror::Error)]
pub enum FinishError {
    /// usage.json could not be written.
    #[error("writing {}", path.display())]
    Usage {
        /// The file.
        path: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// metrics.json could not be read (the world did not write it).
    #[error("reading {}", path.display())]
    ReadMetrics {
        /// The file.
        path: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// metrics.json is not JSON.
    #[error("parsing metrics.json")]
    ParseMetrics(#[source] serde_json::Error),
}

/// What [`finish`] is given: how the run's parts ended.
#[derive(Debug)]
pub struct Ending<'a> {
    /// The run folder.
    pub dir: &'a Path,
    /// The world process failed (then only the diagnostics are merged).
    pub world_failure: Option<WorldFailure>,
    /// Agents that ended badly.
    pub agent_failures: Vec<AgentFailure>,
    /// What the agents used and over which transport (`shm`, `inproc`), for
    /// usage.json; `None` writes none.
    pub usage: Option<(&'a str, &'a [AgentUsage])>,
    /// Draw plot.svg/png and replay.html.
    pub render: bool,
    /// metrics.json as the world that wrote it holds it, when it ran in
    /// this process (then it is not read back); `None`: read the file.
    pub metrics: Option<RunMetrics>,
}

/// The pictures (`render`) and run.mcap (`mcap`) of the run folder `dir`,
/// from one reading of it.
fn render(dir: &Path, render: bool, mcap: bool) -> Result<(), RenderError> {
    let run = mrsim_report::RunData::load(dir)?;
    if render {
        mrsim_report::write_plots(&run, dir)?;
        mrsim_report::write_replay(&run, dir)?;
    }
    if mcap {
        mrsim_report::write_mcap(&run, dir)?;
    }
    Ok(())
}

/// Does the run's scenario.json ask for run.mcap (`[output] mcap = true`)?
/// (Read here rather than handed down: every path to [`finish`] has the
/// folder, and the flag is all that is wanted of the file.)
fn wants_mcap(dir: &Path) -> bool {
    #[derive(serde::Deserialize)]
    struct Flags {
        #[serde(default)]
        mcap: bool,
    }
    #[derive(serde::Deserialize)]
    struct Folder {
        #[serde(default)]
        output: Option<Flags>,
    }
    std::fs::read_to_string(dir.join(mrsim_runfolder::SCENARIO_FILE))
        .ok()
        .and_then(|text| serde_json::from_str::<Folder>(&text).ok())
        .and_then(|f| f.output)
        .is_some_and(|o| o.mcap)
}

/// Finishes a run whose world and agents have all ended.
pub fn finish(end: Ending<'_>) -> Result<Outcome, FinishError> {
    let dir = end.dir.to_path_buf();
    // Every agent has ended: join their diagnostics into diagnostics.csv.
    let diagnostics = mrsim_agents::diagnostics::merge(&dir);
    let mut outcome = Outcome {
        dir,
        diagnostics,
        world_failure: end.world_failure,
        agent_failures: end.agent_failures,
        metrics: None,
        render_error: None,
    };
    if outcome.world_failure.is_some() {
        return Ok(outcome);
    }
    if let Some((transport, usage)) = end.usage {
        crate::usage::write_report(&outcome.dir, transport, usage).map_err(|source| {
            FinishError::Usage {
                path: outcome.dir.join(mrsim_runfolder::USAGE_FILE),
                source,
            }
        })?;
    }
    outcome.metrics = Some(match end.metrics {
        Some(m) => m,
        None => mrsim_runfolder::read_metrics(&outcome.dir).map_err(|e| match e {
            FileError::Io { path, source } => FinishError::ReadMetrics { path, source },
            FileError::Json { source, .. } => FinishError::ParseMetrics(source),
        })?,
    });
    let mcap = wants_mcap(&outcome.dir);
    if end.render || mcap {
        outcome.render_error = render(&outcome.dir, end.render, mcap).err();
    }
    Ok(outcome)
}
