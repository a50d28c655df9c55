//! The world process (`mrsim world`): started by the launcher, or by hand
//! with agents joining from other terminals.

use crate::error::{Invalid, Refusal};
use crate::finish::{Ending, FinishError, Outcome};
use crate::validate::Validated;
use mrsim_scenario::Scenario;
use mrsim_transport::shm::ShmWorld;
use mrsim_transport::zenoh::{ZenohOptions, ZenohWorld};
use mrsim_transport::{Capacity, Namespace, TransportError, WorldTransport};
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// How to run a world, beyond its scenario.
#[derive(Debug, Clone, Default)]
pub struct WorldRequest {
    /// The run id agents use to find this world.
    pub run_id: String,
    /// The output folder; `None`: a fresh folder under `runs/`.
    pub out: Option<PathBuf>,
    /// Give up if not every agent has joined after this long (`None`: wait
    /// forever).
    pub start_timeout: Option<Duration>,
    /// Started by the launcher, which claims the namespace and finishes the
    /// run; a world started by hand does both itself.
    pub launched: bool,
    /// Over Zenoh (where to listen, the config file) instead of iceoryx2.
    pub zenoh: Option<ZenohOptions>,
}

/// Why a world failed.
#[derive(Debug, thiserror::Error)]
pub enum WorldError {
    /// Refused before it started: the output folder, the run id, a run id
    /// in use.
    #[error(transparent)]
    Invalid(#[from] Invalid),
    /// The run's channels could not be created.
    #[error("cannot create run `{run_id}` (is another world using this run id?)")]
    Create {
        /// The run id.
        run_id: String,
        /// Why.
        #[source]
        source: TransportError,
    },
    /// The tick loop failed.
    #[error("world: {0}")]
    Run(mrsim_world::run::WorldRunError),
    /// The run ended but could not be finished.
    #[error(transparent)]
    Finish(#[from] FinishError),
}

impl Refusal for WorldError {
    fn refused(&self) -> Option<&Invalid> {
        match self {
            WorldError::Invalid(i) => Some(i),
            _ => None,
        }
    }
}

/// How a world ended.
#[derive(Debug)]
pub struct WorldOutcome {
    /// Stopped by a signal before its end (it wrote what it had).
    pub interrupted: bool,
    /// A world started by hand finishes its run itself (after waiting up
    /// to 3 s for its agents to exit): what that gave.
    pub finished: Option<Outcome>,
}

/// Runs a world over iceoryx2 (or Zenoh) until its end. A world started by hand calls
/// `on_open` with its run id and scenario once its channels are open (the
/// moment to tell the user how to start the agents).
pub fn serve(
    validated: Validated,
    req: &WorldRequest,
    on_open: &mut dyn FnMut(&str, &Scenario),
) -> Result<WorldOutcome, WorldError> {
    let dir = crate::out::prepare(req.out.as_deref(), &validated.scenario().name)?;
    // Absolute: the setup tells agents where to write their diagnostics.
    let dir = std::fs::canonicalize(&dir).unwrap_or(dir);
    let run_id = req.run_id.as_str();
    let ns = Namespace::new(run_id).map_err(|e| Invalid(e.to_string()))?;
    if !req.launched && req.zenoh.is_none() {
        // A world started by hand owns its namespace: clear what a crashed
        // earlier world of the same run id left behind.
        crate::namespace::claim(&ns)?;
    }
    // An agent process that drives a group of robots sends that many join
    // requests, ready commands and commands at once, and the world's
    // buffers for one process's must hold them all (else the surplus is
    // overwritten: robots that never join, lockstep ticks that wait out
    // the stall timeout). iceoryx2 fixes their size when the world makes
    // its services, before any join. A world its launcher started knows
    // the groups it starts: `robots_per_agent` robots per agent process,
    // and one ROS 2 agent for every robot with planner `ros2`. A world
    // started by hand does not know how its agents will be grouped: any
    // process may drive any number of its robots. Each join says its
    // process's group, and a group larger than the room is refused with
    // the reason rather than losing its commands.
    let launched = req.launched;
    let ros2_group = validated.ros2_robots().len();
    let external = validated.external_robots().len();
    let (scenario, world) = validated.into_world();
    let setup_len = serde_json::to_vec(&serde_json::json!({
        "run_id": run_id, "out_dir": dir, "scenario": scenario
    }))
    .map(|v| v.len())
    .unwrap_or(1 << 16);
    let bodies = scenario.body_count();
    let cap = if launched {
        capacity(
            scenario.robots.len(),
            scenario.world.robots_per_agent as usize,
            external,
            ros2_group,
        )
    } else {
        // Any grouping of all the robots, down to a process each.
        let robots = scenario.robots.len();
        Capacity {
            robots,
            group: robots.max(1),
            processes: robots,
        }
    };
    let create = |source| WorldError::Create {
        run_id: run_id.to_string(),
        source,
    };
    // Over Zenoh the world is kept by its type: what it refused goes into
    // metrics.json after the run.
    let (mut shm, mut zenoh) = (None, None);
    let link: &mut dyn WorldTransport = match &req.zenoh {
        None => shm.insert(ShmWorld::create(&ns, cap, bodies, setup_len).map_err(create)?),
        Some(z) => {
            zenoh.insert(ZenohWorld::create(&ns, z, cap, bodies, setup_len).map_err(create)?)
        }
    };
    if !req.launched {
        on_open(run_id, &scenario);
    }
    let opts = mrsim_world::RunOptions {
        out_dir: dir.clone(),
        run_id: run_id.to_string(),
        transport: if req.zenoh.is_some() { "zenoh" } else { "shm" }.to_string(),
        start_timeout: req.start_timeout,
        verbose: !req.launched || std::env::var_os("MRSIM_VERBOSE").is_some(),
        routes: crate::routes::of(&scenario),
        // Over Zenoh one inbox, sized from the robots, takes every
        // process's messages.
        group_room: req.zenoh.is_none().then_some(cap.commands_per_agent()),
    };
    let outcome = mrsim_world::run(world, link, opts);
    drop((shm, zenoh));
    let outcome = match outcome {
        Ok(outcome) => outcome,
        Err(e) => {
            if !req.launched {
                // A world started by hand cleans its namespace whatever the
                // ending (a launcher cleans its own world's): the agents
                // that joined were told the run is over, and nothing of it
                // may block the next world of this run id.
                std::thread::sleep(Duration::from_millis(300));
                ns.remove_leftovers();
            }
            return Err(WorldError::Run(e));
        }
    };
    let interrupted = outcome.metrics.interrupted;
    if req.launched {
        return Ok(WorldOutcome {
            interrupted,
            finished: None,
        });
    }
    std::thread::sleep(Duration::from_millis(300));
    ns.remove_leftovers();
    wait_for_agents(&outcome.metrics, Duration::from_secs(3));
    let finished = crate::finish::finish(Ending {
        dir: &dir,
        world_failure: None,
        agent_failures: Vec::new(),
        usage: None,
        render: true,
        metrics: Some(outcome.metrics),
    })?;
    Ok(WorldOutcome {
        interrupted,
        finished: Some(finished),
    })
}

/// Waits (at most `limit`) until the agent processes of a hand-started run
/// have ended, so that their diagnostics are complete.
fn wait_for_agents(metrics: &mrsim_world::metrics::RunMetrics, limit: Duration) {
    let start = Instant::now();
    let pids: Vec<u32> = metrics
        .robots
        .values()
        .filter_map(|r| r.agent_pid)
        .collect();
    while start.elapsed() < limit && pids.iter().any(|&p| mrsim_sys::process::pid_alive(p)) {
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// What the world's channels must hold for `robots` robots whose agents
/// `mrsim run` starts one per `per_agent` robots: the `external` robots'
/// agents are their users' programs (one process each at most) and the
/// `ros2` robots share one process, the ROS 2 agent, so neither is grouped.
/// An agent's buffers hold its whole group's messages (at least a ROS 2
/// agent's).
fn capacity(robots: usize, per_agent: usize, external: usize, ros2: usize) -> Capacity {
    let per_agent = per_agent.max(1);
    let grouped = robots.saturating_sub(external + ros2);
    Capacity {
        robots,
        group: per_agent.max(ros2).max(1),
        processes: grouped.div_ceil(per_agent) + external + usize::from(ros2 > 0),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_thousand_groups_of_a_hundred_robots_need_ports_for_a_thousand_agents() {
        let cap = capacity(100_000, 100, 0, 0);
        assert_eq!(cap.processes, 1000);
        assert_eq!(cap.agents(), 1000 + Capacity::SPARE);
        assert_eq!(cap.group, 100);
        // Commands still come one per robot.
        assert_eq!(cap.messages(), 100_000 + Capacity::SPARE);
    }

    #[test]
    fn one_robot_per_agent_needs_a_port_per_robot() {
        let cap = capacity(10_000, 1, 0, 0);
        assert_eq!(cap.agents(), 10_000 + Capacity::SPARE);
        assert_eq!(cap.group, 1);
    }

    #[test]
    fn the_last_group_takes_the_rest_and_is_a_process_of_its_own() {
        assert_eq!(capacity(10_001, 100, 0, 0).processes, 101);
        assert_eq!(capacity(99, 100, 0, 0).processes, 1);
    }

    #[test]
    fn external_robots_and_the_ros2_agent_are_processes_outside_the_groups() {
        // 3 external robots (a process each), 5 ROS 2 robots (one process),
        // 192 grouped by 64 (3 processes).
        let cap = capacity(200, 64, 3, 5);
        assert_eq!(cap.processes, 3 + 3 + 1);
        assert_eq!(cap.group, 64);
        // A ROS 2 agent larger than the groups sets the buffers' size.
        assert_eq!(capacity(200, 4, 0, 50).group, 50);
    }

    #[test]
    fn a_group_size_of_zero_is_taken_as_one() {
        let cap = capacity(10, 0, 0, 0);
        assert_eq!((cap.processes, cap.group), (10, 1));
    }
}
