//! The channels between the mrsim world and its agents.
//!
//! # Shape
//!
//! The world and the agents talk through two small traits, defined here:
//! [`WorldTransport`] (the world's side) and [`AgentTransport`] (one
//! agent's side), with [`ObserverTransport`] for read-only watchers
//! (`mrsim top`, the launcher's progress bar). They carry only the plain
//! wire types of `mrsim-proto`; no iceoryx2 or crossbeam type crosses
//! them, so the world loop and the agent loop are written once and run
//! over either transport, or a later one (a network), without change.
//!
//! Each transport is a folder with one module per side, so that what one
//! side does can be read without the others:
//!
//! - [`shm`]: iceoryx2 shared memory between processes, the transport of
//!   a real run. `shm::world` ([`shm::ShmWorld`]), `shm::agent`
//!   ([`shm::ShmAgent`]), `shm::observer` ([`shm::ShmObserver`]), and what
//!   they share: the run's services and nodes (`shm::service`), the watch
//!   on the world process (`shm::watch`) and the futex page that rings
//!   each tick ([`shm::doorbell`]).
//! - [`inproc`]: crossbeam channels between threads of one process, the
//!   fast path for large headless runs and the lower bound for the IPC
//!   cost. `inproc::world`, `inproc::agent`, and the pool's
//!   `inproc::worker`.
//! - [`zenoh`]: Zenoh sessions over TCP (or TLS), for agents on other
//!   machines. `zenoh::world`, `zenoh::agent`, `zenoh::observer`, the
//!   run's keys (`zenoh::keys`) and the bytes on the wire (`zenoh::wire`).
//!
//! # The protocol
//!
//! Per tick the world publishes one snapshot (a header plus a slice of
//! bodies) and wakes the agents; each agent answers with one command and
//! wakes the world. At start-up an agent sends a join request naming its
//! robot and gets back a token it must put in every command; the world
//! also publishes the run's setup (the resolved scenario as JSON) once,
//! kept for late joiners. The wire types and the protocol version are in
//! `mrsim-proto`.
//!
//! # The one exception: the in-process pool
//!
//! Every agent joins through [`AgentTransport`]. In a run with
//! [`inproc::pooled_channels`] (what `mrsim run --transport inproc` uses),
//! the agents' loop then no longer goes through it: the joined agents are
//! handed to a pool, and a few [`inproc::InprocWorker`]s receive each
//! snapshot once (its bodies shared, not copied) and send the commands of
//! many agents as one message; in lockstep the world's own thread plans
//! for a share of them inside [`WorldTransport::wait`]
//! ([`inproc::InprocWorld::help_with`]). What this bypasses is
//! [`AgentTransport::wait`], [`AgentTransport::with_latest_snapshot`] and
//! [`AgentTransport::send_command`] per agent per tick; what it saves is
//! two thread wake-ups (context switches) per agent per tick, the cost
//! that bounds a thread-per-agent run at many robots. The world side is
//! unchanged: it still sees one [`WorldTransport`] and one command per
//! robot. Nothing else goes around the traits. See [`inproc`] for the
//! details.
#![warn(missing_docs)]

use mrsim_proto::{
    BodyState, CommandMsg, JoinReply, JoinRequest, RobotStats, SnapshotHeader, StatsHeader,
};
use std::time::Duration;

pub mod inproc;
pub mod namespace;
pub mod shm;
#[cfg(test)]
mod test_support;
pub mod zenoh;

