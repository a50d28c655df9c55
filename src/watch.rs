//! The launcher's view of its own run: `mrsim run` follows the world's live
//! statistics as a read-only observer (the same channel `mrsim top` reads)
//! and shows them as a [`Progress`] of ticks.

use crate::progress::{Progress, Style};
use mrsim_proto::{RobotStats, StatsHeader, agent_state, run_phase};
use mrsim_transport::shm::ShmObserver;
use mrsim_transport::{Namespace, ObserverTransport};
use std::time::{Duration, Instant};

/// Follows a run's progress while the launcher waits for its world.
pub struct RunWatch {
    ns: Namespace,
    obs: Option<ShmObserver>,
    progress: Progress,
    last: Option<Instant>,
    stats: StatsHeader,
    robots: Vec<RobotStats>,
}

impl RunWatch {
    /// How often the statistics are read (the world publishes 5 per second).
    pub const INTERVAL: Duration = Duration::from_millis(100);

    /// A watch over run `ns` of `max_ticks` ticks, styled by
    /// [`Style::detect`]; nothing is attached yet.
    pub fn new(ns: &Namespace, max_ticks: u64) -> Self {
        Self {
            ns: ns.clone(),
            obs: None,
            progress: Progress::new(max_ticks, "run"),
            last: None,
            stats: StatsHeader::default(),
            robots: Vec::new(),
        }
    }

    /// Reads the newest statistics (at most every [`Self::INTERVAL`]) and
    /// moves the progress; attaches to the world once it is there. Never
    /// fails: progress is a courtesy.
    pub fn update(&mut self) {
        if self.progress.style() == Style::Off {
            return;
        }
        let now = Instant::now();
        if self
            .last
            .is_some_and(|t| now.saturating_duration_since(t) < Self::INTERVAL)
        {
            return;
        }
        self.last = Some(now);
        if self.obs.is_none() {
            let node = format!("mrsim-run-{}", std::process::id());
            self.obs = ShmObserver::try_connect(&self.ns, &node, false).ok();
        }
        let Some(obs) = self.obs.as_mut() else {
            return;
        };
        if matches!(
            obs.latest_stats(&mut self.stats, &mut self.robots),
            Ok(true)
        ) {
            self.show();
        }
    }

    /// [`Self::update`] from `obs` (an in-process run's observer) instead
    /// of the world's channels.
    pub fn update_from(&mut self, obs: &mut dyn ObserverTransport) {
        if self.progress.style() == Style::Off {
            return;
        }
        if matches!(
            obs.latest_stats(&mut self.stats, &mut self.robots),
            Ok(true)
        ) {
            self.show();
        }
    }

    /// Moves the progress to the statistics last read.
    fn show(&mut self) {
        let s = self.stats;
        let n = self.robots.len();
        if s.phase == run_phase::JOINING {
            let joined = self
                .robots
                .iter()
                .filter(|r| r.state != agent_state::WAITING)
                .count();
            self.progress
                .set_message(format!("waiting for agents: {joined}/{n} joined"));
        } else {
            let at_goal = self.robots.iter().filter(|r| r.reached_goal == 1).count();
            let misses: u64 = self.robots.iter().map(|r| r.deadline_misses).sum();
            self.progress.set_message(format!(
                "t = {:.1} s  {at_goal}/{n} at goal  {} collisions  {misses} misses",
                s.sim_time, s.collisions_total
            ));
        }
        self.progress.set_length(s.max_ticks);
        self.progress.set_position(s.tick);
    }

    /// Ends the progress display and lets go of the world's channels.
    pub fn finish(mut self) {
        // An in-process run's watch has no channels to read again (its
        // last statistics came with its last update).
        if self.obs.is_some() {
            self.update_now();
        }
        self.progress.finish();
        self.obs = None;
    }

    fn update_now(&mut self) {
        self.last = None;
        self.update();
    }
}
