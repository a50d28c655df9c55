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
    // The world says so too, naming where the attempts came from, and
    // counts every refused attempt (each agent retried until its timeout).
    let said = child_stderr(&mut world);
    assert!(
        said.contains("from tcp/127.0.0.1: authentication failed"),
        "{said}"
    );
    let refused = m["auth_refused"].as_u64().unwrap_or(0);
    assert!(refused >= 2, "both agents' attempts counted: {m:#}");
    assert_eq!(m["agents_lost"], 0, "{m:#}");
}

/// What a finished child wrote on its piped stderr.
fn child_stderr(child: &mut Child) -> String {
    use std::io::Read;
    let mut s = String::new();
    if let Some(mut e) = child.stderr.take() {
        let _ = e.read_to_string(&mut s);
    }
    s
}

// ---------------------------------------------------------------------
// Two network namespaces joined by a veth pair: the world in one, agents
// in the other, as on two hosts.

/// Two namespaces `w` (the world's) and `a` (the agents') joined by a veth
/// pair, with 1 ms of netem delay each way; removed when dropped.
struct NetPair {
    w: String,
    a: String,
    veth_a: String,
    world_ip: String,
    /// Why the link has no netem delay (the kernel has no sch_netem), if so.
    no_delay: Option<String>,
}

impl NetPair {
    /// Makes the pair, or says why it cannot (not root, no `ip`, no
    /// namespaces in this container).
    fn new(tag: &str) -> Result<Self, String> {
        // SAFETY: geteuid has no preconditions.
        if unsafe { libc::geteuid() } != 0 {
            return Err("not root: network namespaces need CAP_NET_ADMIN".into());
        }
        use std::sync::atomic::{AtomicUsize, Ordering};
        static N: AtomicUsize = AtomicUsize::new(0);
        let n = N.fetch_add(1, Ordering::SeqCst);
        let pid = std::process::id() % 100_000;
        let mut p = Self {
            w: format!("mrsim-{tag}-w-{pid}-{n}"),
            a: format!("mrsim-{tag}-a-{pid}-{n}"),
            veth_a: format!("vza{pid}{n}"),
            world_ip: format!("10.{}.{}.1", 100 + n % 100, pid % 250),
            no_delay: None,
        };
        let veth_w = format!("vzw{pid}{n}");
        let agent_ip = match p.world_ip.rsplit_once('.') {
            Some((net, _)) => format!("{net}.2"),
            None => return Err(format!("bad address {}", p.world_ip)),
        };
        let steps: Vec<Vec<&str>> = vec![
            vec!["netns", "add", &p.w],
            vec!["netns", "add", &p.a],
            vec![
                "link", "add", &veth_w, "type", "veth", "peer", "name", &p.veth_a,
            ],
            vec!["link", "set", &veth_w, "netns", &p.w],
            vec!["link", "set", &p.veth_a, "netns", &p.a],
        ];
        for s in &steps {
            ip(s)?;
        }
        let w_addr = format!("{}/24", p.world_ip);
        let a_addr = format!("{agent_ip}/24");
        for (ns, dev, addr) in [(&p.w, &veth_w, &w_addr), (&p.a, &p.veth_a, &a_addr)] {
            ip(&["-n", ns, "addr", "add", addr, "dev", dev])?;
            ip(&["-n", ns, "link", "set", dev, "up"])?;
            ip(&["-n", ns, "link", "set", "lo", "up"])?;
            let tc = Command::new("tc")
                .args([
                    "-n", ns, "qdisc", "add", "dev", dev, "root", "netem", "delay", "1ms",
                ])
                .output();
            match tc {
                Ok(o) if o.status.success() => {}
                Ok(o) => p.no_delay = Some(String::from_utf8_lossy(&o.stderr).trim().to_string()),
                Err(e) => p.no_delay = Some(format!("cannot run tc: {e}")),
            }
        }
        if let Some(why) = &p.no_delay {
            eprintln!(
                "note: no 1 ms netem delay on the link ({why}): the namespaces are joined without it"
            );
        }
        Ok(p)
    }

    fn endpoint(&self) -> String {
        format!("tcp/{}:7447", self.world_ip)
    }

    /// `mrsim ARGS` inside namespace `ns`.
    fn mrsim_in(ns: &str) -> Command {
        let mut c = Command::new("ip");
        c.args(["netns", "exec", ns, env!("CARGO_BIN_EXE_mrsim")]);
        c
    }