pub use namespace::{Namespace, NamespaceError};

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
///
/// The world loop (`mrsim_world::run`) is the only caller. Its order, per
/// run: [`publish_setup`](Self::publish_setup) once; then, while agents
/// join, rounds of [`wait`](Self::wait), [`drain_joins`](Self::drain_joins)
/// (each answered with [`reply_join`](Self::reply_join), the batch closed
/// with [`joins_answered`](Self::joins_answered)) and
/// [`drain_commands`](Self::drain_commands) (the ready commands); once all
/// are ready, [`prepare_ticks`](Self::prepare_ticks); then per tick
/// [`expect_answers`](Self::expect_answers),
/// [`publish_snapshot`](Self::publish_snapshot), and rounds of `wait` and
/// `drain_joins`/`drain_commands` until the tick's commands are in or its
/// deadline passes. [`publish_stats`](Self::publish_stats),
/// [`cleanup_dead`](Self::cleanup_dead) and
/// [`termination_requested`](Self::termination_requested) come at any
/// time.
///
/// Every method is required: the last five (from `expect_answers` on) are
/// where a transport makes the loop cheap at hundreds of agents, and each
/// transport says what it does there, even when that is nothing.
pub trait WorldTransport {
    /// Publishes the run's setup (the resolved scenario as JSON), once,
    /// before any join is answered; it must stay readable for agents that
    /// join later ([`AgentTransport::setup`]).
    fn publish_setup(&mut self, setup: &[u8]) -> Result<(), TransportError>;
    /// Publishes one snapshot and wakes every agent (or whatever answers
    /// for them). Called once per tick, and twice at the end with
    /// `finished` set. An agent that has not read the previous snapshot
    /// yet sees only the newest.
    fn publish_snapshot(
        &mut self,
        header: &SnapshotHeader,
        bodies: &[BodyState],
    ) -> Result<(), TransportError>;
    /// Blocks until an agent wakes the world or `timeout` passes. May
    /// return early, spuriously: callers drain and check the clock. Must
    /// return within about `timeout` (the world keeps its tick deadlines
    /// with it).
    fn wait(&mut self, timeout: Duration) -> Result<(), TransportError>;
    /// Hands every command received since the last call to `f`, with the
    /// time it was taken in (CLOCK_MONOTONIC ns), in the order received.
    fn drain_commands(&mut self, f: &mut dyn FnMut(CommandMsg, u64)) -> Result<(), TransportError>;
    /// Hands every join request received since the last call to `f`.
    fn drain_joins(&mut self, f: &mut dyn FnMut(JoinRequest)) -> Result<(), TransportError>;
    /// Sends the answer to one join request (matched by its nonce). The
    /// agents need not hear of it before
    /// [`joins_answered`](Self::joins_answered).
    fn reply_join(&mut self, reply: &JoinReply) -> Result<(), TransportError>;
    /// True once the process was asked to terminate (SIGINT, SIGTERM, or
    /// the in-process stop flag); asked again, still true.
    fn termination_requested(&self) -> bool;

    // The hooks: what a transport does to keep the loop cheap at scale.

    /// Called before each snapshot is published: `count` agents are to
    /// answer tick `tick`. A transport that can count the answers wakes
    /// the world once, when the last of them is in, instead of on every
    /// command; from the first call on, [`wait`](Self::wait) may then
    /// sleep through other wake-ups (join requests, ready commands) for a
    /// few milliseconds. A transport that wakes the world on every command
    /// does nothing here.
    fn expect_answers(&mut self, tick: u64, count: usize);
    /// Called after the [`reply_join`](Self::reply_join)s of one
    /// [`drain_joins`](Self::drain_joins): wakes the agents waiting for
    /// their replies, once for all of them (hundreds of agents joining at
    /// once must not each be woken once per reply). A transport whose
    /// replies wake their agent themselves does nothing here.
    fn joins_answered(&mut self) -> Result<(), TransportError>;
    /// Called when the world has found an agent process dead: frees what
    /// it left behind in the transport, so that a restarted agent can
    /// join again. Cheap when nothing died.
    fn cleanup_dead(&mut self);
    /// Called once, when every agent is ready and tick 0 is next: connect
    /// the tick's channels now and let the agents take up their side, so
    /// that tick 0 costs what any tick costs (over iceoryx2 the snapshot
    /// publisher would otherwise connect inside tick 0's send, and each
    /// agent map its side at its first receive, and agents miss tick 0).
    ///
    /// Returns true if each agent then says so with a second ready
    /// command (the agents' loop sends one on every wake-up that brings no
    /// snapshot before its first, [`mrsim_proto::command_kind::READY`]):
    /// the world then waits for all of them before tick 0. False if there
    /// is nothing to take up (the world starts at once).
    fn prepare_ticks(&mut self) -> Result<bool, TransportError>;
    /// Publishes the run's live statistics for observers
    /// ([`ObserverTransport`]), a few times per second at most. Must not
    /// block, nor wait for a slow observer. A transport without observers
    /// does nothing here.
    fn publish_stats(
        &mut self,
        header: &StatsHeader,
        robots: &[RobotStats],
    ) -> Result<(), TransportError>;
    /// Whether the agent process `pid` that joined is still there, if the
    /// transport knows (over the network: its liveliness token); `None`
    /// (the default) lets the world ask the process table, which is right
    /// only when every agent runs on the world's host.
    fn agent_alive(&self, pid: u32) -> Option<bool> {
        let _ = pid;
        None
    }
    /// What the network refused or dropped before the tick loop saw it,
    /// for metrics.json; `None` (the default) for a transport that hands
    /// the loop everything (shared memory, in-process).
    fn network_counts(&self) -> Option<NetworkCounts> {
        None
    }
}

/// What a networked world transport refused or dropped so far (for
/// metrics.json).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct NetworkCounts {
    /// Connections refused because their credentials failed.
    pub auth_refused: u64,
    /// Commands that did not decode.
    pub commands_malformed: u64,
    /// Join requests that did not decode.
    pub joins_malformed: u64,
    /// Commands and join requests dropped unread because more came than
    /// the inbox holds (a flood).
    pub dropped: u64,
}

