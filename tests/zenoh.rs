//! End-to-end tests of the Zenoh transport: on loopback (always), and
//! between two network namespaces joined by a veth pair (when the test
//! runs as root with `ip` and `tc`; otherwise those tests print why they
//! are skipped). Waits are on the world's outputs (events.jsonl, exits),
//! never fixed sleeps; no test asserts a wall-clock time.

mod common;
use common::*;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

const TWO: &str = r#"name = "two"
[world]
dt = 0.1
duration = 20.0
stall_timeout = 1.0

[[robot]]
name = "a"
start = [0.0, 0.0]
goal = [3.0, 0.0]
planner = "social-force"

[[robot]]
name = "b"
start = [0.0, 4.0]
goal = [3.0, 4.0]
planner = "social-force"
"#;

/// A loopback endpoint on a port free a moment ago.
fn free_endpoint() -> String {
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .expect("a free port")
        .port();
    format!("tcp/127.0.0.1:{port}")
}

/// Waits up to `secs` until a line of the run's events.jsonl satisfies
/// `pred`; panics naming `what` otherwise.
fn wait_for_event(out: &Path, secs: u64, what: &str, pred: impl Fn(&serde_json::Value) -> bool) {
    let start = Instant::now();
    loop {
        let text = std::fs::read_to_string(out.join("events.jsonl")).unwrap_or_default();
        let hit = text
            .lines()
            .filter_map(|l| serde_json::from_str::<serde_json::Value>(l).ok())
            .any(|e| pred(&e));
        if hit {
            return;
        }
        assert!(start.elapsed().as_secs() < secs, "no event: {what}\n{text}");
        std::thread::sleep(Duration::from_millis(50));
    }
}

fn count_events(out: &Path, kind: &str, robot: &str) -> usize {
    events(out)
        .iter()
        .filter(|e| e["type"] == kind && e["robot"] == robot)
        .count()
}

/// `mrsim run SCENARIO --mode lockstep` over `transport`; the run folder.
fn lockstep_run(scenario: &Path, transport: &str, tag: &str) -> PathBuf {
    let out = fresh_dir(tag);
    let id = run_id(tag);
    let o = run(
        scenario,
        &out,
        &id,
        &[
            "--mode",
            "lockstep",
            "--quiet",
            "--no-report",
            "--transport",
            transport,
        ],
    );
    assert_ok(&o);
    assert_eq!(metrics(&out)["transport"], transport);
    out
}

fn trajectory_bytes(dir: &Path) -> Vec<u8> {
    std::fs::read(dir.join("trajectory.csv")).expect("trajectory.csv")
}

#[test]
fn lockstep_over_zenoh_on_loopback_gives_the_trajectory_of_shared_memory_byte_for_byte() {
    let scenario = root().join("scenarios/crossing.toml");
    let shm = lockstep_run(&scenario, "shm", "zl-shm");
    let zenoh = lockstep_run(&scenario, "zenoh", "zl-zenoh");
    let a = trajectory_bytes(&shm);
    assert!(a.len() > 1000, "a real trajectory: {} bytes", a.len());
    assert!(
        a == trajectory_bytes(&zenoh),
        "trajectory.csv differs: {shm:?} {zenoh:?}"
    );
    let m = metrics(&zenoh);
    assert_eq!(m["agents_lost"], 0, "{m:#}");
    assert_eq!(m["commands_rejected"], 0, "{m:#}");
}

fn zenoh_world(file: &Path, out: &Path, id: &str, listen: &str, extra: &[&str]) -> Child {
    mrsim()
        .arg("world")
        .arg(file)
        .args([
            "--run",
            id,
            "--start-timeout",
            "60",
            "--transport",
            "zenoh",
            "--listen",
            listen,
        ])
        .args(extra)
        .arg("--out")
        .arg(out)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("world")
}

fn zenoh_agent(robot: &str, id: &str, connect: &str) -> Command {
    let mut c = mrsim();
    c.args([
        "agent",
        "--robot",
        robot,
        "--run",
        id,
        "--transport",
        "zenoh",
        "--connect",
        connect,
    ]);
    c
}

