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

use crate::error::{Invalid, Refusal};
use crate::launch::{InProcessError, RunResult, run_validated_in_process};
use crate::validate::{ScenarioSource, Validated};
use mrsim_planners::Registry;
use mrsim_runfolder::timing::{Status, read_timing};
use mrsim_runfolder::{SCENARIO_FILE, SOURCE_FILE, SourceDoc, read_json};
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
    let rows = read_timing(dir).map_err(|e| not_a_run(&e))?;
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
    let validated = if req.set.is_empty() {
        same
    } else {
        Validated::with_registry(source(&req.set), req.registry.clone())?
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
    })
}
