//! A worker's side of a pooled in-process run ([`InprocWorker`]).

use super::message::{ToAgent, ToWorld};
use super::poll::Poll;
use crate::TransportError;
use crossbeam::channel::{Receiver, Sender};
use mrsim_proto::{BodyState, CommandMsg, SnapshotHeader, now_ns};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

/// A worker's side of a pooled in-process run: it receives every snapshot
/// once and sends the commands of all its agents in one batch.
pub struct InprocWorker {
    pub(super) rx: Receiver<ToAgent>,
    pub(super) tx: Sender<ToWorld>,
    pub(super) stop: Arc<AtomicBool>,
    pub(super) poll: Poll,
}

/// What an [`InprocWorker`] received.
#[derive(Debug)]
pub enum WorkerEvent {
    /// A snapshot (the newest, when several were waiting).
    Snapshot(SnapshotHeader, Arc<[BodyState]>),
    /// Nothing within the timeout.
    Idle,
    /// The world is gone (its side was dropped).
    WorldGone,
}

impl InprocWorker {
    /// Waits up to `timeout` for the next snapshot.
    pub fn next(&self, timeout: Duration) -> WorkerEvent {
        let first = match self.poll.recv(&self.rx, timeout) {
            Ok(m) => m,
            Err(crossbeam::channel::RecvTimeoutError::Timeout) => return WorkerEvent::Idle,
            Err(crossbeam::channel::RecvTimeoutError::Disconnected) => {
                return WorkerEvent::WorldGone;
            }
        };
        let mut latest = None;
        for m in std::iter::once(first).chain(self.rx.try_iter()) {
            if let ToAgent::Snapshot(h, b) = m {
                latest = Some((h, b));
            }
        }
        match latest {
            Some((h, b)) => WorkerEvent::Snapshot(h, b),
            None => WorkerEvent::Idle,
        }
    }

    /// Sends one snapshot's commands to the world in one message. They
    /// count as received when sent: the world sees none of them earlier.
    pub fn send_commands(&self, cmds: Vec<CommandMsg>) -> Result<(), TransportError> {
        if cmds.is_empty() {
            return Ok(());
        }
        self.tx
            .send(ToWorld::Commands(cmds, now_ns()))
            .map_err(|_| TransportError::Disconnected)
    }

    /// True once the run was asked to stop.
    pub fn termination_requested(&self) -> bool {
        self.stop.load(Ordering::Relaxed)
    }
}
