//! Runs at scale, end to end through the real binary: thousands of robots
//! in-process, robots in groups per agent process, and a large run
//! interrupted. No wall-clock assertions: a slow machine only makes these
//! slower.

use crate::common::*;
use serde_json::Value;
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::process::{Child, Stdio};
use std::time::{Duration, Instant};

/// The crossing benchmark scene with `n` robots, dt 0.1 for `secs` s.
fn crossing(n: usize, secs: f64) -> Vec<String> {
    [
        format!("generate.count={n}"),
        "world.dt=0.1".to_string(),
        format!("world.duration={secs}"),
        "world.arena.min=[-4000,-4000]".to_string(),
        "world.arena.max=[4000,4000]".to_string(),
    ]
    .into_iter()
    .flat_map(|s| ["--set".to_string(), s])
    .collect()
}

fn bench_scene() -> PathBuf {
    root().join("scenarios/bench/crossing-1000.toml")
}

/// Runs the crossing scene with `n` robots and `extra` arguments into a
/// fresh folder; returns the folder.
fn run_crossing(tag: &str, n: usize, secs: f64, extra: &[&str]) -> PathBuf {
    let out = fresh_dir(tag).join("out");
    let id = run_id(tag);
    let mut args: Vec<String> = crossing(n, secs);
    args.extend(extra.iter().map(|s| s.to_string()));
    args.push("--quiet".to_string());
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let result = run(&bench_scene(), &out, &id, &args);
    assert_ok(&result);
    assert_clean(&id);
    out
}

#[test]
fn two_thousand_robots_in_process_each_have_every_row_and_their_metrics() {
    let n = 2000;
    let out = run_crossing("inproc2k", n, 1.0, &["--transport", "inproc"]);
    let m = metrics(&out);
    let ticks = m["ticks"].as_u64().expect("ticks");
    assert_eq!(ticks, 10, "{}", m["ticks"]);
    assert_eq!(m["agents_lost"], 0);
    let robots = m["robots"].as_object().expect("robots");
    assert_eq!(robots.len(), n);
    let names: BTreeSet<String> = robots.keys().cloned().collect();
    for (name, r) in robots {
        assert!(
            r["path_length"].as_f64().is_some_and(|l| l > 0.0),
            "{name}: {r}"
        );
        assert_eq!(r["latency_us"]["count"], ticks, "{name}: {r}");
    }
    // Every robot has a row at every tick, and nothing else is a robot.
    let mut per_tick: BTreeMap<u64, BTreeSet<String>> = BTreeMap::new();
    for row in trajectory(&out) {
        if row.kind == "robot" {
            assert!(
                per_tick
                    .entry(row.tick)
                    .or_default()
                    .insert(row.body.clone()),
                "two rows of {} at tick {}",
                row.body,
                row.tick
            );
        }
    }
    assert_eq!(per_tick.len() as u64, ticks + 1);
    for (tick, bodies) in &per_tick {
        assert!(*bodies == names, "tick {tick}: {} robots", bodies.len());
    }
}

#[test]
fn robots_in_eight_agent_processes_move_exactly_as_with_one_process_each() {
    let n = 256;
    let single = run_crossing("group1", n, 1.0, &[]);
    let grouped = run_crossing("group32", n, 1.0, &["--robots-per-agent", "32"]);
    let a = std::fs::read(single.join("trajectory.csv")).expect("trajectory");
    let b = std::fs::read(grouped.join("trajectory.csv")).expect("trajectory");
    assert!(a.len() > 1000);
    assert!(a == b, "the trajectories differ");
    // Eight processes drove the 256 robots, 32 each.
    let pids = |dir: &Path| -> BTreeMap<u64, usize> {
        let m = metrics(dir);
        let mut count = BTreeMap::new();
        for r in m["robots"].as_object().expect("robots").values() {
            *count
                .entry(r["agent_pid"].as_u64().expect("pid"))
                .or_default() += 1;
        }
        count
    };
    let grouped_pids = pids(&grouped);
    assert_eq!(grouped_pids.len(), 8, "{grouped_pids:?}");
    assert!(grouped_pids.values().all(|&k| k == 32), "{grouped_pids:?}");
    assert_eq!(pids(&single).len(), n);
    // The group size is recorded with the resolved scenario.
    let resolved: Value = serde_json::from_str(
        &std::fs::read_to_string(grouped.join("scenario.json")).expect("scenario.json"),
    )
    .expect("parses");
    assert_eq!(resolved["world"]["robots_per_agent"], 32);
}

