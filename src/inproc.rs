//! Runs with the in-process transport: the world loop in the calling thread
//! and one thread per agent, over `mrsim_transport::inproc` (crossbeam
//! channels). The same world loop, agent loop and planners as a run over
//! iceoryx2, without processes: the fast path for large headless
//! experiments and the lower bound for the IPC cost.

use crate::usage::{AgentUsage, Metered, Scope};
use mrsim_scenario::Scenario;
use mrsim_world::metrics::RunMetrics;
use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::time::Duration;

/// Why an in-process run failed.
#[derive(Debug, thiserror::Error)]
pub enum InprocError {
    /// The world could not be built from the scenario.
    #[error("{0}")]
    World(#[from] mrsim_world::WorldError),
    /// The world loop failed.
    #[error("world: {0}")]
    Run(#[from] mrsim_world::run::RunError),
    /// An agent thread could not be started.
    #[error("cannot start the agent thread for {robot}: {source}")]
    Spawn {
        /// The robot.
        robot: String,
        /// Why.
        source: std::io::Error,
    },
}

/// What an in-process run gives back.
#[derive(Debug, Clone)]
pub struct InprocOutcome {
    /// metrics.json.
    pub metrics: RunMetrics,
    /// Per robot (scenario order): the agent's error, if it ended with one.
    pub agent_errors: Vec<Option<String>>,
    /// Per robot: CPU time of its thread while the run ticked (the peak RSS
    /// is the whole process's).
    pub agent_usage: Vec<AgentUsage>,
}

/// Runs `scenario` with the world in this thread and one thread per agent,
/// writing the outputs (trajectory.csv, events.jsonl, metrics.json,
/// scenario.json) into `out_dir`, which must exist. `stop` ends the run
/// early (the role SIGTERM plays for processes).
pub fn run_scenario(
    scenario: &Scenario,
    out_dir: &Path,
    run_id: &str,
    stop: Arc<AtomicBool>,
) -> Result<InprocOutcome, InprocError> {
    let world = mrsim_world::World::new(scenario)?;
    let n = scenario.robots.len();
    let (mut link, sides) = mrsim_transport::inproc::channels(n, stop);
    let mut handles = Vec::with_capacity(n);
    for (robot, mut side) in scenario.robots.iter().zip(sides) {
        let opts = mrsim_agents::AgentOptions::new(&robot.name);
        let handle = std::thread::Builder::new()
            .name(format!("agent-{}", robot.name))
            // Planners keep little on the stack; 1000 agents fit easily.
            .stack_size(512 * 1024)
            .spawn(move || {
                let mut metered = Metered::new(&mut side, Scope::Thread);
                let result = mrsim_agents::run(&mut metered, &opts);
                let usage = metered.usage();
                (result.err().map(|e| e.to_string()), usage)
            })
            .map_err(|source| InprocError::Spawn {
                robot: robot.name.clone(),
                source,
            })?;
        handles.push(handle);
    }
    let opts = mrsim_world::RunOptions {
        out_dir: out_dir.to_path_buf(),
        run_id: run_id.to_string(),
        transport: "inproc".to_string(),
        start_timeout: Some(Duration::from_secs(60)),
        verbose: std::env::var_os("MRSIM_VERBOSE").is_some(),
    };
    let outcome = mrsim_world::run(world, &mut link, opts);
    // Dropping the world's side disconnects the channels: an agent still
    // waiting sees the world gone and ends.
    drop(link);
    let mut agent_errors = Vec::with_capacity(n);
    let mut agent_usage = Vec::with_capacity(n);
    for h in handles {
        match h.join() {
            Ok((err, usage)) => {
                agent_errors.push(err);
                agent_usage.push(usage);
            }
            Err(_) => {
                agent_errors.push(Some("the agent thread panicked".to_string()));
                agent_usage.push(AgentUsage::default());
            }
        }
    }
    Ok(InprocOutcome {
        metrics: outcome?.metrics,
        agent_errors,
        agent_usage,
    })
}
