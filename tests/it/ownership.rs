//! Only the agent that owns a robot can drive it; strangers are refused.
//! The world and agents are started by hand, as a user would in separate
//! terminals.

use crate::common::*;
use std::process::Stdio;

#[test]
fn a_command_for_a_robot_the_agent_does_not_own_is_rejected_and_logged() {
    let dir = fresh_dir("own");
    let file = dir.join("two.toml");
    std::fs::write(&file, TWO).expect("write");
    let out = dir.join("out");
    let id = run_id("own");
    let mut world = mrsim()
        .arg("world")
        .arg(&file)
        .args(["--run", &id, "--start-timeout", "30", "--out"])
        .arg(&out)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("world");
    // The agent for `a` claims robot 1 (`b`) in every command.
    let mut rogue = mrsim()
        .args(["agent", "--robot", "a", "--run", &id, "--impersonate", "1"])
        .stderr(Stdio::piped())
        .spawn()
        .expect("rogue");
    let mut honest = mrsim()
        .args(["agent", "--robot", "b", "--run", &id])
        .stderr(Stdio::piped())
        .spawn()
        .expect("honest");
    let ws = wait_timeout(&mut world, 60).expect("world ended");
    assert!(ws.success(), "world failed");
    wait_timeout(&mut rogue, 10);
    wait_timeout(&mut honest, 10);

    let m = metrics(&out);
    assert!(m["commands_rejected"].as_u64().unwrap_or(0) > 0, "{m:#}");
    assert!(
        m["robots"]["b"]["commands_rejected"].as_u64().unwrap_or(0) > 0,
        "{m:#}"
    );
    // b was driven only by its own agent and got home; a never moved.
    assert_eq!(m["robots"]["b"]["reached_goal"], true, "{m:#}");
    assert_eq!(m["robots"]["a"]["reached_goal"], false);
    let rows = trajectory(&out);
    let a = track(&rows, "a");
    assert!(
        a.iter().all(|r| r.x.abs() < 1e-6 && r.y.abs() < 1e-6),
        "a moved"
    );
    let ev = events(&out);
    assert!(
        ev.iter()
            .any(|e| e["type"] == "command_rejected" && e["robot"] == "b"),
        "no command_rejected event for b"
    );
    assert_clean(&id);
}

