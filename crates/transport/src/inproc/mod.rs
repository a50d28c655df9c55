//! The in-process transport: the world and its agents as threads of one
//! process, over crossbeam channels. Same interface as [`crate::shm`]; the
//! lower bound for the IPC cost and the fast path for large headless runs.
//!
//! Two layouts: [`channels`] gives every agent its own side (a thread per
//! agent, each woken by every snapshot); [`pooled_channels`] also gives a
//! few [`InprocWorker`]s that receive each snapshot once and answer for
//! many agents in one batch, so a tick costs a few thread wake-ups instead
//! of two per agent (the agents' sides then serve only to join).

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
    /// A worker's commands of one snapshot, and the time they were sent.
    Commands(Vec<CommandMsg>, u64),
}

enum ToAgent {
    Snapshot(SnapshotHeader, Arc<[BodyState]>),
    Reply(JoinReply),
}

/// The world's side of an in-process run.
pub struct InprocWorld {
    rx: Receiver<ToWorld>,
    agents: Vec<Sender<ToAgent>>,
    /// With workers, snapshots go to them, not to the agents' sides.
    workers: Vec<Sender<ToAgent>>,
    setup: Arc<std::sync::Mutex<Option<Vec<u8>>>>,
    pending: Vec<ToWorld>,
    /// Which agent side asked with which nonce, so a reply goes to it alone.
    asked_by: std::collections::HashMap<u64, usize>,
    stop: Arc<AtomicBool>,
    alive: Arc<AtomicBool>,
    /// How [`WorldTransport::wait`] waits for the workers.
    poll: Poll,
    /// Planning the world's thread does itself while it waits (see
    /// [`InprocWorld::help_with`]), and the snapshot it has yet to help with.
    helper: Option<Helper>,
    to_help: Option<(SnapshotHeader, Arc<[BodyState]>)>,
}

/// Work the world's thread takes on while it waits for a snapshot's
/// commands: given the snapshot, it returns commands it made (none when
/// nothing was left to do).
pub type Helper = Box<dyn FnMut(&SnapshotHeader, &Arc<[BodyState]>) -> Vec<CommandMsg> + Send>;

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
            workers: Vec::new(),
            setup,
            pending: Vec::new(),
            asked_by: std::collections::HashMap::new(),
            stop,
            alive,
            poll: Poll::default(),
            helper: None,
            to_help: None,
        },
        sides,
    )
}

/// A worker's side of a pooled in-process run: it receives every snapshot
/// once and sends the commands of all its agents in one batch.
pub struct InprocWorker {
    rx: Receiver<ToAgent>,
    tx: Sender<ToWorld>,
    stop: Arc<AtomicBool>,
    poll: Poll,
}

