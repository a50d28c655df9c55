//! What happened between the robots, end to end: a deadlock found (and
//! named in the summary) where two groups of homing robots meet head-on in
//! a corridor, none where every robot arrives, and the interaction metrics
//! and encounters.csv written beside metrics.json.

use crate::common::*;

/// Runs `scenario` in-process, lockstep, with `extra` arguments; returns
/// the run folder and stdout.
fn lockstep(scenario: &std::path::Path, tag: &str, extra: &[&str]) -> (std::path::PathBuf, String) {
    let dir = fresh_dir(tag);
    let mut args = vec!["--transport", "inproc", "--mode", "lockstep"];
    args.extend_from_slice(extra);
    let out = run(scenario, &dir, &run_id(tag), &args);
    assert_ok(&out);
    (dir, String::from_utf8_lossy(&out.stdout).into_owned())
}

#[test]
fn homing_robots_head_on_in_a_corridor_deadlock_and_the_summary_says_so() {
    let (dir, stdout) = lockstep(
        &root().join("scenarios/corridor.toml"),
        "corr-dl",
        &["--set", "world.end_when_stuck=true"],
    );
    let m = metrics(&dir);
    let deadlocks = m["deadlocks"]
        .as_array()
        .expect("deadlocks in metrics.json");
    assert!(!deadlocks.is_empty(), "{m}");
    // The two heads meet first: they are in the first deadlock.
    let first: Vec<&str> = deadlocks[0]["robots"]
        .as_array()
        .expect("members")
        .iter()
        .filter_map(|v| v.as_str())
        .collect();
    assert!(first.contains(&"l0") && first.contains(&"r0"), "{first:?}");
    assert_eq!(m["ended_stuck"], true, "{m}");
    // Ended early, well before the 60 s the scene allows.
    assert!(m["sim_time"].as_f64().expect("sim_time") < 59.0, "{m}");
    for r in m["robots"].as_object().expect("robots").values() {
        assert_eq!(r["spl"], 0.0, "{r}");
    }
    // The heads were stuck first, and longest; the last robot was declared
    // stuck at the run's last tick.
    let stuck = |n: &str| m["robots"][n]["stuck_time"].as_f64().expect("stuck_time");
    assert!(stuck("l0") > 0.0 && stuck("l0") >= stuck("l1"), "{m}");
    assert!(stdout.contains("deadlock at t = "), "{stdout}");
    assert!(stdout.contains("avoids nothing"), "{stdout}");
    let kinds: Vec<String> = events(&dir)
        .iter()
        .filter_map(|e| e["type"].as_str().map(String::from))
        .collect();
    for k in ["stuck", "deadlock", "all_stuck"] {
        assert!(kinds.iter().any(|t| t == k), "no {k} event: {kinds:?}");
    }
    // The heads met head-on and neither gave way (homing pushes on).
    let text = std::fs::read_to_string(dir.join("encounters.csv")).expect("encounters.csv");
    let rows = mrsim_runfolder::encounters::parse_encounters(&text).expect("encounters.csv reads");
    let heads = rows
        .iter()
        .find(|e| e.a == "l0" && e.b == "r0")
        .expect("l0 and r0 met");
    assert_eq!(heads.kind, "head-on");
    assert!(heads.min_gap <= 0.0, "{heads:?}");
    assert_eq!(heads.min_ttc, Some(0.0));
}

#[test]
fn robots_that_all_arrive_are_neither_stuck_nor_deadlocked() {
    let dir = fresh_dir("arrive-scene");
    let file = dir.join("pass.toml");
    // Two robots swapping ends on lines 0.75 m apart: orca passes.
    std::fs::write(
        &file,
        r#"
name = "pass"
[world]
duration = 30.0
[defaults]
planner = "orca"
radius = 0.25
max_speed = 1.0
max_accel = 2.0
goal_tolerance = 0.1
[[robot]]
name = "a"
start = [-5.0, 0.0]
goal = [5.0, 0.0]
[[robot]]
name = "b"
start = [5.0, 0.75]
goal = [-5.0, 0.75]
"#,
    )
    .expect("write scenario");
    let (out, stdout) = lockstep(&file, "arrive", &[]);
    let m = metrics(&out);
    assert_eq!(m["success_rate"], 1.0, "{m}");
    assert!(m.get("deadlocks").is_none(), "{m}");
    assert!(!stdout.contains("deadlock"), "{stdout}");
    for r in m["robots"].as_object().expect("robots").values() {
        assert_eq!(r["stuck_time"], 0.0, "{r}");
        let spl = r["spl"].as_f64().expect("spl");
        assert!(spl > 0.9 && spl <= 1.0, "{r}");
        // Lines 0.75 m apart, radii 0.25: passing, the surfaces come
        // within the personal distance.
        assert!(r["time_personal"].as_f64().expect("personal") > 0.0, "{r}");
    }
    assert!(m["makespan"].as_f64().is_some() && m["flowtime"].as_f64().is_some());
    let text = std::fs::read_to_string(out.join("encounters.csv")).expect("encounters.csv");
    let rows = mrsim_runfolder::encounters::parse_encounters(&text).expect("encounters.csv reads");
    assert_eq!(rows.len(), 1, "{text}");
    assert_eq!(rows[0].kind, "head-on");
}
