//! The in-process transport: the world and its agents as threads of one
//! process, over crossbeam channels. Same interface as [`crate::shm`]; the
//! lower bound for the IPC cost and the fast path for large headless runs.
//!
//! Two layouts: [`channels`] gives every agent its own side (a thread per
//! agent, each woken by every snapshot); [`pooled_channels`] also gives a
//! few [`InprocWorker`]s that receive each snapshot once and answer for
//! many agents in one batch, so a tick costs a few thread wake-ups instead
//! of two per agent (the agents' sides then serve only to join).
//!
//! # The pool: the one way around [`AgentTransport`]
//!
//! With [`pooled_channels`] an agent joins through its [`InprocAgent`] (an
//! [`AgentTransport`] like any other), and from then on its ticks do not go
//! through it. The runtime (`mrsim run --transport inproc`) hands the
//! joined agents to a pool shared by the workers; each worker receives a
//! snapshot once ([`InprocWorker::next`]), its bodies an `Arc` shared with
//! every other receiver rather than a copy, plans for a share of the
//! pool's robots, and sends all their commands as one message
//! ([`InprocWorker::send_commands`]). In lockstep the world's own thread
//! plans for a share too, inside [`WorldTransport::wait`]
//! ([`InprocWorld::help_with`]), since it has nothing else to do until the
//! commands are in.
//!
//! Bypassed per agent and tick: [`AgentTransport::wait`],
//! [`AgentTransport::with_latest_snapshot`] and
//! [`AgentTransport::send_command`], and with them two thread wake-ups
//! (the agent's, and the world's on its command). Kept: the join, the
//! agent code that plans (the runtime calls the same driver the agent loop
//! does), and the world's side: [`InprocWorld`] is a [`WorldTransport`],
//! and the world loop sees one command per robot per tick, stamped with
//! the time its batch was sent. Nothing else bypasses the traits.
//!
//! One module per role: `world` ([`InprocWorld`]), `agent`
//! ([`InprocAgent`]), `worker` ([`InprocWorker`]), `poll` (how the world
//! and the workers wait) and `message` (what goes over the channels); this
//! module wires them together.
//!
//! [`AgentTransport`]: crate::AgentTransport
//! [`AgentTransport::wait`]: crate::AgentTransport::wait
//! [`AgentTransport::with_latest_snapshot`]: crate::AgentTransport::with_latest_snapshot
//! [`AgentTransport::send_command`]: crate::AgentTransport::send_command
//! [`WorldTransport`]: crate::WorldTransport
//! [`WorldTransport::wait`]: crate::WorldTransport::wait

mod agent;
mod message;
mod observer;
mod poll;
mod worker;
mod world;

pub use agent::InprocAgent;
pub use observer::InprocObserver;
pub use worker::{InprocWorker, WorkerEvent};
pub use world::{Helper, InprocWorld};

use crossbeam::channel::unbounded;
use poll::Poll;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::time::Duration;

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
            replies: Default::default(),
            asked: Default::default(),
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
            stats: Default::default(),
            latest: Default::default(),
        },
        sides,
    )
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::WorldTransport;
    use mrsim_proto::{BodyState, CommandMsg, SnapshotHeader};
    use std::sync::atomic::Ordering;

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
}
