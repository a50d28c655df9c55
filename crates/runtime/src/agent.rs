//! One agent process (`mrsim agent`), over iceoryx2: one robot, or a group
//! of robots driven from one process (`--robots a0,a1,...`).

use crate::error::{Invalid, Refusal};
use crate::usage::{Metered, Scope};
use mrsim_transport::shm::ShmAgent;
use mrsim_transport::zenoh::{ZenohAgent, ZenohOptions};
use mrsim_transport::{AgentTransport, Namespace, TransportError};
use std::path::PathBuf;
use std::time::Duration;

/// Deliberate misbehaviour of an agent, for fault-injection tests.
#[derive(Debug, Clone, Copy, Default)]
pub struct Misbehave {
    /// Put this robot id in every command.
    pub impersonate: Option<u32>,
    /// Misbehave this way.
    pub fault: Option<mrsim_agents::fault::Fault>,
    /// Announce this protocol version.
    pub protocol_version: Option<u32>,
}

/// How long an agent over Zenoh that lost its world keeps trying to reach
/// it again ([`AgentRequest::reconnect`]) unless asked otherwise.
pub const RECONNECT: Duration = Duration::from_secs(30);

/// Which robots of which run, and how.
#[derive(Debug, Clone, Default)]
pub struct AgentRequest {
    /// The robots' names in the scenario (one, or a group).
    pub robots: Vec<String>,
    /// The run id of the world.
    pub run_id: String,
    /// How long to wait for the world and for the join.
    pub timeout: Duration,
    /// Fault injection.
    pub misbehave: Misbehave,
    /// Write what the agent used (CPU while the run ticked, peak RSS) here
    /// at the end.
    pub usage_out: Option<PathBuf>,
    /// Over Zenoh (where the world is, the config file) instead of iceoryx2.
    pub zenoh: Option<ZenohOptions>,
    /// Over Zenoh: how long an agent that lost its world (a link cut, the
    /// world's liveliness gone) keeps trying to reach it again and rejoin,
    /// with a new token, before it ends with "the world is gone". Zero:
    /// it ends at once. (Over shared memory the world is on this machine:
    /// gone is gone.)
    pub reconnect: Duration,
}

/// Why an agent failed.
#[derive(Debug, thiserror::Error)]
pub enum AgentError {
    /// The run id is not a valid namespace.
    #[error(transparent)]
    Invalid(#[from] Invalid),
    /// The world of the run was not found in time.
    #[error("agent {robot}: cannot reach the world of run `{run_id}`")]
    Connect {
        /// The robot.
        robot: String,
        /// The run id.
        run_id: String,
        /// Why.
        #[source]
        source: TransportError,
    },
    /// The agent joined (or tried to) and failed: refused, the world gone,
    /// a transport error.
    #[error("agent {robot}: {error}")]
    Run {
        /// The robot.
        robot: String,
        /// Why.
        error: mrsim_agents::AgentError,
    },
}

impl Refusal for AgentError {
    fn refused(&self) -> Option<&Invalid> {
        match self {
            AgentError::Invalid(i) => Some(i),
            _ => None,
        }
    }
}

/// How an agent ended.
#[derive(Debug)]
pub struct AgentEnd {
    /// Its run.
    pub result: Result<(), AgentError>,
    /// [`AgentRequest::usage_out`] could not be written (the run itself is
    /// not affected).
    pub usage_error: Option<std::io::Error>,
}

/// Connects to the world of the run, joins as the robot and drives it to
/// the end.
pub fn run(req: &AgentRequest) -> AgentEnd {
    let fail = |e: AgentError| AgentEnd {
        result: Err(e),
        usage_error: None,
    };
    let ns = match Namespace::new(&req.run_id) {
        Ok(ns) => ns,
        Err(e) => return fail(Invalid(e.to_string()).into()),
    };
    let robot = mrsim_world::names::first_few(&req.robots, 3);
    let node_name = match req.robots.as_slice() {
        [one] => format!("mrsim-agent-{one}"),
        [first, ..] => format!("mrsim-agent-{first}-{}", req.robots.len()),
        [] => "mrsim-agent".to_string(),
    };
    let connect = |timeout: Duration| -> Result<Box<dyn AgentTransport>, TransportError> {
        match &req.zenoh {
            None => ShmAgent::connect(&ns, &node_name, timeout).map(|a| Box::new(a) as _),
            Some(z) => ZenohAgent::connect(&ns, z, timeout).map(|a| Box::new(a) as _),
        }
    };
    let mut link = match connect(req.timeout) {
        Ok(l) => l,
        Err(source) => {
            return fail(AgentError::Connect {
                robot: robot.clone(),
                run_id: req.run_id.clone(),
                source,
            });
        }
    };
    let opts: Vec<_> = req
        .robots
        .iter()
        .map(|r| {
            let mut opts = mrsim_agents::AgentOptions::new(r);
            opts.join_timeout = req.timeout;
            opts.impersonate = req.misbehave.impersonate;
            opts.fault = req.misbehave.fault;
            if let Some(v) = req.misbehave.protocol_version {
                opts.protocol_version = v;
            }
            opts
        })
        .collect();
    let mut metered = Metered::new(link.as_mut(), Scope::Process);
    let mut result = mrsim_agents::run_group(&mut metered, &opts);
    let mut usage = metered.usage();
    // Over Zenoh a lost world may be a cut link: reach it again within the
    // window and rejoin (each robot with a new token, as a restarted agent).
    let window = if req.zenoh.is_some() {
        req.reconnect
    } else {
        Duration::ZERO
    };
    while matches!(result, Err(mrsim_agents::AgentError::WorldGone)) && !window.is_zero() {
        eprintln!(
            "agent {robot}: the world is gone; trying to reach it again for {:.0} s",
            window.as_secs_f64()
        );
        drop(link);
        link = match connect(window) {
            Ok(l) => l,
            Err(_) => break,
        };
        let mut metered = Metered::new(link.as_mut(), Scope::Process);
        let again = mrsim_agents::run_group(&mut metered, &opts);
        usage = metered.usage();
        match again {
            // Not reached in time (no world of this run answers a join):
            // the world is gone after all.
            Err(
                mrsim_agents::AgentError::Timeout { .. } | mrsim_agents::AgentError::NoWorld { .. },
            ) => {
                break;
            }
            other => {
                eprintln!("agent {robot}: rejoined its world");
                result = other;
            }
        }
    }
    let usage_error = req
        .usage_out
        .as_ref()
        .and_then(|path| crate::usage::write_agent(path, &usage).err());
    AgentEnd {
        result: result
            .map(|_| ())
            .map_err(|error| AgentError::Run { robot, error }),
        usage_error,
    }
}
