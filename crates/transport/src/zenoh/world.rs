//! The world's side over Zenoh ([`ZenohWorld`]): a peer session that
//! listens, answers the setup query, publishes snapshots, join replies
//! and statistics, and takes in commands and join requests through its
//! inbox.

use super::auth::AuthWatch;
use super::inbox::{WorldInbox, encode_reply, lock};
use super::keys::Keys;
use super::seal::{RunKey, TAG_LEN};
use super::wire::{self, encode_slice};
use super::{Role, ZenohOptions, declare_err, open, send_err, terminated};
use crate::{Capacity, Namespace, NetworkCounts, TransportError, WorldTransport};
use mrsim_proto::{
    BodyState, CommandMsg, JoinReply, JoinRequest, RobotStats, SnapshotHeader, StatsHeader,
};
use std::sync::Arc;
use std::time::{Duration, Instant};
use zenoh::Wait;
use zenoh::liveliness::LivelinessToken;
use zenoh::pubsub::{Publisher, Subscriber};
use zenoh::qos::{CongestionControl, Priority};
use zenoh::query::Queryable;
use zenoh::sample::SampleKind;

/// The world's side over Zenoh.
pub struct ZenohWorld {
    session: zenoh::Session,
    keys: Keys,
    inbox: Arc<WorldInbox>,
    snap_pub: Publisher<'static>,
    reply_pub: Publisher<'static>,
    stats_pub: Publisher<'static>,
    setup_queryable: Option<Queryable<()>>,
    _cmd_sub: Subscriber<()>,
    _join_sub: Subscriber<()>,
    _agents_sub: Subscriber<()>,
    _token: LivelinessToken,
    buf: Vec<u8>,
    max_bodies: usize,
    max_robots: usize,
    terminated: std::cell::Cell<bool>,
    /// Refused and dropped messages already reported.
    reported: (u64, u64),
    /// Connections refused for failed authentication (`None`: cannot be
    /// heard in this process).
    auth: Option<AuthWatch>,
    auth_lines: AuthLines,
    /// The key every snapshot is signed with (agents get it when they join).
    key: RunKey,
}

impl ZenohWorld {
    /// Opens the world's session (listening as `opts` says) and declares
    /// everything of run `ns` (at most `max_bodies` bodies per snapshot, a
    /// setup of about `setup_len` bytes). Fails if the address is taken.
    pub fn create(
        ns: &Namespace,
        opts: &ZenohOptions,
        cap: Capacity,
        max_bodies: usize,
        setup_len: usize,
    ) -> Result<Self, TransportError> {
        // Listening for refused handshakes before the first can come.
        let auth = AuthWatch::new();
        if auth.is_none() {
            eprintln!(
                "world: zenoh: another tracing subscriber owns this process: connections refused for failed authentication are not counted"
            );
        }
        use wire::Wire;
        let largest_message = (SnapshotHeader::LEN + max_bodies * BodyState::LEN + TAG_LEN)
            .max(StatsHeader::LEN + cap.robots * RobotStats::LEN)
            .max(setup_len);
        let key = RunKey::generate()?;
        let session = open(opts, Role::World { largest_message })?;
        let keys = Keys::new(ns);
        // Room for every agent's command of a few ticks, then a flood is
        // dropped rather than kept.
        let inbox = Arc::new(WorldInbox::new(cap.messages() * 8 + 256));

        let i = inbox.clone();
        let cmd_sub = session
            .declare_subscriber(keys.command.clone())
            .callback(move |s| i.command(&s.payload().to_bytes()))
            .wait()
            .map_err(|e| declare_err("command subscriber", e))?;
        let i = inbox.clone();
        let join_sub = session
            .declare_subscriber(keys.join.clone())
            .callback(move |s| i.join(&s.payload().to_bytes()))
            .wait()
            .map_err(|e| declare_err("join subscriber", e))?;
        let (i, k) = (inbox.clone(), keys.clone());
        let agents_sub = session
            .liveliness()
            .declare_subscriber(format!("{}/*", keys.agent_alive))
            .history(true)
            .callback(move |s| {
                if let Some(pid) = k.agent_pid(s.key_expr().as_str()) {
                    i.token(pid, s.kind() == SampleKind::Put);
                }
            })
            .wait()
            .map_err(|e| declare_err("agents' liveliness subscriber", e))?;
        let publisher = |key: &str, cc: CongestionControl, what: &str| {
            session
                .declare_publisher(key.to_string())
                .congestion_control(cc)
                .priority(Priority::RealTime)
                .express(true)
                .wait()
                .map_err(|e| declare_err(what, e))
        };
        // Snapshots and replies wait for a full send queue rather than be
        // lost (lockstep would stall on a lost snapshot); statistics are
        // dropped instead (observers need only the newest).
        let snap_pub = publisher(
            &keys.snapshot,
            CongestionControl::Block,
            "snapshot publisher",
        )?;
        let reply_pub = publisher(
            &keys.join_reply,
            CongestionControl::Block,
            "reply publisher",
        )?;
        let stats_pub = publisher(&keys.stats, CongestionControl::Drop, "stats publisher")?;
        let token = session
            .liveliness()
            .declare_token(keys.world_alive.clone())
            .wait()
            .map_err(|e| declare_err("world liveliness token", e))?;
        Ok(Self {
            session,
            keys,
            inbox,
            snap_pub,
            reply_pub,
            stats_pub,
            setup_queryable: None,
            _cmd_sub: cmd_sub,
            _join_sub: join_sub,
            _agents_sub: agents_sub,
            _token: token,
            buf: Vec::new(),
            max_bodies,
            max_robots: cap.robots,
            terminated: std::cell::Cell::new(false),
            reported: (0, 0),
            auth,
            auth_lines: AuthLines::default(),
            key,
        })
    }