/// Four robots on lanes, realtime, far from their goals for a minute.
const FOUR: &str = "name = \"four\"
[world]
dt = 0.05
duration = 60.0
mode = \"realtime\"
[defaults]
max_speed = 1.0
max_accel = 2.0
[[robot]]
name = \"a\"
start = [0.0, 0.0]
goal = [100.0, 0.0]
planner = \"social-force\"
[[robot]]
name = \"b\"
start = [0.0, 5.0]
goal = [100.0, 5.0]
planner = \"social-force\"
[[robot]]
name = \"c\"
start = [0.0, 10.0]
goal = [100.0, 10.0]
planner = \"social-force\"
[[robot]]
name = \"d\"
start = [0.0, 15.0]
goal = [100.0, 15.0]
planner = \"social-force\"
";

/// Waits until events.jsonl satisfies `f`.
fn wait_for_events(out: &Path, secs: u64, f: impl Fn(&[Value]) -> bool) {
    let start = Instant::now();
    loop {
        if let Ok(text) = std::fs::read_to_string(out.join("events.jsonl")) {
            let whole = &text[..text.rfind('\n').map_or(0, |i| i + 1)];
            let ev: Vec<Value> = whole
                .lines()
                .filter_map(|l| serde_json::from_str::<Value>(l).ok())
                .collect();
            if f(&ev) {
                return;
            }
        }
        assert!(
            start.elapsed() < Duration::from_secs(secs),
            "events not seen in {secs} s"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
}

fn stderr_of(c: &mut Child) -> String {
    use std::io::Read;
    let mut s = String::new();
    if let Some(e) = c.stderr.as_mut() {
        let _ = e.read_to_string(&mut s);
    }
    s
}

#[test]
fn a_killed_group_process_loses_all_its_robots_and_its_restart_rejoins_them_together() {
    group_killed_and_restarted("gk", &[]);
}

#[test]
fn over_zenoh_a_killed_group_process_is_restarted_and_its_robots_rejoin_together() {
    group_killed_and_restarted("gkz", &["--transport", "zenoh"]);
}

/// Four robots in two groups of two (`mrsim run` with `link`, its
/// transport's arguments, and `--restart-agents`): the first group's
/// process is killed, both its robots are lost and rejoin from its restart
/// together, the other group's never leave.
fn group_killed_and_restarted(tag: &str, link: &[&str]) {
    let dir = fresh_dir(&format!("groupkill-{tag}"));
    let file = dir.join("s.toml");
    std::fs::write(&file, FOUR).expect("scenario");
    let out = dir.join("out");
    let id = run_id(tag);
    let mut flags = vec!["--robots-per-agent", "2", "--restart-agents"];
    flags.extend(link);
    let mut l = launcher(&file, &out, &id, &flags, Stdio::null());
    let first = wait_for_process(&["agent", "--robots", "a,b", "--run", &id], &[], 30);
    let other = wait_for_process(&["agent", "--robots", "c,d", "--run", &id], &[], 30);
    wait_for_events(&out, 60, |ev| {
        ["a", "b", "c", "d"]
            .iter()
            .all(|r| !events_of(ev, "agent_joined", r).is_empty())
    });
    assert!(!process_gone(first), "the group's agent ended early");
    send_signal(first, libc::SIGKILL);
    let second = wait_for_process(&["agent", "--robots", "a,b", "--run", &id], &[first], 30);
    wait_for_events(&out, 60, |ev| {
        ["a", "b"]
            .iter()
            .all(|r| !events_of(ev, "agent_rejoined", r).is_empty())
    });
    send_signal(l.id(), libc::SIGINT);
    let status = wait_timeout(&mut l, 60).expect("launcher ended");
    let err = stderr_of(&mut l);
    assert_eq!(status.code(), Some(130), "{err}");
    assert!(err.contains("agent for a, b (pid"), "{err}");

    let ev = events(&out);
    for r in ["a", "b"] {
        let lost = events_of(&ev, "agent_lost", r);
        let back = events_of(&ev, "agent_rejoined", r);
        assert_eq!(lost.len(), 1, "{r}: {lost:?}");
        assert_eq!(back.len(), 1, "{r}: {back:?}");
        assert_eq!(lost[0]["pid"], first);
        assert_eq!(back[0]["pid"], second, "{r} rejoined from another process");
    }
    for r in ["c", "d"] {
        assert!(events_of(&ev, "agent_lost", r).is_empty(), "{r} lost");
    }
    let m = metrics(&out);
    assert_eq!(m["robots"]["a"]["agent_pid"], second);
    assert_eq!(m["robots"]["b"]["agent_pid"], second);
    assert_eq!(m["robots"]["c"]["agent_pid"], other);
    assert!(process_gone(first) && process_gone(second) && process_gone(other));
    assert_clean(&id);
}

#[test]
fn an_agent_asked_for_robots_the_world_does_not_have_names_the_first_few_and_a_count() {
    let out = fresh_dir("strangers").join("out");
    let id = run_id("st");
    // A world waiting for its one robot; the agent asks for many others.
    let mut w = hand_started_world(&root().join("scenarios/crossing.toml"), &out, &id, 30);
    let names: Vec<String> = (0..50).map(|i| format!("nobody{i}")).collect();
    let agent = mrsim()
        .args(["agent", "--run", &id, "--timeout", "30", "--robots"])
        .arg(names.join(","))
        .output()
        .expect("agent");
    let _ = w.kill();
    let _ = w.wait();
    remove_leftovers(&id);
    let err = String::from_utf8_lossy(&agent.stderr);
    assert!(!agent.status.success());
    assert!(
        err.contains("agent nobody0, nobody1, nobody2 and 47 more"),
        "{err}"
    );
    assert!(err.lines().count() < 10, "{err}");
}

#[test]
fn ctrl_c_stops_a_run_of_hundreds_of_robots_in_process_and_keeps_its_outputs() {
    let n = 300;
    let out = fresh_dir("inproc-int").join("out");
    let id = run_id("ii");
    let mut args = crossing(n, 600.0);
    args.extend(["--mode", "realtime", "--transport", "inproc"].map(String::from));
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let mut l = mrsim()
        .arg("run")
        .arg(bench_scene())
        .arg("--out")
        .arg(&out)
        .args(["--run", &id])
        .args(&args)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("launcher");
    // Rows of tick 5 on disk: the run is under way.
    let start = Instant::now();
    loop {
        let text = std::fs::read_to_string(out.join("trajectory.csv")).unwrap_or_default();
        if text.lines().any(|l| l.starts_with("5,")) {
            break;
        }
        assert!(start.elapsed() < Duration::from_secs(60), "no rows on disk");
        std::thread::sleep(Duration::from_millis(50));
    }
    send_signal(l.id(), libc::SIGINT);
    let status = wait_timeout(&mut l, 60).expect("launcher ended");
    let err = stderr_of(&mut l);
    assert_eq!(status.code(), Some(130), "{err}");
    let m = metrics(&out);
    assert_eq!(m["interrupted"], true);
    assert_eq!(m["robots"].as_object().map(|r| r.len()), Some(n));
    let ticks = m["ticks"].as_u64().expect("ticks");
    assert!((5..6000).contains(&ticks), "{ticks}");
    // Every tick written whole, up to the last one run.
    let rows = trajectory(&out);
    assert_eq!(rows.iter().map(|r| r.tick).max(), Some(ticks));
    let mut per_tick = vec![0usize; ticks as usize + 1];
    for r in &rows {
        per_tick[r.tick as usize] += 1;
    }
    assert!(per_tick.iter().all(|&k| k == n), "a torn tick");
    assert!(events(&out).iter().any(|e| e["type"] == "interrupted"));
    assert!(out.join("scenario.json").exists());
    // The error of a robot list names a few, not hundreds.
    assert!(err.lines().all(|l| l.len() < 400), "{err}");
}

#[test]
fn robots_per_agent_in_the_scenario_groups_eight_robots_as_three_three_and_two_moving_as_alone() {
    let dir = fresh_dir("uneven");
    let text = std::fs::read_to_string(root().join("scenarios/crossing.toml")).expect("crossing");
    let grouped = text.replacen("[world]\n", "[world]\nrobots_per_agent = 3\n", 1);
    assert_ne!(grouped, text, "the key went in");
    let file = dir.join("grouped.toml");
    std::fs::write(&file, grouped).expect("write");
    let lockstep = ["--mode", "lockstep", "--quiet", "--no-report"];
    let (alone, together) = (dir.join("alone"), dir.join("together"));
    let crossing = root().join("scenarios/crossing.toml");
    assert_ok(&run(&crossing, &alone, &run_id("uneven1"), &lockstep));
    assert_ok(&run(&file, &together, &run_id("uneven3"), &lockstep));
    let read = |d: &Path| std::fs::read(d.join("trajectory.csv")).expect("trajectory");
    assert!(read(&alone) == read(&together), "the trajectories differ");
    // The same groups over Zenoh: one connection per group, the same run.
    let zenoh = dir.join("zenoh");
    let mut over_zenoh = lockstep.to_vec();
    over_zenoh.extend(["--transport", "zenoh"]);
    assert_ok(&run(&file, &zenoh, &run_id("uneven3z"), &over_zenoh));
    assert!(
        read(&alone) == read(&zenoh),
        "over Zenoh the trajectory differs"
    );
    let mz = metrics(&zenoh);
    assert_eq!(mz["transport"], "zenoh");
    let zpid = |r: &str| mz["robots"][r]["agent_pid"].as_u64().expect("pid");
    for g in [
        &["a0", "a1", "a2"][..],
        &["a3", "b0", "b1"][..],
        &["b2", "b3"][..],
    ] {
        assert!(
            g.iter().all(|r| zpid(r) == zpid(g[0])),
            "{g:?} over Zenoh: {mz:#}"
        );
    }
    // Three processes: a0 a1 a2 | a3 b0 b1 | b2 b3, in scenario order.
    let m = metrics(&together);
    let pid = |r: &str| m["robots"][r]["agent_pid"].as_u64().expect("pid");
    let groups: Vec<Vec<&str>> = [
        &["a0", "a1", "a2"][..],
        &["a3", "b0", "b1"][..],
        &["b2", "b3"][..],
    ]
    .iter()
    .map(|g| g.to_vec())
    .collect();
    let mut pids = BTreeSet::new();
    for g in &groups {
        assert!(
            g.iter().all(|r| pid(r) == pid(g[0])),
            "{g:?} share a process: {m:#}"
        );
        pids.insert(pid(g[0]));
    }
    assert_eq!(pids.len(), 3, "{m:#}");
}

/// A random scene of a million robots, spread thin (2 km each way).
const MILLION: &str = "name = \"million\"
[world]
dt = 0.1
duration = 1.0
mode = \"lockstep\"
[generate]
kind = \"random\"
count = 1000000
radius = 2000.0
planner = \"homing\"
";

#[test]
fn a_million_robot_scene_is_checked_and_a_run_past_the_memory_available_is_refused_with_the_estimate()
 {
    let dir = fresh_dir("million");
    let file = dir.join("million.toml");
    std::fs::write(&file, MILLION).expect("write");
    let o = mrsim().arg("check").arg(&file).output().expect("check");
    assert_ok(&o);
    let said = String::from_utf8_lossy(&o.stdout);
    assert!(said.contains("ok (1000000 robots"), "{said}");
    // Refused only where it does not fit: on a machine with the memory the
    // run would start, which this test does not do. Every robot senses the
    // whole scene (no `sensing_range`), so each keeps room for every other.
    use mrsim_runtime::{BASE, PER_ROBOT, SENSED};
    let n: u64 = 1_000_000;
    let need = BASE + n * PER_ROBOT + n * (n - 1) * SENSED;
    let available = std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|t| {
            let line = t
                .lines()
                .find(|l| l.starts_with("MemAvailable:"))?
                .to_string();
            line.split_whitespace().nth(1)?.parse::<u64>().ok()
        })
        .map(|kb| kb * 1024);
    if available.is_none_or(|a| a >= need) {
        skip(
            "a_million_robot_scene_is_checked_and_a_run_past_the_memory_available_is_refused",
            "MRSIM_REQUIRE_SMALL_MEMORY",
            "this machine has the memory for a million robots in-process",
        );
        return;
    }
    let out = dir.join("out");
    let o = run(
        &file,
        &out,
        &run_id("million"),
        &["--transport", "inproc", "--quiet"],
    );
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    for words in [
        "million.toml: this run needs about",
        "1000000 robots x 20 KB, 1000000 of them sensing the whole scene",
        "To make it fit: run fewer robots",
        "`sensing_range` shorter than the scene",
    ] {
        assert!(stderr.contains(words), "`{words}` in: {stderr}");
    }
    // The machine's memory, or a tighter bound it runs under (a container's
    // cgroup, `ulimit -v`): whichever leaves the least room is named.
    assert!(
        [
            "GiB available (MemAvailable",
            "its memory cgroup leaves",
            "its address-space limit leaves",
            "its data limit leaves"
        ]
        .iter()
        .any(|w| stderr.contains(w)),
        "{stderr}"
    );
    assert!(!out.join("metrics.json").exists(), "nothing ran");
}
