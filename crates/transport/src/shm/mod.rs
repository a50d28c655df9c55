//! The iceoryx2 transport: zero-copy shared memory between processes.
//!
//! Services of one run (all under the run's prefix and root path):
//!
//! | service | pattern | from -> to |
//! | --- | --- | --- |
//! | `mrsim/setup` | publish-subscribe `[u8]`, history 1 | world -> agents |
//! | `mrsim/snapshot` | publish-subscribe `[BodyState]` + `SnapshotHeader` | world -> agents |
//! | `mrsim/tick` | event (join replies) | world -> joining agents |
//! | `/dev/shm/PREFIXdoorbell` | futex word ([`crate::doorbell`]): a new snapshot | world -> agents |
//! | `mrsim/join` | publish-subscribe `JoinRequest` | agents -> world |
//! | `mrsim/join-reply` | publish-subscribe `JoinReply` | world -> agents |
//! | `mrsim/command` | publish-subscribe `CommandMsg` | agents -> world |
//! | `mrsim/wake` | event (ready, join requests), notifier-dead event | agents -> world |
//! | `/dev/shm/PREFIXdoorbell` | futex word: the tick's answers counted, the last wakes | agents -> world |
//! | `mrsim/stats` | publish-subscribe `[RobotStats]` + `StatsHeader`, history 1 | world -> observers |
//!
//! An observer ([`ShmObserver`]) only subscribes to `setup`, `snapshot` and
//! `stats`: it never joins, sends or listens to the tick event, and the
//! world's publishers overwrite the oldest sample of a subscriber that falls
//! behind (iceoryx2's safe overflow) instead of waiting for it.
//!
//! Limits (publishers, subscribers, listeners, notifiers, nodes) are raised
//! from the scenario's robot count, with room to spare for restarted agents,
//! strangers and observers. Waiting is event driven (no busy polling).
//!
//! Each tick's wake-up of the agents is the doorbell, not an iceoryx2
//! event: one futex wake for all agents instead of a datagram per agent
//! (see [`crate::doorbell`] for the measurements). The snapshot itself, and
//! everything else, goes through iceoryx2. Likewise an agent's answer to a
//! tick is counted on the doorbell page rather than notified: the world is
//! woken once, by the last answer it waits for, instead of by every
//! command.

pub mod doorbell;

use doorbell::Doorbell;
use crate::{
    AgentTransport, Capacity, Namespace, ObserverTransport, TransportError, WorldTransport,
};
use iceoryx2::port::listener::Listener;
use iceoryx2::port::notifier::Notifier;
use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::port::update_connections::UpdateConnections;
use iceoryx2::prelude::*;
use iceoryx2::sample::Sample;
use mrsim_proto::{
    BodyState, CommandMsg, JoinReply, JoinRequest, RobotStats, SnapshotHeader, StatsHeader, events,
    now_ns,
};
use std::os::unix::fs::PermissionsExt;
use std::time::{Duration, Instant};

type S = ipc::Service;

/// Name of the world's iceoryx2 node.
pub const WORLD_NODE: &str = "mrsim-world";

/// The most join replies an agent's reply subscriber buffers. Every agent
/// sees every reply, so with hundreds joining at once a small buffer drops
/// an agent's own reply before it polls (it would then ask again).
const REPLY_BUFFER_MAX: usize = 128;

fn setup_err(what: impl Into<String>, e: impl std::fmt::Debug) -> TransportError {
    TransportError::Setup {
        what: what.into(),
        detail: format!("{e:?}"),
    }
}

fn service_name(name: &str) -> Result<ServiceName, TransportError> {
    ServiceName::new(name).map_err(|e| setup_err(format!("service name {name}"), e))
}