    /// What was refused or dropped so far.
    pub fn counts(&self) -> NetworkCounts {
        let s = lock(&self.inbox.state);
        NetworkCounts {
            auth_refused: self.auth.as_ref().map_or(0, AuthWatch::total),
            commands_malformed: s.refused_commands,
            joins_malformed: s.refused_joins,
            dropped: s.dropped,
        }
    }

    /// Says on stderr when more bad or excess messages came since the last
    /// report (at most a line per call, called with each drain), and each
    /// connection refused for failed authentication.
    fn report_refusals(&mut self) {
        let c = self.counts();
        let refused = c.commands_malformed + c.joins_malformed;
        if (refused, c.dropped) != self.reported {
            eprintln!(
                "world: zenoh: refused {refused} malformed message(s), dropped {} over the inbox limit (so far)",
                c.dropped
            );
            self.reported = (refused, c.dropped);
        }
        if let Some(auth) = &self.auth {
            let (peers, _) = auth.take();
            for line in self.auth_lines.add(hosts(peers), Instant::now()) {
                eprintln!("world: zenoh: {line}: authentication failed");
            }
        }
    }
}

impl WorldTransport for ZenohWorld {
    fn network_counts(&self) -> Option<NetworkCounts> {
        Some(self.counts())
    }

    fn publish_setup(&mut self, setup: &[u8]) -> Result<(), TransportError> {
        let bytes = zenoh::bytes::ZBytes::from(setup.to_vec());
        let key = self.keys.setup.clone();
        let q = self
            .session
            .declare_queryable(self.keys.setup.clone())
            .callback(move |query| {
                let _ = query.reply(key.clone(), bytes.clone()).wait();
            })
            .wait()
            .map_err(|e| declare_err("setup queryable", e))?;
        self.setup_queryable = Some(q);
        Ok(())
    }

    fn publish_snapshot(
        &mut self,
        header: &SnapshotHeader,
        bodies: &[BodyState],
    ) -> Result<(), TransportError> {
        let n = bodies.len().min(self.max_bodies);
        encode_slice(header, &bodies[..n], &mut self.buf);
        self.key.seal(&mut self.buf);
        self.snap_pub
            .put(self.buf.clone())
            .wait()
            .map_err(|e| send_err("snapshot", e))
    }

    fn wait(&mut self, timeout: Duration) -> Result<(), TransportError> {
        let g = lock(&self.inbox.state);
        drop(self.inbox.waker.wait(g, |s| &mut s.woken, timeout));
        Ok(())
    }

    fn drain_commands(&mut self, f: &mut dyn FnMut(CommandMsg, u64)) -> Result<(), TransportError> {
        let taken = self.inbox.take_commands();
        for (c, at) in &taken {
            f(*c, *at);
        }
        // The vector goes back (emptied) so that the callbacks do not
        // allocate each tick.
        let mut s = lock(&self.inbox.state);
        if s.commands.is_empty() {
            let mut v = taken;
            v.clear();
            s.commands = v;
        }
        drop(s);
        self.report_refusals();
        Ok(())
    }

    fn drain_joins(&mut self, f: &mut dyn FnMut(JoinRequest)) -> Result<(), TransportError> {
        let taken = std::mem::take(&mut lock(&self.inbox.state).joins);
        for j in taken {
            f(j);
        }
        self.report_refusals();
        Ok(())
    }

