//! Fault injection with real processes and real signals: agents that die,
//! hang, stop or send garbage; a world that dies; a launcher that is
//! interrupted. Every "how soon" is measured in ticks from events.jsonl,
//! never on the wall clock.

use crate::common::*;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Child, Stdio};
use std::time::{Duration, Instant};

/// Robots in lanes 5 m apart, each going `goal` m to the right.
fn lanes(names: &[(&str, &str)], goal: f64, world: &str) -> String {
    let mut s = format!(
        "name = \"lanes\"\n[world]\n{world}\n[defaults]\nmax_speed = 1.0\nmax_accel = 2.0\ngoal_tolerance = 0.3\n"
    );
    for (i, (name, planner)) in names.iter().enumerate() {
        let y = 5.0 * i as f64;
        s += &format!(
            "[[robot]]\nname = \"{name}\"\nstart = [0.0, {y}]\ngoal = [{goal}, {y}]\nplanner = \"{planner}\"\n"
        );
    }
    s
}

/// Robots `a` and `b` with social-force planners.
fn two(goal: f64, world: &str) -> String {
    lanes(&[("a", "social-force"), ("b", "social-force")], goal, world)
}

/// A realtime run far longer than any test waits.
const REALTIME_LONG: &str = "dt = 0.05\nduration = 60.0\nmode = \"realtime\"";

/// Starts `mrsim run` and waits for its world and both agents to exist;
/// returns the launcher and their pids (world first).
fn launched(file: &Path, out: &Path, id: &str) -> (Child, u32, Vec<u32>) {
    let l = launcher(file, out, id, &[], Stdio::piped());
    let world = wait_for_process(&["--run", id, "--start-timeout"], &[], 30);
    let agents = ["a", "b"]
        .iter()
        .map(|r| wait_for_process(&["agent", "--robot", r, "--run", id], &[], 30))
        .collect();
    (l, world, agents)
}

fn scenario(tag: &str, text: &str) -> (PathBuf, PathBuf) {
    let dir = fresh_dir(tag);
    let file = dir.join("s.toml");
    std::fs::write(&file, text).expect("write scenario");
    (file, dir.join("out"))
}

fn world(file: &Path, out: &Path, id: &str) -> Child {
    mrsim()
        .arg("world")
        .arg(file)
        .args(["--run", id, "--start-timeout", "60", "--out"])
        .arg(out)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start world")
}

/// Writes the scenario, starts its world by hand under a fresh run id.
fn by_hand(tag: &str, id_tag: &str, text: &str) -> (PathBuf, String, Child) {
    let (file, out) = scenario(tag, text);
    let id = run_id(id_tag);
    let w = world(&file, &out, &id);
    (out, id, w)
}

fn agent(id: &str, robot: &str, fault: Option<&str>) -> Child {
    let mut c = mrsim();
    c.args(["agent", "--robot", robot, "--run", id]);
    if let Some(f) = fault {
        c.args(["--fault", f]);
    }
    c.stderr(Stdio::piped()).spawn().expect("start agent")
}

fn stderr_of(child: &mut Child) -> String {
    use std::io::Read;
    let mut s = String::new();
    if let Some(mut e) = child.stderr.take() {
        let _ = e.read_to_string(&mut s);
    }
    s
}

fn tick(e: &Value) -> u64 {
    e["tick"].as_u64().expect("event tick")
}