/// The iceoryx2 configuration of a run: its own prefix and root path. The
/// root path is created readable by the current user only.
///
/// Nodes do not look for dead nodes when they are created or dropped or
/// open a service (iceoryx2's defaults): each look reads the state of every
/// node of the run (or of the service), so with hundreds of agents starting
/// and ending together they cost O(agents²) file reads and TOML parses,
/// seconds of both cores at 250 agents (profiled). The world cleans up
/// instead, once at its start and whenever an agent process dies; the
/// launcher removes what is left at the end.
pub fn config(ns: &Namespace) -> Result<Config, TransportError> {
    let mut cfg = Config::default();
    cfg.global.node.cleanup_dead_nodes_on_creation = false;
    cfg.global.node.cleanup_dead_nodes_on_destruction = false;
    cfg.global.service.cleanup_dead_nodes_on_open = false;
    cfg.global.prefix =
        FileName::new(ns.prefix().as_bytes()).map_err(|e| setup_err("iceoryx2 prefix", e))?;
    let root = ns.root_path();
    std::fs::create_dir_all(&root)
        .map_err(|e| setup_err(format!("root path {}", root.display()), e))?;
    for dir in [root.as_path(), root.parent().unwrap_or(root.as_path())] {
        // Private by default: only the user who started the run may enter.
        // The shared parent (/tmp/mrsim) stays enterable for other users' runs.
        let mode = if dir == root.as_path() { 0o700 } else { 0o1777 };
        let _ = std::fs::set_permissions(dir, std::fs::Permissions::from_mode(mode));
    }
    let root_str = root.to_string_lossy();
    let path = Path::new(root_str.as_bytes()).map_err(|e| setup_err("iceoryx2 root path", e))?;
    cfg.global.set_root_path(&path);
    Ok(cfg)
}

fn node(cfg: &Config, name: &str) -> Result<Node<S>, TransportError> {
    let node_name = NodeName::new(name).map_err(|e| setup_err(format!("node name {name}"), e))?;
    NodeBuilder::new()
        .name(&node_name)
        .config(cfg)
        .create::<S>()
        .map_err(|e| setup_err(format!("node {name}"), e))
}

/// Waits for events on `listener` until `timeout`; a signal interrupting
/// the wait (EINTR) is a spurious wake-up, not an error: callers check
/// termination and the clock themselves.
///
/// The wait is a `ppoll` on the listener's socket (it returns at once when
/// events are already pending), then the pending events are drained
/// without blocking. iceoryx2's own `timed_wait` times out
/// through a socket receive timeout, which the kernel rounds up to whole
/// jiffies (4 ms at HZ = 250), and sets it and the socket's flags again on
/// every call (three syscalls); `ppoll` sleeps on a high-resolution timer,
/// so the world can wait for commands right up to a tick's deadline
/// without polling.
fn wait_on(listener: &Listener<S>, timeout: Duration) -> Result<(), TransportError> {
    use iceoryx2::port::listener::ListenerWaitError;
    let drain = || match listener.try_wait(|_| {}) {
        Ok(n) => Ok(n > 0),
        Err(ListenerWaitError::InterruptSignal) => Ok(true),
        Err(e) => Err(TransportError::Wait(format!("{e:?}"))),
    };
    if timeout.is_zero() {
        drain()?;
        return Ok(());
    }
    // SAFETY: the descriptor belongs to the listener, which outlives this
    // call; it is only polled here, never closed.
    let fd = unsafe { listener.file_descriptor().native_handle() };
    let mut pfd = libc::pollfd {
        fd,
        events: libc::POLLIN,
        revents: 0,
    };
    let ts = libc::timespec {
        tv_sec: timeout.as_secs().min(i32::MAX as u64) as libc::time_t,
        tv_nsec: timeout.subsec_nanos() as libc::c_long,
    };
    // SAFETY: one valid pollfd, a valid timespec, no signal mask change.
    let r = unsafe { libc::ppoll(&mut pfd, 1, &ts, std::ptr::null()) };
    if r < 0 {
        let e = std::io::Error::last_os_error();
        if e.kind() != std::io::ErrorKind::Interrupted {
            return Err(TransportError::Wait(format!("ppoll: {e}")));
        }
    }
    // Drained also after a timeout. A notifier sends its datagram only
    // while the listener's shared state is not yet "notified", and a
    // notifier that runs between the listener's reset of that state and
    // its emptying of the socket leaves it "notified" with the datagram
    // gone: no notifier sends again, and only a drain resets it. Seen at
    // 256 agents under SCHED_FIFO, the world then woke only at each
    // deadline, for the rest of the run (round trip p50 10.2 ms).
    drain()?;
    Ok(())
}

