//! The run's metrics: the schema of metrics.json (owned by
//! [`mrsim_runfolder`]), re-exported here (the world's callers name it here) with the
//! duration histogram, and what the tick loop accumulates per robot on
//! its way to it.

pub use crate::histogram::DurationHistogram;
pub use mrsim_runfolder::metrics::{
    Deadlock, EndedBy, Episode, Outcome, PathDeviation, Percentiles, RobotMetrics, RunMetrics,
    TimingMetrics,
};

/// Everything measured about one robot.
#[derive(Debug, Clone, Default)]
pub struct RobotAccumulator {
    /// Reached its goal (held for goal_hold_ticks).
    pub reached_goal: bool,
    /// Time it arrived (start of the successful hold), s.
    pub time_to_goal: Option<f64>,
    /// Consecutive ticks within tolerance so far.
    pub hold: u32,
    /// Time the current hold started.
    pub hold_start: f64,
    /// Contacts started with anything but a person.
    pub collisions: u64,
    /// Contacts started with a person.
    pub person_collisions: u64,
    /// Smallest gap reported by its contacts with people.
    pub min_person_contact_gap: f64,
    /// Smallest gap reported by its contacts (negative: overlap). The
    /// clearance proper comes from the states ([`crate::tracking`]); a
    /// robot's `min_clearance` is the smaller of the two.
    pub min_contact_gap: f64,
    /// Realtime: ticks whose command came late or never.
    pub deadline_misses: u64,
    /// Process id of the agent that last drove it.
    pub agent_pid: Option<u32>,
    /// Times lost.
    pub lost: u32,
    /// Commands rejected that named this robot.
    pub rejected: u64,
    /// Commands that came after their tick's deadline.
    pub late: u64,
    /// Realtime under SCHED_DEADLINE: the most reservation overruns its
    /// agent's commands reported (a running count).
    pub overruns: Option<u32>,
    /// Distance to its goal at its last progress (infinity before the
    /// first tick).
    pub progress_distance: f64,
    /// Time of its last progress, s.
    pub progress_time: f64,
    /// Time it was declared stuck, while it is.
    pub stuck_since: Option<f64>,
    /// Seconds stuck, the current spell excluded.
    pub stuck_time: f64,
}
