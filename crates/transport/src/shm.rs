//! The iceoryx2 transport: zero-copy shared memory between processes.
//!
//! Services of one run (all under the run's prefix and root path):
//!
//! | service | pattern | from -> to |
//! | --- | --- | --- |
//! | `mrsim/setup` | publish-subscribe `[u8]`, history 1 | world -> agents |
//! | `mrsim/snapshot` | publish-subscribe `[BodyState]` + `SnapshotHeader` | world -> agents |
//! | `mrsim/tick` | event | world -> agents |
//! | `mrsim/join` | publish-subscribe `JoinRequest` | agents -> world |
//! | `mrsim/join-reply` | publish-subscribe `JoinReply` | world -> agents |
//! | `mrsim/command` | publish-subscribe `CommandMsg` | agents -> world |
//! | `mrsim/wake` | event, notifier-dead event | agents -> world |
//!
//! Limits (publishers, subscribers, listeners, notifiers, nodes) are raised
//! from the scenario's robot count, with room to spare for restarted agents,
//! strangers and observers. Waiting is event driven (no busy polling).

use crate::{AgentTransport, Capacity, Namespace, TransportError, WorldTransport};
use iceoryx2::port::listener::Listener;
use iceoryx2::port::notifier::Notifier;
use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::port::update_connections::UpdateConnections;
use iceoryx2::prelude::*;
use mrsim_proto::{BodyState, CommandMsg, JoinReply, JoinRequest, SnapshotHeader, events, now_ns};
use std::os::unix::fs::PermissionsExt;
use std::time::{Duration, Instant};

type S = ipc::Service;

