//! `metrics.json`: what a run measured, per robot and as a whole.
//!
//! Written once by the world at the end of the run; fields are written in
//! the order declared here. Every struct reads with defaults for missing
//! fields, so a partial file (an older world's, a test's) still reads.

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Percentiles of a duration histogram, µs (all zero when it is empty).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Percentiles {
    /// Median.
    pub p50: f64,
    /// 99th percentile.
    pub p99: f64,
    /// 99.9th percentile.
    pub p999: f64,
    /// Largest sample.
    pub max: f64,
    /// Number of samples.
    pub count: u64,
}

/// Distance of a robot from its designated path over a run.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct PathDeviation {
    /// Mean over the ticks recorded.
    pub mean: f64,
    /// Largest.
    pub max: f64,
}

/// One robot's entry of `metrics.json`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct RobotMetrics {
    /// Planner name.
    pub planner: String,
    /// Reached its goal (and held it for `goal_hold_ticks`).
    pub reached_goal: bool,
    /// Arrival time (start of the successful hold), s; null if never.
    pub time_to_goal: Option<f64>,
    /// Distance travelled.
    pub path_length: f64,
    /// Contacts started with anything.
    pub collisions: u64,
    /// Smallest surface distance to any body or wall (negative: overlap);
    /// null if there was nothing else.
    pub min_clearance: Option<f64>,
    /// Largest speed.
    pub max_speed: f64,
    /// Realtime: ticks whose command came late or never.
    pub deadline_misses: u64,
    /// Snapshot published -> command received, µs.
    pub latency_us: Percentiles,
    /// Snapshot published -> agent awake, µs.
    pub wake_us: Percentiles,
    /// Planner compute time, µs.
    pub compute_us: Percentiles,
    /// Process id of the agent that last drove it.
    pub agent_pid: Option<u32>,
    /// Times its agent was lost.
    pub lost: u32,
    /// Commands rejected that named this robot.
    pub commands_rejected: u64,
    /// Commands that arrived after their deadline.
    pub commands_late: u64,
    /// Distance from the designated path, per tick (null without a path).
    pub path_deviation: Option<PathDeviation>,
    /// Ticks with the centre farther than `boundary` from the path (null
    /// without a path or a boundary).
    pub boundary_violations: Option<u64>,
}

/// `metrics.json`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct RunMetrics {
    /// Scenario name.
    pub scenario: String,
    /// Per robot, keyed by name.
    pub robots: BTreeMap<String, RobotMetrics>,
    /// Contacts started, all robots (a robot-robot contact counts once).
    pub collisions_total: u64,
    /// Fraction of robots that reached their goal.
    pub success_rate: f64,
    /// Ticks simulated.
    pub ticks: u64,
    /// Simulated time, s.
    pub sim_time: f64,
    /// `lockstep` or `realtime`.
    pub mode: String,
    /// Simulated seconds per wall-clock second.
    pub realtime_factor: f64,
    /// Agents lost (died or stalled) during the run.
    pub agents_lost: u64,
    /// Commands rejected (wrong robot, wrong tick, garbage, duplicates).
    pub commands_rejected: u64,
    /// Commands that came after their tick's deadline.
    pub commands_late: u64,
    /// Commands rejected that named no robot of the scenario.
    pub commands_rejected_unknown: u64,
    /// Connections the world refused because their credentials failed
    /// (Zenoh with user/password auth; absent with the other transports).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub auth_refused: Option<u64>,
    /// Commands and join requests the world dropped unread because more
    /// came at once than it holds (a flood; Zenoh only, absent elsewhere).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub messages_dropped: Option<u64>,
    /// Join requests that did not decode (Zenoh only, absent elsewhere;
    /// commands that do not decode are in `commands_rejected_unknown`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub joins_malformed: Option<u64>,
    /// The world process's id.
    pub world_pid: u32,
    /// The run id (iceoryx2 namespace).
    pub run_id: String,
    /// The transport: `shm`, `inproc` or `zenoh`.
    pub transport: String,
    /// True if the run was stopped early by a signal.
    pub interrupted: bool,
    /// How the run kept time and what the world process used.
    pub timing: TimingMetrics,
}

/// `metrics.json`'s `timing`: the run as a real-time system.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct TimingMetrics {
    /// Wall-clock duration of the tick loop, s.
    pub wall_s: f64,
    /// Every robot's snapshot published -> command received, µs.
    pub latency_us: Percentiles,
    /// Every robot's snapshot published -> agent awake, µs.
    pub wake_us: Percentiles,
    /// Every robot's planner compute time, µs.
    pub compute_us: Percentiles,
    /// Realtime: actual tick start (snapshot published) minus scheduled, µs.
    pub jitter_us: Percentiles,
    /// Snapshot published -> last command in, on ticks where every live
    /// agent answered in time, µs.
    pub allin_us: Percentiles,
    /// The world thread's own work per tick: publish, record, take in and
    /// check the commands (not the wait for them), apply, physics, goal
    /// test, µs. The robots' motion metrics and the commands' timing
    /// histograms are computed off the tick loop and are not in it.
    pub world_tick_us: Percentiles,
    /// Rapier's own step within it (all substeps), µs: the floor
    /// `world_tick_us` compares with, the same bodies in the same tick.
    pub physics_us: Percentiles,
    /// CPU seconds of the world's process during the tick loop (with the
    /// in-process transport this includes the agent threads).
    pub process_cpu_s: f64,
    /// Peak resident set size of the world's process at the end, KiB.
    pub process_maxrss_kb: u64,
    /// Time the hypervisor took the CPUs the world may run on away during
    /// the tick loop (/proc/stat's steal), s; null where /proc/stat is
    /// unreadable.
    pub cpus_steal_s: Option<f64>,
}
