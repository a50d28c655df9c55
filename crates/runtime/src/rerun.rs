//! `mrsim rerun`: a run again, in lockstep, with the timing it recorded.
//!
//! A run folder holds how its scenario was given (source.json), the
//! scenario as it ran (scenario.json) and what timing decided for every
//! planner call (timing.csv: the snapshot it read, when its command was
//! sent, accepted, late or lost). The rerun loads the same scenario, forced
//! to lockstep, and has every robot's planner read exactly the recorded
//! snapshots and every command sent exactly when recorded (the world
//! judges and applies them as it did), so a realtime run's trajectory comes
//! out byte for byte. With overrides it is a counterfactual: the same
//! timing, another planner or parameter; it can differ from the recorded
//! run only from the first tick the change can act on; with another
//! `[world.cpus]` (`--set world.cpus.scheduler=deadline`, another count)
//! the robots whose compute is CPU work are timed by the model of the
//! cores instead of the record, a modelled counterfactual
//! ([`Rerunning::modelled`] names them). Planners that are
//! not built in (a program's own, a Python planner) may hold their own
//! random state: the rerun names them as the reason a replay may differ.
//!
//! A run that was cut (its world killed: no metrics.json, or a file with a
//! torn last row) is rerun up to its last tick the trajectory holds whole
//! (the files are flushed together, the trajectory last, so timing.csv
//! holds every call before it), byte for byte for those ticks:
//! [`Rerunning::cut`] says where and why.

use crate::error::{Invalid, Refusal};
use crate::launch::{InProcessError, RunResult, run_validated_in_process};
use crate::validate::{ScenarioSource, Validated};
use mrsim_planners::Registry;
use mrsim_runfolder::stream::{Cut, read_whole_rows};
use mrsim_runfolder::timing::{Status, read_timing};
use mrsim_runfolder::trajectory::read_parquet_trajectory;
use mrsim_runfolder::{
    METRICS_FILE, SCENARIO_FILE, SOURCE_FILE, SourceDoc, TRAJECTORY_FILE, TRAJECTORY_JOURNAL_FILE,
    TRAJECTORY_PARQUET_FILE, read_json,
};
use mrsim_scenario::timing::{CallStatus, RecordedCall};
use mrsim_scenario::{Mode, Scenario};
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::Arc;

/// A rerun of a recorded run.
#[derive(Debug, Clone, Default)]
pub struct Rerun {
    /// The recorded run's folder.
    pub run: PathBuf,
    /// The rerun's folder; `None`: a fresh folder under `runs/`.
    pub out: Option<PathBuf>,
    /// Overrides on top of the recorded run's (a counterfactual).
    pub set: Vec<String>,
    /// The planners the robots' names are looked up in.
    pub registry: Arc<Registry>,
    /// Draw plot.svg/png and replay.html at the end.
    pub render: bool,
}

/// What a rerun gives back.
#[derive(Debug, Clone)]
pub struct Rerunning {
    /// The rerun, as any in-process run.
    pub result: RunResult,
    /// Robots whose planner is not built in (`robot`, `planner`): not known
    /// to be deterministic, the reason a replay may differ.
    pub not_deterministic: Vec<(String, String)>,
    /// Robots whose timing the model of the cores re-decides instead of
    /// the record (a counterfactual with another `[world.cpus]`: the robots
    /// whose compute is CPU work); empty when every robot replays its
    /// recorded times.
    pub modelled: Vec<String>,
    /// The recorded run was cut: the rerun stopped at its last whole tick.
    pub cut: Option<RerunCut>,
}

/// Where a cut run's rerun stopped, and why it was cut.
#[derive(Debug, Clone, PartialEq)]
pub struct RerunCut {
    /// The last tick the rerun ran to (the recorded trajectory's last whole
    /// tick; the last tick timing.csv names when the run kept no
    /// trajectory).
    pub tick: u64,
    /// The files that end at the cut (a torn last row, a Parquet file
    /// without its footer); empty when only metrics.json is missing.
    pub files: Vec<Cut>,
}

