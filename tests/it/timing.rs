//! Timing models through the real binary: in lockstep the model decides
//! (deterministic, and what each model promises), in realtime it is spent
//! for real and recorded, and `mrsim rerun` replays the record exactly.

use crate::common::*;
use std::path::Path;

/// Four orca robots crossing in pairs, one obstacle, 10 Hz, a timing
/// model for every robot given by `timing` (the body of
/// `[defaults.timing]`), `mode` and `duration` seconds.
fn crossing(timing: &str, mode: &str, duration: f64) -> String {
    four_crossing(
        "timed-crossing",
        &format!("duration = {duration}\nmode = \"{mode}\"\nstall_timeout = 10.0"),
        &format!("[defaults.timing]\n{timing}"),
        true,
    )
}

const EVERYTHING: &str = r#"compute = { model = "uniform", min_ms = 20.0, max_ms = 160.0 }
observation_delay_ms = 100.0
actuation_delay_ms = 20.0
snapshot_loss = 0.1
command_loss = 0.05"#;

#[test]
fn a_lockstep_run_with_timing_models_run_twice_gives_identical_trajectories_and_miss_counts() {
    let dir = fresh_dir("timing-twice");
    let text = crossing(EVERYTHING, "lockstep", 8.0);
    let a = run_quietly(&dir, &text, "a", &["--transport", "inproc"]);
    let b = run_quietly(&dir, &text, "b", &["--transport", "inproc"]);
    let c = run_quietly(&dir, &text, "c", &[]);
    let ma = misses_of(&a, 4);
    assert!(
        ma.iter().all(|&(m, l)| m > 0 && l > 0),
        "the model makes misses: {ma:?}"
    );
    for other in [&b, &c] {
        assert_eq!(
            file_bytes(&a, "trajectory.csv"),
            file_bytes(other, "trajectory.csv")
        );
        // The same calls; within a tick in the order the world heard them.
        let sorted = |d: &Path| {
            let mut c = timing_rows(d);
            c.sort();
            c
        };
        assert_eq!(sorted(&a), sorted(other));
        assert_eq!(ma, misses_of(other, 4));
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn compute_above_the_deadline_makes_every_tick_a_miss() {
    let dir = fresh_dir("timing-slow");
    let text = crossing(
        r#"compute = { model = "fixed", ms = 150.0 }"#,
        "lockstep",
        3.0,
    );
    let out = run_quietly(&dir, &text, "slow", &["--transport", "inproc"]);
    let ticks = metrics(&out)["ticks"].as_u64().expect("ticks");
    assert_eq!(ticks, 30);
    for (m, late) in misses_of(&out, 4) {
        assert_eq!(m, ticks, "every tick a miss");
        // Planning on ticks 0, 1, 3, 4, 6, ...: two of every three.
        assert_eq!(late, 20);
    }
    // Never a command applied: every robot holds its start.
    let rows = trajectory(&out);
    for r in rows.iter().filter(|r| r.kind == "robot") {
        assert_eq!((r.vx, r.vy), (0.0, 0.0), "{r:?}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn period_ticks_2_plans_every_other_tick_without_misses() {
    let dir = fresh_dir("timing-period");
    let text = crossing("period_ticks = 2", "lockstep", 3.0);
    let out = run_quietly(&dir, &text, "period", &["--transport", "inproc"]);
    let rows = timing_rows(&out);
    for i in 0..4 {
        let robot = format!("r{i}");
        let ticks: Vec<u64> = rows.iter().filter(|r| r.1 == robot).map(|r| r.0).collect();
        assert_eq!(ticks, (0..30).step_by(2).collect::<Vec<u64>>(), "{robot}");
    }
    assert!(rows.iter().all(|r| r.3 == "accepted"));
    assert_eq!(misses_of(&out, 4), vec![(0, 0); 4]);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn losses_at_rate_p_lose_about_p() {
    let dir = fresh_dir("timing-loss");
    let text = crossing("snapshot_loss = 0.3\ncommand_loss = 0.2", "lockstep", 60.0);
    let out = run_quietly(&dir, &text, "loss", &["--transport", "inproc"]);
    let ticks = metrics(&out)["ticks"].as_u64().expect("ticks") as f64;
    let rows = timing_rows(&out);
    let n = rows.len() as f64;
    // Snapshots read: (1 - 0.3) of 4 robots' ticks; commands lost: 0.2 of
    // those. Four standard errors.
    let read = n / (4.0 * ticks);
    let se = (0.3 * 0.7 / (4.0 * ticks)).sqrt();
    assert!(
        (read - 0.7).abs() < 4.0 * se,
        "read {read} of the snapshots"
    );
    let lost = rows.iter().filter(|r| r.3 == "lost").count() as f64 / n;
    let se = (0.2 * 0.8 / n).sqrt();
    assert!((lost - 0.2).abs() < 4.0 * se, "lost {lost} of the commands");
    // Every tick without an applied command is a miss.
    let accepted = rows.iter().filter(|r| r.3 == "accepted").count() as u64;
    let missed: u64 = misses_of(&out, 4).iter().map(|m| m.0).sum();
    assert_eq!(missed, 4 * ticks as u64 - accepted);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_command_takes_effect_from_the_physics_substep_it_arrives_in() {
    // One orca robot alone, velocity tracked within a substep: 50 ms of
    // compute at 10 Hz, 10 substeps, moves it for the last 5 substeps of
    // tick 0 (0.05 m at 1 m/s), where no model moves it the whole tick.
    let dir = fresh_dir("timing-substep");
    let one = |timing: &str| {
        format!(
            "[world]\ndt = 0.1\nsubsteps = 10\nduration = 0.3\n[defaults]\nmax_accel = 1e6\nmax_speed = 1.0\nplanner = \"orca\"\n{timing}\n[[robot]]\nname = \"r0\"\nstart = [0.0, 0.0]\ngoal = [5.0, 0.0]\n"
        )
    };
    let x1 = |out: &Path| {
        trajectory(out)
            .iter()
            .find(|r| r.tick == 1)
            .map(|r| r.x)
            .expect("tick 1")
    };
    let plain = run_quietly(&dir, &one(""), "plain", &["--transport", "inproc"]);
    let none = run_quietly(
        &dir,
        &one("[defaults.timing]\ncompute = { model = \"none\" }"),
        "none",
        &["--transport", "inproc"],
    );
    let slow = run_quietly(
        &dir,
        &one("[defaults.timing]\ncompute = { model = \"fixed\", ms = 50.0 }"),
        "slow",
        &["--transport", "inproc"],
    );
    let delayed = run_quietly(
        &dir,
        &one(
            "[defaults.timing]\ncompute = { model = \"fixed\", ms = 30.0 }\nactuation_delay_ms = 41.0",
        ),
        "delayed",
        &["--transport", "inproc"],
    );
    assert!((x1(&plain) - 0.1).abs() < 1e-6, "{}", x1(&plain));
    assert_eq!(
        file_bytes(&plain, "trajectory.csv"),
        file_bytes(&none, "trajectory.csv")
    );
    assert!((x1(&slow) - 0.05).abs() < 1e-6, "{}", x1(&slow));
    // Sent at 30 ms, in effect at 71 ms: from the substep at 80 ms.
    assert!((x1(&delayed) - 0.02).abs() < 1e-6, "{}", x1(&delayed));
    let _ = std::fs::remove_dir_all(&dir);
}

/// Runs `mrsim rerun RUN --out OUT [extra]`.
fn rerun(recorded: &Path, out: &Path, extra: &[&str]) -> std::process::Output {
    mrsim()
        .arg("rerun")
        .arg(recorded)
        .arg("--out")
        .arg(out)
        .arg("--no-report")
        .args(extra)
        .output()
        .expect("start mrsim rerun")
}

#[test]
fn a_realtime_run_with_misses_rerun_in_lockstep_gives_the_same_trajectory_byte_for_byte() {
    let dir = fresh_dir("timing-rerun");
    // Agents slowed by a compute model: misses, late commands, planners
    // reading whichever snapshot is newest when they are free.
    let text = crossing(
        "compute = { model = \"uniform\", min_ms = 30.0, max_ms = 180.0 }\nactuation_delay_ms = 10.0\ncommand_loss = 0.05",
        "realtime",
        4.0,
    );
    let rec = run_quietly(&dir, &text, "realtime", &[]);
    // Realtime: every call's CPU measured on the agent's thread clock (the
    // planner's own; this compute model is a wait), and its response time.
    assert!(timing_rows(&rec).iter().all(|r| r.4 > 0));
    let m = metrics(&rec);
    for r in ["r0", "r1", "r2", "r3"] {
        let cpu = &m["robots"][r]["cpu_us"];
        let response = &m["robots"][r]["response_us"];
        assert!(cpu["count"].as_u64() > Some(0), "{r}: {cpu}");
        assert!(
            response["p50"].as_f64() > cpu["p50"].as_f64(),
            "{r}: {response}"
        );
    }
    let recorded = misses_of(&rec, 4);
    assert!(
        recorded.iter().any(|&(m, _)| m > 0),
        "no misses: {recorded:?}"
    );
    let again = dir.join("again");
    let out = rerun(&rec, &again, &[]);
    assert_ok(&out);
    assert_eq!(
        file_bytes(&rec, "trajectory.csv"),
        file_bytes(&again, "trajectory.csv")
    );
    // Misses alike (a command more than a tick late is counted as
    // rejected in realtime, as late in the rerun: the totals of late
    // answers may differ, what they did may not).
    let m = |v: Vec<(u64, u64)>| v.iter().map(|x| x.0).collect::<Vec<_>>();
    assert_eq!(m(recorded), m(misses_of(&again, 4)));

    // A counterfactual: r1 plans with social-force under the same timing.
    // Nothing can differ before r1's first command takes effect.
    let cf = dir.join("counterfactual");
    assert_ok(&rerun(
        &rec,
        &cf,
        &["--set", "robot.r1.planner=social-force"],
    ));
    let first = timing_rows(&rec)
        .iter()
        .filter(|r| r.1 == "r1" && r.3 == "accepted")
        .map(|r| r.0)
        .min()
        .expect("r1 had a command accepted");
    let (a, b) = (trajectory(&rec), trajectory(&cf));
    let key = |r: &Row| format!("{} {} {} {} {} {}", r.tick, r.body, r.x, r.y, r.vx, r.vy);
    for (ra, rb) in a.iter().zip(&b).filter(|(r, _)| r.tick <= first) {
        assert_eq!(key(ra), key(rb), "before r1's first command could act");
    }
    let r1 = |rows: &[Row]| track(rows, "r1").iter().map(|r| key(r)).collect::<Vec<_>>();
    assert_ne!(r1(&a), r1(&b), "the counterfactual changed nothing");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_realtime_run_recorded_as_parquet_writes_timing_parquet_and_reruns_byte_for_byte() {
    let dir = fresh_dir("timing-rerun-parquet");
    let text = crossing(
        "compute = { model = \"uniform\", min_ms = 30.0, max_ms = 180.0 }\ncommand_loss = 0.05",
        "realtime",
        2.0,
    );
    let rec = run_quietly(
        &dir,
        &text,
        "realtime",
        &["--set", "output.trajectory=parquet"],
    );
    assert!(rec.join("timing.parquet").is_file(), "no timing.parquet");
    assert!(
        !rec.join("timing.csv").exists(),
        "timing.csv beside the Parquet file"
    );
    assert!(
        misses_of(&rec, 4).iter().any(|&(m, _)| m > 0),
        "no misses to replay"
    );
    let again = dir.join("again");
    assert_ok(&rerun(&rec, &again, &[]));
    assert!(again.join("timing.parquet").is_file());
    assert_eq!(
        file_bytes(&rec, "trajectory.parquet"),
        file_bytes(&again, "trajectory.parquet")
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn rerun_refuses_a_folder_that_is_not_a_recorded_run() {
    let dir = fresh_dir("timing-rerun-bad");
    let out = rerun(&dir, &dir.join("x"), &[]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("cannot rerun") && err.contains("source.json"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
