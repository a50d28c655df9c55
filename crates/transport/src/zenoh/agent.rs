//! An agent's side over Zenoh ([`ZenohAgent`]): a client session to the
//! world, a liveliness token of its own, the world's token watched, one
//! subscriber of snapshots and a publisher of commands (and, while
//! joining, the join ports).

use super::inbox::{AgentInbox, lock};
use super::keys::Keys;
use super::wire::{self, decode_slice};
use super::{Role, ZenohOptions, declare_err, open, send_err, terminated};
use crate::{AgentTransport, Namespace, TransportError};
use mrsim_proto::{BodyState, CommandMsg, JoinReply, JoinRequest, SnapshotHeader};
use std::sync::Arc;
use std::time::{Duration, Instant};
use zenoh::Wait;
use zenoh::liveliness::LivelinessToken;
use zenoh::pubsub::{Publisher, Subscriber};
use zenoh::qos::{CongestionControl, Priority};
use zenoh::sample::SampleKind;

/// An agent's side over Zenoh.
pub struct ZenohAgent {
    session: zenoh::Session,
    keys: Keys,
    inbox: Arc<AgentInbox>,
    joining: Option<JoinPorts>,
    cmd_pub: Publisher<'static>,
    _snap_sub: Subscriber<()>,
    _world_sub: Subscriber<()>,
    _token: LivelinessToken,
    max_bodies: usize,
    terminated: std::cell::Cell<bool>,
    /// Forged and replayed snapshots already reported.
    reported: (u64, u64),
}

/// The ports an agent joins with, closed once it has joined.
struct JoinPorts {
    join_pub: Publisher<'static>,
    _reply_sub: Subscriber<()>,
    setup: Option<Vec<u8>>,
}

/// Most bodies an agent accepts in one snapshot (more is garbage).
const MAX_BODIES: usize = 1 << 20;

impl ZenohAgent {
    /// Connects to the world of run `ns` as `opts` says, retrying until
    /// `timeout` if the world is not there yet (not listening, or listening
    /// without this run's world token).
    pub fn connect(
        ns: &Namespace,
        opts: &ZenohOptions,
        timeout: Duration,
    ) -> Result<Self, TransportError> {
        let start = Instant::now();
        let mut pause = Duration::from_millis(20);
        let session = loop {
            match open(opts, Role::Client) {
                Ok(s) => break s,
                Err(e) if start.elapsed() >= timeout => {
                    return Err(TransportError::Setup {
                        what: "the world's zenoh session".to_string(),
                        detail: format!(
                            "{e} (is the world listening there, and do the credentials match?)"
                        ),
                    });
                }
                Err(_) => {
                    std::thread::sleep(pause);
                    pause = (pause * 2).min(Duration::from_millis(500));
                }
            }
        };
        let keys = Keys::new(ns);
        let inbox = Arc::new(AgentInbox::default());
        let i = inbox.clone();
        let world_sub = session
            .liveliness()
            .declare_subscriber(keys.world_alive.clone())
            .history(true)
            .callback(move |s| i.world(s.kind() == SampleKind::Put))
            .wait()
            .map_err(|e| declare_err("world liveliness subscriber", e))?;
        let i = inbox.clone();
        let snap_sub = session
            .declare_subscriber(keys.snapshot.clone())
            .callback(move |s| i.snapshot(&s.payload().to_bytes()))
            .wait()
            .map_err(|e| declare_err("snapshot subscriber", e))?;
        let i = inbox.clone();
        let reply_sub = session
            .declare_subscriber(keys.join_reply.clone())
            .callback(move |s| i.reply(&s.payload().to_bytes()))
            .wait()
            .map_err(|e| declare_err("join-reply subscriber", e))?;
        let publisher = |key: &str, what: &str| {
            session
                .declare_publisher(key.to_string())
                .congestion_control(CongestionControl::Block)
                .priority(Priority::RealTime)
                .express(true)
                .wait()
                .map_err(|e| declare_err(what, e))
        };
        let cmd_pub = publisher(&keys.command, "command publisher")?;
        let join_pub = publisher(&keys.join, "join publisher")?;
        let token = session
            .liveliness()
            .declare_token(keys.agent_token(std::process::id()))
            .wait()
            .map_err(|e| declare_err("agent liveliness token", e))?;
        let agent = Self {
            session,
            keys,
            inbox,
            joining: Some(JoinPorts {
                join_pub,
                _reply_sub: reply_sub,
                setup: None,
            }),
            cmd_pub,
            _snap_sub: snap_sub,
            _world_sub: world_sub,
            _token: token,
            max_bodies: MAX_BODIES,
            terminated: std::cell::Cell::new(false),
            reported: (0, 0),
        };
        // The world of this run, not just something listening.
        while !lock(&agent.inbox.state).world_present {
            if start.elapsed() >= timeout {
                return Err(TransportError::Setup {
                    what: format!("the world of run `{}`", ns.run_id()),
                    detail: "connected, but no world of this run answers there".to_string(),
                });
            }
            agent.inbox.wait(Duration::from_millis(100));
        }
        Ok(agent)
    }

