//! The verdict of the schedulability tests: `mrsim check` and the start of
//! `mrsim run` print the task set and what the tests say for a scenario
//! with `[world.cpus]` or CPU robots (and nothing new for any other); the
//! summary after the run sets predicted and measured misses side by side;
//! a sweep over the robot count for each scheduler draws one line per
//! scheduler and mode.

use crate::common::*;

fn check(file: &str, extra: &[&str]) -> String {
    let out = mrsim()
        .arg("check")
        .arg(root().join("scenarios").join(file))
        .args(extra)
        .output()
        .expect("start mrsim");
    assert_ok(&out);
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn line_with<'a>(text: &'a str, start: &str) -> &'a str {
    text.lines()
        .find(|l| l.starts_with(start))
        .unwrap_or_else(|| panic!("no line starting {start:?} in\n{text}"))
}

#[test]
fn every_scene_of_the_cores_is_checked_with_its_task_set_and_verdict() {
    let dir = root().join("scenarios/cores");
    let mut files: Vec<String> = std::fs::read_dir(&dir)
        .expect("scenarios/cores")
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".toml"))
        .collect();
    files.sort();
    assert!(files.len() >= 3, "{files:?}");
    for f in &files {
        for scheduler in ["fair", "fifo", "deadline"] {
            let set = format!("world.cpus.scheduler={scheduler}");
            let text = check(&format!("cores/{f}"), &["--set", &set]);
            assert!(text.contains(": ok ("), "{text}");
            assert!(
                text.contains(&format!("scheduler {scheduler}")),
                "{f}: {text}"
            );
            assert!(text.contains(&format!("{scheduler} tests:")), "{text}");
            line_with(&text, "predicted to miss: ");
        }
    }
}

#[test]
fn two_cores_carry_eight_robots_of_twenty_ms_but_not_twelve() {
    for scheduler in ["fair", "fifo", "deadline"] {
        let set = format!("world.cpus.scheduler={scheduler}");
        let eight = check("cores/circle-8.toml", &["--set", &set]);
        // The world's 0.2 ms above the robots leaves the fifo bound (a
        // sufficient test) unable to clear the last of eight, which the
        // model keeps.
        let none = if scheduler == "fifo" {
            "predicted to miss: 1 of 8 (g07)"
        } else {
            "predicted to miss: none"
        };
        assert_eq!(
            line_with(&eight, "predicted to miss: "),
            none,
            "{scheduler}: {eight}"
        );
        assert!(eight.contains("U = 1.602 <= 2"), "{eight}");
        let twelve = check("cores/circle-12.toml", &["--set", &set]);
        assert!(twelve.contains("fails: some robot must miss"), "{twelve}");
        assert_ne!(
            line_with(&twelve, "predicted to miss: "),
            "predicted to miss: none",
            "{scheduler}: {twelve}"
        );
    }
    // Under fair every one of the twelve shares the cores: 12 x 20 / 2 =
    // 120 ms a call, and the world's 0.2 ms.
    let fair = check("cores/circle-12.toml", &[]);
    assert!(fair.contains("predicted to miss: 12 of 12"), "{fair}");
    assert!(fair.contains("120.1 ms > D = 100 ms"), "{fair}");
}

#[test]
fn a_reservation_confines_the_runaway_where_fifo_lets_it_starve_the_others() {
    let deadline = check("cores/overrun.toml", &[]);
    assert_eq!(
        line_with(&deadline, "predicted to miss: "),
        "predicted to miss: 1 of 9 (runaway)",
        "{deadline}"
    );
    assert!(deadline.contains("throttled"), "{deadline}");
    let fifo = check(
        "cores/overrun.toml",
        &["--set", "world.cpus.scheduler=fifo"],
    );
    let missing = line_with(&fifo, "predicted to miss: ");
    assert!(missing.contains("g0"), "{fifo}");
    let fair = check(
        "cores/overrun.toml",
        &["--set", "world.cpus.scheduler=fair"],
    );
    assert_eq!(
        line_with(&fair, "predicted to miss: "),
        "predicted to miss: 1 of 9 (runaway)",
        "{fair}"
    );
}

#[test]
fn a_scenario_without_cores_or_cpu_work_checks_as_before() {
    let text = check("crossing.toml", &[]);
    assert_eq!(
        text,
        "scenarios/crossing.toml: ok (8 robots, 0 obstacles)\n".replace(
            "scenarios/crossing.toml",
            &root().join("scenarios/crossing.toml").display().to_string(),
        )
    );
    // A timing model whose compute is a wait is no task set either.
    let text = check("crossing.toml", &["--set", "defaults.timing.compute.ms=20"]);
    assert_eq!(text.lines().count(), 1, "{text}");
}

#[test]
fn a_run_prints_the_verdict_first_and_the_predicted_beside_the_measured_misses_last() {
    let dir = fresh_dir("verdict-run");
    let out = run(
        &root().join("scenarios/cores/circle-8.toml"),
        &dir,
        &run_id("verdict-run"),
        &["--transport", "inproc", "--set", "world.duration=2"],
    );
    assert_ok(&out);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.starts_with("task set: 8 robots on 2 cores, scheduler fair"),
        "{text}"
    );
    let side = text
        .split("predicted (fair) and measured misses:")
        .nth(1)
        .unwrap_or_else(|| panic!("no side by side in\n{text}"));
    let m = metrics(&dir);
    let ticks = m["ticks"].as_u64().expect("ticks");
    for (name, r) in m["robots"].as_object().expect("robots") {
        let misses = r["deadline_misses"].as_u64().expect("misses");
        let want = format!("{name} keeps {misses} of {ticks}");
        assert!(
            side.lines()
                .any(|l| l.split_whitespace().collect::<Vec<_>>().join(" ") == want),
            "{want} in {side}"
        );
    }
    assert!(side.contains("robots predicted to miss 0"), "{side}");
}

