//! The scene a bench runs: a generated crossing of two robot streams in a
//! walled arena, as the TOML text `mrsim run` reads.

/// Robot radius, queue spacing and sensing range of the generated scene, m.
const ROBOT_RADIUS: f64 = 0.25;
const SENSING_RANGE: f64 = 3.0;
const HEAD_DISTANCE: f64 = 3.0;

/// The generated scene for `agents` robots: two crossing streams in a walled
/// arena large enough for both queues and their mirrored goals, realtime at
/// `rate` Hz for `duration` s, one physics substep per tick.
pub(super) fn scene_toml(
    agents: usize,
    rate: f64,
    duration: f64,
    planner: &str,
    deadline: f64,
) -> String {
    // Queue spacing of [generate] crossing: three robot radii.
    let queue = agents.div_ceil(2) as f64 * 3.0 * ROBOT_RADIUS;
    let half = (HEAD_DISTANCE + queue + 2.0).ceil();
    format!(
        r#"name = "bench-crossing-{agents}"
description = "mrsim bench: {agents} robots in two streams crossing at right angles, realtime at {rate} Hz, {planner}"
length_unit = "m"

[world]
dt = {dt}
substeps = 1
duration = {duration}
mode = "realtime"
on_deadline_miss = "hold"
deadline = {deadline}
seed = 1
arena = {{ min = [-{half}, -{half}], max = [{half}, {half}] }}

[defaults]
radius = {ROBOT_RADIUS}
max_speed = 1.0
max_accel = 2.0
sensing_range = {SENSING_RANGE}
goal_tolerance = 0.1

[generate]
kind = "crossing"
count = {agents}
radius = {HEAD_DISTANCE}
planner = "{planner}"
"#,
        dt = 1.0 / rate,
    )
}
