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

/// The newest snapshot the world published: the very bodies its workers
/// share, so the world keeps it for observers without a copy.
pub(super) type SharedSnapshot = Arc<Mutex<Option<(SnapshotHeader, Arc<[BodyState]>)>>>;

/// Reads the setup, the live statistics and the newest snapshot of an
/// in-process run. The world keeps a reference to each snapshot it
/// publishes (no copy on the tick loop); an observer copies the bodies
/// only when it asks and the tick has moved.
pub struct InprocObserver {
    pub(super) setup: Arc<Mutex<Option<Vec<u8>>>>,
    pub(super) stats: SharedStats,
    pub(super) seen: u64,
    pub(super) snapshot: SharedSnapshot,
    pub(super) seen_tick: Option<u64>,
    pub(super) alive: Arc<AtomicBool>,
}

impl ObserverTransport for InprocObserver {
    fn setup(&mut self) -> Result<Option<Vec<u8>>, TransportError> {
        Ok(self.setup.lock().ok().and_then(|s| s.clone()))
    }

    fn latest_snapshot(
        &mut self,
        header: &mut SnapshotHeader,
        bodies: &mut Vec<BodyState>,
    ) -> Result<bool, TransportError> {
        let newest = match self.snapshot.lock() {
            Ok(s) => s.clone(),
            Err(_) => return Ok(false),
        };
        match newest {
            Some((h, b)) if self.seen_tick != Some(h.tick) => {
                self.seen_tick = Some(h.tick);
                *header = h;
                bodies.clear();
                bodies.extend_from_slice(&b);
                Ok(true)
            }
            _ => Ok(false),
        }
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
