//! Invalid scenarios are refused before any process starts, with the file,
//! the line and the reason, and exit status 2.

use crate::common::*;

const GOOD: &str = r#"name = "t"
[world]
dt = 0.1
duration = 5.0
arena = { min = [-10, -10], max = [10, 10] }

[[robot]]
name = "a"
start = [0.0, 0.0]
goal = [5.0, 0.0]
planner = "homing"

[[robot]]
name = "b"
start = [0.0, 3.0]
goal = [5.0, 3.0]
planner = "chung-1"

[[obstacle]]
name = "o"
start = [3.0, -3.0]
radius = 0.5
motion = { model = "constant-velocity", velocity = [0.0, 1.0] }
"#;

fn refused(src: &str, line: usize, reason_part: &str) {
    let dir = fresh_dir("invalid");
    let file = dir.join("bad.toml");
    std::fs::write(&file, src).expect("write");
    let out_dir = dir.join("out");
    let o = mrsim()
        .arg("run")
        .arg(&file)
        .arg("--out")
        .arg(&out_dir)
        .output()
        .expect("run");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "stderr: {stderr}");
    let at = format!("bad.toml:{line}");
    assert!(stderr.contains(&at), "expected `{at}` in: {stderr}");
    assert!(
        stderr.to_lowercase().contains(&reason_part.to_lowercase()),
        "expected `{reason_part}` in: {stderr}"
    );
    assert!(!out_dir.join("metrics.json").exists(), "nothing may run");
}

#[test]
fn the_good_file_runs() {
    let dir = fresh_dir("good");
    let file = dir.join("good.toml");
    std::fs::write(&file, GOOD).expect("write");
    let out = dir.join("out");
    let o = run(&file, &out, &run_id("good"), &["--quiet", "--no-report"]);
    assert_ok(&o);
    // It ran: the whole 5 s at dt 0.1 (b's goal is 5 m away under homing),
    // both robots and the obstacle in trajectory.csv.
    let m = metrics(&out);
    assert!(m["ticks"].as_u64().is_some_and(|t| t > 0), "{m:#}");
    for name in ["a", "b"] {
        assert!(
            m["robots"][name].is_object(),
            "no metrics for {name}: {m:#}"
        );
    }
    let rows = trajectory(&out);
    for body in ["a", "b", "o"] {
        assert!(!track(&rows, body).is_empty(), "no rows of {body}");
    }
}

#[test]
fn unknown_key_is_refused_with_its_line() {
    refused(
        &GOOD.replace("planner = \"homing\"", "planner = \"homing\"\nspeeed = 3"),
        12,
        "speeed",
    );
}

#[test]
fn unknown_planner_is_refused_with_its_line() {
    refused(
        &GOOD.replace("planner = \"chung-1\"", "planner = \"teleport\""),
        17,
        "teleport",
    );
}

#[test]
fn unknown_planner_parameter_is_refused_with_its_line() {
    refused(
        &GOOD.replace(
            "planner = \"chung-1\"",
            "planner = \"chung-1\"\nparams = { f_q = 1.0 }",
        ),
        18,
        "f_q",
    );
}

#[test]
fn nan_is_refused_with_its_line() {
    refused(
        &GOOD.replace("goal = [5.0, 3.0]", "goal = [nan, 3.0]"),
        16,
        "must be finite numbers, got [NaN, 3]",
    );
}

#[test]
fn negative_radius_is_refused_with_its_line() {
    refused(&GOOD.replace("radius = 0.5", "radius = -0.5"), 22, "radius");
}

#[test]
fn overlapping_starts_are_refused_with_its_line() {
    refused(
        &GOOD.replace("start = [0.0, 3.0]", "start = [0.1, 0.0]"),
        15,
        "overlap",
    );
}

#[test]
fn duplicate_names_are_refused_with_its_line() {
    refused(
        &GOOD.replace("name = \"b\"", "name = \"a\""),
        13,
        "duplicate name: there is already a robot `a`",
    );
}

#[test]
fn goal_outside_the_arena_is_refused_with_its_line() {
    refused(
        &GOOD.replace("goal = [5.0, 3.0]", "goal = [50.0, 3.0]"),
        16,
        "arena",
    );
}

#[test]
fn unwritable_output_folder_is_refused_before_anything_starts() {
    let dir = fresh_dir("unwritable");
    let file = dir.join("good.toml");
    std::fs::write(&file, GOOD).expect("write");
    let blocker = dir.join("not-a-dir");
    std::fs::write(&blocker, b"x").expect("write");
    let o = mrsim()
        .arg("run")
        .arg(&file)
        .arg("--out")
        .arg(blocker.join("out"))
        .output()
        .expect("run");
    assert_eq!(
        o.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(String::from_utf8_lossy(&o.stderr).contains("output folder"));
}
