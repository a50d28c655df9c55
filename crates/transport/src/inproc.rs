//! The in-process transport: the world and its agents as threads of one
//! process, over crossbeam channels. Same interface as [`crate::shm`]; the
//! lower bound for the IPC cost and the fast path for large headless runs.

use crate::{AgentTransport, TransportError, WorldTransport};
use crossbeam::channel::{Receiver, Sender, unbounded};
use mrsim_proto::{BodyState, CommandMsg, JoinReply, JoinRequest, SnapshotHeader, now_ns};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

enum ToWorld {
    /// A join request and the index of the agent side that sent it.
    Join(JoinRequest, usize),
    Command(CommandMsg, u64),
}

enum ToAgent {
    Snapshot(SnapshotHeader, Arc<[BodyState]>),
    Reply(JoinReply),
}

/// The world's side of an in-process run.
pub struct InprocWorld {
    rx: Receiver<ToWorld>,
    agents: Vec<Sender<ToAgent>>,
    setup: Arc<std::sync::Mutex<Option<Vec<u8>>>>,
    pending: Vec<ToWorld>,
    /// Which agent side asked with which nonce, so a reply goes to it alone.
    asked_by: std::collections::HashMap<u64, usize>,
    stop: Arc<AtomicBool>,
    alive: Arc<AtomicBool>,
}

/// One agent's side of an in-process run.
pub struct InprocAgent {
    index: usize,
    tx: Sender<ToWorld>,
    rx: Receiver<ToAgent>,
    setup: Arc<std::sync::Mutex<Option<Vec<u8>>>>,
    replies: Vec<JoinReply>,
    /// Nonces of this agent's join requests: replies are broadcast to every
    /// agent, and only those answering one of these are kept.
    asked: Vec<u64>,
    pending: Option<(SnapshotHeader, Arc<[BodyState]>)>,
    stop: Arc<AtomicBool>,
    world_alive: Arc<AtomicBool>,
}

/// Creates a world side and `agents` agent sides connected to it. `stop`
/// plays the role of SIGTERM for every side.
pub fn channels(agents: usize, stop: Arc<AtomicBool>) -> (InprocWorld, Vec<InprocAgent>) {
    let (tx, rx) = unbounded();
    let setup = Arc::new(std::sync::Mutex::new(None));
    let alive = Arc::new(AtomicBool::new(true));
    let mut senders = Vec::with_capacity(agents);
    let mut sides = Vec::with_capacity(agents);
    for index in 0..agents {
        let (atx, arx) = unbounded();
        senders.push(atx);
        sides.push(InprocAgent {
            index,
            tx: tx.clone(),
            rx: arx,
            setup: setup.clone(),
            replies: Vec::new(),
            asked: Vec::new(),
            pending: None,
            stop: stop.clone(),
            world_alive: alive.clone(),
        });
    }
    (
        InprocWorld {
            rx,
            agents: senders,
            setup,
            pending: Vec::new(),
            asked_by: std::collections::HashMap::new(),
            stop,
            alive,
        },
        sides,
    )
}

impl Drop for InprocWorld {
    fn drop(&mut self) {
        self.alive.store(false, Ordering::SeqCst);
    }
}

impl InprocWorld {
    fn pump(&mut self) {
        self.pending.extend(self.rx.try_iter());
    }
}

impl WorldTransport for InprocWorld {
    fn publish_setup(&mut self, setup: &[u8]) -> Result<(), TransportError> {
        if let Ok(mut s) = self.setup.lock() {
            *s = Some(setup.to_vec());
        }
        Ok(())
    }

    fn publish_snapshot(
        &mut self,
        header: &SnapshotHeader,
        bodies: &[BodyState],
    ) -> Result<(), TransportError> {
        let h = *header;
        let shared: Arc<[BodyState]> = Arc::from(bodies);
        for a in &self.agents {
            // An agent thread that has ended simply misses the snapshot.
            let _ = a.send(ToAgent::Snapshot(h, shared.clone()));
        }
        Ok(())
    }

    fn wait(&mut self, timeout: Duration) -> Result<(), TransportError> {
        if self.pending.is_empty() {
            match self.rx.recv_timeout(timeout) {
                Ok(m) => self.pending.push(m),
                Err(crossbeam::channel::RecvTimeoutError::Timeout) => {}
                Err(crossbeam::channel::RecvTimeoutError::Disconnected) => {
                    std::thread::sleep(timeout);
                }
            }
        }
        Ok(())
    }

    fn drain_commands(&mut self, f: &mut dyn FnMut(CommandMsg, u64)) -> Result<(), TransportError> {
        self.pump();
        let mut rest = Vec::new();
        for m in self.pending.drain(..) {
            match m {
                ToWorld::Command(c, t) => f(c, t),
                other => rest.push(other),
            }
        }
        self.pending = rest;
        Ok(())
    }

    fn drain_joins(&mut self, f: &mut dyn FnMut(JoinRequest)) -> Result<(), TransportError> {
        self.pump();
        let mut rest = Vec::new();
        for m in self.pending.drain(..) {
            match m {
                ToWorld::Join(j, from) => {
                    self.asked_by.insert(j.nonce, from);
                    f(j)
                }
                other => rest.push(other),
            }
        }
        self.pending = rest;
        Ok(())
    }

    fn reply_join(&mut self, reply: &JoinReply) -> Result<(), TransportError> {
        match self
            .asked_by
            .get(&reply.nonce)
            .and_then(|&i| self.agents.get(i))
        {
            Some(a) => {
                let _ = a.send(ToAgent::Reply(*reply));
            }
            // A nonce nobody asked with: tell everyone (each keeps only
            // replies to its own requests).
            None => {
                for a in &self.agents {
                    let _ = a.send(ToAgent::Reply(*reply));
                }
            }
        }
        Ok(())
    }

    fn termination_requested(&self) -> bool {
        self.stop.load(Ordering::Relaxed)
    }
}

impl InprocAgent {
    fn pump(&mut self, first: Option<ToAgent>) {
        for m in first.into_iter().chain(self.rx.try_iter()) {
            match m {
                ToAgent::Snapshot(h, b) => self.pending = Some((h, b)),
                ToAgent::Reply(r) if self.asked.contains(&r.nonce) => self.replies.push(r),
                ToAgent::Reply(_) => {}
            }
        }
    }
}

impl AgentTransport for InprocAgent {
    fn request_join(&mut self, req: &JoinRequest) -> Result<(), TransportError> {
        if !self.asked.contains(&req.nonce) {
            self.asked.push(req.nonce);
        }
        self.tx
            .send(ToWorld::Join(*req, self.index))
            .map_err(|_| TransportError::Disconnected)
    }

    fn poll_join_reply(&mut self, nonce: u64) -> Result<Option<JoinReply>, TransportError> {
        self.pump(None);
        Ok(self
            .replies
            .iter()
            .position(|r| r.nonce == nonce)
            .map(|i| self.replies.swap_remove(i)))
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
