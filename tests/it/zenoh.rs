//! End-to-end tests of the Zenoh transport: on loopback (always), and
//! between two network namespaces joined by a veth pair (when the test
//! runs as root with `ip` and `tc`; otherwise those tests print why they
//! are skipped). Waits are on the world's outputs (events.jsonl, exits),
//! never fixed sleeps; no test asserts a wall-clock time.

use crate::common::*;
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
fn a_zenoh_world_refuses_strangers_with_a_reason_and_every_replayed_command_is_rejected() {
    let dir = fresh_dir("zown");
    let file = dir.join("two.toml");
    std::fs::write(&file, TWO).expect("write");
    let out = dir.join("out");
    let id = run_id("zown");
    let ep = free_endpoint();
    // Lockstep: a replay reaches the world within its tick or after it,
    // never judged late, so every one is refused.
    let mut world = zenoh_world(&file, &out, &id, &ep, &["--mode", "lockstep"]);
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
    // One replay for each command b had applied (the last one may come
    // after the world ended), each refused as a replay; a's none.
    let applied = m["robots"]["b"]["latency_us"]["count"]
        .as_u64()
        .unwrap_or(0);
    let rejected = m["robots"]["b"]["commands_rejected"].as_u64().unwrap_or(0);
    assert!(applied > 10, "b drove: {m:#}");
    assert!(
        rejected + 1 >= applied && rejected <= applied,
        "{applied} commands applied, {rejected} replays rejected: {m:#}"
    );
    assert_eq!(m["robots"]["a"]["commands_rejected"], 0, "{m:#}");
    for e in events(&out)
        .iter()
        .filter(|e| e["type"] == "command_rejected")
    {
        assert_eq!(e["robot"], "b", "{e}");
        let reason = e["reason"].as_str().unwrap_or("");
        assert!(
            reason == "second command in one tick" || reason == "command for a past tick",
            "{e}"
        );
    }
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

/// Reads a child's piped stderr on a thread until it ends.
fn read_stderr(child: &mut Child) -> std::thread::JoinHandle<String> {
    let mut e = child.stderr.take();
    std::thread::spawn(move || {
        use std::io::Read;
        let mut s = String::new();
        if let Some(e) = &mut e {
            let _ = e.read_to_string(&mut s);
        }
        s
    })
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
/// pair; removed when dropped. The link itself adds no delay (netem is
/// missing from many kernels): [`DelayRelay`] gives one where a test needs it.
struct NetPair {
    w: String,
    a: String,
    veth_a: String,
    world_ip: String,
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
        let p = Self {
            w: format!("mrsim-{tag}-w-{pid}-{n}"),
            a: format!("mrsim-{tag}-a-{pid}-{n}"),
            veth_a: format!("vza{pid}{n}"),
            world_ip: format!("10.{}.{}.1", 100 + n % 100, pid % 250),
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
        self.agent_to(&self.endpoint(), robot, id, local, extra)
    }

    /// An agent as [`NetPair::agent`] that connects to `endpoint`.
    fn agent_to(
        &self,
        endpoint: &str,
        robot: &str,
        id: &str,
        local: bool,
        extra: &[&str],
    ) -> Child {
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
            .args(["--connect", endpoint, "--timeout", "30"])
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

/// A TCP relay in the world's namespace that holds every chunk of bytes
/// `delay` in each direction before passing it on: agents that connect to
/// [`DelayRelay::endpoint`] reach the world's endpoint over a link `delay`
/// slower each way, whatever the kernel's qdiscs. Stops accepting when
/// dropped.
struct DelayRelay {
    endpoint: String,
    stop: std::sync::Arc<std::sync::atomic::AtomicBool>,
}

impl DelayRelay {
    /// Listens on port 7448 of the world's address inside `net.w` and
    /// relays to the world's endpoint (port 7447).
    fn new(net: &NetPair, delay: Duration) -> Self {
        use std::sync::atomic::{AtomicBool, Ordering};
        let stop = std::sync::Arc::new(AtomicBool::new(false));
        let ns = PathBuf::from("/var/run/netns").join(&net.w);
        let listen = format!("{}:7448", net.world_ip);
        let upstream = format!("{}:7447", net.world_ip);
        let (ready_tx, ready_rx) = std::sync::mpsc::channel();
        let flag = stop.clone();
        std::thread::spawn(move || {
            // Sockets belong to the namespace of the thread that makes them:
            // this thread enters the world's, and makes them all.
            let entered = std::fs::File::open(&ns)
                .map_err(|e| e.to_string())
                .and_then(|f| {
                    use std::os::fd::AsRawFd;
                    // SAFETY: setns(2) on an open namespace file, for this thread only.
                    let r = unsafe { libc::setns(f.as_raw_fd(), libc::CLONE_NEWNET) };
                    if r == 0 {
                        Ok(())
                    } else {
                        Err(std::io::Error::last_os_error().to_string())
                    }
                });
            let listener = entered.and_then(|()| {
                let l = std::net::TcpListener::bind(&listen).map_err(|e| e.to_string())?;
                l.set_nonblocking(true).map_err(|e| e.to_string())?;
                Ok(l)
            });
            let listener = match listener {
                Ok(l) => {
                    let _ = ready_tx.send(Ok(()));
                    l
                }
                Err(e) => {
                    let _ = ready_tx.send(Err(e));
                    return;
                }
            };
            while !flag.load(Ordering::SeqCst) {
                match listener.accept() {
                    Ok((down, _)) => {
                        let Ok(up) = std::net::TcpStream::connect(&upstream) else {
                            continue;
                        };
                        let _ = down.set_nonblocking(false);
                        let _ = down.set_nodelay(true);
                        let _ = up.set_nodelay(true);
                        for (from, to) in [(&down, &up), (&up, &down)] {
                            if let (Ok(from), Ok(to)) = (from.try_clone(), to.try_clone()) {
                                delayed_pipe(from, to, delay);
                            }
                        }
                    }
                    Err(_) => std::thread::sleep(Duration::from_millis(10)),
                }
            }
        });
        match ready_rx.recv() {
            Ok(Ok(())) => {}
            Ok(Err(e)) => panic!("the delaying relay cannot listen: {e}"),
            Err(e) => panic!("the delaying relay ended: {e}"),
        }
        Self {
            endpoint: format!("tcp/{}:7448", net.world_ip),
            stop,
        }
    }
}

impl Drop for DelayRelay {
    fn drop(&mut self) {
        self.stop.store(true, std::sync::atomic::Ordering::SeqCst);
    }
}

/// Copies `from` to `to`, each chunk written `delay` after it was read
/// (a reader and a writer thread, so the delay does not cut the rate);
/// closes `to`'s write side when `from` ends.
fn delayed_pipe(mut from: std::net::TcpStream, mut to: std::net::TcpStream, delay: Duration) {
    use std::io::{Read, Write};
    let (tx, rx) = std::sync::mpsc::channel::<(Instant, Vec<u8>)>();
    std::thread::spawn(move || {
        let mut buf = vec![0u8; 64 * 1024];
        while let Ok(n) = from.read(&mut buf) {
            if n == 0 || tx.send((Instant::now(), buf[..n].to_vec())).is_err() {
                break;
            }
        }
    });
    std::thread::spawn(move || {
        for (read_at, bytes) in rx {
            let due = read_at + delay;
            let now = Instant::now();
            if due > now {
                std::thread::sleep(due - now);
            }
            if to.write_all(&bytes).is_err() {
                break;
            }
        }
        let _ = to.shutdown(std::net::Shutdown::Write);
    });
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

/// The pair, or None after saying why `test` is skipped (a failure under
/// `MRSIM_REQUIRE_NETNS=1`, as CI sets it).
fn net_pair(tag: &str, test: &str) -> Option<NetPair> {
    match NetPair::new(tag) {
        Ok(p) => Some(p),
        Err(why) => {
            skip(
                test,
                "MRSIM_REQUIRE_NETNS",
                &format!("cannot make network namespaces ({why})"),
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

/// The median round trip (snapshot published -> command received) of every
/// robot of a run folder, µs.
fn round_trips(out: &Path) -> Vec<(String, f64)> {
    let m = metrics(out);
    m["robots"]
        .as_object()
        .expect("robots")
        .iter()
        .map(|(n, r)| (n.clone(), r["latency_us"]["p50"].as_f64().unwrap_or(0.0)))
        .collect()
}

#[test]
fn across_namespaces_with_1ms_delay_each_way_lockstep_matches_shm_and_16_realtime_agents_answer_through_it()
 {
    const TEST: &str = "across_namespaces_with_1ms_delay_each_way";
    let Some(net) = net_pair("d", TEST) else {
        return;
    };
    let _heavy = heavy();
    let relay = DelayRelay::new(&net, Duration::from_millis(1));
    // Lockstep: world in one namespace, all eight agents in the other.
    let scenario = root().join("scenarios/crossing.toml");
    let shm = lockstep_run(&scenario, "shm", "zn-shm");
    let out = fresh_dir("zn-lock");
    let id = run_id("znlock");
    let mut world = net.world(&scenario, &out, &id, &["--mode", "lockstep"]);
    let mut agents: Vec<Child> = ["a0", "a1", "a2", "a3", "b0", "b1", "b2", "b3"]
        .iter()
        .map(|r| net.agent_to(&relay.endpoint, r, &id, false, &[]))
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
    // The delay is real: every answer crossed the relay twice (snapshot
    // out, command back). Load can only lengthen a round trip.
    for (robot, p50) in round_trips(&out) {
        assert!(p50 >= 2000.0, "{robot}: median round trip {p50} µs < 2 ms");
    }

    // Realtime: 16 agents at 20 Hz over the delayed link. Whether an
    // answer makes its 50 ms deadline depends on the machine's load, so
    // what is asserted is what load cannot change: nobody lost, every
    // robot answered through the relay, and no round trip shorter than the
    // relay's delay.
    let dir = fresh_dir("zn-rt");
    let file = dir.join("row.toml");
    std::fs::write(&file, realtime_row(16, 3.0, 4.0)).expect("write");
    let out = dir.join("out");
    let id = run_id("znrt");
    let mut world = net.world(&file, &out, &id, &[]);
    let mut agents: Vec<Child> = (0..16)
        .map(|i| net.agent_to(&relay.endpoint, &format!("r{i}"), &id, false, &[]))
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
    for (robot, r) in robots {
        let answered = r["latency_us"]["count"].as_u64().unwrap_or(0);
        assert!(answered > 0, "{robot} never answered: {m:#}");
    }
    for (robot, p50) in round_trips(&out) {
        assert!(p50 >= 2000.0, "{robot}: median round trip {p50} µs < 2 ms");
    }
}

#[test]
fn agents_behind_a_cut_link_are_lost_and_rejoin_once_it_is_back() {
    let Some(net) = net_pair(
        "c",
        "agents_behind_a_cut_link_are_lost_and_rejoin_once_it_is_back",
    ) else {
        return;
    };
    let _heavy = heavy();
    // Nobody arrives and the run outlasts any wait: the test ends it with
    // SIGINT once the cut-off agents are back, so no part of it (a 3 s
    // lease, an exit, a restart, a rejoin) races the run's clock.
    cut_link_mid_run(
        &net,
        &realtime_row(4, 700.0, 600.0),
        &[],
        Rejoin::ByThemselves,
        "zn-cut",
    );
}

#[test]
fn in_lockstep_agents_behind_a_cut_link_are_lost_the_run_goes_on_and_they_rejoin() {
    let Some(net) = net_pair(
        "l",
        "in_lockstep_agents_behind_a_cut_link_are_lost_the_run_goes_on_and_they_rejoin",
    ) else {
        return;
    };
    let _heavy = heavy();
    // Lockstep waits for the agents behind the cut until their lease runs
    // out (3 s), then goes on without them. stall_timeout is long (20 s):
    // on a loaded machine the agents beside the world, starved while the
    // cut-off ones start again, may take seconds for a tick, and are not
    // the ones lost. They take 50 ms a tick so that the run does not spin;
    // it is long enough to outlast the cut and the rejoin, and ended by
    // SIGINT after them.
    let scenario = realtime_row(4, 700.0, 600.0)
        .replace("mode = \"realtime\"", "mode = \"lockstep\"")
        .replace("stall_timeout = 2.0", "stall_timeout = 20.0");
    assert!(scenario.contains("stall_timeout = 20.0"));
    assert!(scenario.contains("lockstep"));
    cut_link_mid_run(
        &net,
        &scenario,
        &["--fault", "slow-ms=50"],
        Rejoin::StartedAgain,
        "zn-lcut",
    );
}

/// How the agents cut off come back once the link is up again.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Rejoin {
    /// They keep trying to reach the world (`--reconnect`, 30 s by default)
    /// and rejoin by themselves.
    ByThemselves,
    /// They end (`--reconnect 0`) and are started again by hand.
    StartedAgain,
}

/// Runs `scenario` (robots r0..r3) with the world and r0, r1 in one
/// namespace (r0, r1 with `near_args`) and r2, r3 behind the link in the
/// other; once all joined the link goes down: r2 and r3 are lost; the link
/// comes up and they rejoin as `rejoin` says, each with a new token; then
/// the test interrupts the world, which writes its outputs.
fn cut_link_mid_run(net: &NetPair, scenario: &str, near_args: &[&str], rejoin: Rejoin, tag: &str) {
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
    let far_args: &[&str] = match rejoin {
        Rejoin::ByThemselves => &[],
        Rejoin::StartedAgain => &["--reconnect", "0"],
    };
    let mut far: Vec<Child> = ["r2", "r3"]
        .iter()
        .map(|r| net.agent(r, &id, false, far_args))
        .collect();
    for r in ["r0", "r1", "r2", "r3"] {
        wait_for_event(&out, 60, &format!("{r} joined"), |e| {
            e["type"] == "agent_joined" && e["robot"] == r
        });
    }
    net.link(false);
    for r in ["r2", "r3"] {
        wait_for_event(&out, 60, &format!("{r} lost"), |e| {
            e["type"] == "agent_lost" && e["robot"] == r
        });
    }
    let mut back: Vec<Child> = Vec::new();
    match rejoin {
        Rejoin::StartedAgain => {
            // The agents behind the link find their world gone and end.
            for a in &mut far {
                let s = wait_timeout(a, 60).expect("far agent ended");
                assert!(
                    !s.success(),
                    "an agent cut off from its world ends with an error"
                );
            }
            net.link(true);
            back = ["r2", "r3"]
                .iter()
                .map(|r| net.agent(r, &id, false, &[]))
                .collect();
        }
        Rejoin::ByThemselves => {
            // Still running, trying to reach the world.
            for a in &mut far {
                assert!(a.try_wait().ok().flatten().is_none(), "a far agent ended");
            }
            net.link(true);
        }
    }
    for r in ["r2", "r3"] {
        wait_for_event(&out, 60, &format!("{r} rejoined"), |e| {
            e["type"] == "agent_rejoined" && e["robot"] == r
        });
    }
    // Each by a join, with a new token.
    for r in ["r2", "r3"] {
        let how: Vec<_> = events(&out)
            .iter()
            .filter(|e| e["type"] == "agent_rejoined" && e["robot"] == r)
            .map(|e| e["token"].clone())
            .collect();
        assert!(how.contains(&serde_json::json!("new")), "{r}: {how:?}");
    }
    assert!(
        world.try_wait().ok().flatten().is_none(),
        "the run outlasts the cut and the rejoin"
    );
    send_signal(world.id(), libc::SIGINT);
    let ws = wait_timeout(&mut world, 60).expect("world ended");
    assert_eq!(ws.code(), Some(130), "an interrupted world: {ws:?}");
    for a in near.iter_mut().chain(back.iter_mut()).chain(far.iter_mut()) {
        wait_timeout(a, 10);
    }
    let m = metrics(&out);
    assert_eq!(m["interrupted"], true, "{m:#}");
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
    // Lockstep, so that an honest answer is never late and never rejected
    // however loaded the machine; the agents take 50 ms a tick, so the run
    // (160 ticks) lasts at least 8 s: every stranger's message arrives
    // while it runs (a slower machine only makes the run longer).
    let scenario = realtime_row(2, 25.0, 8.0).replace("mode = \"realtime\"", "mode = \"lockstep\"");
    std::fs::write(&file, scenario).expect("write");
    let out = dir.join("out");
    let id = run_id("zbad");
    let ep = free_endpoint();
    let mut world = zenoh_world(&file, &out, &id, &ep, &[]);
    let mut agents: Vec<Child> = ["r0", "r1"]
        .iter()
        .map(|r| {
            zenoh_agent(r, &id, &ep)
                .args(["--fault", "slow-ms=50"])
                .spawn()
                .expect("agent")
        })
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
    // command of another run, or forged). They name ticks all over the run
    // and a send time far ahead, so that only the token can refuse most of
    // them: every refusal must say so.
    let forged: Vec<Vec<u8>> = (0..20u64)
        .map(|i| {
            wire::encode(&mrsim_proto::CommandMsg {
                robot_id: 0,
                token: 0xdead_beef + i,
                tick: i * 8,
                sent_ns: u64::MAX / 2,
                kind: mrsim_proto::command_kind::VELOCITY,
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
    let reasons: Vec<String> = events(&out)
        .iter()
        .filter(|e| e["type"] == "command_rejected" && e["robot"] == "r0")
        .map(|e| e["reason"].as_str().unwrap_or("").to_string())
        .collect();
    assert!(
        reasons
            .iter()
            .all(|r| r == "not sent by the agent that owns this robot"),
        "refused for another reason than the token: {reasons:?}"
    );
    assert_eq!(m["joins_malformed"], 0, "{m:#}");
    assert_eq!(m["auth_refused"], 0, "{m:#}");
}

#[test]
fn a_zenoh_run_shows_its_progress_like_a_shared_memory_run() {
    let _heavy = heavy();
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

/// A long lockstep run of two robots (r0, r1) whose agents take 50 ms a
/// tick, so that everything a test sends arrives while it runs (160 ticks:
/// at least 8 s, longer on a slower machine), and the world and its agents
/// over Zenoh on a free loopback port: (run folder, run id, endpoint,
/// world, agents), both agents joined.
fn long_lockstep_pair(tag: &str) -> (PathBuf, String, String, Child, Vec<Child>) {
    let dir = fresh_dir(tag);
    let file = dir.join("row.toml");
    std::fs::write(&file, long_lockstep_row()).expect("write");
    let out = dir.join("out");
    let id = run_id(tag);
    let ep = free_endpoint();
    let world = zenoh_world(&file, &out, &id, &ep, &[]);
    let agents: Vec<Child> = ["r0", "r1"]
        .iter()
        .map(|r| {
            zenoh_agent(r, &id, &ep)
                .args(["--fault", "slow-ms=50"])
                .stderr(Stdio::piped())
                .spawn()
                .expect("agent")
        })
        .collect();
    for r in ["r0", "r1"] {
        wait_for_event(&out, 60, &format!("{r} joined"), |e| {
            e["type"] == "agent_joined" && e["robot"] == r
        });
    }
    (out, id, ep, world, agents)
}

/// The scenario of [`long_lockstep_pair`]: two robots 25 m from their
/// goals, 8 s of run.
fn long_lockstep_row() -> String {
    realtime_row(2, 25.0, 8.0).replace("mode = \"realtime\"", "mode = \"lockstep\"")
}

/// The same scenario in lockstep over shared memory, undisturbed: the
/// trajectory a disturbed Zenoh run must still give.
fn undisturbed_trajectory(tag: &str) -> Vec<u8> {
    let dir = fresh_dir(tag);
    let file = dir.join("row.toml");
    std::fs::write(&file, long_lockstep_row()).expect("write");
    trajectory_bytes(&lockstep_run(&file, "shm", tag))
}

#[test]
fn a_flood_of_forged_commands_is_dropped_past_the_inbox_and_the_run_ends_as_undisturbed() {
    use mrsim_transport::Namespace;
    use mrsim_transport::zenoh::{ZenohOptions, keys::Keys, publish_raw, wire};
    let expected = undisturbed_trajectory("zflood-shm");
    let (out, id, ep, mut world, mut agents) = long_lockstep_pair("zflood");
    let ns = Namespace::new(&id).expect("run id");
    let opts = ZenohOptions {
        endpoint: Some(ep),
        config_file: None,
    };
    // 20,000 well-formed commands for r0 with tokens the world never gave,
    // in one burst: some seventy times the world's inbox for two agents. The world
    // drains its inbox at most once per wake-up, each drain handing every
    // command to the tick loop (which records each refusal), while Zenoh's
    // receive thread only decodes and queues: the inbox overflows, the
    // more so the busier the machine. The agents' own commands carry the
    // tokens they were given and are never crowded out.
    const SENT: u64 = 20_000;
    let flood: Vec<Vec<u8>> = (0..SENT)
        .map(|i| {
            wire::encode(&mrsim_proto::CommandMsg {
                robot_id: 0,
                token: 0x000f_100d_0000 + i,
                tick: 1_000_000 + i,
                kind: mrsim_proto::command_kind::VELOCITY,
                ..Default::default()
            })
        })
        .collect();
    // The world says how many it dropped after each drain: its stderr is
    // read as it comes, so that a full pipe never stops it.
    let said = read_stderr(&mut world);
    publish_raw(&opts, &ns, &Keys::new(&ns).command, &flood).expect("flood");
    let ws = wait_timeout(&mut world, 120).expect("world ended");
    assert!(ws.success(), "the world ran to its end");
    for a in &mut agents {
        wait_timeout(a, 10);
    }
    let said = said.join().expect("world's stderr");
    let m = metrics(&out);
    let dropped = m["messages_dropped"].as_u64().unwrap_or(0);
    let rejected = m["robots"]["r0"]["commands_rejected"].as_u64().unwrap_or(0);
    // Every command of the flood is either dropped unread or refused by
    // the tick loop, none of them lost or applied.
    assert_eq!(dropped + rejected, SENT, "{m:#}");
    assert!(
        dropped > 0,
        "a flood seventy times the inbox was dropped in part: {m:#}"
    );
    assert!(
        said.contains(&format!("dropped {dropped} over the inbox limit")),
        "{said}"
    );
    // And the run is the one nobody disturbed, to the byte.
    assert_eq!(m["agents_lost"], 0, "{m:#}");
    assert_eq!(m["robots"]["r1"]["commands_rejected"], 0, "{m:#}");
    assert_eq!(m["commands_rejected_unknown"], 0, "{m:#}");
    assert!(
        trajectory_bytes(&out) == expected,
        "the flood changed the trajectory: {out:?}"
    );
}

#[test]
fn malformed_and_refused_joins_are_counted_and_recorded_while_honest_agents_join() {
    use mrsim_proto::{FixedStr, JoinRequest, PROTOCOL_VERSION};
    use mrsim_transport::Namespace;
    use mrsim_transport::zenoh::{ZenohOptions, keys::Keys, publish_raw, wire};
    let dir = fresh_dir("zjoin");
    let file = dir.join("two.toml");
    std::fs::write(&file, TWO).expect("write");
    let out = dir.join("out");
    let id = run_id("zjoin");
    let ep = free_endpoint();
    let mut world = zenoh_world(&file, &out, &id, &ep, &["--mode", "lockstep"]);
    let ns = Namespace::new(&id).expect("run id");
    let opts = ZenohOptions {
        endpoint: Some(ep.clone()),
        config_file: None,
    };
    // Before any agent: 30 join requests that do not decode (garbage of
    // every length but the right one), one of another protocol version and
    // one for a robot the scenario does not have. The world answers while
    // it waits for its agents: nothing here depends on timing.
    let garbage: Vec<Vec<u8>> = (0..30usize)
        .map(|i| vec![0xA5; if i == 7 { 0 } else { i * 3 + 1 }])
        .collect();
    let request = |version: u32, robot: &str, nonce: u64| {
        wire::encode(&JoinRequest {
            protocol_version: version,
            pid: 4_000_000 + nonce as u32,
            nonce,
            robot: FixedStr::new(robot),
            group: 1,
        })
    };
    let refused = vec![
        request(PROTOCOL_VERSION + 1, "a", 11),
        request(PROTOCOL_VERSION, "no-such-robot", 12),
    ];
    let join = Keys::new(&ns).join;
    // The world's token comes once all its subscribers are declared.
    mrsim_transport::zenoh::ZenohObserver::connect(&ns, &opts, false, Duration::from_secs(60))
        .expect("the world is up");
    publish_raw(&opts, &ns, &join, &garbage).expect("garbage joins");
    publish_raw(&opts, &ns, &join, &refused).expect("refused joins");
    for what in ["protocol version", "no-such-robot"] {
        wait_for_event(&out, 60, what, |e| {
            e["type"] == "join_refused" && e.to_string().contains(what)
        });
    }
    let mut agents: Vec<Child> = ["a", "b"]
        .iter()
        .map(|r| zenoh_agent(r, &id, &ep).spawn().expect("agent"))
        .collect();
    let ws = wait_timeout(&mut world, 90).expect("world ended");
    assert!(ws.success(), "world failed");
    for a in &mut agents {
        wait_timeout(a, 10);
    }
    let m = metrics(&out);
    assert_eq!(m["joins_malformed"], 30, "{m:#}");
    assert_eq!(m["messages_dropped"], 0, "{m:#}");
    assert_eq!(m["success_rate"], 1.0, "{m:#}");
    assert_eq!(m["agents_lost"], 0, "{m:#}");
    let reasons: Vec<String> = events(&out)
        .iter()
        .filter(|e| e["type"] == "join_refused")
        .map(|e| e.to_string())
        .collect();
    assert_eq!(reasons.len(), 2, "{reasons:?}");
    assert!(
        reasons
            .iter()
            .any(|r| r.contains(&format!("protocol version {}", PROTOCOL_VERSION + 1))),
        "{reasons:?}"
    );
    assert!(
        reasons.iter().any(|r| r.contains("no-such-robot")),
        "{reasons:?}"
    );
    for r in ["a", "b"] {
        assert_eq!(count_events(&out, "agent_joined", r), 1, "{r}");
    }
    let said = child_stderr(&mut world);
    assert!(said.contains("refused 30 malformed message(s)"), "{said}");
}

#[test]
fn forged_snapshots_are_counted_by_the_agents_and_never_planned_on() {
    use mrsim_proto::{BodyState, SnapshotHeader};
    use mrsim_transport::Namespace;
    use mrsim_transport::zenoh::{ZenohOptions, keys::Keys, publish_raw, wire};
    let expected = undisturbed_trajectory("zforge-shm");
    let (out, id, ep, mut world, mut agents) = long_lockstep_pair("zforge");
    let ns = Namespace::new(&id).expect("run id");
    let opts = ZenohOptions {
        endpoint: Some(ep),
        config_file: None,
    };
    // Wait for the ticks to run: tick 0 goes out only once both agents are
    // ready, and each is ready only after its join reply brought it the
    // run's key. A watcher of the run's snapshots sees it.
    {
        use mrsim_transport::ObserverTransport;
        use mrsim_transport::zenoh::ZenohObserver;
        let mut watch =
            ZenohObserver::connect(&ns, &opts, true, Duration::from_secs(30)).expect("observer");
        let (mut header, mut bodies) = (SnapshotHeader::default(), Vec::new());
        let start = Instant::now();
        while !(watch
            .latest_snapshot(&mut header, &mut bodies)
            .expect("snapshot")
            && header.tick >= 1)
        {
            assert!(start.elapsed() < Duration::from_secs(60), "no tick 1");
            std::thread::sleep(Duration::from_millis(20));
        }
    }
    // 25 snapshots of a tick far ahead with both robots elsewhere, each
    // followed by a tag of the right length under a key of the forger's
    // (or none): an agent that planned on one would answer a tick the
    // world has not reached, a refused command, and drive elsewhere.
    const FORGED: usize = 25;
    let forged: Vec<Vec<u8>> = (0..FORGED)
        .map(|i| {
            let header = SnapshotHeader {
                tick: 5_000 + i as u64,
                body_count: 2,
                ..Default::default()
            };
            let bodies: Vec<BodyState> = (0..2)
                .map(|id| BodyState {
                    id,
                    position: [-3.0, id as f64],
                    radius: 0.2,
                    ..Default::default()
                })
                .collect();
            let mut b = Vec::new();
            wire::encode_slice(&header, &bodies, &mut b);
            if i % 5 != 0 {
                b.extend_from_slice(&[i as u8; 32]);
            }
            b
        })
        .collect();
    publish_raw(&opts, &ns, &Keys::new(&ns).snapshot, &forged).expect("forged snapshots");
    let ws = wait_timeout(&mut world, 120).expect("world ended");
    assert!(ws.success(), "the world ran to its end");
    // Every forged snapshot went through the world to each agent before
    // the world's later snapshots on the same link: each agent saw them
    // all before the last, and says so as it ends.
    for (a, r) in agents.iter_mut().zip(["r0", "r1"]) {
        wait_timeout(a, 10);
        let said = child_stderr(a);
        assert!(
            said.contains(&format!(
                "refused {FORGED} snapshot(s) that failed authentication and 0 replayed"
            )),
            "{r}: {said}"
        );
    }
    let m = metrics(&out);
    assert_eq!(
        m["commands_rejected"], 0,
        "nothing answered a forged tick: {m:#}"
    );
    assert_eq!(m["agents_lost"], 0, "{m:#}");
    assert!(
        trajectory_bytes(&out) == expected,
        "a forged snapshot changed the trajectory: {out:?}"
    );
}

/// Runs `openssl ARGS` in `dir`; the error says what failed.
fn openssl(dir: &Path, args: &[&str]) -> Result<(), String> {
    let o = Command::new("openssl")
        .current_dir(dir)
        .args(args)
        .output()
        .map_err(|e| format!("cannot run openssl: {e}"))?;
    if o.status.success() {
        Ok(())
    } else {
        Err(format!(
            "openssl {}: {}",
            args.join(" "),
            String::from_utf8_lossy(&o.stderr).trim()
        ))
    }
}

/// A certificate authority `NAME.pem` (key `NAME-key.pem`) made in `dir`.
fn test_ca(dir: &Path, name: &str) -> Result<(), String> {
    openssl(
        dir,
        &[
            "req",
            "-x509",
            "-newkey",
            "ec",
            "-pkeyopt",
            "ec_paramgen_curve:prime256v1",
            "-nodes",
            "-days",
            "2",
            "-subj",
            &format!("/CN=mrsim test {name}"),
            "-keyout",
            &format!("{name}-key.pem"),
            "-out",
            &format!("{name}.pem"),
        ],
    )
}

/// In `dir`: a CA `ca.pem`, the world's certificate `world-cert.pem` for
/// 127.0.0.1 signed by it (key `world-key.pem`), and another CA
/// `stranger.pem` that signed nothing of the world's.
fn test_certificates(dir: &Path) -> Result<(), String> {
    test_ca(dir, "ca")?;
    test_ca(dir, "stranger")?;
    openssl(
        dir,
        &[
            "req",
            "-newkey",
            "ec",
            "-pkeyopt",
            "ec_paramgen_curve:prime256v1",
            "-nodes",
            "-subj",
            "/CN=127.0.0.1",
            "-keyout",
            "world-key.pem",
            "-out",
            "world.csr",
        ],
    )?;
    std::fs::write(
        dir.join("world.ext"),
        "basicConstraints=CA:FALSE\nkeyUsage=digitalSignature\nextendedKeyUsage=serverAuth\nsubjectAltName=IP:127.0.0.1,DNS:localhost\n",
    )
    .map_err(|e| e.to_string())?;
    openssl(
        dir,
        &[
            "x509",
            "-req",
            "-in",
            "world.csr",
            "-CA",
            "ca.pem",
            "-CAkey",
            "ca-key.pem",
            "-CAcreateserial",
            "-days",
            "2",
            "-extfile",
            "world.ext",
            "-out",
            "world-cert.pem",
        ],
    )
}

#[test]
fn over_tls_a_run_goes_through_and_an_agent_that_does_not_trust_the_worlds_ca_is_refused() {
    const TEST: &str =
        "over_tls_a_run_goes_through_and_an_agent_that_does_not_trust_the_worlds_ca_is_refused";
    let dir = fresh_dir("ztls");
    if let Err(why) = test_certificates(&dir) {
        skip(
            TEST,
            "MRSIM_REQUIRE_OPENSSL",
            &format!("cannot make test certificates ({why})"),
        );
        return;
    }
    let file = dir.join("two.toml");
    std::fs::write(&file, TWO).expect("write");
    let tls = |fields: &str| format!("{{ transport: {{ link: {{ tls: {{ {fields} }} }} }} }}");
    let path = |name: &str| dir.join(name).display().to_string();
    let world_cfg = dir.join("world.json5");
    std::fs::write(
        &world_cfg,
        tls(&format!(
            "listen_certificate: \"{}\", listen_private_key: \"{}\"",
            path("world-cert.pem"),
            path("world-key.pem")
        )),
    )
    .expect("write");
    let agent_cfg = dir.join("agent.json5");
    std::fs::write(
        &agent_cfg,
        tls(&format!("root_ca_certificate: \"{}\"", path("ca.pem"))),
    )
    .expect("write");
    let stranger_cfg = dir.join("stranger.json5");
    std::fs::write(
        &stranger_cfg,
        tls(&format!(
            "root_ca_certificate: \"{}\"",
            path("stranger.pem")
        )),
    )
    .expect("write");
    let out = dir.join("out");
    let id = run_id("ztls");
    let port = free_endpoint()
        .rsplit_once(':')
        .map(|(_, p)| p.to_string())
        .expect("port");
    let ep = format!("tls/127.0.0.1:{port}");
    let cfg = world_cfg.display().to_string();
    let mut world = zenoh_world(
        &file,
        &out,
        &id,
        &ep,
        &["--mode", "lockstep", "--zenoh-config", &cfg],
    );
    // An agent that trusts another CA never gets a session; nor does one
    // that speaks plain TCP to the TLS port.
    let o = zenoh_agent("a", &id, &ep)
        .args(["--timeout", "3", "--zenoh-config"])
        .arg(&stranger_cfg)
        .output()
        .expect("stranger");
    assert!(!o.status.success(), "an agent trusting another CA joined");
    assert!(stderr_of(&o).contains("cannot set up"), "{}", stderr_of(&o));
    let plain = format!("tcp/127.0.0.1:{port}");
    let o = zenoh_agent("a", &id, &plain)
        .args(["--timeout", "3"])
        .output()
        .expect("plain tcp");
    assert!(!o.status.success(), "a plain TCP agent joined a TLS world");
    // Agents that trust the world's CA run the scenario to its end.
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
    assert!(
        ws.success(),
        "the TLS world failed: {}",
        child_stderr(&mut world)
    );
    for a in &mut agents {
        wait_timeout(a, 10);
    }
    let m = metrics(&out);
    assert_eq!(m["transport"], "zenoh");
    assert_eq!(m["success_rate"], 1.0, "{m:#}");
    assert_eq!(m["agents_lost"], 0, "{m:#}");
    for r in ["a", "b"] {
        assert_eq!(count_events(&out, "agent_joined", r), 1, "{r}");
    }
}

/// How many of process `pid`'s threads are of Zenoh's runtime `name`
/// (which names them `NAME-N`).
fn runtime_threads(pid: u32, name: &str) -> usize {
    let Ok(tasks) = std::fs::read_dir(format!("/proc/{pid}/task")) else {
        return 0;
    };
    let prefix = format!("{name}-");
    tasks
        .flatten()
        .filter_map(|t| std::fs::read_to_string(t.path().join("comm")).ok())
        .filter(|comm| comm.starts_with(&prefix))
        .count()
}

#[test]
fn the_world_accepts_on_its_receiving_threads_and_an_agent_reads_on_its_application_thread_unless_told_otherwise()
 {
    let dir = fresh_dir("zrt");
    let file = dir.join("row.toml");
    // Nobody arrives and the run outlasts the test, which ends it: every
    // process is there when its threads are counted.
    std::fs::write(&file, realtime_row(2, 700.0, 600.0)).expect("write");
    let out = dir.join("out");
    let id = run_id("zrt");
    let ep = free_endpoint();
    let mut world = mrsim()
        .arg("world")
        .arg(&file)
        .args([
            "--run",
            &id,
            "--start-timeout",
            "60",
            "--transport",
            "zenoh",
        ])
        .args(["--listen", &ep, "--out"])
        .arg(&out)
        .env_remove("ZENOH_RUNTIME")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("world");
    let spawn = |robot: &str, runtime: Option<&str>| {
        let mut c = zenoh_agent(robot, &id, &ep);
        match runtime {
            Some(r) => c.env("ZENOH_RUNTIME", r),
            None => c.env_remove("ZENOH_RUNTIME"),
        };
        c.stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("agent")
    };
    let mut a = spawn("r0", None);
    let mut b = spawn("r1", Some("(rx: (worker_threads: 2))"));
    for r in ["r0", "r1"] {
        wait_for_event(&out, 60, &format!("{r} joined"), |e| {
            e["type"] == "agent_joined" && e["robot"] == r
        });
    }
    // Every process has accepted or opened a link and read from it by
    // now: a runtime of its own for that would have its threads.
    let threads = |pid: u32| (runtime_threads(pid, "rx"), runtime_threads(pid, "acc"));
    let [w, a_threads, b_threads] = [world.id(), a.id(), b.id()].map(threads);
    for c in [&mut world, &mut a, &mut b] {
        let _ = c.kill();
        let _ = c.wait();
    }
    remove_leftovers(&id);
    assert!(w.0 > 0 && w.1 == 0, "the world's (rx, acc) threads: {w:?}");
    assert_eq!(a_threads, (0, 0), "an agent's (rx, acc) threads");
    assert!(
        b_threads.0 > 0,
        "an agent given ZENOH_RUNTIME keeps it: (rx, acc) threads {b_threads:?}"
    );
}
