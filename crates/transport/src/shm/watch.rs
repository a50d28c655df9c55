//! Whether the run's world process is alive, as an agent or an observer
//! sees it: one scan of the run's iceoryx2 nodes, then its process id.

use super::service::{S, WORLD_NODE, config, setup_err};
use crate::{Namespace, TransportError};
use iceoryx2::prelude::*;
use std::time::{Duration, Instant};

/// Whether a live world process holds run `ns` (its iceoryx2 node is
/// listed alive). A crashed world's node is listed dead, so this is false
/// for a run that only left stale shared memory behind.
pub fn world_running(ns: &Namespace) -> Result<bool, TransportError> {
    world_node_alive(&config(ns)?).ok_or_else(|| setup_err("node list", "cannot list nodes"))
}

/// Some(alive) if the node list could be read.
fn world_node_alive(cfg: &Config) -> Option<bool> {
    find_world(cfg).map(|w| w != WorldSeen::Gone)
}

/// What a scan of the run's iceoryx2 nodes says about the world.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum WorldSeen {
    /// Listed alive, owned by this process id.
    Alive(u32),
    /// A node whose state cannot be read (being created or cleaned up
    /// right now) may be the world: not proof that it is gone.
    Unsure,
    /// No live world node.
    Gone,
}

/// Scans the run's nodes for the world's (a directory walk over every
/// node of the run: with hundreds of agents, do it once and then watch the
/// process id, see [`WorldWatch`]).
fn find_world(cfg: &Config) -> Option<WorldSeen> {
    let mut seen = WorldSeen::Gone;
    let listed = Node::<S>::list(cfg, |state| {
        use iceoryx2::node::NodeView;
        match &state {
            NodeState::Alive(view) => match view.details() {
                Some(d) if d.name().as_str() == WORLD_NODE => {
                    seen = WorldSeen::Alive(d.process_id().value() as u32);
                    CallbackProgression::Stop
                }
                _ => CallbackProgression::Continue,
            },
            NodeState::Inaccessible(_) | NodeState::Undefined(_) => {
                seen = WorldSeen::Unsure;
                CallbackProgression::Continue
            }
            _ => CallbackProgression::Continue,
        }
    });
    listed.ok().map(|_| seen)
}

/// An agent's or observer's watch on the world process. An agent learns
/// the world's process id from its join reply; an observer finds it with
/// one scan of the run's node list. After that only the process id is
/// checked (one `kill(pid, 0)`): with hundreds of agents checking a few
/// times a second, a node-list scan each is O(agents²) file reads per
/// second, taken from the very world they are waiting for.
#[derive(Debug)]
pub(super) struct WorldWatch {
    /// The world's process id, once known (an agent learns it from its
    /// join reply).
    pub(super) pid: Option<u32>,
    last_check: Instant,
    missing: u32,
    alive: bool,
}

impl WorldWatch {
    pub(super) fn new() -> Self {
        Self {
            pid: None,
            last_check: Instant::now(),
            missing: 0,
            alive: true,
        }
    }

    /// False once the world is known to be gone: two checks `every` apart
    /// both said so.
    pub(super) fn alive(&mut self, cfg: &Config, every: Duration) -> bool {
        if !self.alive || self.last_check.elapsed() < every {
            return self.alive;
        }
        self.last_check = Instant::now();
        let seen = match self.pid {
            Some(pid) if mrsim_sys::process::pid_alive(pid) => WorldSeen::Alive(pid),
            Some(_) => WorldSeen::Gone,
            None => find_world(cfg).unwrap_or(WorldSeen::Unsure),
        };
        match seen {
            WorldSeen::Alive(pid) => {
                self.pid = Some(pid);
                self.missing = 0;
            }
            WorldSeen::Unsure => self.missing = 0,
            WorldSeen::Gone => {
                self.missing += 1;
                self.alive = self.missing < 2;
            }
        }
        self.alive
    }
}