/// Name of the world's iceoryx2 node.
pub const WORLD_NODE: &str = "mrsim-world";

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
pub fn config(ns: &Namespace) -> Result<Config, TransportError> {
    let mut cfg = Config::default();
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

/// Waits for events on `listener`; a signal interrupting the wait (EINTR)
/// is a spurious wake-up, not an error: callers check termination and the
/// clock themselves.
fn wait_on(listener: &Listener<S>, timeout: Duration) -> Result<(), TransportError> {
    use iceoryx2::port::listener::ListenerWaitError;
    match listener.timed_wait(|_| {}, timeout) {
        Ok(_) | Err(ListenerWaitError::InterruptSignal) => Ok(()),
        Err(e) => Err(TransportError::Wait(format!("{e:?}"))),
    }
}

fn terminated(node: &Node<S>) -> bool {
    node.wait(Duration::ZERO).is_err()
}

/// The world's side over iceoryx2.
pub struct ShmWorld {
    node: Node<S>,
    setup_pub: Publisher<S, [u8], ()>,
    snap_pub: Publisher<S, [BodyState], SnapshotHeader>,
    tick: Notifier<S>,
    cmd_sub: Subscriber<S, CommandMsg, ()>,
    join_sub: Subscriber<S, JoinRequest, ()>,
    reply_pub: Publisher<S, JoinReply, ()>,
    wake: Listener<S>,
    max_bodies: usize,
}

impl ShmWorld {
    /// Creates every service of the run. Fails if another world of the same
    /// run already exists.
    pub fn create(
        ns: &Namespace,
        cap: Capacity,
        max_bodies: usize,
        max_setup_len: usize,
    ) -> Result<Self, TransportError> {
        let cfg = config(ns)?;
        let node = node(&cfg, WORLD_NODE)?;
        // A crashed earlier run of the same id may have left dead nodes.
        let _ = node.try_cleanup_dead_nodes();
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

        let snap = node
            .service_builder(&service_name("mrsim/snapshot")?)
            .publish_subscribe::<[BodyState]>()
            .user_header::<SnapshotHeader>()
            .history_size(1)
            .subscriber_max_buffer_size(2)
            .max_publishers(1)
            .max_subscribers(agents + 2)
            .max_nodes(nodes)
            .create()
            .map_err(|e| setup_err("service mrsim/snapshot", e))?;
        let snap_pub = snap
            .publisher_builder()
            .initial_max_slice_len(max_bodies.max(1))
            .create()
            .map_err(|e| setup_err("snapshot publisher", e))?;

        let tick_service = node
            .service_builder(&service_name("mrsim/tick")?)
            .event()
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
            // Every agent sees every reply: with hundreds joining at once,
            // a small buffer drops an agent's own reply before it polls.
            .subscriber_max_buffer_size((agents + 2).clamp(8, 128))
            .max_publishers(1)
            .max_subscribers(agents + 2)
            .max_nodes(nodes)
            .create()
            .map_err(|e| setup_err("service mrsim/join-reply", e))?;
        let reply_pub = reply
            .publisher_builder()
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

        Ok(Self {
            node,
            setup_pub,
            snap_pub,
            tick,
            cmd_sub,
            join_sub,
            reply_pub,
            wake,
            max_bodies,
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
        let mut sample = self
            .snap_pub
            .loan_slice_uninit(n)
            .map_err(|e| TransportError::Send {
                what: "snapshot",
                detail: format!("{e:?}"),
            })?;
        *sample.user_header_mut() = *header;
        let sample = sample.write_from_slice(&bodies[..n]);
        sample.send().map_err(|e| TransportError::Send {
            what: "snapshot",
            detail: format!("{e:?}"),
        })?;
        self.tick
            .notify_with_custom_event_id(EventId::new(events::SNAPSHOT))
            .map_err(|e| TransportError::Send {
                what: "tick event",
                detail: format!("{e:?}"),
            })?;
        Ok(())
    }

    fn wait(&mut self, timeout: Duration) -> Result<(), TransportError> {
        wait_on(&self.wake, timeout)
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
        terminated(&self.node)
    }

    fn cleanup_dead(&mut self) {
        let _ = self.node.try_cleanup_dead_nodes();
    }
}

/// An agent's side over iceoryx2.
pub struct ShmAgent {
    cfg: Config,
    node: Node<S>,
    setup_sub: Subscriber<S, [u8], ()>,
    snap_sub: Subscriber<S, [BodyState], SnapshotHeader>,
    tick: Listener<S>,
    join_pub: Publisher<S, JoinRequest, ()>,
    reply_sub: Subscriber<S, JoinReply, ()>,
    cmd_pub: Publisher<S, CommandMsg, ()>,
    wake: Notifier<S>,
    last_world_check: Instant,
    world_alive: bool,
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
        loop {
            match Self::try_connect(ns, node_name) {
                Ok(agent) => return Ok(agent),
                Err(e) if start.elapsed() >= timeout => return Err(e),
                Err(_) => std::thread::sleep(Duration::from_millis(50)),
            }
        }
    }

    fn try_connect(ns: &Namespace, node_name: &str) -> Result<Self, TransportError> {
        let cfg = config(ns)?;
        let node = node(&cfg, node_name)?;
        let setup_sub = node
            .service_builder(&service_name("mrsim/setup")?)
            .publish_subscribe::<[u8]>()
            .open()
            .map_err(|e| {
                setup_err(
                    "service mrsim/setup (is the world running with this run id?)",
                    e,
                )
            })?
            .subscriber_builder()
            .create()
            .map_err(|e| setup_err("setup subscriber", e))?;
        let snap_sub = node
            .service_builder(&service_name("mrsim/snapshot")?)
            .publish_subscribe::<[BodyState]>()
            .user_header::<SnapshotHeader>()
            .open()
            .map_err(|e| setup_err("service mrsim/snapshot", e))?
            .subscriber_builder()
            .create()
            .map_err(|e| setup_err("snapshot subscriber", e))?;
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
        Ok(Self {
            cfg,
            node,
            setup_sub,
            snap_sub,
            tick,
            join_pub,
            reply_sub,
            cmd_pub,
            wake,
            last_world_check: Instant::now(),
            world_alive: true,
        })
    }

    fn check_world(&mut self) -> bool {
        let mut alive = false;
        let listed = Node::<S>::list(&self.cfg, |state| {
            if let NodeState::Alive(view) = &state {
                use iceoryx2::node::NodeView;
                if view
                    .details()
                    .as_ref()
                    .is_some_and(|d| d.name().as_str() == WORLD_NODE)
                {
                    alive = true;
                    return CallbackProgression::Stop;
                }
            }
            CallbackProgression::Continue
        });
        listed.is_err() || alive
    }
}

impl AgentTransport for ShmAgent {
    fn request_join(&mut self, req: &JoinRequest) -> Result<(), TransportError> {
        self.join_pub
            .send_copy(*req)
            .map_err(|e| TransportError::Send {
                what: "join request",
                detail: format!("{e:?}"),
            })?;
        self.wake
            .notify_with_custom_event_id(EventId::new(events::JOIN_REQUEST))
            .map_err(|e| TransportError::Send {
                what: "wake event",
                detail: format!("{e:?}"),
            })?;
        Ok(())
    }

    fn poll_join_reply(&mut self, nonce: u64) -> Result<Option<JoinReply>, TransportError> {
        loop {
            match self.reply_sub.receive() {
                Ok(Some(s)) if s.payload().nonce == nonce => return Ok(Some(*s.payload())),
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
        match self.setup_sub.receive() {
            Ok(Some(s)) => Ok(Some(s.payload().to_vec())),
            Ok(None) => Ok(None),
            Err(e) => Err(TransportError::Receive {
                what: "setup",
                detail: format!("{e:?}"),
            }),
        }
    }

    fn wait(&mut self, timeout: Duration) -> Result<(), TransportError> {
        wait_on(&self.tick, timeout)
    }

    fn latest_snapshot(
        &mut self,
        header: &mut SnapshotHeader,
        bodies: &mut Vec<BodyState>,
    ) -> Result<bool, TransportError> {
        let mut got = false;
        loop {
            match self.snap_sub.receive() {
                Ok(Some(s)) => {
                    *header = *s.user_header();
                    bodies.clear();
                    bodies.extend_from_slice(s.payload());
                    got = true;
                }
                Ok(None) => return Ok(got),
                Err(e) => {
                    return Err(TransportError::Receive {
                        what: "snapshot",
                        detail: format!("{e:?}"),
                    });
                }
            }
        }
    }

    fn send_command(&mut self, cmd: &CommandMsg) -> Result<(), TransportError> {
        self.cmd_pub
            .send_copy(*cmd)
            .map_err(|e| TransportError::Send {
                what: "command",
                detail: format!("{e:?}"),
            })?;
        self.wake
            .notify_with_custom_event_id(EventId::new(events::COMMAND))
            .map_err(|e| TransportError::Send {
                what: "wake event",
                detail: format!("{e:?}"),
            })?;
        Ok(())
    }

    fn world_alive(&mut self) -> bool {
        if self.world_alive && self.last_world_check.elapsed() >= Duration::from_millis(200) {
            self.last_world_check = Instant::now();
            self.world_alive = self.check_world();
        }
        self.world_alive
    }

    fn termination_requested(&self) -> bool {
        terminated(&self.node)
    }
}
