//! A read-only observer over Zenoh ([`ZenohObserver`]): a client session
//! that subscribes to the snapshots and statistics and asks for the setup;
//! it never joins, sends or wakes the world.

use super::agent::query_setup;
use super::inbox::{AgentInbox, lock};
use super::keys::Keys;
use super::wire::decode_slice;
use super::{Role, ZenohOptions, declare_err, open};
use crate::{Namespace, ObserverTransport, TransportError};
use mrsim_proto::{BodyState, RobotStats, SnapshotHeader, StatsHeader};
use std::sync::Arc;
use std::time::{Duration, Instant};
use zenoh::Wait;
use zenoh::pubsub::Subscriber;
use zenoh::sample::SampleKind;

/// A read-only observer over Zenoh.
pub struct ZenohObserver {
    session: zenoh::Session,
    keys: Keys,
    inbox: Arc<AgentInbox>,
    _subs: Vec<Subscriber<()>>,
    setup_given: bool,
}

/// Most bodies or robots an observer accepts in one message.
const MAX_ITEMS: usize = 1 << 20;

impl ZenohObserver {
    /// Connects to the world of run `ns`, retrying until `timeout`. Without
    /// `snapshots` only the setup and the statistics are read.
    pub fn connect(
        ns: &Namespace,
        opts: &ZenohOptions,
        snapshots: bool,
        timeout: Duration,
    ) -> Result<Self, TransportError> {
        let start = Instant::now();
        loop {
            match Self::try_connect(ns, opts, snapshots) {
                Ok(o) => {
                    while !lock(&o.inbox.state).world_present {
                        if start.elapsed() >= timeout {
                            return Err(TransportError::Setup {
                                what: format!("the world of run `{}`", ns.run_id()),
                                detail: "connected, but no world of this run answers there"
                                    .to_string(),
                            });
                        }
                        o.inbox.wait(Duration::from_millis(100));
                    }
                    return Ok(o);
                }
                Err(e) if start.elapsed() >= timeout => return Err(e),
                Err(_) => std::thread::sleep(Duration::from_millis(100)),
            }
        }
    }

    /// One attempt of [`ZenohObserver::connect`] (the world's token may not
    /// have arrived yet).
    pub fn try_connect(
        ns: &Namespace,
        opts: &ZenohOptions,
        snapshots: bool,
    ) -> Result<Self, TransportError> {
        let session = open(opts, Role::Client)?;
        let keys = Keys::new(ns);
        let inbox = Arc::new(AgentInbox::default());
        let mut subs = Vec::new();
        let i = inbox.clone();
        subs.push(
            session
                .liveliness()
                .declare_subscriber(keys.world_alive.clone())
                .history(true)
                .callback(move |s| i.world(s.kind() == SampleKind::Put))
                .wait()
                .map_err(|e| declare_err("world liveliness subscriber", e))?,
        );
        let i = inbox.clone();
        subs.push(
            session
                .declare_subscriber(keys.stats.clone())
                .callback(move |s| i.stats(&s.payload().to_bytes()))
                .wait()
                .map_err(|e| declare_err("stats subscriber", e))?,
        );
        if snapshots {
            let i = inbox.clone();
            subs.push(
                session
                    .declare_subscriber(keys.snapshot.clone())
                    .callback(move |s| i.snapshot(&s.payload().to_bytes()))
                    .wait()
                    .map_err(|e| declare_err("snapshot subscriber", e))?,
            );
        }
        Ok(Self {
            session,
            keys,
            inbox,
            _subs: subs,
            setup_given: false,
        })
    }
}

impl ObserverTransport for ZenohObserver {
    fn setup(&mut self) -> Result<Option<Vec<u8>>, TransportError> {
        // Given once, as a history-1 subscriber hands it once.
        if self.setup_given {
            return Ok(None);
        }
        let got = query_setup(&self.session, &self.keys)?;
        self.setup_given = got.is_some();
        Ok(got)
    }

    fn latest_snapshot(
        &mut self,
        header: &mut SnapshotHeader,
        bodies: &mut Vec<BodyState>,
    ) -> Result<bool, TransportError> {
        // The observer has no key (it never joins): it reads the
        // snapshot's message without checking its tag, and acts on none.
        let mut s = lock(&self.inbox.state);
        Ok(s.take_snapshot(|m| decode_slice(m, MAX_ITEMS, header, bodies)) == Some(true))
    }

    fn latest_stats(
        &mut self,
        header: &mut StatsHeader,
        robots: &mut Vec<RobotStats>,
    ) -> Result<bool, TransportError> {
        let mut s = lock(&self.inbox.state);
        Ok(std::mem::take(&mut s.fresh_stats) && decode_slice(&s.stats, MAX_ITEMS, header, robots))
    }

    fn world_alive(&mut self) -> bool {
        let s = lock(&self.inbox.state);
        !s.world_seen || s.world_present
    }
}
