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
    /// Every planner call's response time: its snapshot published ->
    /// its command sent (timing.csv's `sent_ns`), accepted or late, µs.
    /// Present when the run records timing.csv (realtime, or a timing
    /// model in lockstep).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub response_us: Option<Percentiles>,
    /// Every planner call's CPU (timing.csv's `cpu_ns`: measured on the
    /// agent's thread clock in realtime; the modelled CPU work in lockstep,
    /// 0 for a `cpu = false` wait), µs. Present with `response_us`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cpu_us: Option<Percentiles>,
    /// Realtime under SCHED_DEADLINE: the reservation overruns its agent
    /// counted (SIGXCPU on `SCHED_FLAG_DL_OVERRUN`); absent when none.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub overruns: Option<u32>,
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
    /// Success weighted by path length (Anderson et al. 2018): S l /
    /// max(p, l), S 1 if it reached its goal, l the straight start-goal
    /// distance, p the path length. Absent in older files.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub spl: Option<f64>,
    /// Seconds before arrival (or the end) at ticks where its speed was
    /// below 5 % of its `max_speed`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub time_not_moving: Option<f64>,
    /// Smallest time to collision with a body whose surface was within the
    /// social distance, both at their velocities of the tick, s (0 when
    /// overlapping); null if never finite.
    #[serde(skip_serializing_if = "Option::is_none", with = "present")]
    pub ttc_min: Option<Option<f64>>,
    /// Seconds with the smallest surface gap to another body below 0.45 m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub time_intimate: Option<f64>,
    /// ... below 1.2 m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub time_personal: Option<f64>,
    /// ... below 3.6 m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub time_social: Option<f64>,
    /// Mean of |a_k - a_(k-1)| / dt over ticks, a_k = (v_k - v_(k-1)) / dt.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub jerk_mean: Option<f64>,
    /// Mean angle between the direction of motion and the straight line to
    /// the goal over the ticks it moved, rad (SocNavBench).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub path_irregularity: Option<f64>,
    /// Sum of the changes of the direction of motion, rad.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub heading_change: Option<f64>,
    /// Seconds it was stuck (its distance to its goal fell by less than 5 %
    /// of `max_speed` x `[world] stuck_after` in `stuck_after` seconds),
    /// counted from each time it was declared so.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stuck_time: Option<f64>,
    /// Its episode's outcome under `[world] end_on` (absent without it).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub outcome: Option<Outcome>,
    /// When its episode ended, s: its arrival for a success, its first
    /// contact for a collision, the time limit for a timeout, the run's
    /// end otherwise (absent without `[world] end_on`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub outcome_time: Option<f64>,
    /// The body its first contact was with, by name (`wallK` for a wall);
    /// present for a collision.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub collided_with: Option<String>,
    /// Contacts started with a person (not in `collisions`). This key and
    /// the other `person_` ones and `discomfort_time` are present only in
    /// a scene with people; the keys above them leave people out.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub person_collisions: Option<u64>,
    /// Smallest surface distance to any person (negative: overlap).
    #[serde(skip_serializing_if = "Option::is_none", with = "present")]
    pub person_min_clearance: Option<Option<f64>>,
    /// `ttc_min` over the people: smallest time to collision with a person
    /// within the social distance, s; null if never finite.
    #[serde(skip_serializing_if = "Option::is_none", with = "present")]
    pub person_ttc_min: Option<Option<f64>>,
    /// Seconds with the smallest surface gap to a person below 0.45 m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub person_time_intimate: Option<f64>,
    /// ... below 1.2 m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub person_time_personal: Option<f64>,
    /// ... below 3.6 m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub person_time_social: Option<f64>,
    /// Seconds with the smallest surface gap to a person below CrowdNav's
    /// discomfort distance, 0.2 m (overlaps included).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub discomfort_time: Option<f64>,
}

/// How a robot's episode ended (`[world] end_on`), as the crowd-navigation
/// benchmarks count an episode (CrowdNav's `ReachGoal`, `Collision`,
/// `Timeout`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Outcome {
    /// At its goal within the time limit, without a contact before it.
    Success,
    /// A contact before it reached its goal.
    Collision,
    /// Not at its goal when the time limit ended the run (`end_on` names
    /// `"timeout"`).
    Timeout,
    /// Not at its goal when the run ended otherwise: another robot's
    /// contact ended it, every robot was stuck, it was interrupted, or it
    /// reached its duration with `end_on` not naming `"timeout"`.
    Unfinished,
}

impl Outcome {
    /// The name as written in metrics.json.
    pub fn name(self) -> &'static str {
        match self {
            Outcome::Success => "success",
            Outcome::Collision => "collision",
            Outcome::Timeout => "timeout",
            Outcome::Unfinished => "unfinished",
        }
    }
}

