//! What a sweep takes from a run: its metrics.json and scenario.json
//! boiled down to the columns of sweep.csv.

use std::path::Path;

/// One run's row of sweep.csv: its metrics boiled down to the columns.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SweepRow {
    /// Fraction of robots that reached their goals.
    pub success_rate: f64,
    /// Contacts started, all robots (with people not among them).
    pub collisions_total: f64,
    /// Contacts started between a robot and a person.
    pub person_collisions_total: f64,
    /// Max time_to_goal if every robot arrived, else the run's duration.
    pub makespan: f64,
    /// Mean over robots of path_length / straight start-goal distance.
    pub path_ratio: Option<f64>,
    /// Min over robots of min_clearance.
    pub min_clearance: Option<f64>,
    /// Mean time_to_goal of the robots that arrived.
    pub time_to_goal: Option<f64>,
    /// Agents lost during the run.
    pub agents_lost: f64,
    /// Ticks run.
    pub ticks: f64,
    /// The run's `spl` (mean over robots).
    pub spl: Option<f64>,
    /// Sum of the robots' times to goal, if every robot arrived.
    pub flowtime: Option<f64>,
    /// Contacts per robot-kilometre.
    pub collisions_per_robot_km: Option<f64>,
    /// Deadlocks detected.
    pub deadlocks: f64,
    /// Means over robots of the interaction metrics, in the order of
    /// [`ROBOT_MEANS`].
    pub robot_means: [Option<f64>; ROBOT_MEANS.len()],
    /// Deadline misses per robot and tick (lockstep: those its timing
    /// model decides; realtime: those measured).
    pub miss_rate: Option<f64>,
    /// The fraction of robots the schedulability verdict predicts may
    /// miss deadlines (`mrsim_scenario::schedulability`), for a scenario
    /// with `[world.cpus]` or CPU robots.
    pub predicted_missing: Option<f64>,
}

/// How a per-robot metric is read from a robot's entry of metrics.json.
pub type RobotColumn = (
    &'static str,
    fn(&mrsim_runfolder::RobotMetrics) -> Option<f64>,
);

/// The per-robot metrics sweep.csv reports as a mean over the run's robots.
pub const ROBOT_MEANS: [RobotColumn; 9] = [
    ("time_not_moving", |r| r.time_not_moving),
    ("ttc_min", |r| r.ttc_min.flatten()),
    ("time_intimate", |r| r.time_intimate),
    ("time_personal", |r| r.time_personal),
    ("time_social", |r| r.time_social),
    ("jerk_mean", |r| r.jerk_mean),
    ("path_irregularity", |r| r.path_irregularity),
    ("heading_change", |r| r.heading_change),
    ("stuck_time", |r| r.stuck_time),
];

/// How a metric column is read from a run's metrics.
pub type Column = (&'static str, fn(&SweepRow) -> Option<f64>);

/// The metric columns of sweep.csv, in order, with how to get each.
pub const METRICS: [Column; 24] = [
    ("success_rate", |m| Some(m.success_rate)),
    ("collisions_total", |m| Some(m.collisions_total)),
    // 1 if the run had any collision, with a person too: its mean is the
    // collision rate.
    ("collided", |m| {
        Some(f64::from(u8::from(
            m.collisions_total + m.person_collisions_total > 0.0,
        )))
    }),
    ("makespan", |m| Some(m.makespan)),
    ("path_length_ratio", |m| m.path_ratio),
    ("min_clearance", |m| m.min_clearance),
    ("time_to_goal", |m| m.time_to_goal),
    ("agents_lost", |m| Some(m.agents_lost)),
    ("ticks", |m| Some(m.ticks)),
    ("spl", |m| m.spl),
    ("flowtime", |m| m.flowtime),
    ("collisions_per_robot_km", |m| m.collisions_per_robot_km),
    ("deadlocks", |m| Some(m.deadlocks)),
    ("time_not_moving", |m| m.robot_means[0]),
    ("ttc_min", |m| m.robot_means[1]),
    ("time_intimate", |m| m.robot_means[2]),
    ("time_personal", |m| m.robot_means[3]),
    ("time_social", |m| m.robot_means[4]),
    ("jerk_mean", |m| m.robot_means[5]),
    ("path_irregularity", |m| m.robot_means[6]),
    ("heading_change", |m| m.robot_means[7]),
    ("stuck_time", |m| m.robot_means[8]),
    ("miss_rate", |m| m.miss_rate),
    ("predicted_missing", |m| m.predicted_missing),
];

/// A run folder's file that could not be read, in words.
fn file_error(e: mrsim_runfolder::FileError) -> String {
    match e {
        mrsim_runfolder::FileError::Io { path, source } => {
            format!("reading {}: {source}", path.display())
        }
        mrsim_runfolder::FileError::Json { path, source } => {
            format!("parsing {}: {source}", path.display())
        }
    }
}

/// Reads a run folder's metrics.json and scenario.json (with the run
/// folder's schema and the scenario's own type).
pub fn read_run(dir: &Path) -> Result<SweepRow, String> {
    let m = mrsim_runfolder::read_metrics(dir).map_err(file_error)?;
    let sc: mrsim_scenario::Scenario =
        mrsim_runfolder::read_json(dir, mrsim_runfolder::SCENARIO_FILE).map_err(file_error)?;
    let ticks = m.ticks as f64;
    let mut arrived = Vec::new();
    let mut ratios = Vec::new();
    let mut clearance: Option<f64> = None;
    let mut all_arrived = true;
    let none = Default::default();
    for r in &sc.robots {
        let rm = m.robots.get(&r.name).unwrap_or(&none);
        match rm.time_to_goal {
            Some(t) if rm.reached_goal => arrived.push(t),
            _ => all_arrived = false,
        }
        let straight = (r.goal[0] - r.start[0]).hypot(r.goal[1] - r.start[1]);
        if straight > 0.0 {
            ratios.push(rm.path_length / straight);
        }
        if let Some(c) = rm.min_clearance {
            clearance = Some(clearance.map_or(c, |m: f64| m.min(c)));
        }
    }
    let mean = |xs: &[f64]| (!xs.is_empty()).then(|| xs.iter().sum::<f64>() / xs.len() as f64);
    let makespan = if all_arrived && !arrived.is_empty() {
        arrived.iter().copied().fold(f64::MIN, f64::max)
    } else {
        ticks * sc.world.dt
    };
    let robot_means = ROBOT_MEANS.map(|(_, get)| {
        let xs: Vec<f64> = m.robots.values().filter_map(get).collect();
        mean(&xs)
    });
    let slots = m.robots.len() as f64 * ticks;
    let miss_rate = (slots > 0.0).then(|| {
        m.robots
            .values()
            .map(|r| r.deadline_misses as f64)
            .sum::<f64>()
            / slots
    });
    let predicted_missing = mrsim_scenario::schedulability::of_scenario(&sc)
        .map(|(set, v)| v.predicted_misses().len() as f64 / set.tasks.len().max(1) as f64);
    Ok(SweepRow {
        miss_rate,
        predicted_missing,
        spl: m.spl,
        flowtime: m.flowtime.flatten(),
        collisions_per_robot_km: m.collisions_per_robot_km.flatten(),
        deadlocks: m.deadlocks.len() as f64,
        robot_means,
        success_rate: m.success_rate,
        collisions_total: m.collisions_total as f64,
        person_collisions_total: m.person_collisions_total.unwrap_or(0) as f64,
        makespan,
        path_ratio: mean(&ratios),
        min_clearance: clearance,
        time_to_goal: mean(&arrived),
        agents_lost: m.agents_lost as f64,
        ticks,
    })
}
