//! The scenario file as written: every key optional and spanned, unknown
//! keys refused. `resolve` turns it into the types of `types.rs`.

use crate::types::{
    Kinematics, Lane, LengthUnit, MissPolicy, Mode, ParamValue, Route, TrajectoryFormat,
    UnknownCells, VelocitySource,
};
use serde::Deserialize;
use std::collections::BTreeMap;
use toml::Spanned;

/// A value with the byte range it came from.
pub(crate) type S<T> = Spanned<T>;
/// A point.
pub(crate) type P = [f64; 2];

/// A point as written: exactly two numbers (serde's `[f64; 2]` would
/// silently drop a third one).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Pt(pub P);

impl<'de> Deserialize<'de> for Pt {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = Vec::<f64>::deserialize(d)?;
        match v.as_slice() {
            [x, y] => Ok(Pt([*x, *y])),
            _ => Err(serde::de::Error::invalid_length(v.len(), &"a point [x, y]")),
        }
    }
}
/// A `params` table.
pub(crate) type RawParams = BTreeMap<String, S<ParamValue>>;

/// The whole file.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub(crate) struct RawDoc {
    pub name: Option<S<String>>,
    pub description: Option<S<String>>,
    pub length_unit: Option<S<LengthUnit>>,
    pub world: Option<S<RawWorld>>,
    pub defaults: Option<S<RawRobot>>,
    pub robot: Vec<S<RawRobot>>,
    pub obstacle: Vec<S<RawObstacle>>,
    pub person: Vec<S<RawPerson>>,
    pub crowd: Vec<S<RawCrowd>>,
    pub wall: Vec<S<RawWall>>,
    pub generate: Option<S<RawGenerate>>,
    pub map: Option<S<RawMap>>,
    pub output: Option<S<RawOutput>>,
}

/// `[output]`.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub(crate) struct RawOutput {
    pub trajectory: Option<S<TrajectoryFormat>>,
    pub every: Option<S<i64>>,
    pub mcap: Option<S<bool>>,
    pub encounter_gap: Option<S<f64>>,
}

/// `[map]`.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub(crate) struct RawMap {
    pub file: Option<S<String>>,
    pub unknown: Option<S<UnknownCells>>,
}

/// `[world]`.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub(crate) struct RawWorld {
    pub dt: Option<S<f64>>,
    pub substeps: Option<S<u32>>,
    pub duration: Option<S<f64>>,
    pub mode: Option<S<Mode>>,
    pub on_deadline_miss: Option<S<MissPolicy>>,
    pub seed: Option<S<u64>>,
    pub arena: Option<S<RawArena>>,
    pub deadline: Option<S<f64>>,
    pub stall_timeout: Option<S<f64>>,
    pub robots_per_agent: Option<S<u32>>,
    pub stuck_after: Option<S<f64>>,
    pub end_when_stuck: Option<S<bool>>,
    pub end_on: Option<S<Vec<S<String>>>>,
    pub cpus: Option<S<RawCpus>>,
}

/// `[world.cpus]`.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub(crate) struct RawCpus {
    pub count: Option<S<i64>>,
    pub scheduler: Option<S<String>>,
    pub world_ms: Option<S<f64>>,
}

/// `arena = { min, max }`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawArena {
    pub min: S<Pt>,
    pub max: S<Pt>,
}

/// One `[[robot]]`, and also `[defaults]` (without name, start, goal).
#[derive(Debug, Default, Clone, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub(crate) struct RawRobot {
    pub name: Option<S<String>>,
    pub start: Option<S<Pt>>,
    pub goal: Option<S<Pt>>,
    pub planner: Option<S<String>>,
    pub params: Option<S<RawParams>>,
    pub radius: Option<S<f64>>,
    pub shape: Option<S<RawShape>>,
    pub mass: Option<S<f64>>,
    pub damping: Option<S<f64>>,
    pub max_speed: Option<S<f64>>,
    pub max_accel: Option<S<f64>>,
    pub velocity_lag: Option<S<f64>>,
    pub sensing_range: Option<S<f64>>,
    pub field_of_view_deg: Option<S<f64>>,
    pub goal_tolerance: Option<S<f64>>,
    pub goal_hold_ticks: Option<S<u32>>,
    pub velocity_source: Option<S<VelocitySource>>,
    pub position_noise: Option<S<f64>>,
    pub path: Option<S<Vec<Pt>>>,
    pub boundary: Option<S<f64>>,
    pub kinematics: Option<S<Kinematics>>,
    pub max_angular_speed: Option<S<f64>>,
    pub max_angular_accel: Option<S<f64>>,
    pub lookahead: Option<S<f64>>,
    pub wheelbase: Option<S<f64>>,
    pub max_steering_deg: Option<S<f64>>,
    pub max_steering_rate_deg: Option<S<f64>>,
    pub max_reverse_speed: Option<S<f64>>,
    pub goal_heading_deg: Option<S<f64>>,
    pub goal_heading_tolerance_deg: Option<S<f64>>,
    pub route: Option<S<Route>>,
    pub lane: Option<S<Lane>>,
    pub sensor: Option<S<RawSensor>>,
    pub timing: Option<S<RawTiming>>,
}