#[test]
fn a_lockstep_sweep_of_robot_counts_for_each_scheduler_draws_a_line_per_scheduler() {
    let dir = fresh_dir("verdict-sweep");
    let out = mrsim()
        .arg("sweep")
        .arg(root().join("scenarios/cores/circle-8.toml"))
        .args([
            "--set",
            "generate.count=4,12",
            "--set",
            "world.cpus.scheduler=fair,fifo,deadline",
            "--set",
            "world.duration=1",
            "--x",
            "generate.count",
            "--metrics",
            "miss_rate,predicted_missing,success_rate,collided",
        ])
        .arg("--out")
        .arg(dir.join("o"))
        .output()
        .expect("start mrsim");
    assert_ok(&out);
    let csv = std::fs::read_to_string(dir.join("o/sweep.csv")).expect("sweep.csv");
    let rows: Vec<Vec<&str>> = csv.lines().map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 1 + 2 * 3, "{csv}");
    let h = &rows[0];
    let col = |n: &str| h.iter().position(|c| *c == n).expect("column");
    let mut got: Vec<(&str, &str)> = rows[1..]
        .iter()
        .map(|r| (r[col("generate.count")], r[col("world.cpus.scheduler")]))
        .collect();
    got.sort();
    assert_eq!(
        got,
        [
            ("12", "deadline"),
            ("12", "fair"),
            ("12", "fifo"),
            ("4", "deadline"),
            ("4", "fair"),
            ("4", "fifo")
        ]
    );
    for r in &rows[1..] {
        let rate: f64 = r[col("miss_rate")].parse().expect("a miss rate");
        assert!((0.0..=1.0).contains(&rate), "{csv}");
        // The verdict: 4 x 20 ms fit on two cores under every scheduler;
        // 12 x 20 ms (U = 2.4) do not.
        let predicted: f64 = r[col("predicted_missing")].parse().expect("a prediction");
        match r[col("generate.count")] {
            "4" => assert_eq!(predicted, 0.0, "{csv}"),
            _ => assert!(predicted > 0.0, "{csv}"),
        }
    }
    let svg = std::fs::read_to_string(dir.join("o/sweep.svg")).expect("sweep.svg");
    for label in ["scheduler=fair", "scheduler=fifo", "scheduler=deadline"] {
        assert!(svg.contains(label), "no line {label} in the figure");
    }
}

/// The robots with deadline misses in a lockstep run of `file` under
/// `scheduler`, and the summary's last line of the side by side.
fn missing_in_model(file: &str, scheduler: &str) -> (Vec<String>, String) {
    let tag = format!("vm-{scheduler}");
    let dir = fresh_dir(&tag);
    let set = format!("world.cpus.scheduler={scheduler}");
    let out = run(
        &root().join("scenarios/cores").join(file),
        &dir,
        &run_id(&tag),
        &[
            "--transport",
            "inproc",
            "--set",
            &set,
            "--set",
            "world.duration=3",
        ],
    );
    assert_ok(&out);
    let m = metrics(&dir);
    let missing = m["robots"]
        .as_object()
        .expect("robots")
        .iter()
        .filter(|(_, r)| r["deadline_misses"].as_u64().unwrap_or(0) > 0)
        .map(|(n, _)| n.clone())
        .collect();
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    let last = line_with(&text, "  robots predicted to miss").to_string();
    (missing, last)
}

#[test]
fn the_cores_model_misses_where_the_verdict_predicts_and_the_verdict_is_never_the_bolder() {
    // Under deadline the reservation throttles the runaway alone.
    let (missing, last) = missing_in_model("overrun.toml", "deadline");
    assert_eq!(missing, ["runaway"], "{last}");
    assert!(last.contains("matches 9 of 9"), "{last}");
    // Under fifo the runaway holds a core and starves some of the others;
    // every robot that misses in the model was predicted to.
    let fifo = check(
        "cores/overrun.toml",
        &["--set", "world.cpus.scheduler=fifo"],
    );
    let predicted = line_with(&fifo, "predicted to miss: ").to_string();
    let (missing, last) = missing_in_model("overrun.toml", "fifo");
    assert!(missing.len() > 1, "{missing:?}");
    for r in &missing {
        assert!(
            predicted.contains(r.as_str()),
            "{r} missed, not predicted: {predicted}"
        );
    }
    // U = 2.44 > 0.95 m: the real-time throttling may make any robot late.
    assert!(last.contains("robots predicted to miss 9"), "{last}");
    // Twelve robots under fifo: the lowest priorities starve, the middle
    // ones are late where the throttling holds the cores; the first four
    // keep every deadline.
    let (missing, _) = missing_in_model("circle-12.toml", "fifo");
    assert_eq!(
        missing,
        ["g04", "g05", "g06", "g07", "g08", "g09", "g10", "g11"]
    );
}
