//! Runs counted as the crowd-navigation benchmarks count episodes
//! (`[world] end_on = ["collision", "timeout"]`): a robot's first contact
//! ends the run there, the time limit makes the robots not at their goals
//! timeouts, and metrics.json and the summary say each robot's outcome.

use crate::common::*;

/// A robot on `homing` (which avoids nothing) from (0, 0) to (6, 0), a
/// static obstacle of radius 0.5 at (3, 0) in its way, and a second robot
/// far from both on its own free line; `world` is the `[world]` table's
/// extra lines.
fn scene(world: &str) -> String {
    format!(
        r#"name = "episode"
[world]
dt = 0.1
duration = 10.0
{world}

[defaults]
radius = 0.3
max_speed = 1.0
max_accel = 10.0
mass = 1.0
goal_tolerance = 0.2
goal_hold_ticks = 1

[[robot]]
name = "r0"
start = [0.0, 0.0]
goal = [6.0, 0.0]
planner = "homing"

[[robot]]
name = "r1"
start = [0.0, 5.0]
goal = [9.0, 5.0]
planner = "homing"

[[obstacle]]
name = "o"
start = [3.0, 0.0]
radius = 0.5
motion = {{ model = "static" }}
"#
    )
}

#[test]
fn a_robot_driven_into_an_obstacle_ends_the_run_at_its_first_contact() {
    let dir = fresh_dir("episode-contact");
    let counted = run_quietly(
        &dir,
        &scene(r#"end_on = ["collision", "timeout"]"#),
        "counted",
        &["--transport", "inproc"],
    );
    let m = metrics(&counted);
    let r0 = &m["robots"]["r0"];
    assert_eq!(r0["outcome"], "collision", "{m:#}");
    assert_eq!(r0["collided_with"], "o", "{m:#}");
    assert_eq!(r0["collisions"], 1, "one contact, then the end: {m:#}");
    // r1 was on its way when r0's contact ended the run.
    assert_eq!(m["robots"]["r1"]["outcome"], "unfinished", "{m:#}");
    let e = &m["episode"];
    assert_eq!(e["outcome"], "collision", "{e:#}");
    assert_eq!(e["ended_by"], "collision", "{e:#}");
    assert_eq!(e["collision"], 1, "{e:#}");
    assert_eq!(e["unfinished"], 1, "{e:#}");
    assert_eq!(e["end_on"], serde_json::json!(["collision", "timeout"]));

    // The contact's tick is the run's last: the trajectory stops there,
    // with r0's disc touching the obstacle's (centres 0.8 apart, within
    // the step it covered in its last tick).
    let ticks = m["ticks"].as_u64().expect("ticks");
    let hit = events(&counted)
        .into_iter()
        .find(|e| e["type"] == "collision")
        .expect("a collision event");
    assert_eq!(hit["tick"].as_u64(), Some(ticks), "{hit}");
    let rows = trajectory(&counted);
    let last = rows.iter().map(|r| r.tick).max().expect("rows");
    assert_eq!(last, ticks, "the trajectory runs to the contact's tick");
    let end = *track(&rows, "r0").last().expect("r0's rows");
    let gap = norm(end.x - 3.0, end.y) - 0.8;
    assert!(
        gap <= 0.01 && gap > -0.11,
        "r0 ends at its contact: gap {gap}"
    );
    assert!(
        (e["time"].as_f64().expect("time") - end.time).abs() < 1e-9,
        "{e:#} against {end:?}"
    );
    assert!(
        (r0["outcome_time"].as_f64().expect("outcome_time") - end.time).abs() < 1e-9,
        "{r0:#}"
    );

    // Counted as mrsim counts it, the same scene runs on to its duration
    // (r0 pushes against the obstacle), and has no episode.
    let plain = run_quietly(&dir, &scene(""), "plain", &["--transport", "inproc"]);
    let p = metrics(&plain);
    assert!(p["episode"].is_null(), "{p:#}");
    assert!(p["robots"]["r0"]["outcome"].is_null(), "{p:#}");
    assert_eq!(p["ticks"], 100, "{p:#}");
    assert!(ticks < 40, "the contact came within 4 s: {ticks}");
}

#[test]
fn robots_not_at_their_goals_at_the_time_limit_are_timeouts() {
    // r1 arrives (9 m at 1 m/s in 10 s; goal tolerance 0.2); r0, its goal
    // moved behind the free side of the obstacle beyond its reach in 4 s,
    // does not.
    let world = "end_on = [\"collision\", \"timeout\"]\nduration = 4.0";
    let text = scene(world)
        .replace("duration = 10.0\n", "")
        .replace("goal = [6.0, 0.0]", "goal = [0.0, -8.0]")
        .replace("goal = [9.0, 5.0]", "goal = [3.0, 5.0]");
    let dir = fresh_dir("episode-timeout");
    let out = run_quietly(&dir, &text, "timeout", &["--transport", "inproc"]);
    let m = metrics(&out);
    assert_eq!(m["robots"]["r0"]["outcome"], "timeout", "{m:#}");
    assert_eq!(m["robots"]["r1"]["outcome"], "success", "{m:#}");
    let t1 = m["robots"]["r1"]["time_to_goal"]
        .as_f64()
        .expect("r1 arrived");
    assert_eq!(m["robots"]["r1"]["outcome_time"].as_f64(), Some(t1));
    let e = &m["episode"];
    assert_eq!(e["outcome"], "timeout", "{e:#}");
    assert_eq!(e["ended_by"], "time-limit", "{e:#}");
    assert_eq!(
        (e["success"].as_u64(), e["timeout"].as_u64()),
        (Some(1), Some(1))
    );
    assert_eq!(e["time_to_goal"].as_f64(), Some(t1), "{e:#}");

    // Without "timeout" the time limit ends the run all the same, but a
    // robot not at its goal then is unfinished, not a timeout.
    let text = text.replace(r#"["collision", "timeout"]"#, r#"["collision"]"#);
    let out = run_quietly(&dir, &text, "collision-only", &["--transport", "inproc"]);
    let m = metrics(&out);
    assert_eq!(m["robots"]["r0"]["outcome"], "unfinished", "{m:#}");
    assert_eq!(m["episode"]["outcome"], "unfinished", "{m:#}");
}

#[test]
fn the_summary_names_the_episode_s_outcome() {
    let dir = fresh_dir("episode-summary");
    let file = dir.join("s.toml");
    std::fs::write(&file, scene(r#"end_on = ["collision", "timeout"]"#)).expect("write");
    let o = run(
        &file,
        &dir.join("out"),
        &run_id("ep-summary"),
        &["--transport", "inproc", "--no-report"],
    );
    assert_ok(&o);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        stdout
            .contains("episode (collision, timeout): collision, ended by a robot's first contact")
            && stdout.contains("r0 collision with o at")
            && stdout.contains("r1 unfinished"),
        "{stdout}"
    );
}

#[test]
fn an_unknown_end_condition_is_refused_with_its_line() {
    let text = scene("end_on = [\"collision\",\n  \"crash\"]");
    let got = refused_text(&text);
    assert!(
        got.contains("s.toml:6:")
            && got.contains("unknown condition `crash` (known: collision, timeout)"),
        "{got}"
    );
    let got = refused_text(&scene(r#"end_on = ["timeout", "timeout"]"#));
    assert!(
        got.contains("s.toml:5:") && got.contains("`timeout` is listed twice"),
        "{got}"
    );
    let got = refused_text(&scene(r#"end_on = "collision""#));
    assert!(got.contains("s.toml:5"), "{got}");
}

/// What `mrsim check` says of a scenario it refuses (exit status 2).
fn refused_text(text: &str) -> String {
    let dir = fresh_dir("episode-refused");
    let file = dir.join("s.toml");
    std::fs::write(&file, text).expect("write");
    let o = mrsim().arg("check").arg(&file).output().expect("run");
    let stderr = String::from_utf8_lossy(&o.stderr).to_string();
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    stderr
}
