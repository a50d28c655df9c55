//! What a run asks of each process it starts, in the runtime's own request
//! types, and the caller's [`Starter`] that turns it into a command.
//!
//! The runtime knows what the world, an agent and the ROS 2 agent are to
//! do; only the program that starts the run knows how its executable is
//! asked for that (the `mrsim` command line spells its own flags, and
//! parses them back into these same types in the started process).

use crate::agent::AgentRequest;
use crate::ros2::Ros2Request;
use crate::validate::ScenarioSource;
use crate::world::WorldRequest;

/// A process of a run started as processes.
#[derive(Debug, Clone)]
pub enum ProcessSpec {
    /// The world.
    World {
        /// The scenario file and its overrides (the world validates its
        /// own copy).
        scenario: ScenarioSource,
        /// How to run it.
        request: WorldRequest,
    },
    /// The agent of one robot or of a group of robots.
    Agent(AgentRequest),
    /// The ROS 2 agent of the robots with planner `ros2`.
    Ros2(Ros2Request),
}

/// Builds the command that starts a process of a run (its program and
/// arguments; the runtime sets stdin and spawns it).
pub trait Starter {
    /// The command for `spec`; an error when the program cannot be found.
    fn command(&self, spec: &ProcessSpec) -> std::io::Result<std::process::Command>;
}