/// True once SIGINT or SIGTERM arrived. iceoryx2 reports a termination
/// request only once (its signal handler's last signal is taken when read),
/// so the answer is kept in `seen`: asked twice, a loop must hear it twice.
///
/// Reads iceoryx2's signal flag directly: `Node::wait(Duration::ZERO)`,
/// which reads the same flag, also makes a `nanosleep(0)` system call, once
/// per agent per tick.
fn terminated(seen: &std::cell::Cell<bool>) -> bool {
    if !seen.get() && iceoryx2_bb_posix::signal::SignalHandler::termination_requested() {
        seen.set(true);
    }
    seen.get()
}

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
        // still queued (the world's subscribers only): with the default 128,
        // a 1000-agent join discarded the duplicates with ~200 warnings of
        // 40 kB each on stderr.
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
            .subscriber_max_buffer_size(4)
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
        // every subscriber's buffer full of distinct replies, here 1002 x
        // 130 samples at 1000 agents, which made each agent's join-reply
        // connection 132 kB (64 kB of it resident in the world, 45 MB of
        // the world's peak RSS while a thousand agents joined). Replies go
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
            .subscriber_max_buffer_size(8)
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
        // The join-time connections go first (1000 agents' connections of
        // both kinds at once raised the world's peak RSS by ~15 MB), then
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

/// An agent's side over iceoryx2.
pub struct ShmAgent {
    ports: AgentPorts,
    bell: Doorbell,
    cfg: Config,
    /// Kept for the ports' lifetime: the agent's registration in the run.
    _node: Node<S>,
    world: WorldWatch,
    terminated: std::cell::Cell<bool>,
}

/// An agent's ports on the run's services.
struct AgentPorts {
    /// Needed only to join: dropped once joined (each port is a shared
    /// memory connection the world maps too, 16 kB of its RSS per agent).
    joining: Option<JoinPorts>,
    snap_sub: Subscriber<S, [BodyState], SnapshotHeader>,
    cmd_pub: Publisher<S, CommandMsg, ()>,
    wake: Notifier<S>,
}

/// The ports an agent joins with.
struct JoinPorts {
    setup_sub: Subscriber<S, [u8], ()>,
    join_pub: Publisher<S, JoinRequest, ()>,
    reply_sub: Subscriber<S, JoinReply, ()>,
    /// Woken when join replies are published; snapshots ring the doorbell.
    tick: Listener<S>,
}

impl AgentPorts {
    fn joining(&self, what: &'static str) -> Result<&JoinPorts, TransportError> {
        self.joining.as_ref().ok_or_else(|| TransportError::Setup {
            what: what.to_string(),
            detail: "this agent has already joined (its join ports are closed)".to_string(),
        })
    }
}

impl ShmAgent {
    /// Opens the run's services as the agent called `node_name`, retrying
    /// until `timeout` if the world has not created them yet.
    pub fn connect(
        ns: &Namespace,
        node_name: &str,
        timeout: Duration,
    ) -> Result<Self, TransportError> {
        let start = Instant::now();
        // Hundreds of agents started with their world retry until it has
        // created the run's services: back off. Each attempt makes its own
        // node: a world started by hand clears the run's folder (what a
        // crashed earlier world left) and with it a node made before.
        let mut pause = Duration::from_millis(10);
        loop {
            match Self::try_connect(ns, node_name) {
                Ok(agent) => return Ok(agent),
                Err(e) if start.elapsed() >= timeout => return Err(e),
                Err(_) => {
                    std::thread::sleep(pause);
                    pause = (pause * 2).min(Duration::from_millis(200));
                }
            }
        }
    }

