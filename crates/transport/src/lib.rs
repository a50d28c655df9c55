//! The channels between the mrsim world and its agents.
//!
//! The world and the agents talk through two small traits,
//! [`WorldTransport`] and [`AgentTransport`], that carry only the plain wire
//! types of `mrsim-proto`. No iceoryx2 type crosses this interface, so the
//! agent loop and the world loop can be driven over shared memory between
//! processes ([`shm`]), over crossbeam channels between threads
//! ([`inproc`]), or (later) over a network transport, without change.
//!
//! Per tick the world publishes one snapshot (a header plus a slice of
//! bodies) and wakes the agents; each agent answers with one command and
//! wakes the world. At start-up an agent sends a join request naming its
//! robot and gets back a token it must put in every command; the world also
//! publishes the run's setup (the resolved scenario as JSON) once, kept for
//! late joiners.
#![warn(missing_docs)]

use mrsim_proto::{
    BodyState, CommandMsg, JoinReply, JoinRequest, RobotStats, SnapshotHeader, StatsHeader,
};
use std::time::Duration;

pub mod inproc;
pub mod namespace;
pub mod shm;

pub use namespace::{Namespace, NamespaceError};
pub use shm::doorbell;

/// What went wrong in a transport operation.
#[derive(Debug, thiserror::Error)]
pub enum TransportError {
    /// A channel or port could not be created or opened; `what` names it.
    #[error("cannot set up {what}: {detail}")]
    Setup {
        /// The channel or port.
        what: String,
        /// The underlying error.
        detail: String,
    },
    /// Sending a message failed.
    #[error("cannot send {what}: {detail}")]
    Send {
        /// What was being sent.
        what: &'static str,
        /// The underlying error.
        detail: String,
    },
    /// Receiving a message failed.
    #[error("cannot receive {what}: {detail}")]
    Receive {
        /// What was being received.
        what: &'static str,
        /// The underlying error.
        detail: String,
    },
    /// Waiting for a wake-up failed.
    #[error("cannot wait for a wake-up: {0}")]
    Wait(String),
    /// The other side is gone (in-process channels disconnected).
    #[error("the other side has disconnected")]
    Disconnected,
}

/// The world's side of the channels.
pub trait WorldTransport {
    /// Publishes the run's setup (the resolved scenario as JSON); kept for
    /// agents that join later.
    fn publish_setup(&mut self, setup: &[u8]) -> Result<(), TransportError>;
    /// Publishes one snapshot and wakes every agent.
    fn publish_snapshot(
        &mut self,
        header: &SnapshotHeader,
        bodies: &[BodyState],
    ) -> Result<(), TransportError>;
    /// Blocks until an agent wakes the world or `timeout` passes (may return
    /// early, spuriously: callers check the clock).
    fn wait(&mut self, timeout: Duration) -> Result<(), TransportError>;
    /// Called before each snapshot is published: `count` agents are to
    /// answer tick `tick`. A transport that can count the answers wakes the
    /// world once, when the last of them is in, instead of on every
    /// command; from the first call on, [`WorldTransport::wait`] may sleep
    /// through other wake-ups (join requests, ready commands) for a few
    /// milliseconds. The default wakes the world on every command.
    fn expect_answers(&mut self, _tick: u64, _count: usize) {}
    /// Hands every command received since the last call to `f`, with the
    /// time it was taken in (CLOCK_MONOTONIC ns).
    fn drain_commands(&mut self, f: &mut dyn FnMut(CommandMsg, u64)) -> Result<(), TransportError>;
    /// Hands every join request received since the last call to `f`.
    fn drain_joins(&mut self, f: &mut dyn FnMut(JoinRequest)) -> Result<(), TransportError>;
    /// Answers a join request. The agents may not hear of it before
    /// [`WorldTransport::joins_answered`].
    fn reply_join(&mut self, reply: &JoinReply) -> Result<(), TransportError>;
    /// Wakes the agents waiting for their join replies, once for all the
    /// replies sent since the last call (hundreds of agents joining at once
    /// must not each be woken once per reply).
    fn joins_answered(&mut self) -> Result<(), TransportError> {
        Ok(())
    }
    /// True once the process was asked to terminate (SIGINT, SIGTERM).
    fn termination_requested(&self) -> bool;
    /// Frees what dead agent processes left behind, so a restarted agent can
    /// join again. Cheap when nothing died.
    fn cleanup_dead(&mut self) {}
    /// Every agent is ready and the first tick is next: connect the tick's
    /// channels now, and let the agents take up their side, so that tick 0
    /// costs what any tick costs. Over iceoryx2 the snapshot publisher
    /// connected to its subscribers inside tick 0's send and each agent
    /// mapped its side at its first receive: at 256 agents ~7 ms, and up
    /// to a third of them missed tick 0.
    ///
    /// True if each agent then says so with a second ready command (the
    /// agents' loop sends one on every wake-up that brings no snapshot
    /// before its first, [`mrsim_proto::command_kind::READY`]), so the
    /// world can wait for all of them before tick 0: on two cores 256
    /// agents taking up their side at once can take longer than a tick.
    fn prepare_ticks(&mut self) -> Result<bool, TransportError> {
        Ok(false)
    }
    /// Publishes the run's live statistics for observers (a few times per
    /// second at most). Must not block; a transport without observers
    /// ignores it.
    fn publish_stats(
        &mut self,
        _header: &StatsHeader,
        _robots: &[RobotStats],
    ) -> Result<(), TransportError> {
        Ok(())
    }
}