/// `[defaults.timing]`, `[robot.timing]`.
#[derive(Debug, Default, Clone, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub(crate) struct RawTiming {
    pub compute: Option<S<RawCompute>>,
    pub observation_delay_ms: Option<S<f64>>,
    pub actuation_delay_ms: Option<S<f64>>,
    pub period_ticks: Option<S<i64>>,
    pub snapshot_loss: Option<S<f64>>,
    pub command_loss: Option<S<f64>>,
    pub priority: Option<S<RawPriority>>,
    pub reservation: Option<S<RawReservation>>,
}

/// `priority = 1..99 | "rate-monotonic"` as written.
#[derive(Debug, Clone, Deserialize)]
#[serde(untagged)]
pub(crate) enum RawPriority {
    Level(i64),
    Name(String),
}

/// `reservation = { runtime_ms, period_ms }`.
#[derive(Debug, Default, Clone, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub(crate) struct RawReservation {
    pub runtime_ms: Option<S<f64>>,
    pub period_ms: Option<S<f64>>,
}

/// `compute = { model, ... }`: the union of every model's keys.
#[derive(Debug, Default, Clone, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub(crate) struct RawCompute {
    pub model: Option<S<String>>,
    pub ms: Option<S<f64>>,
    pub min_ms: Option<S<f64>>,
    pub max_ms: Option<S<f64>>,
    pub median_ms: Option<S<f64>>,
    pub sigma: Option<S<f64>>,
    pub base_ms: Option<S<f64>>,
    pub per_body_ms: Option<S<f64>>,
    pub cpu: Option<S<bool>>,
}

/// `sensor = { kind = "lidar", beams, fov_deg, range, noise, record }`.
#[derive(Debug, Default, Clone, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub(crate) struct RawSensor {
    pub kind: Option<S<String>>,
    pub beams: Option<S<u32>>,
    pub fov_deg: Option<S<f64>>,
    pub range: Option<S<f64>>,
    pub noise: Option<S<f64>>,
    pub record: Option<S<bool>>,
}

/// One `[[obstacle]]`.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub(crate) struct RawObstacle {
    pub name: Option<S<String>>,
    pub start: Option<S<Pt>>,
    pub radius: Option<S<f64>>,
    pub shape: Option<S<RawShape>>,
    pub heading_deg: Option<S<f64>>,
    pub motion: Option<S<RawMotion>>,
}

/// `shape = { kind = ..., ... }`: the union of every kind's keys; which
/// apply is checked per kind.
#[derive(Debug, Default, Clone, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub(crate) struct RawShape {
    pub kind: Option<S<String>>,
    pub length: Option<S<f64>>,
    pub width: Option<S<f64>>,
    pub points: Option<S<Vec<Pt>>>,
}

/// `motion = { model = ..., ... }`: the union of every model's keys; which
/// apply is checked per model.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub(crate) struct RawMotion {
    pub model: Option<S<String>>,
    pub velocity: Option<S<Pt>>,
    pub points: Option<S<Vec<Pt>>>,
    pub speed: Option<S<f64>>,
    #[serde(rename = "loop")]
    pub looped: Option<S<bool>>,
    pub distribution: Option<S<String>>,
    pub accel_sigma: Option<S<f64>>,
    pub alpha1: Option<S<f64>>,
    pub beta1: Option<S<f64>>,
    pub max_speed: Option<S<f64>>,
    pub behavior: Option<S<String>>,
    pub target: Option<S<String>>,
    pub goal: Option<S<Pt>>,
    pub max_accel: Option<S<f64>>,
    pub alpha2: Option<S<f64>>,
    pub beta2: Option<S<f64>>,
}