    fn try_connect(ns: &Namespace, node_name: &str) -> Result<Self, TransportError> {
        // The doorbell first, and only if its world is running: the node
        // and ports are then made after that world cleared what a killed
        // earlier world of the run left (see the `doorbell` module).
        let bell = Doorbell::open(ns)?;
        let cfg = config(ns)?;
        let node = node(&cfg, node_name)?;
        ns.make_private();
        let ports = Self::open(&node)?;
        Ok(Self {
            ports,
            bell,
            cfg,
            _node: node,
            world: WorldWatch::new(),
            terminated: std::cell::Cell::new(false),
        })
    }

    fn open(node: &Node<S>) -> Result<AgentPorts, TransportError> {
        let setup_sub = setup_subscriber(node)?;
        let snap_sub = snapshot_subscriber(node)?;
        let tick = node
            .service_builder(&service_name("mrsim/tick")?)
            .event()
            .open()
            .map_err(|e| setup_err("service mrsim/tick", e))?
            .listener_builder()
            .create()
            .map_err(|e| setup_err("tick listener", e))?;
        let reply_sub = node
            .service_builder(&service_name("mrsim/join-reply")?)
            .publish_subscribe::<JoinReply>()
            .open()
            .map_err(|e| setup_err("service mrsim/join-reply", e))?
            .subscriber_builder()
            .create()
            .map_err(|e| setup_err("join-reply subscriber", e))?;
        let join_pub = node
            .service_builder(&service_name("mrsim/join")?)
            .publish_subscribe::<JoinRequest>()
            .open()
            .map_err(|e| setup_err("service mrsim/join", e))?
            .publisher_builder()
            .create()
            .map_err(|e| setup_err("join publisher", e))?;
        let cmd_pub = node
            .service_builder(&service_name("mrsim/command")?)
            .publish_subscribe::<CommandMsg>()
            .open()
            .map_err(|e| setup_err("service mrsim/command", e))?
            .publisher_builder()
            .create()
            .map_err(|e| setup_err("command publisher", e))?;
        let wake = node
            .service_builder(&service_name("mrsim/wake")?)
            .event()
            .open()
            .map_err(|e| setup_err("service mrsim/wake", e))?
            .notifier_builder()
            .create()
            .map_err(|e| setup_err("wake notifier", e))?;
        Ok(AgentPorts {
            joining: Some(JoinPorts {
                setup_sub,
                join_pub,
                reply_sub,
                tick,
            }),
            snap_sub,
            cmd_pub,
            wake,
        })
    }
}

/// Publishes `cmd` and tells the world: an answer to a tick is counted on
/// the doorbell (the last one the world waits for wakes it), a ready
/// command wakes it through its listener.
fn send_command(
    cmd_pub: &Publisher<S, CommandMsg, ()>,
    wake: &Notifier<S>,
    bell: &Doorbell,
    cmd: &CommandMsg,
) -> Result<(), TransportError> {
    cmd_pub.send_copy(*cmd).map_err(|e| TransportError::Send {
        what: "command",
        detail: format!("{e:?}"),
    })?;
    if cmd.kind != mrsim_proto::command_kind::READY {
        return bell.answered(cmd.tick);
    }
    wake.notify_with_custom_event_id(EventId::new(events::COMMAND))
        .map_err(|e| TransportError::Send {
            what: "wake event",
            detail: format!("{e:?}"),
        })?;
    Ok(())
}

/// Whether a live world process holds run `ns` (its iceoryx2 node is
/// listed alive). A crashed world's node is listed dead, so this is false
/// for a run that only left stale shared memory behind.
pub fn world_running(ns: &Namespace) -> Result<bool, TransportError> {
    world_node_alive(&config(ns)?).ok_or_else(|| setup_err("node list", "cannot list nodes"))
}

/// Some(alive) if the node list could be read.
fn world_node_alive(cfg: &Config) -> Option<bool> {
    find_world(cfg).map(|w| w != WorldSeen::Gone)
}

/// What a scan of the run's iceoryx2 nodes says about the world.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum WorldSeen {
    /// Listed alive, owned by this process id.
    Alive(u32),
    /// A node whose state cannot be read (being created or cleaned up
    /// right now) may be the world: not proof that it is gone.
    Unsure,
    /// No live world node.
    Gone,
}

