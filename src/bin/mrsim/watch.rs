//! The launcher's view of its own run: `mrsim run` follows the world's live
//! statistics as a read-only observer (the same channel `mrsim top` reads:
//! iceoryx2, or Zenoh for a Zenoh run) and shows them as a [`Progress`] of
//! ticks, and (with `--live`) feeds the live page from the same observer.

use crate::progress::{Progress, Style};
use mrsim_proto::{RobotStats, StatsHeader, agent_state, run_phase};
use mrsim_transport::shm::ShmObserver;
use mrsim_transport::zenoh::{ZenohObserver, ZenohOptions};
use mrsim_transport::{Namespace, ObserverTransport};
use std::sync::mpsc;
use std::time::{Duration, Instant};

/// Follows a run's progress while the launcher waits for its world.
pub struct RunWatch {
    ns: Namespace,
    obs: Option<Box<dyn ObserverTransport>>,
    /// Over Zenoh: the observer being connected on its own thread (a
    /// connection attempt may take longer than the launcher's 20 ms round).
    zenoh: Option<mpsc::Receiver<ZenohObserver>>,
    progress: Progress,
    last: Option<Instant>,
    stats: StatsHeader,
    robots: Vec<RobotStats>,
    /// `--live`: the page's pump, which reads the observer for both.
    live: Option<mrsim_live::Pump>,
}

/// How long a Zenoh watch keeps trying to reach its world (a run's world
/// waits a minute for its agents; progress is a courtesy).
const CONNECT_LIMIT: Duration = Duration::from_secs(120);

impl RunWatch {
    /// How often the statistics (and, for the live page, the snapshot)
    /// are read: the world publishes statistics 5 times a second.
    pub const INTERVAL: Duration = Duration::from_millis(50);

    /// A watch over run `ns` of `max_ticks` ticks, styled by
    /// [`Style::detect`], over iceoryx2 or (with `zenoh`) Zenoh; nothing is
    /// attached yet.
    pub fn new(
        ns: &Namespace,
        max_ticks: u64,
        zenoh: Option<ZenohOptions>,
        live: Option<mrsim_live::Feed>,
    ) -> Self {
        let progress = Progress::new(max_ticks, "run");
        // The live page draws the bodies: it needs the snapshots too.
        let snapshots = live.is_some();
        let zenoh = zenoh
            .filter(|_| progress.style() != Style::Off || live.is_some())
            .map(|opts| {
                let (tx, rx) = mpsc::channel();
                let ns = ns.clone();
                std::thread::spawn(move || {
                    if let Ok(o) = ZenohObserver::connect(&ns, &opts, snapshots, CONNECT_LIMIT) {
                        let _ = tx.send(o);
                    }
                });
                rx
            });
        Self {
            ns: ns.clone(),
            obs: None,
            zenoh,
            progress,
            last: None,
            stats: StatsHeader::default(),
            robots: Vec::new(),
            live: live.map(mrsim_live::Pump::new),
        }
    }

    /// Off: neither a progress to show nor a page to feed.
    fn idle(&self) -> bool {
        self.progress.style() == Style::Off && self.live.is_none()
    }

    /// Reads the newest statistics from `obs` (through the live page's
    /// pump, when there is one, which takes the snapshot too); true if new
    /// ones arrived.
    fn read(
        live: &mut Option<mrsim_live::Pump>,
        obs: &mut dyn ObserverTransport,
        stats: &mut StatsHeader,
        robots: &mut Vec<RobotStats>,
    ) -> bool {
        match live {
            Some(pump) => {
                let new = matches!(pump.pump(obs), Ok(true));
                if new {
                    let (s, r) = pump.stats();
                    *stats = *s;
                    robots.clear();
                    robots.extend_from_slice(r);
                }
                new
            }
            None => matches!(obs.latest_stats(stats, robots), Ok(true)),
        }
    }

    /// Reads the newest statistics (at most every [`Self::INTERVAL`]) and
    /// moves the progress; attaches to the world once it is there. Never
    /// fails: progress is a courtesy.
    pub fn update(&mut self) {
        if self.idle() {
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
            self.obs = match &self.zenoh {
                Some(rx) => rx.try_recv().ok().map(|o| Box::new(o) as _),
                None => {
                    let node = format!("mrsim-run-{}", std::process::id());
                    ShmObserver::try_connect(&self.ns, &node, self.live.is_some())
                        .ok()
                        .map(|o| Box::new(o) as _)
                }
            };
        }
        let Some(obs) = self.obs.as_mut() else {
            return;
        };
        if Self::read(
            &mut self.live,
            obs.as_mut(),
            &mut self.stats,
            &mut self.robots,
        ) {
            self.show();
        }
    }

    /// [`Self::update`] from `obs` (an in-process run's observer) instead
    /// of the world's channels.
    pub fn update_from(&mut self, obs: &mut dyn ObserverTransport) {
        if self.idle() {
            return;
        }
        let now = Instant::now();
        if self.live.is_some()
            && self
                .last
                .is_some_and(|t| now.saturating_duration_since(t) < Self::INTERVAL)
        {
            return;
        }
        self.last = Some(now);
        if Self::read(&mut self.live, obs, &mut self.stats, &mut self.robots) {
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
