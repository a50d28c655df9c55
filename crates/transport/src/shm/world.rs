//! The world's side over iceoryx2 ([`ShmWorld`]): it creates every
//! service of the run, publishes the setup, the snapshots and the
//! statistics, answers joins and takes in the agents' commands.

use super::doorbell::Doorbell;
use super::service::{S, WORLD_NODE, config, node, service_name, setup_err, terminated, wait_on};
use crate::{Capacity, Namespace, TransportError, WorldTransport};
use iceoryx2::port::listener::Listener;
use iceoryx2::port::notifier::Notifier;
use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::port::update_connections::UpdateConnections;
use iceoryx2::prelude::*;
use mrsim_proto::{
    BodyState, CommandMsg, JoinReply, JoinRequest, RobotStats, SnapshotHeader, StatsHeader, events,
    now_ns,
};
use std::time::Duration;

/// The most join replies an agent's reply subscriber buffers. Every agent
/// sees every reply, so with hundreds joining at once a small buffer drops
/// an agent's own reply before it polls (it would then ask again).
const REPLY_BUFFER_MAX: usize = 128;

/// The world's side over iceoryx2.
pub struct ShmWorld {
    node: Node<S>,
    setup_pub: Publisher<S, [u8], ()>,
    snap_pub: Publisher<S, [BodyState], SnapshotHeader>,
    /// Join replies only; snapshots ring `bell`.
    tick: Notifier<S>,
    bell: Doorbell,
    cmd_sub: Subscriber<S, CommandMsg, ()>,
    join_sub: Subscriber<S, JoinRequest, ()>,
    reply_pub: Publisher<S, JoinReply, ()>,
    wake: Listener<S>,
    max_bodies: usize,
    terminated: std::cell::Cell<bool>,
    stats_pub: Publisher<S, [RobotStats], StatsHeader>,
    max_robots: usize,
    replies_pending: bool,
    /// Set once the world waits for answers counted on the doorbell
    /// ([`WorldTransport::expect_answers`]).
    counting: bool,
}

/// The longest the world sleeps on the answer count before it looks at
/// its iceoryx2 listener (join requests, ready commands and dead notifiers
/// of agents restarting during the run).
const ANSWER_SLICE: Duration = Duration::from_millis(5);