    fn world(&self, scenario: &Path, out: &Path, id: &str, extra: &[&str]) -> Child {
        Self::mrsim_in(&self.w)
            .arg("world")
            .arg(scenario)
            .args(["--run", id, "--start-timeout", "60", "--transport", "zenoh"])
            .args(["--listen", &self.endpoint()])
            .args(extra)
            .arg("--out")
            .arg(out)
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .expect("world in its namespace")
    }

    /// An agent in the agents' namespace (or, `local`, in the world's),
    /// with `extra` arguments.
    fn agent(&self, robot: &str, id: &str, local: bool, extra: &[&str]) -> Child {
        Self::mrsim_in(if local { &self.w } else { &self.a })
            .args([
                "agent",
                "--robot",
                robot,
                "--run",
                id,
                "--transport",
                "zenoh",
            ])
            .args(["--connect", &self.endpoint(), "--timeout", "30"])
            .args(extra)
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("agent in its namespace")
    }

    fn link(&self, up: bool) {
        let state = if up { "up" } else { "down" };
        ip(&["-n", &self.a, "link", "set", &self.veth_a, state]).expect("link set");
    }
}

impl Drop for NetPair {
    fn drop(&mut self) {
        // Deleting a namespace deletes its end of the veth pair, and so
        // the pair.
        let _ = ip(&["netns", "del", &self.w]);
        let _ = ip(&["netns", "del", &self.a]);
    }
}

fn ip(args: &[&str]) -> Result<(), String> {
    let o = Command::new("ip")
        .args(args)
        .output()
        .map_err(|e| format!("cannot run ip (iproute2): {e}"))?;
    if o.status.success() {
        Ok(())
    } else {
        Err(format!(
            "ip {}: {}",
            args.join(" "),
            String::from_utf8_lossy(&o.stderr).trim()
        ))
    }
}

/// The pair, or None after printing why these tests are skipped.
fn net_pair(tag: &str) -> Option<NetPair> {
    match NetPair::new(tag) {
        Ok(p) => Some(p),
        Err(why) => {
            eprintln!(
                "skipped: cannot make network namespaces ({why}); the loopback tests still ran"
            );
            None
        }
    }
}

/// A realtime scenario of `n` robots in a row, each driving 1 m/s towards
/// a goal `dist` m ahead, ticking at 20 Hz for `duration` s.
fn realtime_row(n: usize, dist: f64, duration: f64) -> String {
    let mut s = format!(
        "name = \"row\"\n[world]\ndt = 0.05\nduration = {duration}\nmode = \"realtime\"\nstall_timeout = 2.0\narena = {{ min = [-5.0, -5.0], max = [{}, {}] }}\n[defaults]\nplanner = \"homing\"\nradius = 0.2\nmax_speed = 1.0\n",
        dist + 5.0,
        n as f64 + 5.0
    );
    for i in 0..n {
        s.push_str(&format!(
            "[[robot]]\nname = \"r{i}\"\nstart = [0.0, {i}.0]\ngoal = [{dist}, {i}.0]\n"
        ));
    }
    s
}

#[test]
fn across_namespaces_with_1ms_delay_lockstep_matches_shm_and_16_realtime_agents_miss_nothing() {
    let Some(net) = net_pair("d") else { return };
    // Lockstep: world in one namespace, all eight agents in the other.
    let scenario = root().join("scenarios/crossing.toml");
    let shm = lockstep_run(&scenario, "shm", "zn-shm");
    let out = fresh_dir("zn-lock");
    let id = run_id("znlock");
    let mut world = net.world(&scenario, &out, &id, &["--mode", "lockstep"]);
    let mut agents: Vec<Child> = ["a0", "a1", "a2", "a3", "b0", "b1", "b2", "b3"]
        .iter()
        .map(|r| net.agent(r, &id, false, &[]))
        .collect();
    let ws = wait_timeout(&mut world, 120).expect("world ended");
    assert!(ws.success(), "lockstep world failed");
    agents.iter_mut().for_each(|a| {
        wait_timeout(a, 10);
    });
    assert!(
        trajectory_bytes(&shm) == trajectory_bytes(&out),
        "trajectory.csv differs across namespaces: {shm:?} {out:?}"
    );

    // Realtime: 16 agents at 20 Hz over the delayed link, no deadline miss.
    let dir = fresh_dir("zn-rt");
    let file = dir.join("row.toml");
    std::fs::write(&file, realtime_row(16, 3.0, 4.0)).expect("write");
    let out = dir.join("out");
    let id = run_id("znrt");
    let mut world = net.world(&file, &out, &id, &[]);
    let mut agents: Vec<Child> = (0..16)
        .map(|i| net.agent(&format!("r{i}"), &id, false, &[]))
        .collect();
    let ws = wait_timeout(&mut world, 120).expect("world ended");
    assert!(ws.success(), "realtime world failed");
    agents.iter_mut().for_each(|a| {
        wait_timeout(a, 10);
    });
    let m = metrics(&out);
    assert_eq!(m["agents_lost"], 0, "{m:#}");
    let robots = m["robots"].as_object().expect("robots");
    assert_eq!(robots.len(), 16);
    let misses: u64 = robots
        .values()
        .map(|r| r["deadline_misses"].as_u64().unwrap_or(0))
        .sum();
    assert_eq!(misses, 0, "{m:#}");
}

