//! An agent's side over iceoryx2 ([`ShmAgent`]): it joins through the
//! join ports, then reads each snapshot straight from the world's sample
//! and answers with one command, counted on the doorbell.

use super::doorbell::Doorbell;
use super::service::{
    S, config, newest_sample, node, receive_newest, service_name, setup_err, setup_subscriber,
    snapshot_subscriber, terminated, wait_on,
};
use super::watch::WorldWatch;
use crate::{AgentTransport, Namespace, TransportError};
use iceoryx2::port::listener::Listener;
use iceoryx2::port::notifier::Notifier;
use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::*;
use mrsim_proto::{BodyState, CommandMsg, JoinReply, JoinRequest, SnapshotHeader, events};
use std::time::{Duration, Instant};

/// An agent's side over iceoryx2.
pub struct ShmAgent {
    ports: AgentPorts,
    bell: Doorbell,
    cfg: Config,
    /// Kept for the ports' lifetime: the agent's registration in the run.
    _node: Node<S>,
    world: WorldWatch,
    terminated: std::cell::Cell<bool>,
    /// The nonces this agent joined with, and replies to them received
    /// while it looked for another one's (an agent driving several robots
    /// asks for each with its own nonce, and every agent receives every
    /// reply).
    asked: std::collections::HashSet<u64>,
    replies: std::collections::HashMap<u64, JoinReply>,
}

/// An agent's ports on the run's services.
struct AgentPorts {
    /// Needed only to join: dropped once joined (each port is a shared
    /// memory connection the world maps too).
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
            asked: Default::default(),
            replies: Default::default(),
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

impl AgentTransport for ShmAgent {
    fn request_join(&mut self, req: &JoinRequest) -> Result<(), TransportError> {
        self.asked.insert(req.nonce);
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
                Ok(Some(s)) => {
                    let reply = *s.payload();
                    if self.asked.contains(&reply.nonce) {
                        if reply.world_pid != 0 {
                            self.world.pid = Some(reply.world_pid);
                        }
                        self.replies.insert(reply.nonce, reply);
                    }
                }
                Ok(None) => break,
                Err(e) => {
                    return Err(TransportError::Receive {
                        what: "join reply",
                        detail: format!("{e:?}"),
                    });
                }
            }
        }
        Ok(self.replies.remove(&nonce))
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