/// Why a rerun did not happen or failed.
#[derive(Debug, thiserror::Error)]
pub enum RerunError {
    /// The folder is not a rerunnable run's, or the scenario or overrides
    /// are refused (nothing ran).
    #[error(transparent)]
    Invalid(#[from] Invalid),
    /// The rerun itself failed.
    #[error(transparent)]
    Run(#[from] InProcessError),
}

impl Refusal for RerunError {
    fn refused(&self) -> Option<&Invalid> {
        match self {
            RerunError::Invalid(i) => Some(i),
            RerunError::Run(e) => e.refused(),
        }
    }
}

/// Reruns `req.run` in lockstep with its recorded timing.
pub fn rerun(req: &Rerun) -> Result<Rerunning, RerunError> {
    let dir = &req.run;
    let not_a_run =
        |e: &dyn std::fmt::Display| Invalid(format!("cannot rerun {}: {e}", dir.display()));
    let doc: SourceDoc = read_json(dir, SOURCE_FILE).map_err(|e| not_a_run(&e))?;
    let recorded: Scenario = read_json(dir, SCENARIO_FILE).map_err(|e| not_a_run(&e))?;
    let timing = read_timing(dir).map_err(|e| not_a_run(&e))?;
    let cut = cut_of(dir, &recorded, &timing).map_err(|e| not_a_run(&e))?;
    let rows = timing.rows;
    let source = |extra: &[String]| ScenarioSource {
        path: doc.file.clone(),
        set: doc.set.iter().chain(extra).cloned().collect(),
        mode: Some(Mode::Lockstep),
    };
    // The file must still say what it said when the run was made.
    let same = Validated::with_registry(source(&[]), req.registry.clone())?;
    let mut expected = recorded.clone();
    expected.world.mode = Mode::Lockstep;
    if same.scenario() != &expected {
        return Err(Invalid(format!(
            "cannot rerun {}: {} no longer gives the scenario the run recorded in its {SCENARIO_FILE}",
            dir.display(),
            same.origin()
        ))
        .into());
    }
    let mut set = req.set.clone();
    if let Some(c) = &cut {
        if c.tick == 0 {
            return Err(Invalid(format!(
                "cannot rerun {}: the run was cut before any tick after tick 0 reached its trajectory",
                dir.display()
            ))
            .into());
        }
        // The run ends at the cut: max_ticks = duration / dt, rounded.
        set.push(format!(
            "world.duration={:?}",
            c.tick as f64 * recorded.world.dt
        ));
    }
    let validated = if set.is_empty() {
        same
    } else {
        Validated::with_registry(source(&set), req.registry.clone())?
    };
    let mut calls: BTreeMap<String, Vec<RecordedCall>> = BTreeMap::new();
    for r in rows {
        calls.entry(r.robot).or_default().push(RecordedCall {
            tick: r.tick,
            sent_ns: r.sent_ns,
            status: match r.status {
                Status::Accepted => CallStatus::Accepted,
                Status::Late => CallStatus::Late,
                Status::Lost => CallStatus::Lost,
            },
            cpu_ns: r.cpu_ns,
        });
    }
    let not_deterministic = validated
        .robots_with_own_planners()
        .into_iter()
        .filter_map(|name| {
            let r = validated
                .scenario()
                .robots
                .iter()
                .find(|r| r.name == name)?;
            Some((name.to_string(), r.planner.clone()))
        })
        .collect();
    // Another `[world.cpus]` (scheduler, count, the world's CPU): the
    // recorded times were those of the old cores, so the model decides
    // anew for the robots whose compute is CPU work.
    let cores = &validated.scenario().world.cpus;
    let modelled: Vec<String> = if cores.is_some() && *cores != recorded.world.cpus {
        validated
            .scenario()
            .robots
            .iter()
            .filter(|r| r.timing.as_ref().is_some_and(|t| t.cpu))
            .map(|r| r.name.clone())
            .collect()
    } else {
        Vec::new()
    };
    let validated = validated.with_replay_except(calls, &modelled)?;
    let result = run_validated_in_process(validated, req.out.clone(), req.render, None)?;
    Ok(Rerunning {
        result,
        not_deterministic,
        modelled,
        cut,
    })
}

/// Whether the run in `dir` was cut and where its rerun must stop: `None`
/// for a run that ended (metrics.json written, no torn file).
fn cut_of(
    dir: &std::path::Path,
    recorded: &Scenario,
    timing: &mrsim_runfolder::timing::Timing,
) -> Result<Option<RerunCut>, String> {
    let mut files: Vec<Cut> = timing.cut.iter().cloned().collect();
    let last_timing_tick = timing.rows.iter().map(|r| r.tick).max();
    let csv = |path: &std::path::Path, files: &mut Vec<Cut>| -> Result<Option<u64>, String> {
        let Some((text, torn)) =
            read_whole_rows(path).map_err(|e| format!("{}: {e}", path.display()))?
        else {
            return Ok(None);
        };
        files.extend(torn);
        mrsim_runfolder::csv::last_whole_tick(&text)
            .map_err(|e| format!("{}:{}: {}", path.display(), e.line, e.reason))
    };
    let last_tick = match recorded.output.trajectory {
        mrsim_scenario::TrajectoryFormat::Csv => csv(&dir.join(TRAJECTORY_FILE), &mut files)?,
        mrsim_scenario::TrajectoryFormat::Parquet => {
            let parquet = dir.join(TRAJECTORY_PARQUET_FILE);
            match read_parquet_trajectory(&parquet) {
                Ok(table) => table.rows().last().map(|r| r.tick),
                Err(_) => {
                    let t = csv(&dir.join(TRAJECTORY_JOURNAL_FILE), &mut files)?;
                    files.push(Cut {
                        path: parquet,
                        line: 0,
                        detail: format!(
                            "no Parquet footer; read its journal {TRAJECTORY_JOURNAL_FILE}"
                        ),
                    });
                    t
                }
            }
        }
        mrsim_scenario::TrajectoryFormat::None => last_timing_tick,
    };
    if files.is_empty() && dir.join(METRICS_FILE).exists() {
        return Ok(None);
    }
    Ok(Some(RerunCut {
        tick: last_tick.unwrap_or(0),
        files,
    }))
}