#[test]
fn agents_behind_a_cut_link_are_lost_and_rejoin_once_it_is_back() {
    let Some(net) = net_pair("c") else { return };
    // Slow enough that nobody arrives before the end: 25 m at 1 m/s, 20 s.
    cut_link_mid_run(&net, &realtime_row(4, 25.0, 20.0), &[], "zn-cut");
}

#[test]
fn in_lockstep_agents_behind_a_cut_link_are_lost_the_run_finishes_and_they_rejoin() {
    let Some(net) = net_pair("l") else { return };
    // Lockstep waits for the agents behind the cut until stall_timeout
    // (2 s), then goes on without them. The agents beside the world take
    // 50 ms a tick so that the run (600 ticks, 30 s) outlasts the cut and
    // the rejoin (about 5 s) on a busy machine.
    let scenario =
        realtime_row(4, 25.0, 30.0).replace("mode = \"realtime\"", "mode = \"lockstep\"");
    assert!(scenario.contains("lockstep"));
    cut_link_mid_run(&net, &scenario, &["--fault", "slow-ms=50"], "zn-lcut");
}

/// Runs `scenario` (robots r0..r3) with the world and r0, r1 in one
/// namespace (r0, r1 with `near_args`) and r2, r3 behind the link in the
/// other; once all joined the link goes down: r2 and r3 are lost and their
/// agents end; the link comes up, they are started again (by hand, as a
/// remote agent is) and rejoin; the run finishes with its outputs.
fn cut_link_mid_run(net: &NetPair, scenario: &str, near_args: &[&str], tag: &str) {
    let dir = fresh_dir(tag);
    let file = dir.join("row.toml");
    std::fs::write(&file, scenario).expect("write");
    let out = dir.join("out");
    let id = run_id(tag);
    let mut world = net.world(&file, &out, &id, &[]);
    let mut near: Vec<Child> = ["r0", "r1"]
        .iter()
        .map(|r| net.agent(r, &id, true, near_args))
        .collect();
    let mut far: Vec<Child> = ["r2", "r3"]
        .iter()
        .map(|r| net.agent(r, &id, false, &[]))
        .collect();
    for r in ["r0", "r1", "r2", "r3"] {
        wait_for_event(&out, 60, &format!("{r} joined"), |e| {
            e["type"] == "agent_joined" && e["robot"] == r
        });
    }
    net.link(false);
    for r in ["r2", "r3"] {
        wait_for_event(&out, 30, &format!("{r} lost"), |e| {
            e["type"] == "agent_lost" && e["robot"] == r
        });
    }
    // The agents behind the link find their world gone and end.
    for a in &mut far {
        let s = wait_timeout(a, 30).expect("far agent ended");
        assert!(
            !s.success(),
            "an agent cut off from its world ends with an error"
        );
    }
    net.link(true);
    let mut back: Vec<Child> = ["r2", "r3"]
        .iter()
        .map(|r| net.agent(r, &id, false, &[]))
        .collect();
    for r in ["r2", "r3"] {
        wait_for_event(&out, 30, &format!("{r} rejoined"), |e| {
            e["type"] == "agent_rejoined" && e["robot"] == r
        });
    }
    let ws = wait_timeout(&mut world, 90).expect("world ended");
    assert!(ws.success(), "the run finishes after the cut");
    for a in near.iter_mut().chain(back.iter_mut()) {
        wait_timeout(a, 10);
    }
    let m = metrics(&out);
    assert_eq!(m["agents_lost"], 2, "{m:#}");
    assert!(m["ticks"].as_u64().unwrap_or(0) > 0, "{m:#}");
    assert!(out.join("trajectory.csv").exists());
    for r in ["r0", "r1"] {
        assert_eq!(count_events(&out, "agent_lost", r), 0, "{r} stayed");
    }
}