/// One `[[person]]`.
#[derive(Debug, Default, Clone, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub(crate) struct RawPerson {
    pub name: Option<S<String>>,
    pub start: Option<S<Pt>>,
    pub goal: Option<S<Pt>>,
    pub waypoints: Option<S<Vec<Pt>>>,
    pub cyclic: Option<S<bool>>,
    pub radius: Option<S<f64>>,
    pub preferred_speed: Option<S<f64>>,
    pub sees_robots: Option<S<bool>>,
    pub behavior: Option<S<RawBehavior>>,
    pub group: Option<S<String>>,
    pub motion: Option<S<RawPersonMotion>>,
}

/// One `[[crowd]]`: a pattern's keys and a person's.
#[derive(Debug, Default, Clone, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub(crate) struct RawCrowd {
    pub count: Option<S<i64>>,
    pub pattern: Option<S<String>>,
    pub name_prefix: Option<S<String>>,
    pub circle_radius: Option<S<f64>>,
    pub square_width: Option<S<f64>>,
    pub center: Option<S<Pt>>,
    pub area: Option<S<RawArena>>,
    pub radius: Option<S<f64>>,
    pub preferred_speed: Option<S<f64>>,
    pub sees_robots: Option<S<bool>>,
    pub behavior: Option<S<RawBehavior>>,
    pub group: Option<S<String>>,
    pub motion: Option<S<RawPersonMotion>>,
}

/// A person's `motion = { model = ..., ... }`: the union of every model's
/// keys; which apply is checked per model.
#[derive(Debug, Default, Clone, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub(crate) struct RawPersonMotion {
    pub model: Option<S<String>>,
    pub neighbor_dist: Option<S<f64>>,
    pub max_neighbors: Option<S<i64>>,
    pub time_horizon: Option<S<f64>>,
    pub time_horizon_obst: Option<S<f64>>,
    pub radius_margin: Option<S<f64>>,
    pub relaxation_time: Option<S<f64>>,
    pub force_desired: Option<S<f64>>,
    pub force_social: Option<S<f64>>,
    pub force_obstacle: Option<S<f64>>,
    pub sigma_obstacle: Option<S<f64>>,
    pub force_group_gaze: Option<S<f64>>,
    pub force_group_coherence: Option<S<f64>>,
    pub force_group_repulsion: Option<S<f64>>,
    pub group_overlap: Option<S<f64>>,
    pub robot_scale: Option<S<f64>>,
}

/// One `[[wall]]`.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub(crate) struct RawWall {
    pub segment: Option<S<Vec<Pt>>>,
}

/// `[generate]`.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub(crate) struct RawGenerate {
    pub kind: Option<S<String>>,
    pub count: Option<S<u32>>,
    pub radius: Option<S<f64>>,
    pub center: Option<S<Pt>>,
    pub planner: Option<S<String>>,
    pub params: Option<S<RawParams>>,
    pub robot_radius: Option<S<f64>>,
    pub name_prefix: Option<S<String>>,
    pub jitter: Option<S<f64>>,
}

/// A person's `behavior`: a name, or a table of `kind` and its keys.
#[derive(Debug, Clone)]
pub(crate) enum RawBehavior {
    /// `behavior = "scared"`.
    Name(String),
    /// `behavior = { kind = "scared", ... }`.
    Table(Box<RawBehaviorTable>),
}

impl<'de> Deserialize<'de> for RawBehavior {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = RawBehavior;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a behaviour name or a table { kind = ..., ... }")
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<RawBehavior, E> {
                Ok(RawBehavior::Name(v.to_string()))
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                m: A,
            ) -> Result<RawBehavior, A::Error> {
                RawBehaviorTable::deserialize(serde::de::value::MapAccessDeserializer::new(m))
                    .map(|t| RawBehavior::Table(Box::new(t)))
            }
        }
        d.deserialize_any(V)
    }
}

/// `behavior = { kind = ..., ... }`: the union of every behaviour's keys;
/// which apply is checked per behaviour.
#[derive(Debug, Default, Clone, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub(crate) struct RawBehaviorTable {
    pub kind: Option<S<String>>,
    pub detect_dist: Option<S<f64>>,
    pub duration: Option<S<f64>>,
    pub once: Option<S<bool>>,
    pub vel: Option<S<f64>>,
    pub other_force_factor: Option<S<f64>>,
    pub stop_dist: Option<S<f64>>,
    pub front_dist: Option<S<f64>>,
}