/// Creates a world side, `agents` agent sides (to join with) and `workers`
/// worker sides (to answer snapshots with), all connected. `stop` plays the
/// role of SIGTERM for every side.
///
/// `spin` is how long the world and the workers poll for the other's next
/// message before they block ([`Duration::ZERO`]: they block at once). In
/// lockstep with few robots the world and its workers hand each tick back
/// and forth within tens of microseconds, and a blocked thread takes about
/// as long again to be woken on a virtual machine (a halted vCPU must be
/// woken by the host), so polling keeps the wake-ups off the critical path.
/// A side polls only while its previous wait was shorter than `spin`: with
/// many robots a wait is hundreds of microseconds, and polling through it
/// would take the CPU from the threads that do the work. In real time the
/// next snapshot is a tick away, so pass zero.
pub fn pooled_channels(
    agents: usize,
    workers: usize,
    stop: Arc<AtomicBool>,
    spin: Duration,
) -> (InprocWorld, Vec<InprocAgent>, Vec<InprocWorker>) {
    let (mut world, sides) = channels(agents, stop.clone());
    world.poll = Poll::new(spin);
    let tx = sides
        .first()
        .map(|s| s.tx.clone())
        .unwrap_or_else(|| unbounded().0);
    let mut pool = Vec::with_capacity(workers);
    for _ in 0..workers.max(1) {
        let (wtx, wrx) = unbounded();
        world.workers.push(wtx);
        pool.push(InprocWorker {
            rx: wrx,
            tx: tx.clone(),
            stop: stop.clone(),
            poll: Poll::new(spin),
        });
    }
    (world, sides, pool)
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

/// How a side waits for its next message: poll for up to `spin`, then
/// block; poll only while the previous wait was shorter than `spin`.
#[derive(Debug, Default)]
struct Poll {
    spin: Duration,
    /// The previous wait, from the call to the message.
    last: std::cell::Cell<Duration>,
}

impl Poll {
    fn new(spin: Duration) -> Self {
        Self {
            spin,
            last: std::cell::Cell::new(Duration::ZERO),
        }
    }

    /// True if the next wait starts by polling.
    fn polls(&self) -> bool {
        !self.spin.is_zero() && self.last.get() < self.spin
    }

    /// Receives from `rx` within `timeout`. The poll yields the CPU between
    /// tries, so a thread whose turn it is (the world stepping, a worker
    /// planning) sharing the core is delayed by no more than a context
    /// switch per try.
    fn recv<T>(
        &self,
        rx: &Receiver<T>,
        timeout: Duration,
    ) -> Result<T, crossbeam::channel::RecvTimeoutError> {
        use crossbeam::channel::{RecvTimeoutError, TryRecvError};
        let start = std::time::Instant::now();
        let got = if self.polls() {
            let spin = self.spin.min(timeout);
            loop {
                match rx.try_recv() {
                    Ok(m) => break Ok(m),
                    Err(TryRecvError::Disconnected) => break Err(RecvTimeoutError::Disconnected),
                    Err(TryRecvError::Empty) => {}
                }
                let spent = start.elapsed();
                if spent >= spin {
                    break rx.recv_timeout(timeout.saturating_sub(spent));
                }
                std::thread::yield_now();
            }
        } else {
            rx.recv_timeout(timeout)
        };
        if got.is_ok() {
            self.last.set(start.elapsed());
        }
        got
    }
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

#[cfg(test)]
mod tests {
    use super::*;
    use crossbeam::channel::RecvTimeoutError;

    #[test]
    fn a_helping_world_takes_its_own_commands_once_per_snapshot() {
        let stop = Arc::new(AtomicBool::new(false));
        let (mut world, _sides, pool) = pooled_channels(2, 1, stop, Duration::ZERO);
        let helped = Arc::new(std::sync::atomic::AtomicU64::new(0));
        let seen = helped.clone();
        world.help_with(Box::new(move |h, b| {
            seen.fetch_add(1, Ordering::Relaxed);
            vec![CommandMsg {
                robot_id: b.len() as u32 - 1,
                tick: h.tick,
                ..Default::default()
            }]
        }));
        let header = SnapshotHeader {
            tick: 3,
            ..Default::default()
        };
        world
            .publish_snapshot(&header, &[BodyState::default(); 2])
            .expect("publish");
        // The worker still gets the snapshot.
        assert!(matches!(
            pool[0].next(Duration::from_secs(1)),
            WorkerEvent::Snapshot(h, _) if h.tick == 3
        ));
        let mut got = Vec::new();
        world.wait(Duration::from_secs(1)).expect("wait");
        world
            .drain_commands(&mut |c, _| got.push((c.robot_id, c.tick)))
            .expect("drain");
        assert_eq!(got, [(1, 3)]);
        // Helped once: the next wait waits for the workers.
        world.wait(Duration::from_millis(5)).expect("wait");
        assert_eq!(helped.load(Ordering::Relaxed), 1);
    }

    #[test]
    fn a_polling_side_gets_a_message_sent_while_it_polls() {
        let (tx, rx) = unbounded();
        let poll = Poll::new(Duration::from_secs(5));
        let sender = std::thread::spawn(move || {
            std::thread::sleep(Duration::from_millis(2));
            tx.send(7u32)
        });
        assert_eq!(poll.recv(&rx, Duration::from_secs(10)), Ok(7));
        assert!(sender.join().is_ok_and(|r| r.is_ok()));
    }

    #[test]
    fn a_polling_side_sees_the_sender_gone_and_an_empty_channel_time_out() {
        let (tx, rx) = unbounded::<u32>();
        let poll = Poll::new(Duration::from_millis(1));
        assert_eq!(
            poll.recv(&rx, Duration::from_millis(5)),
            Err(RecvTimeoutError::Timeout)
        );
        drop(tx);
        assert_eq!(
            poll.recv(&rx, Duration::from_millis(5)),
            Err(RecvTimeoutError::Disconnected)
        );
    }

    #[test]
    fn a_side_polls_only_while_its_waits_are_shorter_than_the_spin() {
        let (tx, rx) = unbounded();
        let poll = Poll::new(Duration::from_millis(200));
        assert!(poll.polls());
        // A wait of at least 300 ms: the next one blocks at once.
        let sender = std::thread::spawn(move || {
            std::thread::sleep(Duration::from_millis(300));
            let _ = tx.send(1u32);
            tx
        });
        assert_eq!(poll.recv(&rx, Duration::from_secs(10)), Ok(1));
        assert!(!poll.polls());
        // A message already waiting is a short wait: polling resumes.
        let tx = sender.join().expect("sender");
        let _ = tx.send(2);
        assert_eq!(poll.recv(&rx, Duration::from_secs(10)), Ok(2));
        assert!(poll.polls());
        // Zero spin never polls.
        assert!(!Poll::new(Duration::ZERO).polls());
    }
}