/// An agent's side of the channels.
pub trait AgentTransport {
    /// Sends a join request.
    fn request_join(&mut self, req: &JoinRequest) -> Result<(), TransportError>;
    /// The reply to the request with this nonce, if it has arrived.
    fn poll_join_reply(&mut self, nonce: u64) -> Result<Option<JoinReply>, TransportError>;
    /// The run's setup, once the world has published it.
    fn setup(&mut self) -> Result<Option<Vec<u8>>, TransportError>;
    /// Blocks until the world wakes this agent or `timeout` passes (may
    /// return early, spuriously).
    fn wait(&mut self, timeout: Duration) -> Result<(), TransportError>;
    /// Copies the newest snapshot received since the last call into
    /// `header` and `bodies`; false if none arrived.
    fn latest_snapshot(
        &mut self,
        header: &mut SnapshotHeader,
        bodies: &mut Vec<BodyState>,
    ) -> Result<bool, TransportError>;
    /// Sends a command and wakes the world.
    fn send_command(&mut self, cmd: &CommandMsg) -> Result<(), TransportError>;
    /// False once the world is known to be gone.
    fn world_alive(&mut self) -> bool;
    /// True once the process was asked to terminate (SIGINT, SIGTERM).
    fn termination_requested(&self) -> bool;
    /// The agent has joined and read the setup: the ports used only to
    /// join may be closed (joining again then fails).
    fn joined(&mut self) {}
    /// Calls `f` once with the newest snapshot received since the last
    /// call, and a sender of commands (as [`send_command`]); false, without
    /// calling it, if none arrived. The default copies the snapshot into
    /// `scratch` first (with [`latest_snapshot`]); over shared memory
    /// [`shm::ShmAgent`] lends `f` the world's sample itself, which at 256
    /// robots saves each agent a 16 kB copy every tick.
    ///
    /// [`send_command`]: Self::send_command
    /// [`latest_snapshot`]: Self::latest_snapshot
    fn with_latest_snapshot(
        &mut self,
        scratch: &mut (SnapshotHeader, Vec<BodyState>),
        f: &mut SnapshotFn<'_>,
    ) -> Result<bool, TransportError> {
        let (header, bodies) = scratch;
        if !self.latest_snapshot(header, bodies)? {
            return Ok(false);
        }
        f(header, bodies, &mut |m| self.send_command(m));
        Ok(true)
    }
}

/// What [`AgentTransport::with_latest_snapshot`] calls: the snapshot's
/// header and bodies, and a sender of commands.
pub type SnapshotFn<'a> = dyn FnMut(&SnapshotHeader, &[BodyState], &mut SendFn<'_>) + 'a;

/// Sends one command (and wakes the world).
pub type SendFn<'a> = dyn FnMut(&CommandMsg) -> Result<(), TransportError> + 'a;

/// A read-only observer of a running world (`mrsim top`, the launcher's
/// progress bar): it reads the setup, the snapshots and the live
/// statistics, never joins, never sends, and never wakes the world, so it
/// cannot slow it down or count as an agent.
pub trait ObserverTransport {
    /// The run's setup (the resolved scenario as JSON), once available.
    fn setup(&mut self) -> Result<Option<Vec<u8>>, TransportError>;
    /// Copies the newest snapshot received since the last call into
    /// `header` and `bodies`; false if none arrived.
    fn latest_snapshot(
        &mut self,
        header: &mut SnapshotHeader,
        bodies: &mut Vec<BodyState>,
    ) -> Result<bool, TransportError>;
    /// Copies the newest statistics received since the last call into
    /// `header` and `robots`; false if none arrived.
    fn latest_stats(
        &mut self,
        header: &mut StatsHeader,
        robots: &mut Vec<RobotStats>,
    ) -> Result<bool, TransportError>;
    /// False once the world is known to be gone.
    fn world_alive(&mut self) -> bool;
}

/// How many participants the channels must hold.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Capacity {
    /// Robots in the scenario (one agent each).
    pub robots: usize,
}

impl Capacity {
    /// Room for strangers, restarted agents and observers beyond the robots.
    pub const SPARE: usize = 16;

    /// Maximum number of agent-side ports of one kind.
    pub fn agents(&self) -> usize {
        self.robots + Self::SPARE
    }
}