/// What ended a run counted as an episode.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum EndedBy {
    /// A robot's first contact (`end_on` names `"collision"`).
    Collision,
    /// Every robot at its goal.
    Goals,
    /// The run's duration, its time limit.
    TimeLimit,
    /// Every robot not at its goal stuck (`end_when_stuck`).
    Stuck,
    /// A signal.
    Interrupted,
}

/// metrics.json's `episode`: the run counted as the benchmarks count an
/// episode (`[world] end_on`), over its robots.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Episode {
    /// The conditions of `end_on`, as written.
    pub end_on: Vec<String>,
    /// The run's outcome: `collision` if any robot collided, else
    /// `timeout` if any timed out, else `unfinished` if any is, else
    /// `success` (with one robot, that robot's).
    pub outcome: Outcome,
    /// What ended the run.
    pub ended_by: EndedBy,
    /// Simulated time at the end, s.
    pub time: f64,
    /// Robots of each outcome.
    pub success: u32,
    /// Robots that collided.
    pub collision: u32,
    /// Robots that timed out.
    pub timeout: u32,
    /// Robots left unfinished.
    pub unfinished: u32,
    /// Mean time to goal of the robots that succeeded, s; null if none.
    pub time_to_goal: Option<f64>,
}

/// A key that may be absent (an older file: `None`) or present and null
/// (`Some(None)`): serde reads a present null as absent unless told.
mod present {
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    pub fn serialize<S: Serializer>(v: &Option<Option<f64>>, s: S) -> Result<S::Ok, S::Error> {
        v.flatten().serialize(s)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Option<f64>>, D::Error> {
        Option::<f64>::deserialize(d).map(Some)
    }
}

/// A group of stuck robots within each other's sensing range.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Deadlock {
    /// Tick it was detected at.
    pub tick: u64,
    /// Simulated time it was detected at, s.
    pub time: f64,
    /// Its members, by name.
    pub robots: Vec<String>,
}

/// encounters.csv's header.
pub const ENCOUNTERS_HEADER: &str = "a,b,start_tick,end_tick,min_gap,min_ttc,kind,gave_way,b_kind";

/// One row of encounters.csv: two bodies within `[output] encounter_gap`
/// of each other from `start_tick` to `end_tick`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Encounter {
    /// The body of lower index (a robot), by name.
    pub a: String,
    /// The other body, by name.
    pub b: String,
    /// First tick within the gap.
    pub start_tick: u64,
    /// Last tick within the gap.
    pub end_tick: u64,
    /// Smallest surface gap (negative: overlap).
    pub min_gap: f64,
    /// Smallest time to collision, s; empty if never finite.
    pub min_ttc: Option<f64>,
    /// `head-on`, `crossing`, `overtaking` or `standing`.
    pub kind: String,
    /// `a`, `b`, `both` or `none`.
    pub gave_way: String,
    /// What `b` is: `robot`, `obstacle` or `person` (empty in a file
    /// written before the column).
    #[serde(default)]
    pub b_kind: String,
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
    /// Mean of the robots' `spl` (absent in older files).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub spl: Option<f64>,
    /// Time the last robot arrived, s; null unless every robot arrived.
    #[serde(skip_serializing_if = "Option::is_none", with = "present")]
    pub makespan: Option<Option<f64>>,
    /// Sum of the robots' times to goal, s; null unless every robot
    /// arrived.
    #[serde(skip_serializing_if = "Option::is_none", with = "present")]
    pub flowtime: Option<Option<f64>>,
    /// Contacts per thousand length units travelled by all robots; null
    /// when nothing moved.
    #[serde(skip_serializing_if = "Option::is_none", with = "present")]
    pub collisions_per_robot_km: Option<Option<f64>>,
    /// The deadlocks detected, in order.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub deadlocks: Vec<Deadlock>,
    /// True if the run ended early because every robot not at its goal was
    /// stuck (`[world] end_when_stuck`).
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub ended_stuck: bool,
    /// The run counted as an episode (`[world] end_on`; absent without it).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub episode: Option<Episode>,
    /// Contacts started between a robot and a person, all robots (not in
    /// `collisions_total`); present only in a scene with people, as are
    /// the next two.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub person_collisions_total: Option<u64>,
    /// Smallest of the robots' `person_min_clearance`.
    #[serde(skip_serializing_if = "Option::is_none", with = "present")]
    pub person_min_clearance: Option<Option<f64>>,
    /// Sum of the robots' `discomfort_time`, s.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub discomfort_time: Option<f64>,
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