fn stderr_of(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn a_zenoh_world_refuses_strangers_with_a_reason_and_replayed_commands_are_rejected() {
    let dir = fresh_dir("zown");
    let file = dir.join("two.toml");
    std::fs::write(&file, TWO).expect("write");
    let out = dir.join("out");
    let id = run_id("zown");
    let ep = free_endpoint();
    let mut world = zenoh_world(&file, &out, &id, &ep, &[]);
    let mut a = zenoh_agent("a", &id, &ep).spawn().expect("a");
    wait_for_event(&out, 30, "a joined", |e| {
        e["type"] == "agent_joined" && e["robot"] == "a"
    });
    for (robot, extra, expect) in [
        ("zz", &[][..], "no robot named `zz`"),
        ("a", &[][..], "already driven"),
        (
            "b",
            &["--protocol-version", "99"][..],
            "protocol version 99 refused",
        ),
    ] {
        let o = zenoh_agent(robot, &id, &ep)
            .args(["--timeout", "20"])
            .args(extra)
            .output()
            .expect("stranger");
        assert!(!o.status.success(), "{robot} {extra:?} was let in");
        assert!(stderr_of(&o).contains(expect), "{}", stderr_of(&o));
    }
    // The agent of a run that does not exist on this address finds no world.
    let o = zenoh_agent("b", "zown-no-such-run", &ep)
        .args(["--timeout", "2"])
        .output()
        .expect("wrong run");
    assert!(!o.status.success());
    assert!(
        stderr_of(&o).contains("no world of this run"),
        "{}",
        stderr_of(&o)
    );
    // b replays each command a tick later: every replay is rejected.
    let mut b = zenoh_agent("b", &id, &ep)
        .args(["--fault", "double"])
        .spawn()
        .expect("b");
    let ws = wait_timeout(&mut world, 90).expect("world ended");
    assert!(ws.success(), "world failed");
    wait_timeout(&mut a, 10);
    wait_timeout(&mut b, 10);
    let m = metrics(&out);
    assert_eq!(m["transport"], "zenoh");
    assert_eq!(m["agents_lost"], 0, "{m:#}");
    assert!(
        m["commands_rejected"].as_u64().unwrap_or(0) > 0,
        "replays rejected: {m:#}"
    );
    let refused: Vec<String> = events(&out)
        .iter()
        .filter(|e| e["type"] == "join_refused")
        .filter_map(|e| e["reason"].as_str().map(String::from))
        .collect();
    assert_eq!(refused.len(), 3, "{refused:?}");
    assert_eq!(count_events(&out, "agent_joined", "b"), 1);
}

#[test]
fn with_user_and_password_auth_an_agent_without_the_credentials_cannot_join() {
    let dir = fresh_dir("zauth");
    let file = dir.join("two.toml");
    std::fs::write(&file, TWO).expect("write");
    let dict = dir.join("credentials.txt");
    std::fs::write(&dict, "robot:s3cret\n").expect("write");
    let world_cfg = dir.join("world.json5");
    std::fs::write(
        &world_cfg,
        format!(
            "{{ transport: {{ auth: {{ usrpwd: {{ user: \"robot\", password: \"s3cret\", dictionary_file: \"{}\" }} }} }} }}",
            dict.display()
        ),
    )
    .expect("write");
    let agent_cfg = dir.join("agent.json5");
    std::fs::write(
        &agent_cfg,
        "{ transport: { auth: { usrpwd: { user: \"robot\", password: \"s3cret\" } } } }",
    )
    .expect("write");
    let out = dir.join("out");
    let id = run_id("zauth");
    let ep = free_endpoint();
    let cfg = world_cfg.to_string_lossy().into_owned();
    let mut world = zenoh_world(&file, &out, &id, &ep, &["--zenoh-config", &cfg]);
    // Without credentials: never connected, and it says what to check.
    let o = zenoh_agent("a", &id, &ep)
        .args(["--timeout", "3"])
        .output()
        .expect("no credentials");
    assert!(!o.status.success(), "an agent without credentials joined");
    assert!(stderr_of(&o).contains("credentials"), "{}", stderr_of(&o));
    // A wrong password fails alike.
    let wrong = dir.join("wrong.json5");
    std::fs::write(
        &wrong,
        "{ transport: { auth: { usrpwd: { user: \"robot\", password: \"guess\" } } } }",
    )
    .expect("write");
    let o = zenoh_agent("a", &id, &ep)
        .args(["--timeout", "3", "--zenoh-config"])
        .arg(&wrong)
        .output()
        .expect("wrong password");
    assert!(!o.status.success(), "an agent with a wrong password joined");
    // With them, the run goes through; nobody else ever joined.
    let mut agents: Vec<Child> = ["a", "b"]
        .iter()
        .map(|r| {
            zenoh_agent(r, &id, &ep)
                .arg("--zenoh-config")
                .arg(&agent_cfg)
                .spawn()
                .expect("agent")
        })
        .collect();
    let ws = wait_timeout(&mut world, 90).expect("world ended");
    assert!(ws.success());
    for a in &mut agents {
        wait_timeout(a, 10);
    }
    let m = metrics(&out);
    assert_eq!(m["success_rate"], 1.0, "{m:#}");
    assert_eq!(count_events(&out, "agent_joined", "a"), 1);
}
