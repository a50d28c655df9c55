//! A finished run as read from its folder ([`RunData`], loaded by
//! [`RunData::load`]), and the lookups the pictures make in it.

use crate::records::{BodyKind, BodyTrack, DiagnosticSample, Event, Trajectory};
use mrsim_scenario::Scenario;
use std::collections::{BTreeMap, HashMap};
use std::path::PathBuf;

pub use mrsim_runfolder::{
    DIAGNOSTICS_FILE, EVENTS_FILE, METRICS_FILE, Percentiles, RobotMetrics, SCENARIO_FILE,
    TRAJECTORY_FILE,
};

/// `metrics.json`, the run folder crate's schema (the name this crate has
/// always used for it).
pub type Metrics = mrsim_runfolder::RunMetrics;

/// Everything in a finished run's folder.
#[derive(Debug, Clone, PartialEq)]
pub struct RunData {
    /// The folder it was read from.
    pub dir: PathBuf,
    /// `scenario.json`.
    pub scenario: Scenario,
    /// `trajectory.csv`.
    pub trajectory: Trajectory,
    /// `events.jsonl`, known types only, in file order.
    pub events: Vec<Event>,
    /// `metrics.json`, `None` if the file is absent (a run cut short).
    pub metrics: Option<Metrics>,
    /// `diagnostics.csv`, `None` if the file is absent or empty. Values may
    /// be `inf`, `-inf` or `NaN` (the plots leave them out).
    pub diagnostics: Option<Vec<DiagnosticSample>>,
    /// `routes.csv`: each routed robot's route, start to goal (empty if
    /// the file is absent).
    pub routes: BTreeMap<String, Vec<[f64; 2]>>,
    /// `encounters.csv`'s rows (empty if the file is absent).
    pub encounters: Vec<mrsim_runfolder::metrics::Encounter>,
    /// The files that end where the run was cut (its world killed): each
    /// was read up to its last whole row. Empty for a run that ended.
    pub cut: Vec<mrsim_runfolder::stream::Cut>,
}

impl RunData {
    /// Colour index of a robot: its place in the scenario, or after the
    /// scenario's robots in trajectory order for a robot the scenario does
    /// not list.
    pub fn robot_index(&self, name: &str) -> Option<usize> {
        if let Some(i) = self.scenario.robot_index(name) {
            return Some(i);
        }
        self.trajectory
            .bodies
            .iter()
            .filter(|b| b.kind == BodyKind::Robot && self.scenario.robot_index(&b.name).is_none())
            .position(|b| b.name == name)
            .map(|i| self.scenario.robots.len() + i)
    }

    /// The scenario's robot entries by name (one lookup per robot, not a
    /// scan: pictures of 10,000 robots look each one up).
    pub fn specs_by_name(&self) -> HashMap<&str, &mrsim_scenario::RobotSpec> {
        self.scenario
            .robots
            .iter()
            .map(|r| (r.name.as_str(), r))
            .collect()
    }

    /// The recorded tracks by body name.
    pub fn tracks_by_name(&self) -> HashMap<&str, &BodyTrack> {
        self.trajectory
            .bodies
            .iter()
            .map(|b| (b.name.as_str(), b))
            .collect()
    }

    /// Robot names in colour order: the scenario's, then any other robot in
    /// the trajectory.
    pub fn robot_names(&self) -> Vec<String> {
        let listed: std::collections::HashSet<&str> = self
            .scenario
            .robots
            .iter()
            .map(|r| r.name.as_str())
            .collect();
        let mut names: Vec<String> = self
            .scenario
            .robots
            .iter()
            .map(|r| r.name.clone())
            .collect();
        for b in &self.trajectory.bodies {
            if b.kind == BodyKind::Robot && !listed.contains(b.name.as_str()) {
                names.push(b.name.clone());
            }
        }
        names
    }
}