    fn reply_join(&mut self, reply: &JoinReply) -> Result<(), TransportError> {
        if reply.accepted == 1 {
            self.inbox.issued(reply.token);
        }
        self.reply_pub
            .put(encode_reply(reply, &self.key))
            .wait()
            .map_err(|e| send_err("join reply", e))
    }

    fn termination_requested(&self) -> bool {
        terminated(&self.terminated)
    }

    fn expect_answers(&mut self, tick: u64, count: usize) {
        self.inbox.expect(tick, count);
    }

    fn joins_answered(&mut self) -> Result<(), TransportError> {
        // Each reply wakes its agent when it arrives. An agent that joins
        // mid-run subscribed after the current tick's snapshot went out
        // (shared memory keeps the last one for it; Zenoh does not): it
        // goes out again, after the replies on the same link, or a
        // lockstep world would wait for an answer to a snapshot its new
        // agent never saw. Agents that answered it already skip it.
        if !self.buf.is_empty() {
            self.snap_pub
                .put(self.buf.clone())
                .wait()
                .map_err(|e| send_err("snapshot", e))?;
        }
        Ok(())
    }

    fn cleanup_dead(&mut self) {
        // Nothing is left behind: a dead agent's session and token go with
        // its connection.
    }

    fn prepare_ticks(&mut self) -> Result<bool, TransportError> {
        // Routes are set up when subscribers are declared: nothing to take
        // up before tick 0.
        Ok(false)
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
        let mut buf = Vec::new();
        encode_slice(&header, &robots[..n], &mut buf);
        self.stats_pub
            .put(buf)
            .wait()
            .map_err(|e| send_err("stats", e))
    }

    fn agent_alive(&self, pid: u32) -> Option<bool> {
        Some(self.inbox.alive(pid))
    }
}

/// The host of each refused peer (an agent retries from a fresh port
/// each time: the port says nothing).
fn hosts(peers: Vec<Option<String>>) -> Vec<String> {
    peers
        .into_iter()
        .map(|p| match p {
            Some(p) => match p.rsplit_once(':') {
                Some((host, _)) => host.to_string(),
                None => p,
            },
            None => "an unknown address".to_string(),
        })
        .collect()
}

/// How often at most the world repeats that a host keeps failing.
const AUTH_REPEAT: Duration = Duration::from_secs(5);

/// The world's lines about refused connections: a host's first refusal
/// at once, then (an agent retries for as long as its timeout) at most a
/// line per host every [`AUTH_REPEAT`] with how many came since.
#[derive(Default)]
struct AuthLines {
    /// Per host: when it was last reported, refusals not reported yet.
    hosts: Vec<(String, Instant, u64)>,
}

impl AuthLines {
    /// The lines to print now, given the hosts refused since the last call.
    fn add(&mut self, refused: Vec<String>, now: Instant) -> Vec<String> {
        let mut lines = Vec::new();
        for host in refused {
            match self.hosts.iter_mut().find(|(h, _, _)| *h == host) {
                Some((_, _, n)) => *n += 1,
                None => {
                    lines.push(format!("refused a connection from {host}"));
                    self.hosts.push((host, now, 0));
                }
            }
        }
        for (host, last, n) in &mut self.hosts {
            if *n > 0 && now.duration_since(*last) >= AUTH_REPEAT {
                lines.push(match *n {
                    1 => format!("refused a connection from {host}"),
                    n => format!("refused {n} connections from {host}"),
                });
                (*last, *n) = (now, 0);
            }
        }
        lines
    }
}

#[cfg(test)]
mod auth_line_tests {
    use super::*;

    #[test]
    fn a_host_that_keeps_failing_is_reported_at_once_then_summed_up() {
        let mut l = AuthLines::default();
        let t = Instant::now();
        let h = || vec!["tcp/10.0.0.2".to_string()];
        assert_eq!(l.add(h(), t), ["refused a connection from tcp/10.0.0.2"]);
        assert!(l.add(h(), t + Duration::from_secs(1)).is_empty());
        assert!(l.add(h(), t + Duration::from_secs(2)).is_empty());
        assert_eq!(
            l.add(vec![], t + AUTH_REPEAT),
            ["refused 2 connections from tcp/10.0.0.2"]
        );
        assert_eq!(
            hosts(vec![Some("tcp/10.0.0.2:5001".into()), None]),
            ["tcp/10.0.0.2", "an unknown address"]
        );
    }
}