/// Scans the run's nodes for the world's (a directory walk over every
/// node of the run: with hundreds of agents, do it once and then watch the
/// process id, see [`WorldWatch`]).
fn find_world(cfg: &Config) -> Option<WorldSeen> {
    let mut seen = WorldSeen::Gone;
    let listed = Node::<S>::list(cfg, |state| {
        use iceoryx2::node::NodeView;
        match &state {
            NodeState::Alive(view) => match view.details() {
                Some(d) if d.name().as_str() == WORLD_NODE => {
                    seen = WorldSeen::Alive(d.process_id().value() as u32);
                    CallbackProgression::Stop
                }
                _ => CallbackProgression::Continue,
            },
            NodeState::Inaccessible(_) | NodeState::Undefined(_) => {
                seen = WorldSeen::Unsure;
                CallbackProgression::Continue
            }
            _ => CallbackProgression::Continue,
        }
    });
    listed.ok().map(|_| seen)
}

/// An agent's or observer's watch on the world process. An agent learns
/// the world's process id from its join reply; an observer finds it with
/// one scan of the run's node list. After that only the process id is
/// checked (one `kill(pid, 0)`): with hundreds of agents checking a few
/// times a second, a node-list scan each (O(agents²) file reads per second
/// on 2 cores) starved the very world they were waiting for.
#[derive(Debug)]
struct WorldWatch {
    pid: Option<u32>,
    last_check: Instant,
    missing: u32,
    alive: bool,
}

impl WorldWatch {
    fn new() -> Self {
        Self {
            pid: None,
            last_check: Instant::now(),
            missing: 0,
            alive: true,
        }
    }

