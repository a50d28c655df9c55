//! End-to-end tests of the spine: the launcher starts one world process and
//! one agent process per robot over iceoryx2, and the outputs, isolation and
//! ownership rules hold. No test asserts a wall-clock time.

use crate::common::*;
use std::collections::BTreeSet;
use std::process::Stdio;

#[test]
fn demo_in_lockstep_brings_every_robot_to_its_goal_driven_by_separate_processes() {
    let out = fresh_dir("demo");
    let id = run_id("demo");
    let o = mrsim()
        .args(["run", "--mode", "lockstep", "--run", &id, "--out"])
        .arg(&out)
        .output()
        .expect("start mrsim");
    assert_ok(&o);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("run folder:"), "{stdout}");
    let m = metrics(&out);
    assert_eq!(m["success_rate"], 1.0, "{m:#}");
    let robots = m["robots"].as_object().expect("robots");
    assert_eq!(robots.len(), 8);
    let world_pid = m["world_pid"].as_u64().expect("world_pid");
    let pids: BTreeSet<u64> = robots
        .values()
        .map(|r| r["agent_pid"].as_u64().expect("agent_pid"))
        .collect();
    assert_eq!(pids.len(), 8, "every robot has its own agent process");
    assert!(!pids.contains(&world_pid));
    let planners: BTreeSet<&str> = robots
        .values()
        .map(|r| r["planner"].as_str().unwrap_or(""))
        .collect();
    assert!(planners.len() >= 4, "the demo mixes planners: {planners:?}");
    for f in [
        "trajectory.csv",
        "events.jsonl",
        "scenario.json",
        "plot.svg",
        "plot.png",
        "replay.html",
    ] {
        assert!(out.join(f).exists(), "{f} missing");
    }
    assert_clean(&id);
}

#[test]
fn lockstep_runs_of_one_scenario_give_identical_trajectories() {
    let scenario = root().join("scenarios/crossing.toml");
    let (a, b) = (fresh_dir("det-a"), fresh_dir("det-b"));
    assert_ok(&run(&scenario, &a, &run_id("deta"), &[]));
    assert_ok(&run(&scenario, &b, &run_id("detb"), &[]));
    let ta = std::fs::read(a.join("trajectory.csv")).expect("a");
    let tb = std::fs::read(b.join("trajectory.csv")).expect("b");
    assert!(ta.len() > 1000);
    assert!(ta == tb, "trajectories differ");
}

#[test]
fn two_runs_at_once_do_not_interfere() {
    let scenario = root().join("scenarios/corridor.toml");
    let (a, b) = (fresh_dir("par-a"), fresh_dir("par-b"));
    let (ia, ib) = (run_id("para"), run_id("parb"));
    let spawn = |out: &std::path::Path, id: &str| {
        mrsim()
            .arg("run")
            .arg(&scenario)
            .arg("--out")
            .arg(out)
            .args(["--run", id, "--quiet"])
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("spawn")
    };
    let pa = spawn(&a, &ia);
    let pb = spawn(&b, &ib);
    let oa = pa.wait_with_output().expect("a");
    let ob = pb.wait_with_output().expect("b");
    assert_ok(&oa);
    assert_ok(&ob);
    // Same scenario, lockstep: if either run had seen the other's robots or
    // commands, the trajectories would differ.
    let ta = std::fs::read(a.join("trajectory.csv")).expect("a");
    let tb = std::fs::read(b.join("trajectory.csv")).expect("b");
    assert!(ta == tb, "parallel runs diverged");
    for m in [metrics(&a), metrics(&b)] {
        assert_eq!(m["commands_rejected"], 0);
        assert_eq!(m["agents_lost"], 0);
    }
    assert_clean(&ia);
    assert_clean(&ib);
}

#[test]
fn summary_table_has_a_row_per_robot_with_the_promised_columns() {
    let out = fresh_dir("table");
    let o = run(
        &root().join("scenarios/crossing.toml"),
        &out,
        &run_id("table"),
        &[],
    );
    assert_ok(&o);
    let stdout = String::from_utf8_lossy(&o.stdout);
    let header = stdout.lines().next().expect("header");
    for col in [
        "robot", "planner", "goal", "t_goal", "path", "coll", "min clr", "lat p99", "misses",
    ] {
        assert!(header.contains(col), "missing column {col}: {header}");
    }
    let n = metrics(&out)["robots"]
        .as_object()
        .map(|r| r.len())
        .unwrap_or(0);
    for name in metrics(&out)["robots"].as_object().expect("robots").keys() {
        assert!(
            stdout.lines().any(|l| l.starts_with(name.as_str())),
            "no row for {name}"
        );
    }
    assert!(n > 0);
}

#[test]
fn trajectory_has_every_body_every_tick() {
    let out = fresh_dir("traj");
    assert_ok(&run(
        &root().join("scenarios/crossing.toml"),
        &out,
        &run_id("traj"),
        &[],
    ));
    let rows = trajectory(&out);
    let m = metrics(&out);
    let bodies: BTreeSet<&str> = rows.iter().map(|r| r.body.as_str()).collect();
    let ticks = m["ticks"].as_u64().expect("ticks");
    assert_eq!(rows.len() as u64, (ticks + 1) * bodies.len() as u64);
    assert!(
        rows.iter()
            .all(|r| r.kind == "robot" || r.kind == "obstacle")
    );
}
