//! Live statistics for observers (`mrsim top`, the launcher's progress
//! bar): the world publishes every robot's agent state, latency p50/p99,
//! deadline misses and collisions at most every [`LiveStats::PERIOD`] of
//! wall time, from buffers allocated once, so the tick loop neither
//! allocates nor waits for it.

use mrsim_proto::{RobotStats, StatsHeader};
use mrsim_transport::{TransportError, WorldTransport};
use std::time::{Duration, Instant};

/// The buffer and the clock of the stats publication.
#[derive(Debug)]
pub struct LiveStats {
    robots: Vec<RobotStats>,
    last: Option<Instant>,
}

impl LiveStats {
    /// Wall time between two publications (5 per second).
    pub const PERIOD: Duration = Duration::from_millis(200);

    /// Room for `robots` rows; nothing published yet.
    pub fn new(robots: usize) -> Self {
        Self {
            robots: (0..robots)
                .map(|i| RobotStats {
                    robot_id: i as u32,
                    ..Default::default()
                })
                .collect(),
            last: None,
        }
    }

    /// True if a publication is due: never yet, or [`Self::PERIOD`] ago.
    pub fn due(&self, now: Instant) -> bool {
        self.last
            .is_none_or(|t| now.saturating_duration_since(t) >= Self::PERIOD)
    }

    /// The rows to fill before [`Self::publish`].
    pub fn robots_mut(&mut self) -> &mut [RobotStats] {
        &mut self.robots
    }

    /// Publishes the rows under `header` and restarts the period.
    pub fn publish(
        &mut self,
        link: &mut dyn WorldTransport,
        header: &StatsHeader,
        now: Instant,
    ) -> Result<(), TransportError> {
        self.last = Some(now);
        link.publish_stats(header, &self.robots)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_publication_is_due_at_first_and_then_once_per_period() {
        let mut live = LiveStats::new(3);
        let t0 = Instant::now();
        assert!(live.due(t0));
        live.last = Some(t0);
        assert!(!live.due(t0 + LiveStats::PERIOD / 2));
        assert!(live.due(t0 + LiveStats::PERIOD));
        assert_eq!(live.robots_mut().len(), 3);
        assert_eq!(live.robots_mut()[2].robot_id, 2);
    }
}
