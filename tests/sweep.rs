//! `mrsim sweep` end to end: 2 values x 2 seeds of a tiny scenario give a
//! sweep.csv of the right shape, and the same command gives the same file.

mod common;
use common::*;

const SCENARIO: &str = r#"
name = "sweep-tiny"
[world]
dt = 0.1
duration = 2.0
[[robot]]
name = "r0"
start = [0.0, 0.0]
goal = [1.0, 0.0]
max_speed = 1.0
max_accel = 2.0
goal_tolerance = 0.1
[[obstacle]]
name = "o1"
start = [0.5, 1.0]
radius = 0.2
motion = { model = "random", accel_sigma = 1.0, max_speed = 0.5 }
"#;

fn sweep(dir: &std::path::Path, scenario: &std::path::Path) -> std::process::Output {
    mrsim()
        .arg("sweep")
        .arg(scenario)
        .args([
            "--set",
            "robot.r0.max_speed=0.5,1.5",
            "--seeds",
            "2",
            "--jobs",
            "2",
        ])
        .arg("--out")
        .arg(dir)
        .output()
        .expect("start mrsim")
}

#[test]
fn a_sweep_of_two_values_and_two_seeds_writes_four_rows_and_repeats_exactly() {
    let dir = fresh_dir("sweep");
    let scenario = dir.join("tiny.toml");
    std::fs::write(&scenario, SCENARIO).expect("write scenario");
    let out = sweep(&dir.join("a"), &scenario);
    assert_ok(&out);
    let csv = std::fs::read_to_string(dir.join("a/sweep.csv")).expect("sweep.csv");
    let rows: Vec<Vec<&str>> = csv.lines().map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 5, "{csv}");
    let header = &rows[0];
    for col in [
        "robot.r0.max_speed",
        "seed",
        "success_rate",
        "collisions_total",
        "collided",
        "makespan",
        "path_length_ratio",
        "min_clearance",
        "time_to_goal",
        "agents_lost",
        "ticks",
        "run",
    ] {
        assert!(header.contains(&col), "no column {col} in {header:?}");
    }
    let col = |name: &str| header.iter().position(|h| *h == name).expect("column");
    let got: Vec<(&str, &str)> = rows[1..]
        .iter()
        .map(|r| (r[col("robot.r0.max_speed")], r[col("seed")]))
        .collect();
    assert_eq!(
        got,
        [("0.5", "1"), ("0.5", "2"), ("1.5", "1"), ("1.5", "2")]
    );
    for r in &rows[1..] {
        assert_eq!(r.len(), header.len());
        // Each row's run folder holds that run, made at that speed.
        let run = dir.join("a").join(r[col("run")]);
        let m = metrics(&run);
        assert_eq!(m["mode"], "lockstep");
        assert_eq!(r[col("ticks")], m["ticks"].to_string());
        let sc: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(run.join("scenario.json")).expect("scenario.json"),
        )
        .expect("scenario.json parses");
        assert_eq!(
            sc["robots"][0]["max_speed"].as_f64().map(|v| v.to_string()),
            Some(r[col("robot.r0.max_speed")].to_string())
        );
        assert_eq!(sc["world"]["seed"].to_string(), r[col("seed")]);
    }
    // The summary has one line per combination.
    let summary = std::fs::read_to_string(dir.join("a/summary.csv")).expect("summary.csv");
    assert_eq!(summary.lines().count(), 3, "{summary}");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("±"), "{stdout}");

    let again = sweep(&dir.join("b"), &scenario);
    assert_ok(&again);
    let csv2 = std::fs::read_to_string(dir.join("b/sweep.csv")).expect("sweep.csv");
    assert_eq!(csv, csv2);
}

#[test]
fn a_sweep_with_a_bad_value_is_refused_before_any_run() {
    let dir = fresh_dir("sweep-bad");
    let scenario = dir.join("tiny.toml");
    std::fs::write(&scenario, SCENARIO).expect("write scenario");
    let out = mrsim()
        .arg("sweep")
        .arg(&scenario)
        .args(["--set", "robot.r0.max_speed=1,-2"])
        .arg("--out")
        .arg(dir.join("o"))
        .output()
        .expect("start mrsim");
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("max_speed=-2"), "{err}");
    assert!(!dir.join("o").exists());
}
