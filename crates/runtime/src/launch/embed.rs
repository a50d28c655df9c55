//! The embedding API: a scenario run headless in the calling program, its
//! own planners among the built-in ones.

use super::prepare::{Prepared, check_memory, check_transport, write_source};
use super::{RunRequest, Transport};
use crate::error::{Invalid, Refusal};
use crate::finish::{AgentFailure, FinishError};
use crate::inproc::InprocError;
use crate::sched::Applied;
use crate::validate::{ScenarioSource, Validated};
use mrsim_transport::Namespace;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

/// A run in this process, headless: what a program that brings its own
/// planners asks for ([`run_in_process`]).
#[derive(Debug, Clone, Default)]
pub struct InProcess {
    /// The scenario file and its overrides.
    pub scenario: ScenarioSource,
    /// The planners the robots' names are looked up in: the built-in ones
    /// and the program's own ([`mrsim_planners::Registry::register`]).
    pub registry: Arc<mrsim_planners::Registry>,
    /// The output folder; `None`: a fresh folder under `runs/`.
    pub out: Option<PathBuf>,
    /// Draw plot.svg/png and replay.html at the end.
    pub render: bool,
    /// In lockstep: the longest one robot's answer may take before the run
    /// stops with [`InProcessError::Planner`] ([`RunRequest::plan_timeout`]).
    pub plan_timeout: Option<Duration>,
}

/// Why a run in this process failed: only what such a run can meet (it
/// starts no process).
#[derive(Debug, thiserror::Error)]
pub enum InProcessError {
    /// Refused before anything ran: the scenario (file, line, key), a
    /// robot's planner or its parameters, the output folder.
    #[error(transparent)]
    Invalid(#[from] Invalid),
    /// The run could not be carried out (its output files, its threads).
    #[error(transparent)]
    Run(#[from] InprocError),
    /// A robot's planner failed in a lockstep run (panicked, returned a
    /// non-finite command, or took longer than the plan timeout): the run
    /// stopped at that tick; the outputs so far are in `dir`.
    #[error("{failure}; the run stopped there, outputs so far are in {}", dir.display())]
    Planner {
        /// Which robot, which tick, how.
        failure: mrsim_agents::PlanFailure,
        /// The run folder.
        dir: PathBuf,
    },
    /// The run ended but could not be finished (usage.json, metrics.json,
    /// routes.csv).
    #[error(transparent)]
    Finish(#[from] FinishError),
}

impl Refusal for InProcessError {
    fn refused(&self) -> Option<&Invalid> {
        match self {
            InProcessError::Invalid(i) => Some(i),
            _ => None,
        }
    }
}

/// What a finished in-process run gives back.
#[derive(Debug, Clone)]
pub struct RunResult {
    /// The run folder (trajectory.csv, events.jsonl, metrics.json, ...).
    pub dir: PathBuf,
    /// metrics.json, typed.
    pub metrics: mrsim_runfolder::RunMetrics,
    /// Agents that ended badly while the world ran to its end.
    pub agent_failures: Vec<AgentFailure>,
}

/// Runs a scenario in this process (the world in the calling thread, the
/// robots' planners in a pool of threads, as `--transport inproc`), its
/// robots' planners built from `req.registry`. Unlike `mrsim run` it takes
/// no termination signals over (the calling program keeps its own) and
/// claims no shared memory. A refusal ([`InProcessError::Invalid`]) comes before
/// anything ran; a planner that fails in lockstep stops the run
/// ([`InProcessError::Planner`], the outputs so far written).
pub fn run_in_process(req: &InProcess) -> Result<RunResult, InProcessError> {
    let validated = Validated::with_registry(req.scenario.clone(), req.registry.clone())?;
    run_validated_in_process(validated, req.out.clone(), req.render, req.plan_timeout)
}

/// [`run_in_process`] of a scenario already validated.
pub(crate) fn run_validated_in_process(
    validated: Validated,
    out: Option<PathBuf>,
    render: bool,
    plan_timeout: Option<Duration>,
) -> Result<RunResult, InProcessError> {
    let request = RunRequest {
        out,
        transport: Transport::Inproc,
        render,
        plan_timeout,
        ..Default::default()
    };
    check_transport(&validated, request.transport)?;
    check_memory(&validated, request.transport)?;
    // Realtime under `[world.cpus]` is refused in process (no agent
    // process of its own per robot to take a policy).
    let cores = crate::cores::claim(
        validated.scenario(),
        validated.origin(),
        request.transport,
        &[],
    )?;
    let dir = crate::out::prepare(request.out.as_deref(), &validated.scenario().name)?;
    write_source(&dir, validated.source())?;
    let ns = Namespace::new(&Namespace::fresh_run_id()).map_err(|e| Invalid(e.to_string()))?;
    let prepared = Prepared {
        validated,
        request,
        dir,
        ns,
        applied: Applied::default(),
        cores,
    };
    let outcome = prepared.run_inproc(&mut |_| {})?;
    let metrics = outcome.metrics.ok_or_else(|| {
        InProcessError::Finish(FinishError::ReadMetrics {
            path: outcome.dir.join(mrsim_runfolder::METRICS_FILE),
            source: std::io::Error::other("the run wrote no metrics"),
        })
    })?;
    Ok(RunResult {
        dir: outcome.dir,
        metrics,
        agent_failures: outcome.agent_failures,
    })
}