    fn joining(&mut self, what: &'static str) -> Result<&mut JoinPorts, TransportError> {
        self.joining.as_mut().ok_or_else(|| TransportError::Setup {
            what: what.to_string(),
            detail: "this agent has already joined (its join ports are closed)".to_string(),
        })
    }

    /// Snapshots refused so far: failed authentication, and replayed.
    pub fn snapshots_refused(&self) -> (u64, u64) {
        let s = lock(&self.inbox.state);
        (s.forged, s.replayed)
    }

    /// Says on stderr when more snapshots were refused since the last
    /// report (at most a line per snapshot taken).
    fn report_refusals(&mut self) {
        let now = self.snapshots_refused();
        if now != self.reported {
            eprintln!(
                "agent: zenoh: refused {} snapshot(s) that failed authentication and {} replayed (so far)",
                now.0, now.1
            );
            self.reported = now;
        }
    }
}

impl Drop for ZenohAgent {
    fn drop(&mut self) {
        self.report_refusals();
    }
}

/// Asks the world of `keys` for the setup (blocks up to a second).
pub(super) fn query_setup(
    session: &zenoh::Session,
    keys: &Keys,
) -> Result<Option<Vec<u8>>, TransportError> {
    let replies = session
        .get(keys.setup.clone())
        .timeout(Duration::from_secs(1))
        .wait()
        .map_err(|e| TransportError::Receive {
            what: "setup",
            detail: e.to_string(),
        })?;
    while let Ok(reply) = replies.recv() {
        if let Ok(sample) = reply.result() {
            return Ok(Some(sample.payload().to_bytes().into_owned()));
        }
    }
    Ok(None)
}

impl AgentTransport for ZenohAgent {
    fn request_join(&mut self, req: &JoinRequest) -> Result<(), TransportError> {
        let bytes = wire::encode(req);
        // Its accepted reply brings the key of the run's snapshots.
        lock(&self.inbox.state).nonce = Some(req.nonce);
        self.joining("join publisher")?
            .join_pub
            .put(bytes)
            .wait()
            .map_err(|e| send_err("join request", e))
    }

    fn poll_join_reply(&mut self, nonce: u64) -> Result<Option<JoinReply>, TransportError> {
        self.joining("join-reply subscriber")?;
        let mut s = lock(&self.inbox.state);
        let found = s.replies.iter().position(|(r, _)| r.nonce == nonce);
        let reply = found.map(|i| s.replies[i].clone());
        s.replies.clear();
        match reply {
            Some((r, None)) if r.accepted == 1 => Err(TransportError::Setup {
                what: "the world's join reply".to_string(),
                detail: "it accepted this agent but sent no key for the run's snapshots (a world of another mrsim version?)".to_string(),
            }),
            Some((r, _)) => Ok(Some(r)),
            None => Ok(None),
        }
    }

    fn setup(&mut self) -> Result<Option<Vec<u8>>, TransportError> {
        if let Some(s) = &self.joining("setup query")?.setup {
            return Ok(Some(s.clone()));
        }
        let got = query_setup(&self.session, &self.keys)?;
        self.joining("setup query")?.setup = got.clone();
        Ok(got)
    }

    fn wait(&mut self, timeout: Duration) -> Result<(), TransportError> {
        self.inbox.wait(timeout);
        Ok(())
    }

    fn latest_snapshot(
        &mut self,
        header: &mut SnapshotHeader,
        bodies: &mut Vec<BodyState>,
    ) -> Result<bool, TransportError> {
        let mut s = lock(&self.inbox.state);
        let max = self.max_bodies;
        let got = s.take_snapshot(|m| decode_slice(m, max, header, bodies));
        if got == Some(false) {
            s.refused += 1;
        }
        drop(s);
        self.report_refusals();
        Ok(got == Some(true))
    }

    fn send_command(&mut self, cmd: &CommandMsg) -> Result<(), TransportError> {
        self.cmd_pub
            .put(wire::encode(cmd))
            .wait()
            .map_err(|e| send_err("command", e))
    }

    fn world_alive(&mut self) -> bool {
        let s = lock(&self.inbox.state);
        !s.world_seen || s.world_present
    }

    fn termination_requested(&self) -> bool {
        terminated(&self.terminated)
    }

    fn joined(&mut self) {
        self.joining = None;
    }
}