/// An agent's side of the channels.
///
/// The agent loop (`mrsim_agents`) is the only caller. Its order:
/// [`request_join`](Self::request_join), then [`wait`](Self::wait) and
/// [`poll_join_reply`](Self::poll_join_reply) until the reply comes (asking
/// again now and then), [`setup`](Self::setup) until it is there,
/// [`joined`](Self::joined); then per wake-up
/// [`with_latest_snapshot`](Self::with_latest_snapshot) (or
/// [`latest_snapshot`](Self::latest_snapshot) and
/// [`send_command`](Self::send_command)), with
/// [`world_alive`](Self::world_alive) and
/// [`termination_requested`](Self::termination_requested) checked between
/// waits.
pub trait AgentTransport {
    /// Sends a join request (and wakes the world).
    fn request_join(&mut self, req: &JoinRequest) -> Result<(), TransportError>;
    /// The reply to the request with this nonce, if it has arrived;
    /// replies to other nonces are dropped.
    fn poll_join_reply(&mut self, nonce: u64) -> Result<Option<JoinReply>, TransportError>;
    /// The run's setup, once the world has published it.
    fn setup(&mut self) -> Result<Option<Vec<u8>>, TransportError>;
    /// Blocks until the world wakes this agent (a snapshot, a join reply)
    /// or `timeout` passes. May return early, spuriously.
    fn wait(&mut self, timeout: Duration) -> Result<(), TransportError>;
    /// Copies the newest snapshot received since the last call into
    /// `header` and `bodies` (older ones are dropped); false if none
    /// arrived.
    fn latest_snapshot(
        &mut self,
        header: &mut SnapshotHeader,
        bodies: &mut Vec<BodyState>,
    ) -> Result<bool, TransportError>;
    /// Sends a command and wakes the world (or counts the answer toward
    /// the world's wake-up, see [`WorldTransport::expect_answers`]).
    fn send_command(&mut self, cmd: &CommandMsg) -> Result<(), TransportError>;
    /// False once the world is known to be gone. Called a few times per
    /// second; must be cheap.
    fn world_alive(&mut self) -> bool;
    /// True once the process was asked to terminate (SIGINT, SIGTERM, or
    /// the in-process stop flag); asked again, still true.
    fn termination_requested(&self) -> bool;
    /// The agent has joined and read the setup: the ports used only to
    /// join may be closed (joining again then fails). The default keeps
    /// them (a transport whose join ports cost nothing).
    fn joined(&mut self) {}
    /// Calls `f` once with the newest snapshot received since the last
    /// call, and a sender of commands (as [`send_command`]); false, without
    /// calling it, if none arrived. The default copies the snapshot into
    /// `scratch` first (with [`latest_snapshot`]); [`shm::ShmAgent`] lends
    /// `f` the world's shared-memory sample itself instead, which saves
    /// each agent a copy of every snapshot.
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
    /// Robots in the scenario.
    pub robots: usize,
    /// Robots one agent drives at most (1 unless agents drive groups):
    /// an agent sends that many commands a tick, and the world's buffer
    /// for each agent's commands must hold them all.
    pub group: usize,
    /// Agent processes the run has at most: one per robot, or fewer when
    /// agents drive groups. Every agent process holds one port of each
    /// kind, and iceoryx2 visits every port slot a service has room for on
    /// each send and receive, so room for a port per robot when 1,000
    /// processes drive 100,000 robots makes each join reply and each
    /// snapshot a hundred times the work.
    pub processes: usize,
}

impl Capacity {
    /// Room for strangers, restarted agents and observers beyond the
    /// agent processes.
    pub const SPARE: usize = 16;

    /// A run of `robots` robots whose agents drive `group` robots each
    /// (the last one the rest): `robots / group` processes, rounded up.
    pub fn grouped(robots: usize, group: usize) -> Self {
        let group = group.max(1);
        Self {
            robots,
            group,
            processes: robots.div_ceil(group),
        }
    }

    /// Maximum number of agent-side ports of one kind: a port per agent
    /// process and [`Self::SPARE`] more.
    pub fn agents(&self) -> usize {
        self.processes.min(self.robots) + Self::SPARE
    }

    /// Maximum number of messages of one kind the agents send the world
    /// at once (a command or a join request per robot), with
    /// [`Self::SPARE`] more.
    pub fn messages(&self) -> usize {
        self.robots + Self::SPARE
    }

    /// The commands the world's buffer for one agent process holds: its
    /// [`Capacity::group`], and at least 8.
    pub fn commands_per_agent(&self) -> usize {
        self.group.max(8)
    }
}