impl ShmWorld {
    /// Creates every service of the run. Fails if another world of the same
    /// run already exists.
    pub fn create(
        ns: &Namespace,
        cap: Capacity,
        max_bodies: usize,
        max_setup_len: usize,
    ) -> Result<Self, TransportError> {
        let mut cfg = config(ns)?;
        // Room for every agent's join port closing with a re-asked request
        // still queued (the world's subscribers only): iceoryx2's default
        // (128) is smaller than a large run, and it then discards the
        // duplicates with a long warning each on stderr.
        cfg.defaults
            .publish_subscribe
            .subscriber_expired_connection_buffer = cap.agents();
        let node = node(&cfg, WORLD_NODE)?;
        ns.make_private();
        // A crashed earlier run of the same id may have left dead nodes.
        let _ = node.try_cleanup_dead_nodes();
        // Before any service: an agent that finds the services finds it.
        let bell = Doorbell::create(ns)?;
        let agents = cap.agents();
        let nodes = agents + 4;

        let setup = node
            .service_builder(&service_name("mrsim/setup")?)
            .publish_subscribe::<[u8]>()
            .history_size(1)
            .subscriber_max_buffer_size(1)
            .max_publishers(1)
            .max_subscribers(agents + 2)
            .max_nodes(nodes)
            .create()
            .map_err(|e| setup_err("service mrsim/setup", e))?;
        let setup_pub = setup
            .publisher_builder()
            .initial_max_slice_len(max_setup_len.max(1))
            .create()
            .map_err(|e| setup_err("setup publisher", e))?;

        let snap_pub = slice_publisher(&node, "snapshot", 2, agents + 2, nodes, max_bodies)?;

        let tick_service = node
            .service_builder(&service_name("mrsim/tick")?)
            .event()
            .event_id_max_value(events::MAX_ID)
            .max_notifiers(2)
            .max_listeners(agents + 2)
            .max_nodes(nodes)
            .create()
            .map_err(|e| setup_err("service mrsim/tick", e))?;
        let tick = tick_service
            .notifier_builder()
            .create()
            .map_err(|e| setup_err("tick notifier", e))?;

        let join = node
            .service_builder(&service_name("mrsim/join")?)
            .publish_subscribe::<JoinRequest>()
            .subscriber_max_buffer_size(cap.group.max(4))
            .max_publishers(agents)
            .max_subscribers(2)
            .max_nodes(nodes)
            .create()
            .map_err(|e| setup_err("service mrsim/join", e))?;
        let join_sub = join
            .subscriber_builder()
            .create()
            .map_err(|e| setup_err("join subscriber", e))?;

        let reply = node
            .service_builder(&service_name("mrsim/join-reply")?)
            .publish_subscribe::<JoinReply>()
            .subscriber_max_buffer_size((agents + 2).clamp(8, REPLY_BUFFER_MAX))
            .max_publishers(1)
            .max_subscribers(agents + 2)
            .max_nodes(nodes)
            .create()
            .map_err(|e| setup_err("service mrsim/join-reply", e))?;
        // iceoryx2 sizes every connection by the publisher's worst case:
        // every subscriber's buffer full of distinct replies, which grows
        // with the square of the agents and at a thousand of them is most
        // of the world's peak RSS while they join. Replies go
        // to every subscriber alike, so a buffer holds only the newest
        // replies: in use at once are at most a buffer's worth, the ones
        // the agents hold while reading (two each at most), and the one
        // being sent. Twice that leaves a margin.
        let reply_samples = 2 * (REPLY_BUFFER_MAX + 2 * (agents + 2) + 1);
        let reply_pub = reply
            .publisher_builder()
            .override_sample_preallocation(move |_| reply_samples)
            .create()
            .map_err(|e| setup_err("join-reply publisher", e))?;

        let cmd = node
            .service_builder(&service_name("mrsim/command")?)
            .publish_subscribe::<CommandMsg>()
            // A group's agent sends a command per robot, all at once.
            .subscriber_max_buffer_size(cap.commands_per_agent())
            .max_publishers(agents)
            .max_subscribers(2)
            .max_nodes(nodes)
            .create()
            .map_err(|e| setup_err("service mrsim/command", e))?;
        let cmd_sub = cmd
            .subscriber_builder()
            .create()
            .map_err(|e| setup_err("command subscriber", e))?;

        let wake_service = node
            .service_builder(&service_name("mrsim/wake")?)
            .event()
            .event_id_max_value(events::MAX_ID)
            .max_notifiers(agents)
            .max_listeners(2)
            .max_nodes(nodes)
            .notifier_dead_event(EventId::new(events::NOTIFIER_DEAD))
            .create()
            .map_err(|e| setup_err("service mrsim/wake", e))?;
        let wake = wake_service
            .listener_builder()
            .create()
            .map_err(|e| setup_err("wake listener", e))?;

        // Only observers (`mrsim top`, the launcher) read the statistics.
        let stats_pub = slice_publisher(&node, "stats", 1, Capacity::SPARE + 2, nodes, cap.robots)?;

        Ok(Self {
            node,
            setup_pub,
            snap_pub,
            tick,
            bell,
            cmd_sub,
            join_sub,
            reply_pub,
            wake,
            max_bodies,
            terminated: std::cell::Cell::new(false),
            stats_pub,
            max_robots: cap.robots,
            replies_pending: false,
            counting: false,
        })
    }
}

impl WorldTransport for ShmWorld {
    fn publish_setup(&mut self, setup: &[u8]) -> Result<(), TransportError> {
        let sample =
            self.setup_pub
                .loan_slice_uninit(setup.len())
                .map_err(|e| TransportError::Send {
                    what: "setup",
                    detail: format!("{e:?}"),
                })?;
        let sample = sample.write_from_slice(setup);
        sample.send().map_err(|e| TransportError::Send {
            what: "setup",
            detail: format!("{e:?}"),
        })?;
        Ok(())
    }

    fn publish_snapshot(
        &mut self,
        header: &SnapshotHeader,
        bodies: &[BodyState],
    ) -> Result<(), TransportError> {
        let n = bodies.len().min(self.max_bodies);
        send_slice(&self.snap_pub, "snapshot", header, &bodies[..n])?;
        self.bell.ring()
    }

    fn wait(&mut self, timeout: Duration) -> Result<(), TransportError> {
        if !self.counting {
            return wait_on(&self.wake, timeout);
        }
        // What the listener has (a restarted agent's join, a dead
        // notifier) is taken in with the commands after this returns.
        wait_on(&self.wake, Duration::ZERO)?;
        self.bell
            .wait_answers(timeout.min(ANSWER_SLICE))
            .map(|_| ())
    }

    fn expect_answers(&mut self, tick: u64, count: usize) {
        self.bell.expect(tick, count);
        self.counting = true;
    }

    fn drain_commands(&mut self, f: &mut dyn FnMut(CommandMsg, u64)) -> Result<(), TransportError> {
        loop {
            match self.cmd_sub.receive() {
                Ok(Some(sample)) => f(*sample.payload(), now_ns()),
                Ok(None) => return Ok(()),
                Err(e) => {
                    return Err(TransportError::Receive {
                        what: "command",
                        detail: format!("{e:?}"),
                    });
                }
            }
        }
    }

