//! The world's side of an in-process run ([`InprocWorld`]).

use super::message::{ToAgent, ToWorld};
use super::observer::InprocObserver;
use super::poll::Poll;
use crate::{TransportError, WorldTransport};
use crossbeam::channel::{Receiver, Sender};
use mrsim_proto::{
    BodyState, CommandMsg, JoinReply, JoinRequest, RobotStats, SnapshotHeader, StatsHeader, now_ns,
};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

/// The world's side of an in-process run.
pub struct InprocWorld {
    pub(super) rx: Receiver<ToWorld>,
    pub(super) agents: Vec<Sender<ToAgent>>,
    /// With workers, snapshots go to them, not to the agents' sides.
    pub(super) workers: Vec<Sender<ToAgent>>,
    pub(super) setup: Arc<std::sync::Mutex<Option<Vec<u8>>>>,
    pub(super) pending: Vec<ToWorld>,
    /// Which agent side asked with which nonce, so a reply goes to it alone.
    pub(super) asked_by: std::collections::HashMap<u64, usize>,
    pub(super) stop: Arc<AtomicBool>,
    pub(super) alive: Arc<AtomicBool>,
    /// How [`WorldTransport::wait`] waits for the workers.
    pub(super) poll: Poll,
    /// Planning the world's thread does itself while it waits (see
    /// [`InprocWorld::help_with`]), and the snapshot it has yet to help with.
    pub(super) helper: Option<Helper>,
    pub(super) to_help: Option<(SnapshotHeader, Arc<[BodyState]>)>,
    /// The newest live statistics, for [`InprocObserver`]s.
    pub(super) stats: super::observer::SharedStats,
    /// The newest snapshot, for [`InprocObserver`]s (the live page): the
    /// one the workers already share, so keeping it is a reference count.
    pub(super) latest: super::observer::SharedSnapshot,
}

/// Work the world's thread takes on while it waits for a snapshot's
/// commands: given the snapshot, it returns commands it made (none when
/// nothing was left to do).
pub type Helper = Box<dyn FnMut(&SnapshotHeader, &Arc<[BodyState]>) -> Vec<CommandMsg> + Send>;

impl Drop for InprocWorld {
    fn drop(&mut self) {
        self.alive.store(false, Ordering::SeqCst);
    }
}

impl InprocWorld {
    fn pump(&mut self) {
        self.pending.extend(self.rx.try_iter());
    }

    /// Lends the world's thread to the workers: on its first
    /// [`WorldTransport::wait`] after each snapshot, the world runs
    /// `helper` on that snapshot and takes the commands it returns as
    /// received. In lockstep the world has nothing else to do until the
    /// commands are in, and a pool of one worker fewer plus the world's
    /// thread keeps one busy thread per CPU instead of more threads than
    /// CPUs taking turns.
    pub fn help_with(&mut self, helper: Helper) {
        self.helper = Some(helper);
    }

    /// A read-only observer of this run's setup, live statistics and newest
    /// snapshot (the launcher's progress, the live page).
    pub fn observer(&self) -> InprocObserver {
        InprocObserver {
            setup: self.setup.clone(),
            stats: self.stats.clone(),
            seen: 0,
            snapshot: self.latest.clone(),
            seen_tick: None,
            alive: self.alive.clone(),
        }
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
        if let Ok(mut latest) = self.latest.lock() {
            *latest = Some((h, shared.clone()));
        }
        if self.helper.is_some() {
            self.to_help = Some((h, shared.clone()));
        }
        let to = if self.workers.is_empty() {
            &self.agents
        } else {
            &self.workers
        };
        for a in to {
            // An agent thread that has ended simply misses the snapshot.
            let _ = a.send(ToAgent::Snapshot(h, shared.clone()));
        }
        Ok(())
    }

    fn wait(&mut self, timeout: Duration) -> Result<(), TransportError> {
        if let (Some(help), Some((h, b))) = (self.helper.as_mut(), self.to_help.take()) {
            let cmds = help(&h, &b);
            if !cmds.is_empty() {
                self.pending.push(ToWorld::Commands(cmds, now_ns()));
                return Ok(());
            }
        }
        if self.pending.is_empty() {
            match self.poll.recv(&self.rx, timeout) {
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
                ToWorld::Commands(cs, t) => cs.into_iter().for_each(|c| f(c, t)),
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

    /// Nothing to count: every command (or worker batch) is a message of
    /// its own, and [`WorldTransport::wait`] returns on the first.
    fn expect_answers(&mut self, _tick: u64, _count: usize) {}

    /// Nothing to do: each reply went to its agent's channel in
    /// [`WorldTransport::reply_join`], which wakes that agent.
    fn joins_answered(&mut self) -> Result<(), TransportError> {
        Ok(())
    }

    /// Nothing to free: an agent thread's channel is dropped with it.
    fn cleanup_dead(&mut self) {}

    /// Nothing to connect: the channels exist from [`super::channels`] on.
    fn prepare_ticks(&mut self) -> Result<bool, TransportError> {
        Ok(false)
    }

    /// Kept for [`InprocObserver`]s (a copy at most every 200 ms: the
    /// world publishes no more often).
    fn publish_stats(
        &mut self,
        header: &StatsHeader,
        robots: &[RobotStats],
    ) -> Result<(), TransportError> {
        if let Ok(mut s) = self.stats.lock() {
            s.0 += 1;
            s.1 = *header;
            s.2.clear();
            s.2.extend_from_slice(robots);
        }
        Ok(())
    }
}