/// Waits up to `secs` for an event (complete line) matching `f`.
fn wait_for_event(out: &Path, secs: u64, f: impl Fn(&Value) -> bool) -> Value {
    let start = Instant::now();
    loop {
        if let Ok(text) = std::fs::read_to_string(out.join("events.jsonl")) {
            let whole = &text[..text.rfind('\n').map_or(0, |i| i + 1)];
            if let Some(v) = whole
                .lines()
                .filter_map(|l| serde_json::from_str::<Value>(l).ok())
                .find(|v| f(v))
            {
                return v;
            }
        }
        assert!(
            start.elapsed() < Duration::from_secs(secs),
            "event not seen in {secs} s"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// Waits up to `secs` (a failure guard, not a timing) until the complete
/// lines of events.jsonl satisfy `f`; returns them.
fn wait_for_events(out: &Path, secs: u64, f: impl Fn(&[Value]) -> bool) -> Vec<Value> {
    let start = Instant::now();
    loop {
        if let Ok(text) = std::fs::read_to_string(out.join("events.jsonl")) {
            let whole = &text[..text.rfind('\n').map_or(0, |i| i + 1)];
            let ev: Vec<Value> = whole
                .lines()
                .filter_map(|l| serde_json::from_str::<Value>(l).ok())
                .collect();
            if f(&ev) {
                return ev;
            }
        }
        assert!(
            start.elapsed() < Duration::from_secs(secs),
            "events not seen in {secs} s"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// Waits until both agents of a two-robot run have joined (their
/// `agent_joined` events are on disk).
fn wait_for_both_joined(out: &Path) {
    wait_for_events(out, 60, |ev| {
        ["a", "b"]
            .iter()
            .all(|r| !events_of(ev, "agent_joined", r).is_empty())
    });
}

/// Waits until process `pid` (an agent with no world to join) sits in its
/// retry loop: alive, asleep, and woken from sleep at least four times
/// (`voluntary_ctxt_switches` in /proc), i.e. it has looked for a world
/// and not found one. An agent emits nothing while it waits; this is the
/// nearest state to observe.
fn wait_until_waiting(pid: u32) {
    let switches = || -> Option<u64> {
        let status = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
        status
            .lines()
            .find_map(|l| l.strip_prefix("voluntary_ctxt_switches:"))?
            .trim()
            .parse()
            .ok()
    };
    let start = Instant::now();
    loop {
        assert!(!process_gone(pid), "agent {pid} ended while waiting");
        if switches().is_some_and(|n| n >= 4) && process_state(pid) == Some('S') {
            return;
        }
        assert!(
            start.elapsed() < Duration::from_secs(30),
            "agent {pid} never settled into waiting"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// Longest run of consecutive ticks in `ticks` (sorted), and where it ends.
fn longest_streak(ticks: &[u64]) -> (u64, u64) {
    let (mut best, mut end, mut cur) = (0, 0, 0);
    for (k, t) in ticks.iter().enumerate() {
        cur = if k > 0 && ticks[k - 1] + 1 == *t {
            cur + 1
        } else {
            1
        };
        if cur > best {
            best = cur;
            end = *t;
        }
    }
    (best, end)
}

#[test]
fn an_agent_killed_mid_run_in_lockstep_is_lost_at_once_braked_and_the_others_finish() {
    let text = lanes(
        &[
            ("a", "social-force"),
            ("b", "social-force"),
            ("c", "social-force"),
        ],
        4.0,
        // A stall timeout far longer than the run: only the death of the
        // process can explain a loss.
        "dt = 0.1\nduration = 60.0\nstall_timeout = 30.0",
    );
    let (out, id, mut w) = by_hand("kill-lock", "kl", &text);
    // a SIGKILLs itself at tick 20: a real SIGKILL at a known tick.
    let mut a = agent(&id, "a", Some("die-at-tick=20"));
    let mut b = agent(&id, "b", None);
    let mut c = agent(&id, "c", None);
    let ws = wait_timeout(&mut w, 60).expect("world ended");
    assert!(ws.success(), "world failed: {}", stderr_of(&mut w));
    use std::os::unix::process::ExitStatusExt;
    let sa = wait_timeout(&mut a, 10).expect("a ended");
    assert_eq!(sa.signal(), Some(libc::SIGKILL));
    wait_timeout(&mut b, 10);
    wait_timeout(&mut c, 10);

    let ev = events(&out);
    let lost = events_of(&ev, "agent_lost", "a");
    assert_eq!(lost.len(), 1, "{lost:?}");
    let lost_tick = tick(lost[0]);
    assert!(
        (20..=23).contains(&lost_tick),
        "lost at tick {lost_tick}, killed at 20"
    );
    assert!(
        lost[0]["reason"].as_str().unwrap_or("").contains("died"),
        "{:?}",
        lost[0]
    );
    let m = metrics(&out);
    assert_eq!(m["agents_lost"], 1, "{m:#}");
    assert_eq!(m["robots"]["a"]["lost"], 1);
    assert_eq!(m["robots"]["b"]["reached_goal"], true);
    assert_eq!(m["robots"]["c"]["reached_goal"], true);
    assert_eq!(m["robots"]["a"]["reached_goal"], false);
    // The lost robot did not hold the run open until `duration`.
    assert!(m["ticks"].as_u64().unwrap_or(u64::MAX) < 600, "{m:#}");
    // It braked: at rest, in place, from a few ticks after the loss on.
    let rows = trajectory(&out);
    let a_rows: Vec<&Row> = track(&rows, "a")
        .into_iter()
        .filter(|r| r.tick >= lost_tick + 10)
        .collect();
    assert!(!a_rows.is_empty());
    for r in &a_rows {
        assert!(r.vx.hypot(r.vy) < 1e-6, "a still moving at tick {}", r.tick);
        assert!((r.x - a_rows[0].x).abs() < 1e-9 && (r.y - a_rows[0].y).abs() < 1e-9);
    }
    // It was moving before: the brake is what stopped it.
    let before = track(&rows, "a")
        .into_iter()
        .find(|r| r.tick == lost_tick)
        .expect("row at the lost tick");
    assert!(before.vx.hypot(before.vy) > 0.1, "{before:?}");
    assert_clean(&id);
}

#[test]
fn a_killed_agent_in_realtime_is_restarted_by_the_launcher_and_rejoins_its_robot() {
    let text = two(4.0, "dt = 0.05\nduration = 30.0\nmode = \"realtime\"");
    let (file, out) = scenario("restart", &text);
    let id = run_id("rs");
    let mut l = launcher(&file, &out, &id, &["--restart-agents"], Stdio::piped());
    let first = wait_for_process(&["agent", "--robot", "a", "--run", &id], &[], 30);
    // Killed mid-run: once both agents have joined (the clock then runs).
    wait_for_both_joined(&out);
    if process_gone(first) {
        l.kill().ok();
        panic!("agent a ended before it was killed: {}", stderr_of(&mut l));
    }
    send_signal(first, libc::SIGKILL);
    let second = wait_for_process(&["agent", "--robot", "a", "--run", &id], &[first], 30);
    let status = wait_timeout(&mut l, 60).expect("launcher ended");
    let err = stderr_of(&mut l);
    assert!(status.success(), "{status:?}\n{err}");
    assert!(
        err.contains(&format!("agent for a (pid {first}) was killed by signal 9"))
            && err.contains("restarting it"),
        "{err}"
    );

    let ev = events(&out);
    let lost = events_of(&ev, "agent_lost", "a");
    let back = events_of(&ev, "agent_rejoined", "a");
    assert_eq!(lost.len(), 1, "{lost:?}");
    assert_eq!(back.len(), 1, "{back:?}");
    assert_eq!(lost[0]["pid"], first);
    assert_eq!(back[0]["pid"], second);
    assert!(tick(back[0]) >= tick(lost[0]));
    // Lost because its process died (seen by the world's process check),
    // not by a timeout: no wall-clock bound on how soon.
    assert!(
        lost[0]["reason"]
            .as_str()
            .unwrap_or("")
            .contains(&format!("agent process {first} died")),
        "{}",
        lost[0]
    );
    let m = metrics(&out);
    assert_eq!(m["agents_lost"], 1, "{m:#}");
    assert_eq!(m["robots"]["a"]["agent_pid"], second);
    // The new agent drove the same robot on from where it was, home.
    assert_eq!(m["robots"]["a"]["reached_goal"], true, "{m:#}");
    assert_eq!(m["robots"]["b"]["reached_goal"], true, "{m:#}");
    assert!(process_gone(first) && process_gone(second));
    assert_clean(&id);
}

#[test]
fn an_agent_killed_twenty_times_still_rejoins_within_the_port_limits() {
    // 2 robots: every channel has room for 2 + 16 agents. Twenty dead agents
    // only fit if what each left behind is cleaned up.
    let text = two(3.0, "dt = 0.1\nduration = 30.0");
    let (out, id, mut w) = by_hand("limits", "lim", &text);
    let lines = {
        use std::io::BufRead;
        let err = w.stderr.take().expect("world stderr");
        let (tx, rx) = std::sync::mpsc::channel::<String>();
        std::thread::spawn(move || {
            for l in std::io::BufReader::new(err).lines().map_while(Result::ok) {
                let _ = tx.send(l);
            }
        });
        rx
    };
    let wait_line = |want: &str| {
        let deadline = Instant::now() + Duration::from_secs(30);
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            match lines.recv_timeout(left) {
                Ok(l) if l.contains(want) => return,
                Ok(_) => {}
                Err(_) => panic!("the world never said `{want}`"),
            }
        }
    };
    for _ in 0..20 {
        let mut a = agent(&id, "a", None);
        let pid = a.id();
        wait_line(&format!("(pid {pid})"));
        send_signal(pid, libc::SIGKILL);
        let _ = a.wait();
        wait_line(&format!("lost the agent for a: agent process {pid} died"));
    }
    // The 21st agent for a joins (a lost robot does not hold the start
    // back, so a must be driven again before b completes the roster).
    let mut a = agent(&id, "a", None);
    wait_line(&format!("rejoined (pid {})", a.id()));
    let mut b = agent(&id, "b", None);
    let ws = wait_timeout(&mut w, 60).expect("world ended");
    assert!(ws.success());
    wait_timeout(&mut a, 10);
    wait_timeout(&mut b, 10);
    let ev = events(&out);
    assert_eq!(events_of(&ev, "agent_lost", "a").len(), 20);
    assert_eq!(events_of(&ev, "agent_rejoined", "a").len(), 20);
    let m = metrics(&out);
    assert_eq!(m["agents_lost"], 20);
    assert_eq!(m["success_rate"], 1.0, "{m:#}");
    assert_clean(&id);
}

#[test]
fn an_agent_stopped_in_realtime_misses_deadlines_while_the_world_keeps_ticking() {
    // Goals out of reach: the run lasts exactly `duration` (200 ticks of
    // 50 ms; the stop and the return take a few seconds of it whatever the
    // machine, as each waits for what the world has written).
    let text = two(100.0, "dt = 0.05\nduration = 10.0\nmode = \"realtime\"");
    let (file, out) = scenario("stop-rt", &text);
    let id = run_id("srt");
    let mut l = launcher(&file, &out, &id, &[], Stdio::piped());
    let pid = wait_for_process(&["agent", "--robot", "a", "--run", &id], &[], 30);
    wait_for_both_joined(&out);
    send_signal(pid, libc::SIGSTOP);
    // Stopped until the world has logged ten misses of a in a row.
    wait_for_events(&out, 60, |ev| {
        let t: Vec<u64> = events_of(ev, "deadline_miss", "a")
            .iter()
            .map(|e| tick(e))
            .collect();
        longest_streak(&t).0 >= 10
    });
    send_signal(pid, libc::SIGCONT);
    let status = wait_timeout(&mut l, 60).expect("launcher ended");
    assert!(status.success(), "{}", stderr_of(&mut l));
    let m = metrics(&out);
    // Every tick happened although a did not answer for a second; a stopped
    // process is alive, so it was never lost.
    assert_eq!(m["ticks"], 200, "{m:#}");
    assert_eq!(m["agents_lost"], 0, "{m:#}");
    let ev = events(&out);
    let misses: Vec<u64> = events_of(&ev, "deadline_miss", "a")
        .iter()
        .map(|e| tick(e))
        .collect();
    let (streak, end) = longest_streak(&misses);
    assert!(streak >= 10, "longest run of misses {streak}: {misses:?}");
    // After SIGCONT it answered again.
    let answered_after = (end + 1..200).any(|t| !misses.contains(&t));
    assert!(
        answered_after,
        "a never answered after the stop: {misses:?}"
    );
    assert!(m["robots"]["a"]["deadline_misses"].as_u64().unwrap_or(0) >= 10);
    assert_clean(&id);
}

#[test]
fn an_agent_stopped_in_lockstep_is_lost_after_stall_timeout_and_rejoins_on_sigcont() {
    let text = two(100.0, "dt = 0.1\nduration = 40.0\nstall_timeout = 1.0");
    let (out, id, mut w) = by_hand("stop-ls", "sls", &text);
    let mut a = agent(&id, "a", Some("stop-at-tick=5"));
    // b's planner takes 5 ms: the run lasts long enough to see a come back.
    let mut b = agent(&id, "b", Some("slow-ms=5"));
    let lost = wait_for_event(&out, 30, |e| e["type"] == "agent_lost" && e["robot"] == "a");
    assert_eq!(process_state(a.id()), Some('T'));
    send_signal(a.id(), libc::SIGCONT);
    let ws = wait_timeout(&mut w, 60).expect("world ended");
    assert!(ws.success());
    assert!(wait_timeout(&mut a, 10).is_some_and(|s| s.success()));
    wait_timeout(&mut b, 10);

    assert_eq!(tick(&lost), 5, "{lost}");
    assert!(
        lost["reason"]
            .as_str()
            .unwrap_or("")
            .contains("stall_timeout"),
        "{lost}"
    );
    let ev = events(&out);
    let back = events_of(&ev, "agent_rejoined", "a");
    assert_eq!(back.len(), 1, "{back:?}");
    let back_tick = tick(back[0]);
    let m = metrics(&out);
    assert_eq!(m["ticks"], 400, "{m:#}");
    assert_eq!(m["agents_lost"], 1);
    // Between loss and return a was braked still; after it, a drives again.
    let rows = trajectory(&out);
    let a_rows = track(&rows, "a");
    let at = |t: u64| a_rows.iter().find(|r| r.tick == t).expect("row");
    assert!(at(back_tick).vx.abs() < 1e-6);
    assert!(
        at(399).x > at(back_tick).x + 1.0,
        "a did not move after rejoining"
    );
    assert_clean(&id);
}

#[test]
fn a_planner_stuck_in_a_loop_is_lost_in_lockstep_and_misses_every_deadline_in_realtime() {
    // Lockstep: lost after stall_timeout, the others finish.
    let text = two(3.0, "dt = 0.1\nduration = 30.0\nstall_timeout = 1.0");
    let (out, id, mut w) = by_hand("hang-ls", "hls", &text);
    let mut a = agent(&id, "a", Some("hang-at-tick=5"));
    let mut b = agent(&id, "b", None);
    assert!(wait_timeout(&mut w, 60).is_some_and(|s| s.success()));
    wait_timeout(&mut a, 10);
    wait_timeout(&mut b, 10);
    let ev = events(&out);
    let lost = events_of(&ev, "agent_lost", "a");
    assert_eq!(lost.len(), 1);
    assert_eq!(tick(lost[0]), 5);
    assert!(
        lost[0]["reason"]
            .as_str()
            .unwrap_or("")
            .contains("stall_timeout")
    );
    assert_eq!(metrics(&out)["robots"]["b"]["reached_goal"], true);
    assert_clean(&id);

    // Realtime: the world does not wait; every tick from the hang on is a miss.
    let text = two(100.0, "dt = 0.05\nduration = 2.0\nmode = \"realtime\"");
    let (out, id, mut w) = by_hand("hang-rt", "hrt", &text);
    let mut a = agent(&id, "a", Some("hang-at-tick=5"));
    let mut b = agent(&id, "b", None);
    assert!(wait_timeout(&mut w, 60).is_some_and(|s| s.success()));
    wait_timeout(&mut a, 10);
    wait_timeout(&mut b, 10);
    let m = metrics(&out);
    assert_eq!(m["ticks"], 40, "{m:#}");
    assert_eq!(m["agents_lost"], 0);
    let misses: Vec<u64> = events_of(&events(&out), "deadline_miss", "a")
        .iter()
        .map(|e| tick(e))
        .collect();
    assert!((5..40).all(|t| misses.contains(&t)), "{misses:?}");
    assert_clean(&id);
}

#[test]
fn when_the_world_is_killed_the_launcher_names_it_and_every_agent_exits() {
    let text = two(100.0, REALTIME_LONG);
    let (file, out) = scenario("world-dies", &text);
    let id = run_id("wd");
    let (mut l, wpid, agents) = launched(&file, &out, &id);
    wait_for_both_joined(&out);
    send_signal(wpid, libc::SIGKILL);
    let status = wait_timeout(&mut l, 30).expect("launcher ended");
    let err = stderr_of(&mut l);
    assert_eq!(status.code(), Some(1), "{err}");
    assert!(
        err.contains(&format!(
            "the world process (pid {wpid}) was killed by signal 9 (SIGKILL)"
        )),
        "{err}"
    );
    // The agents' own messages (their stderr is the launcher's).
    assert_eq!(err.matches("the world is gone").count(), 2, "{err}");
    assert!(agents.iter().all(|p| process_gone(*p)));
    assert_clean(&id);
}

#[test]
fn a_killed_hand_started_world_leaves_nothing_that_blocks_the_next_world_of_that_run_id() {
    let long = two(100.0, REALTIME_LONG);
    let (out, id, mut w) = by_hand("stale", "st", &long);
    let mut a = agent(&id, "a", None);
    let mut b = agent(&id, "b", None);
    wait_for_event(&out, 30, |e| {
        e["type"] == "agent_joined" && e["robot"] == "b"
    });
    send_signal(w.id(), libc::SIGKILL);
    let _ = w.wait();
    for ag in [&mut a, &mut b] {
        let s = wait_timeout(ag, 15).expect("agent ended");
        let err = stderr_of(ag);
        assert_eq!(s.code(), Some(1), "{err}");
        assert!(err.contains("the world is gone"), "{err}");
    }
    assert!(
        !shm_leftovers(&id).is_empty(),
        "the killed world left no shared memory: nothing to prove"
    );
    // The next world of the same run id starts, runs and cleans up, with
    // one agent started before it (among the dead world's leftovers, which
    // it must not take for a world) and one after it.
    let short = two(3.0, "dt = 0.1\nduration = 30.0");
    let (file, out) = scenario("stale2", &short);
    let mut a = agent(&id, "a", None);
    wait_until_waiting(a.id());
    let mut w = world(&file, &out, &id);
    let mut b = agent(&id, "b", None);
    let ws = wait_timeout(&mut w, 60).expect("world ended");
    assert!(ws.success(), "{}", stderr_of(&mut w));
    for ag in [&mut a, &mut b] {
        let s = wait_timeout(ag, 10);
        assert!(s.is_some_and(|s| s.success()), "{s:?}: {}", stderr_of(ag));
    }
    assert_eq!(metrics(&out)["success_rate"], 1.0);
    assert_clean(&id);
}

#[test]
fn sigint_or_sigterm_to_the_launcher_stops_everything_and_writes_an_interrupted_run() {
    for sig in [libc::SIGINT, libc::SIGTERM] {
        let text = two(100.0, REALTIME_LONG);
        let (file, out) = scenario("interrupt", &text);
        let id = run_id("int");
        let (mut l, wpid, mut pids) = launched(&file, &out, &id);
        pids.push(wpid);
        wait_for_event(&out, 30, |e| {
            e["type"] == "agent_joined" && e["robot"] == "b"
        });
        send_signal(l.id(), sig);
        let status = wait_timeout(&mut l, 30).expect("launcher ended");
        assert_eq!(status.code(), Some(130), "{}", stderr_of(&mut l));
        assert!(pids.iter().all(|p| process_gone(*p)), "left running");
        let m = metrics(&out);
        assert_eq!(m["interrupted"], true, "{m:#}");
        // The agents ended with the run, they were not lost.
        assert_eq!(m["agents_lost"], 0, "{m:#}");
        let ticks = m["ticks"].as_u64().unwrap_or(0);
        assert!(ticks > 0 && ticks < 1200, "{m:#}");
        // Everything gathered so far was written.
        let rows = trajectory(&out);
        assert_eq!(rows.iter().map(|r| r.tick).max(), Some(ticks));
        assert!(events(&out).iter().any(|e| e["type"] == "interrupted"));
        assert_clean(&id);
    }
}

#[test]
fn a_killed_world_leaves_a_trajectory_flushed_during_the_run_with_only_whole_ticks() {
    let mut text = two(100.0, REALTIME_LONG);
    text += "[[obstacle]]\nname = \"o\"\nstart = [50.0, 20.0]\nradius = 1.0\nmotion = { model = \"constant-velocity\", velocity = [0.0, 1.0] }\n";
    let (out, id, mut w) = by_hand("flush", "fl", &text);
    let mut a = agent(&id, "a", None);
    let mut b = agent(&id, "b", None);
    // Rows of tick 20 (1 s of the run) reach the disk while the world runs:
    // the recorder flushes during the run, not only at its end.
    let start = Instant::now();
    loop {
        let text = std::fs::read_to_string(out.join("trajectory.csv")).unwrap_or_default();
        if text.lines().any(|l| l.starts_with("20,")) {
            break;
        }
        assert!(start.elapsed() < Duration::from_secs(30), "no rows on disk");
        std::thread::sleep(Duration::from_millis(50));
    }
    assert!(w.try_wait().expect("world").is_none(), "world ended early");
    send_signal(w.id(), libc::SIGKILL);
    let _ = w.wait();
    wait_timeout(&mut a, 15);
    wait_timeout(&mut b, 15);
    let text = std::fs::read_to_string(out.join("trajectory.csv")).expect("trajectory");
    assert!(text.ends_with('\n'), "torn last line");
    let rows = trajectory(&out); // every line parses into 8 fields
    let last = rows.iter().map(|r| r.tick).max().expect("rows");
    assert!(last >= 20);
    for t in 0..=last {
        let n = rows.iter().filter(|r| r.tick == t).count();
        assert_eq!(n, 3, "tick {t} has {n} of 3 rows");
    }
    remove_leftovers(&id);
}

#[test]
fn bad_commands_are_rejected_counted_logged_and_never_drive_a_robot() {
    let robots = [
        ("honest", "social-force", None),
        ("nan", "social-force", Some("nan")),
        ("inf", "orca", Some("inf")),
        ("huge", "social-force", Some("huge")),
        ("hugev", "orca", Some("huge")),
        ("past", "social-force", Some("past-tick")),
        ("future", "social-force", Some("future-tick")),
        ("double", "social-force", Some("double")),
        // Asks to join twice: one agent, one token, driven normally.
        ("twice", "social-force", Some("join-twice")),
        // Last: its commands name robot 0, `honest`.
        ("other", "social-force", Some("other-robot")),
    ];
    let names: Vec<(&str, &str)> = robots.iter().map(|(n, p, _)| (*n, *p)).collect();
    let text = lanes(
        &names,
        4.0,
        "dt = 0.1\nduration = 15.0\nstall_timeout = 2.0",
    );
    let (out, id, mut w) = by_hand("bad", "bad", &text);
    let mut agents: Vec<Child> = robots.iter().map(|(n, _, f)| agent(&id, n, *f)).collect();
    assert!(wait_timeout(&mut w, 60).is_some_and(|s| s.success()));
    for a in &mut agents {
        wait_timeout(a, 10);
    }
    let m = metrics(&out);
    let ev = events(&out);
    let ticks = m["ticks"].as_u64().expect("ticks");
    assert_eq!(ticks, 150, "nan and inf never arrive: the run lasts");
    let rejected: Vec<&Value> = ev
        .iter()
        .filter(|e| e["type"] == "command_rejected")
        .collect();
    assert_eq!(m["commands_rejected"], rejected.len() as u64);
    let reasons = |robot: &str| -> Vec<&str> {
        rejected
            .iter()
            .filter(|e| e["robot"] == robot)
            .filter_map(|e| e["reason"].as_str())
            .collect()
    };
    let rows = trajectory(&out);
    let still = |robot: &str| {
        let t = track(&rows, robot);
        t.iter().all(|r| r.x == 0.0 && r.vx == 0.0 && r.vy == 0.0)
    };
    // NaN and infinity: rejected every tick, the robot brakes (never moves),
    // and the world does not wait for a better answer (not lost).
    for r in ["nan", "inf"] {
        let why = reasons(r);
        assert_eq!(why.len() as u64, ticks, "{r}: {why:?}");
        assert!(why.iter().all(|w| w.contains("non-finite")), "{why:?}");
        assert_eq!(m["robots"][r]["commands_rejected"], ticks);
        assert_eq!(m["robots"][r]["lost"], 0);
        assert!(still(r), "{r} moved");
    }
    // Absurd magnitudes are clamped to the robot's limits (max_speed 1.0;
    // rapier keeps velocities in f32, hence the 1e-6).
    for r in ["huge", "hugev"] {
        let v = m["robots"][r]["max_speed"].as_f64().expect("max_speed");
        assert!(v > 0.5 && v <= 1.0 + 1e-6, "{r}: max speed {v}");
        assert!(
            track(&rows, r)
                .iter()
                .all(|p| p.x.is_finite() && p.vx.hypot(p.vy) <= 1.0 + 1e-6)
        );
    }
    // Wrong ticks: never applied; unanswered, the robot is lost and brakes.
    // Once the world has stopped waiting for the lost robot it ticks on
    // without it, so an answer to an old snapshot that names "the next
    // tick" can arrive when that tick is already past: rejected as a past
    // tick. How often depends on the scheduler, so either reason counts for
    // it, and at least one must be the fault's own.
    for (r, why, also) in [
        ("past", "past tick", "past tick"),
        ("future", "future tick", "past tick"),
    ] {
        let got = reasons(r);
        assert!(
            got.iter().any(|w| w.contains(why))
                && got.iter().all(|w| w.contains(why) || w.contains(also)),
            "{got:?}"
        );
        assert_eq!(m["robots"][r]["lost"], 1);
        assert!(still(r), "{r} moved");
    }
    // Two per tick: the second is rejected (as a second command, or as one
    // for a past tick when the world has moved on before it arrives), every
    // tick; the first drives the robot home. The last tick's second command
    // can arrive after the world has stopped reading (the run is over), so
    // it may go uncounted.
    let got = reasons("double");
    assert!(
        got.len() as u64 == ticks || got.len() as u64 + 1 == ticks,
        "{} rejections in {ticks} ticks: {got:?}",
        got.len()
    );
    assert!(
        got.iter()
            .all(|w| w.contains("second command") || w.contains("past tick")),
        "{got:?}"
    );
    assert_eq!(m["robots"]["double"]["reached_goal"], true);
    // Commands for another robot: rejected (counted on the robot named),
    // `honest` is driven only by its own agent; `other` is lost and still.
    let got = reasons("honest");
    assert!(!got.is_empty() && got.iter().all(|w| w.contains("owns this robot")));
    assert_eq!(m["robots"]["honest"]["reached_goal"], true);
    assert_eq!(m["robots"]["other"]["lost"], 1);
    assert!(still("other"));
    assert_eq!(m["robots"]["twice"]["reached_goal"], true);
    assert_eq!(m["robots"]["twice"]["commands_rejected"], 0);
    assert_eq!(events_of(&ev, "agent_joined", "twice").len(), 1);
    assert_eq!(m["agents_lost"], 3, "{m:#}");
    assert_clean(&id);
}

#[test]
fn a_runs_shared_memory_and_root_path_are_private_to_its_user() {
    use std::os::unix::fs::PermissionsExt;
    let text = lanes(&[("a", "social-force")], 3.0, "dt = 0.1\nduration = 30.0");
    let (_out, id, mut w) = by_hand("private", "prv", &text);
    let root = PathBuf::from(format!("/tmp/mrsim/{id}"));
    // The world says it waits for its agents once every service is made.
    let err = w.stderr.take().expect("world stderr");
    let mut lines = std::io::BufRead::lines(std::io::BufReader::new(err));
    let up = lines.any(|l| l.is_ok_and(|l| l.contains("waiting for 1 agents to join")));
    assert!(up, "the world ended before it waited for its agents");
    // Keep reading, so that the world's later lines never meet a closed pipe.
    std::thread::spawn(move || lines.for_each(drop));
    let mode = |p: &Path| std::fs::metadata(p).expect("metadata").permissions().mode() & 0o777;
    assert_eq!(mode(&root), 0o700, "root path");
    let entries = shm_leftovers(&id);
    assert!(
        entries.iter().any(|e| e.ends_with("global_mgmt")),
        "{entries:?}"
    );
    for e in &entries {
        let m = mode(&Path::new("/dev/shm").join(e));
        assert_eq!(m & 0o077, 0, "/dev/shm/{e} has mode {m:o}");
    }
    let mut a = agent(&id, "a", None);
    assert!(wait_timeout(&mut w, 60).is_some_and(|s| s.success()));
    wait_timeout(&mut a, 10);
    assert_clean(&id);
}
