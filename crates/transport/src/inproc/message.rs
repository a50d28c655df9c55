//! What the in-process sides send each other over their channels.

use mrsim_proto::{BodyState, CommandMsg, JoinReply, JoinRequest, SnapshotHeader};
use std::sync::Arc;

/// To the world, from an agent's side or a worker.
pub(super) enum ToWorld {
    /// A join request and the index of the agent side that sent it.
    Join(JoinRequest, usize),
    /// An agent side's command, and the time it was sent.
    Command(CommandMsg, u64),
    /// A worker's commands of one snapshot, and the time they were sent.
    Commands(Vec<CommandMsg>, u64),
}

/// To an agent's side or a worker, from the world.
pub(super) enum ToAgent {
    /// A snapshot, its bodies shared by every receiver (not copied).
    Snapshot(SnapshotHeader, Arc<[BodyState]>),
    /// A join reply.
    Reply(JoinReply),
}
