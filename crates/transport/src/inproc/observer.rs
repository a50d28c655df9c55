//! A read-only observer of an in-process run ([`InprocObserver`]): the
//! launcher's progress, as [`crate::shm::ShmObserver`] is for a world
//! process.

use crate::{ObserverTransport, TransportError};
use mrsim_proto::{BodyState, RobotStats, SnapshotHeader, StatsHeader};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

/// The newest live statistics the world published, and how many it has
/// published (an observer copies them only when that count moved).
pub(super) type SharedStats = Arc<Mutex<(u64, StatsHeader, Vec<RobotStats>)>>;

/// Reads the setup and the live statistics of an in-process run. It gets
/// no snapshots ([`ObserverTransport::latest_snapshot`] always says none
/// arrived): the launcher's progress needs only the statistics, and a copy
/// of every snapshot for an observer would cost the tick loop.
pub struct InprocObserver {
    pub(super) setup: Arc<Mutex<Option<Vec<u8>>>>,
    pub(super) stats: SharedStats,
    pub(super) seen: u64,
    pub(super) alive: Arc<AtomicBool>,
}

impl ObserverTransport for InprocObserver {
    fn setup(&mut self) -> Result<Option<Vec<u8>>, TransportError> {
        Ok(self.setup.lock().ok().and_then(|s| s.clone()))
    }

    fn latest_snapshot(
        &mut self,
        _header: &mut SnapshotHeader,
        _bodies: &mut Vec<BodyState>,
    ) -> Result<bool, TransportError> {
        Ok(false)
    }

    fn latest_stats(
        &mut self,
        header: &mut StatsHeader,
        robots: &mut Vec<RobotStats>,
    ) -> Result<bool, TransportError> {
        let Ok(s) = self.stats.lock() else {
            return Ok(false);
        };
        if s.0 == self.seen {
            return Ok(false);
        }
        self.seen = s.0;
        *header = s.1;
        robots.clear();
        robots.extend_from_slice(&s.2);
        Ok(true)
    }

    fn world_alive(&mut self) -> bool {
        self.alive.load(Ordering::SeqCst)
    }
}