#[test]
fn garbage_another_runs_messages_and_forged_commands_are_counted_and_the_world_runs_on() {
    use mrsim_transport::Namespace;
    use mrsim_transport::zenoh::{ZenohOptions, keys::Keys, publish_raw, wire};
    let dir = fresh_dir("zbad");
    let file = dir.join("row.toml");
    // Long enough that every stranger's message arrives while it runs.
    std::fs::write(&file, realtime_row(2, 25.0, 8.0)).expect("write");
    let out = dir.join("out");
    let id = run_id("zbad");
    let ep = free_endpoint();
    let mut world = zenoh_world(&file, &out, &id, &ep, &[]);
    let mut agents: Vec<Child> = ["r0", "r1"]
        .iter()
        .map(|r| zenoh_agent(r, &id, &ep).spawn().expect("agent"))
        .collect();
    for r in ["r0", "r1"] {
        wait_for_event(&out, 60, &format!("{r} joined"), |e| {
            e["type"] == "agent_joined" && e["robot"] == r
        });
    }
    let opts = ZenohOptions {
        endpoint: Some(ep.clone()),
        config_file: None,
    };
    let ns = Namespace::new(&id).expect("run id");
    let command = Keys::new(&ns).command;
    // 200 messages that are no command at all.
    let garbage: Vec<Vec<u8>> = (0..200u32)
        .map(|i| vec![i as u8; (i % 40) as usize])
        .collect();
    publish_raw(&opts, &ns, &command, &garbage).expect("garbage");
    // 20 well-formed commands for r0 with a token it was never given (a
    // command of another run, or forged).
    let forged: Vec<Vec<u8>> = (0..20u64)
        .map(|i| {
            wire::encode(&mrsim_proto::CommandMsg {
                robot_id: 0,
                token: 0xdead_beef + i,
                tick: i,
                ..Default::default()
            })
        })
        .collect();
    publish_raw(&opts, &ns, &command, &forged).expect("forged");
    // Commands on another run's key never reach this world.
    let other = Keys::new(&Namespace::new("zbad-other-run").expect("run id")).command;
    let _ = publish_raw(
        &ZenohOptions {
            endpoint: Some(ep.clone()),
            config_file: None,
        },
        &Namespace::new("zbad-other-run").expect("run id"),
        &other,
        &forged,
    );
    let ws = wait_timeout(&mut world, 90).expect("world ended");
    assert!(ws.success(), "the world ran to its end");
    for a in &mut agents {
        wait_timeout(a, 10);
    }
    let said = child_stderr(&mut world);
    assert!(said.contains("refused 200 malformed message(s)"), "{said}");
    let m = metrics(&out);
    assert_eq!(m["agents_lost"], 0, "{m:#}");
    assert_eq!(m["commands_rejected_unknown"], 200, "the garbage: {m:#}");
    let forged_seen = m["robots"]["r0"]["commands_rejected"].as_u64().unwrap_or(0)
        + m["messages_dropped"].as_u64().unwrap_or(0);
    assert_eq!(
        forged_seen, 20,
        "the forged commands, not the other run's: {m:#}"
    );
    assert_eq!(m["robots"]["r1"]["commands_rejected"], 0, "{m:#}");
    assert_eq!(m["joins_malformed"], 0, "{m:#}");
    assert_eq!(m["auth_refused"], 0, "{m:#}");
}

#[test]
fn a_zenoh_run_shows_its_progress_like_a_shared_memory_run() {
    let dir = fresh_dir("zprog");
    let file = dir.join("row.toml");
    // Realtime, 8 s: the launcher's observer has time to attach.
    std::fs::write(&file, realtime_row(2, 25.0, 8.0)).expect("write");
    let out = dir.join("out");
    let o = mrsim()
        .env("MRSIM_PROGRESS", "lines")
        .arg("run")
        .arg(&file)
        .arg("--out")
        .arg(&out)
        .args([
            "--run",
            &run_id("zprog"),
            "--no-report",
            "--transport",
            "zenoh",
        ])
        .output()
        .expect("run");
    assert_ok(&o);
    let said = stderr_of(&o);
    let lines: Vec<&str> = said
        .lines()
        .filter(|l| l.starts_with("run: ") && l.contains("at goal"))
        .collect();
    assert!(!lines.is_empty(), "no progress lines:\n{said}");
    assert!(lines.iter().any(|l| l.contains("/160 (")), "{said}");
}
