//! A read-only observer over iceoryx2 ([`ShmObserver`]).

use super::doorbell::Doorbell;
use super::service::{
    S, config, node, receive_newest, service_name, setup_err, setup_subscriber, snapshot_subscriber,
};
use super::watch::WorldWatch;
use crate::{Namespace, ObserverTransport, TransportError};
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::*;
use mrsim_proto::{BodyState, RobotStats, SnapshotHeader, StatsHeader};
use std::time::{Duration, Instant};

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