    /// False once the world is known to be gone: two checks `every` apart
    /// both said so.
    fn alive(&mut self, cfg: &Config, every: Duration) -> bool {
        if !self.alive || self.last_check.elapsed() < every {
            return self.alive;
        }
        self.last_check = Instant::now();
        let seen = match self.pid {
            Some(pid) if mrsim_sys::process::pid_alive(pid) => WorldSeen::Alive(pid),
            Some(_) => WorldSeen::Gone,
            None => find_world(cfg).unwrap_or(WorldSeen::Unsure),
        };
        match seen {
            WorldSeen::Alive(pid) => {
                self.pid = Some(pid);
                self.missing = 0;
            }
            WorldSeen::Unsure => self.missing = 0,
            WorldSeen::Gone => {
                self.missing += 1;
                self.alive = self.missing < 2;
            }
        }
        self.alive
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

/// Subscribes to the run's setup.
fn setup_subscriber(node: &Node<S>) -> Result<Subscriber<S, [u8], ()>, TransportError> {
    node.service_builder(&service_name("mrsim/setup")?)
        .publish_subscribe::<[u8]>()
        .open()
        .map_err(|e| {
            setup_err(
                "service mrsim/setup (is a world running with this run id?)",
                e,
            )
        })?
        .subscriber_builder()
        .create()
        .map_err(|e| setup_err("setup subscriber", e))
}

/// Subscribes to the run's snapshots.
fn snapshot_subscriber(
    node: &Node<S>,
) -> Result<Subscriber<S, [BodyState], SnapshotHeader>, TransportError> {
    node.service_builder(&service_name("mrsim/snapshot")?)
        .publish_subscribe::<[BodyState]>()
        .user_header::<SnapshotHeader>()
        .open()
        .map_err(|e| setup_err("service mrsim/snapshot", e))?
        .subscriber_builder()
        .create()
        .map_err(|e| setup_err("snapshot subscriber", e))
}

/// The newest sample waiting on `sub`, the older ones received and
/// released on the way; `None` if none was waiting. Always to the empty
/// queue: one doorbell ring is not always one snapshot (a new subscriber
/// also gets the publisher's history, unrung), and taking the oldest of
/// two left an agent a tick behind for good.
fn newest_sample<T, H>(
    sub: &Subscriber<S, [T], H>,
    what: &'static str,
) -> Result<Option<Sample<S, [T], H>>, TransportError>
where
    T: std::fmt::Debug + ZeroCopySend + 'static,
    H: std::fmt::Debug + ZeroCopySend + 'static,
{
    let mut newest = None;
    loop {
        match sub.receive() {
            Ok(Some(s)) => newest = Some(s),
            Ok(None) => return Ok(newest),
            Err(e) => {
                return Err(TransportError::Receive {
                    what,
                    detail: format!("{e:?}"),
                });
            }
        }
    }
}

/// Copies the newest sample waiting on `sub` (header and slice) and
/// drops the older ones; false if none was waiting.
fn receive_newest<T, H>(
    sub: &Subscriber<S, [T], H>,
    what: &'static str,
    header: &mut H,
    out: &mut Vec<T>,
) -> Result<bool, TransportError>
where
    T: std::fmt::Debug + ZeroCopySend + Copy + 'static,
    H: std::fmt::Debug + ZeroCopySend + Copy + 'static,
{
    let Some(s) = newest_sample(sub, what)? else {
        return Ok(false);
    };
    *header = *s.user_header();
    out.clear();
    out.extend_from_slice(s.payload());
    Ok(true)
}

impl AgentTransport for ShmAgent {
    fn request_join(&mut self, req: &JoinRequest) -> Result<(), TransportError> {
        self.ports
            .joining("join publisher")?
            .join_pub
            .send_copy(*req)
            .map_err(|e| TransportError::Send {
                what: "join request",
                detail: format!("{e:?}"),
            })?;
        self.ports
            .wake
            .notify_with_custom_event_id(EventId::new(events::JOIN_REQUEST))
            .map_err(|e| TransportError::Send {
                what: "wake event",
                detail: format!("{e:?}"),
            })?;
        Ok(())
    }

    fn poll_join_reply(&mut self, nonce: u64) -> Result<Option<JoinReply>, TransportError> {
        loop {
            match self
                .ports
                .joining("join-reply subscriber")?
                .reply_sub
                .receive()
            {
                Ok(Some(s)) if s.payload().nonce == nonce => {
                    let reply = *s.payload();
                    if reply.world_pid != 0 {
                        self.world.pid = Some(reply.world_pid);
                    }
                    return Ok(Some(reply));
                }
                Ok(Some(_)) => continue,
                Ok(None) => return Ok(None),
                Err(e) => {
                    return Err(TransportError::Receive {
                        what: "join reply",
                        detail: format!("{e:?}"),
                    });
                }
            }
        }
    }

    fn setup(&mut self) -> Result<Option<Vec<u8>>, TransportError> {
        match self.ports.joining("setup subscriber")?.setup_sub.receive() {
            Ok(Some(s)) => Ok(Some(s.payload().to_vec())),
            Ok(None) => Ok(None),
            Err(e) => Err(TransportError::Receive {
                what: "setup",
                detail: format!("{e:?}"),
            }),
        }
    }

    fn wait(&mut self, timeout: Duration) -> Result<(), TransportError> {
        match &self.ports.joining {
            Some(j) => wait_on(&j.tick, timeout),
            None => self.bell.wait(timeout).map(|_| ()),
        }
    }

    fn latest_snapshot(
        &mut self,
        header: &mut SnapshotHeader,
        bodies: &mut Vec<BodyState>,
    ) -> Result<bool, TransportError> {
        receive_newest(&self.ports.snap_sub, "snapshot", header, bodies)
    }

    fn send_command(&mut self, cmd: &CommandMsg) -> Result<(), TransportError> {
        send_command(&self.ports.cmd_pub, &self.ports.wake, &self.bell, cmd)
    }

    fn with_latest_snapshot(
        &mut self,
        _scratch: &mut (SnapshotHeader, Vec<BodyState>),
        f: &mut crate::SnapshotFn<'_>,
    ) -> Result<bool, TransportError> {
        let Some(sample) = newest_sample(&self.ports.snap_sub, "snapshot")? else {
            return Ok(false);
        };
        let (cmd_pub, wake, bell) = (&self.ports.cmd_pub, &self.ports.wake, &self.bell);
        f(sample.user_header(), sample.payload(), &mut |m| {
            send_command(cmd_pub, wake, bell, m)
        });
        Ok(true)
    }

    fn joined(&mut self) {
        self.ports.joining = None;
    }

    fn world_alive(&mut self) -> bool {
        self.world.alive(&self.cfg, Duration::from_millis(200))
    }

    fn termination_requested(&self) -> bool {
        terminated(&self.terminated)
    }
}

/// A read-only observer over iceoryx2: subscribes to the setup, the
/// snapshots and the live statistics of a run, nothing else.
pub struct ShmObserver {
    cfg: Config,
    _node: Node<S>,
    setup_sub: Subscriber<S, [u8], ()>,
    snap_sub: Option<Subscriber<S, [BodyState], SnapshotHeader>>,
    stats_sub: Subscriber<S, [RobotStats], StatsHeader>,
    world: WorldWatch,
}

impl ShmObserver {
    /// Opens the run's services as the observer called `node_name`,
    /// retrying until `timeout` if the world has not created them yet.
    /// Without `snapshots` only the setup and the statistics are read (the
    /// launcher's progress bar needs no more).
    pub fn connect(
        ns: &Namespace,
        node_name: &str,
        snapshots: bool,
        timeout: Duration,
    ) -> Result<Self, TransportError> {
        let start = Instant::now();
        loop {
            match Self::try_connect(ns, node_name, snapshots) {
                Ok(o) => return Ok(o),
                Err(e) if start.elapsed() >= timeout => return Err(e),
                Err(_) => std::thread::sleep(Duration::from_millis(50)),
            }
        }
    }

    /// One attempt of [`ShmObserver::connect`].
    pub fn try_connect(
        ns: &Namespace,
        node_name: &str,
        snapshots: bool,
    ) -> Result<Self, TransportError> {
        // As an agent: nothing of a killed world (see the `doorbell` module).
        drop(Doorbell::open(ns)?);
        let cfg = config(ns)?;
        let node = node(&cfg, node_name)?;
        let setup_sub = setup_subscriber(&node)?;
        let stats_sub = node
            .service_builder(&service_name("mrsim/stats")?)
            .publish_subscribe::<[RobotStats]>()
            .user_header::<StatsHeader>()
            .open()
            .map_err(|e| setup_err("service mrsim/stats", e))?
            .subscriber_builder()
            .create()
            .map_err(|e| setup_err("stats subscriber", e))?;
        let snap_sub = if snapshots {
            Some(snapshot_subscriber(&node)?)
        } else {
            None
        };
        Ok(Self {
            cfg,
            _node: node,
            setup_sub,
            snap_sub,
            stats_sub,
            world: WorldWatch::new(),
        })
    }
}

impl ObserverTransport for ShmObserver {
    fn setup(&mut self) -> Result<Option<Vec<u8>>, TransportError> {
        let mut newest = None;
        loop {
            match self.setup_sub.receive() {
                Ok(Some(s)) => newest = Some(s.payload().to_vec()),
                Ok(None) => return Ok(newest),
                Err(e) => {
                    return Err(TransportError::Receive {
                        what: "setup",
                        detail: format!("{e:?}"),
                    });
                }
            }
        }
    }

    fn latest_snapshot(
        &mut self,
        header: &mut SnapshotHeader,
        bodies: &mut Vec<BodyState>,
    ) -> Result<bool, TransportError> {
        let Some(sub) = &self.snap_sub else {
            return Ok(false);
        };
        receive_newest(sub, "snapshot", header, bodies)
    }

    fn latest_stats(
        &mut self,
        header: &mut StatsHeader,
        robots: &mut Vec<RobotStats>,
    ) -> Result<bool, TransportError> {
        receive_newest(&self.stats_sub, "stats", header, robots)
    }

    fn world_alive(&mut self) -> bool {
        self.world.alive(&self.cfg, Duration::from_millis(250))
    }
}
