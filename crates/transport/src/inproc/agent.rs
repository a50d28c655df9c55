//! One agent's side of an in-process run ([`InprocAgent`]).

use super::message::{ToAgent, ToWorld};
use crate::{AgentTransport, TransportError};
use crossbeam::channel::{Receiver, Sender};
use mrsim_proto::{BodyState, CommandMsg, JoinReply, JoinRequest, SnapshotHeader, now_ns};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

/// One agent's side of an in-process run.
pub struct InprocAgent {
    pub(super) index: usize,
    pub(super) tx: Sender<ToWorld>,
    pub(super) rx: Receiver<ToAgent>,
    pub(super) setup: Arc<std::sync::Mutex<Option<Vec<u8>>>>,
    pub(super) replies: std::collections::HashMap<u64, JoinReply>,
    /// Nonces of this agent's join requests: replies are broadcast to every
    /// agent, and only those answering one of these are kept.
    pub(super) asked: std::collections::HashSet<u64>,
    pub(super) pending: Option<(SnapshotHeader, Arc<[BodyState]>)>,
    pub(super) stop: Arc<AtomicBool>,
    pub(super) world_alive: Arc<AtomicBool>,
}

impl InprocAgent {
    fn pump(&mut self, first: Option<ToAgent>) {
        for m in first.into_iter().chain(self.rx.try_iter()) {
            match m {
                ToAgent::Snapshot(h, b) => self.pending = Some((h, b)),
                ToAgent::Reply(r) if self.asked.contains(&r.nonce) => {
                    self.replies.insert(r.nonce, r);
                }
                ToAgent::Reply(_) => {}
            }
        }
    }
}

impl AgentTransport for InprocAgent {
    fn request_join(&mut self, req: &JoinRequest) -> Result<(), TransportError> {
        self.asked.insert(req.nonce);
        self.tx
            .send(ToWorld::Join(*req, self.index))
            .map_err(|_| TransportError::Disconnected)
    }

    fn poll_join_reply(&mut self, nonce: u64) -> Result<Option<JoinReply>, TransportError> {
        self.pump(None);
        Ok(self.replies.remove(&nonce))
    }

    fn setup(&mut self) -> Result<Option<Vec<u8>>, TransportError> {
        Ok(self.setup.lock().ok().and_then(|s| s.clone()))
    }

    fn wait(&mut self, timeout: Duration) -> Result<(), TransportError> {
        if self.pending.is_none() {
            match self.rx.recv_timeout(timeout) {
                Ok(m) => self.pump(Some(m)),
                Err(crossbeam::channel::RecvTimeoutError::Timeout) => {}
                Err(crossbeam::channel::RecvTimeoutError::Disconnected) => {
                    self.world_alive.store(false, Ordering::SeqCst);
                }
            }
        }
        Ok(())
    }

    fn latest_snapshot(
        &mut self,
        header: &mut SnapshotHeader,
        bodies: &mut Vec<BodyState>,
    ) -> Result<bool, TransportError> {
        self.pump(None);
        match self.pending.take() {
            Some((h, b)) => {
                *header = h;
                bodies.clear();
                bodies.extend_from_slice(&b);
                Ok(true)
            }
            None => Ok(false),
        }
    }

    fn send_command(&mut self, cmd: &CommandMsg) -> Result<(), TransportError> {
        self.tx
            .send(ToWorld::Command(*cmd, now_ns()))
            .map_err(|_| TransportError::Disconnected)
    }

    fn world_alive(&mut self) -> bool {
        self.world_alive.load(Ordering::SeqCst)
    }

    fn termination_requested(&self) -> bool {
        self.stop.load(Ordering::Relaxed)
    }
}