    fn drain_joins(&mut self, f: &mut dyn FnMut(JoinRequest)) -> Result<(), TransportError> {
        let mut any = false;
        loop {
            match self.join_sub.receive() {
                Ok(Some(sample)) => {
                    if !any {
                        // iceoryx2 hands the setup's history to a new
                        // subscriber only when the publisher updates its
                        // connections: do it before answering the joins.
                        any = true;
                        let _ = self.setup_pub.update_connections();
                    }
                    f(*sample.payload())
                }
                Ok(None) => return Ok(()),
                Err(e) => {
                    return Err(TransportError::Receive {
                        what: "join request",
                        detail: format!("{e:?}"),
                    });
                }
            }
        }
    }

    fn reply_join(&mut self, reply: &JoinReply) -> Result<(), TransportError> {
        self.reply_pub
            .send_copy(*reply)
            .map_err(|e| TransportError::Send {
                what: "join reply",
                detail: format!("{e:?}"),
            })?;
        self.replies_pending = true;
        Ok(())
    }

    fn joins_answered(&mut self) -> Result<(), TransportError> {
        if !std::mem::take(&mut self.replies_pending) {
            return Ok(());
        }
        // Agents waiting for their reply listen on the tick event.
        self.tick
            .notify_with_custom_event_id(EventId::new(events::JOIN_REPLY))
            .map_err(|e| TransportError::Send {
                what: "tick event",
                detail: format!("{e:?}"),
            })?;
        Ok(())
    }

    fn termination_requested(&self) -> bool {
        terminated(&self.terminated)
    }

    fn prepare_ticks(&mut self) -> Result<bool, TransportError> {
        // The join-time connections go first (holding both kinds at once
        // raises the world's peak RSS at a thousand agents), then
        // the snapshot publisher connects to every subscriber, and a ring
        // with no snapshot wakes the agents to map their side (they find
        // nothing to read, and wait again).
        self.update_join_connections();
        // Best effort: the first send connects whatever this could not.
        let _ = self.snap_pub.update_connections();
        self.bell.ring()?;
        Ok(true)
    }

    fn cleanup_dead(&mut self) {
        let _ = self.node.try_cleanup_dead_nodes();
    }

    fn publish_stats(
        &mut self,
        header: &StatsHeader,
        robots: &[RobotStats],
    ) -> Result<(), TransportError> {
        let n = robots.len().min(self.max_robots);
        let header = StatsHeader {
            robot_count: n as u32,
            ..*header
        };
        self.update_join_connections();
        send_slice(&self.stats_pub, "stats", &header, &robots[..n])
    }
}

impl ShmWorld {
    /// Observers that subscribed since the last call get the setup's
    /// history only when its publisher updates its connections (cheap when
    /// nobody new came); agents that have joined closed their setup and
    /// join-reply subscribers, whose connections this unmaps.
    fn update_join_connections(&self) {
        let _ = self.setup_pub.update_connections();
        let _ = self.reply_pub.update_connections();
    }
}

/// Creates the world's publisher of `mrsim/NAME`: a slice of `T` of up to
/// `max_len` items after a header `H`, history 1 (late subscribers get the
/// newest), `buffer` samples per subscriber.
fn slice_publisher<T, H>(
    node: &Node<S>,
    name: &str,
    buffer: usize,
    max_subscribers: usize,
    max_nodes: usize,
    max_len: usize,
) -> Result<Publisher<S, [T], H>, TransportError>
where
    T: std::fmt::Debug + ZeroCopySend + 'static,
    H: std::fmt::Debug + ZeroCopySend + 'static,
{
    node.service_builder(&service_name(&format!("mrsim/{name}"))?)
        .publish_subscribe::<[T]>()
        .user_header::<H>()
        .history_size(1)
        .subscriber_max_buffer_size(buffer)
        .max_publishers(1)
        .max_subscribers(max_subscribers)
        .max_nodes(max_nodes)
        .create()
        .map_err(|e| setup_err(format!("service mrsim/{name}"), e))?
        .publisher_builder()
        .initial_max_slice_len(max_len.max(1))
        .create()
        .map_err(|e| setup_err(format!("{name} publisher"), e))
}

/// Sends `header` and `items` as one sample (no allocation: the sample is
/// loaned from shared memory).
fn send_slice<T, H>(
    publisher: &Publisher<S, [T], H>,
    what: &'static str,
    header: &H,
    items: &[T],
) -> Result<(), TransportError>
where
    T: std::fmt::Debug + ZeroCopySend + Copy + 'static,
    H: std::fmt::Debug + ZeroCopySend + Copy + Default + 'static,
{
    let send_err = |e: &dyn std::fmt::Debug| TransportError::Send {
        what,
        detail: format!("{e:?}"),
    };
    let mut sample = publisher
        .loan_slice_uninit(items.len())
        .map_err(|e| send_err(&e))?;
    *sample.user_header_mut() = *header;
    let sample = sample.write_from_slice(items);
    sample.send().map_err(|e| send_err(&e))?;
    Ok(())
}