#[test]
fn a_stranger_is_refused_with_a_clear_message_and_the_run_is_unaffected() {
    let dir = fresh_dir("stranger");
    let file = dir.join("two.toml");
    std::fs::write(&file, TWO).expect("write");
    let out = dir.join("out");
    let id = run_id("str");
    let mut world = mrsim()
        .arg("world")
        .arg(&file)
        .args(["--run", &id, "--start-timeout", "30", "--out"])
        .arg(&out)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("world");
    let a = mrsim()
        .args(["agent", "--robot", "a", "--run", &id])
        .spawn()
        .expect("a");
    // a has joined before anyone else asks for it (on a busy machine the
    // second agent for a could otherwise ask first, and be accepted).
    let joined = |line: &str| line.contains("\"agent_joined\"") && line.contains("\"robot\":\"a\"");
    let start = std::time::Instant::now();
    while !std::fs::read_to_string(out.join("events.jsonl")).is_ok_and(|t| t.lines().any(joined)) {
        assert!(start.elapsed().as_secs() < 30, "agent a did not join");
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    // Wrong robot name.
    let o = mrsim()
        .args(["agent", "--robot", "zz", "--run", &id, "--timeout", "20"])
        .output()
        .expect("zz");
    assert!(!o.status.success());
    let msg = String::from_utf8_lossy(&o.stderr);
    assert!(msg.contains("no robot named `zz`"), "{msg}");
    // The robot is already driven.
    let o = mrsim()
        .args(["agent", "--robot", "a", "--run", &id, "--timeout", "20"])
        .output()
        .expect("a2");
    assert!(!o.status.success());
    let msg = String::from_utf8_lossy(&o.stderr);
    assert!(msg.contains("already driven"), "{msg}");
    // Another protocol version.
    let o = mrsim()
        .args(["agent", "--robot", "b", "--run", &id, "--timeout", "20"])
        .args(["--protocol-version", "99"])
        .output()
        .expect("old");
    assert!(!o.status.success());
    let msg = String::from_utf8_lossy(&o.stderr);
    assert!(
        msg.contains("protocol version 99 refused") && msg.contains("speaks version"),
        "{msg}"
    );
    let mut b = mrsim()
        .args(["agent", "--robot", "b", "--run", &id])
        .spawn()
        .expect("b");
    let ws = wait_timeout(&mut world, 60).expect("world ended");
    assert!(ws.success());
    let mut a = a;
    wait_timeout(&mut a, 10);
    wait_timeout(&mut b, 10);
    let m = metrics(&out);
    assert_eq!(m["success_rate"], 1.0, "{m:#}");
    assert_eq!(m["commands_rejected"], 0);
    assert_eq!(m["agents_lost"], 0);
    // Each refusal is in the events, with its reason; none of them drove b
    // (b joined once, after the refusals, and was never lost).
    let ev = events(&out);
    let refused: Vec<&str> = ev
        .iter()
        .filter(|e| e["type"] == "join_refused")
        .filter_map(|e| e["reason"].as_str())
        .collect();
    assert_eq!(refused.len(), 3, "{refused:?}");
    assert!(refused.iter().any(|r| r.contains("protocol version 99")));
    let b_joins = ev
        .iter()
        .filter(|e| e["robot"] == "b" && e["type"] == "agent_joined")
        .count();
    assert_eq!(b_joins, 1);
    assert_clean(&id);
}

#[test]
fn a_hand_started_world_that_times_out_waiting_names_the_missing_robot_and_leaves_nothing_behind() {
    let dir = fresh_dir("own-timeout");
    let file = dir.join("two.toml");
    std::fs::write(&file, TWO).expect("write");
    let id = run_id("owntimeout");
    // Only `b` gets an agent: the world gives up on `a` after its
    // --start-timeout and must still clear the run's shared memory.
    let mut world = mrsim()
        .arg("world")
        .arg(&file)
        .args(["--run", &id, "--start-timeout", "3", "--out"])
        .arg(dir.join("out"))
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("world");
    let mut honest = mrsim()
        .args(["agent", "--robot", "b", "--run", &id])
        .stderr(Stdio::piped())
        .spawn()
        .expect("agent");
    let ws = wait_timeout(&mut world, 60).expect("world ended");
    assert!(!ws.success(), "a world whose robots did not all join fails");
    wait_timeout(&mut honest, 30);
    let mut err = String::new();
    use std::io::Read;
    if let Some(mut e) = world.stderr.take() {
        let _ = e.read_to_string(&mut err);
    }
    assert!(err.contains("agents for a did not join"), "{err}");
    assert_clean(&id);
}

/// Twelve robots on a circle, lockstep, a 1 s stall timeout: more than the
/// world's default room for one process's commands (8).
const TWELVE: &str = r#"name = "twelve"
[world]
dt = 0.1
duration = 3.0
stall_timeout = 1.0

[generate]
kind = "circle"
count = 12
radius = 6.0
name_prefix = "r"
"#;

#[test]
fn a_hand_started_group_of_twelve_robots_loses_no_command() {
    let dir = fresh_dir("group12");
    let file = dir.join("twelve.toml");
    std::fs::write(&file, TWELVE).expect("write");
    let out = dir.join("out");
    let id = run_id("g12");
    let mut world = hand_started_world(&file, &out, &id, 60);
    let names: Vec<String> = (0..12).map(|i| format!("r{i:02}")).collect();
    let mut group = mrsim()
        .args(["agent", "--run", &id, "--robots", &names.join(",")])
        .stderr(Stdio::piped())
        .spawn()
        .expect("group");
    let ws = wait_timeout(&mut world, 120).expect("world ended");
    assert!(ws.success(), "world failed");
    let gs = wait_timeout(&mut group, 20).expect("group ended");
    assert!(gs.success(), "the group's agent failed");

    // Every tick got all twelve commands: no robot waited out the stall
    // timeout (which loses it), every robot was driven to the end.
    let m = metrics(&out);
    assert_eq!(m["ticks"], 30, "{m:#}");
    assert_eq!(m["agents_lost"], 0, "{m:#}");
    assert_eq!(m["commands_rejected"], 0, "{m:#}");
    let rows = trajectory(&out);
    for name in &names {
        assert_eq!(m["robots"][name]["lost"], 0, "{name}: {m:#}");
        let t = track(&rows, name);
        let moved = norm(t[t.len() - 1].x - t[0].x, t[t.len() - 1].y - t[0].y);
        assert!(moved > 0.1, "{name} moved {moved}");
    }
    assert!(events_of(&events(&out), "agent_lost", "r00").is_empty());
    assert_clean(&id);
}
