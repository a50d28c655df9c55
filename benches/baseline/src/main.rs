//! `mrsim-baseline`: the raw iceoryx2 baseline of `mrsim bench --baseline`,
//! a program of its own (not an `mrsim` command): the same fan-out
//! as a run (one world process publishing a tick over iceoryx2 and waking
//! every agent process with the run's doorbell, as a run does; each agent
//! answering over iceoryx2 and counting its answer on the doorbell, the
//! last answer waking the world, as in a run), with a
//! minimal payload (the tick number out, agent index and
//! tick back), agents that reply at once, and no mrsim protocol (no
//! snapshot, join, ownership, physics or recording). Its all-replies-in
//! time is the floor mrsim's own all-in time is compared against, and its
//! per-reply round trip (tick published -> that agent's reply taken in) the
//! floor of mrsim's round trip.

use anyhow::{Context, Result, anyhow};
use clap::{Args, Parser, Subcommand};
use iceoryx2::prelude::*;
use mrsim_proto::now_ns;
use mrsim_transport::Namespace;
use mrsim_transport::shm::doorbell::Doorbell;
use mrsim_world::metrics::DurationHistogram;
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

type S = ipc::Service;

/// Tick value that tells the agents to stop.
const STOP: u64 = u64::MAX;
/// Tick value of an agent's hello (sent until the world has seen it).
const HELLO: u64 = u64::MAX - 1;

/// The raw iceoryx2 fan-out baseline of `mrsim bench --baseline`.
#[derive(Debug, Parser)]
#[command(name = "mrsim-baseline", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Side,
}

#[derive(Debug, Subcommand)]
enum Side {
    /// The world side: starts the agents, ticks, writes the result.
    World(WorldArgs),
    /// The agent side (started by `world`).
    Agent(AgentArgs),
}

fn main() {
    let result = match Cli::parse().command {
        Side::World(args) => world(&args),
        Side::Agent(args) => agent(&args),
    };
    if let Err(e) = result {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}

/// `mrsim-baseline world`.
#[derive(Debug, Clone, Args)]
struct WorldArgs {
    /// Run id (iceoryx2 namespace).
    #[arg(long)]
    run: String,
    /// Number of agent processes to start.
    #[arg(long)]
    agents: usize,
    /// Ticks per second.
    #[arg(long, default_value_t = 100.0)]
    rate: f64,
    /// Seconds to tick.
    #[arg(long, default_value_t = 10.0)]
    duration: f64,
    /// Deadline as a fraction of the tick.
    #[arg(long, default_value_t = 1.0)]
    deadline: f64,
    /// Where to write the result (JSON).
    #[arg(long)]
    out: PathBuf,
}

/// `mrsim-baseline agent`.
#[derive(Debug, Clone, Args)]
struct AgentArgs {
    /// Run id of the baseline world.
    #[arg(long)]
    run: String,
    /// This agent's index.
    #[arg(long)]
    index: u64,
}

fn name(s: &str) -> Result<ServiceName> {
    ServiceName::new(s).map_err(|e| anyhow!("service name {s}: {e:?}"))
}

fn make_node(ns: &Namespace, node: &str) -> Result<Node<S>> {
    let cfg = mrsim_transport::shm::config(ns).map_err(|e| anyhow!("{e}"))?;
    NodeBuilder::new()
        .name(&NodeName::new(node).map_err(|e| anyhow!("node name {node}: {e:?}"))?)
        .config(&cfg)
        .create::<S>()
        .map_err(|e| anyhow!("node {node}: {e:?}"))
}

/// The world side: starts the agents, ticks, measures tick published -> last
/// reply in.
fn world(args: &WorldArgs) -> Result<()> {
    let positive = |x: f64| x.is_finite() && x > 0.0;
    if args.agents == 0 || !positive(args.rate) || !positive(args.duration) {
        return Err(anyhow!(
            "mrsim-baseline world: --agents, --rate and --duration must be positive"
        ));
    }
    let ns = Namespace::new(&args.run).map_err(|e| anyhow!("{e}"))?;
    ns.remove_leftovers();
    let result = world_inner(args, &ns);
    std::thread::sleep(Duration::from_millis(100));
    ns.remove_leftovers();
    result
}

fn world_inner(args: &WorldArgs, ns: &Namespace) -> Result<()> {
    let n = args.agents;
    let node = make_node(ns, "base-world")?;
    // Before the services: an agent that finds them finds the doorbell.
    let mut bell = Doorbell::create(ns).map_err(|e| anyhow!("{e}"))?;
    let nodes = n + 4;
    let tick_pub = node
        .service_builder(&name("base/tick")?)
        .publish_subscribe::<u64>()
        .subscriber_max_buffer_size(2)
        .max_publishers(1)
        .max_subscribers(n + 2)
        .max_nodes(nodes)
        .create()
        .map_err(|e| anyhow!("base/tick: {e:?}"))?
        .publisher_builder()
        .create()
        .map_err(|e| anyhow!("tick publisher: {e:?}"))?;
    let reply_sub = node
        .service_builder(&name("base/reply")?)
        .publish_subscribe::<[u64; 2]>()
        .subscriber_max_buffer_size(8)
        .max_publishers(n + 2)
        .max_subscribers(2)
        .max_nodes(nodes)
        .create()
        .map_err(|e| anyhow!("base/reply: {e:?}"))?
        .subscriber_builder()
        .create()
        .map_err(|e| anyhow!("reply subscriber: {e:?}"))?;
    let wake = node
        .service_builder(&name("base/wake")?)
        .event()
        .max_notifiers(n + 2)
        .max_listeners(2)
        .max_nodes(nodes)
        .create()
        .map_err(|e| anyhow!("base/wake: {e:?}"))?
        .listener_builder()
        .create()
        .map_err(|e| anyhow!("wake listener: {e:?}"))?;

    let exe = std::env::current_exe().context("cannot find the mrsim-baseline executable")?;
    let mut children: Vec<Child> = Vec::with_capacity(n);
    for i in 0..n {
        children.push(
            Command::new(&exe)
                .args(["agent", "--run", &args.run, "--index"])
                .arg(i.to_string())
                .stdin(Stdio::null())
                .spawn()
                .context("cannot start a baseline agent")?,
        );
    }
    let reap = |children: &mut Vec<Child>| {
        let start = Instant::now();
        for c in children.iter_mut() {
            loop {
                if let Ok(Some(_)) = c.try_wait() {
                    break;
                }
                if start.elapsed() > Duration::from_secs(3) {
                    let _ = c.kill();
                    let _ = c.wait();
                    break;
                }
                std::thread::sleep(Duration::from_millis(5));
            }
        }
    };

    // Wait for every agent's hello.
    let mut seen = vec![false; n];
    let mut joined = 0;
    let start = Instant::now();
    while joined < n {
        if start.elapsed() > Duration::from_secs(60) {
            let _ = tick_pub.send_copy(STOP);
            let _ = bell.ring();
            reap(&mut children);
            return Err(anyhow!(
                "baseline: only {joined} of {n} agents connected within 60 s"
            ));
        }
        let _ = wake.timed_wait(|_| {}, Duration::from_millis(20));
        while let Ok(Some(s)) = reply_sub.receive() {
            let [i, t] = *s.payload();
            if t == HELLO && (i as usize) < n && !seen[i as usize] {
                seen[i as usize] = true;
                joined += 1;
            }
        }
    }
    // Tell them they were seen (tick 0 is the first real one; the hello
    // loop stops on any tick).
    let period = Duration::from_secs_f64(1.0 / args.rate);
    let deadline = period.mul_f64(args.deadline.clamp(0.01, 1.0));
    let ticks = (args.duration * args.rate).round().max(1.0) as u64;
    let mut allin = DurationHistogram::default();
    let mut roundtrip = DurationHistogram::default();
    let mut misses = 0u64;
    let mut got = vec![u64::MAX; n];
    // As mrsim's world: under --rt, one level below its agents while it
    // ticks.
    let below = mrsim_sys::sched::BelowAgents::enter();
    let t0 = Instant::now() + Duration::from_millis(50);
    for tick in 0..ticks {
        let at = t0 + period.mul_f64(tick as f64);
        while Instant::now() < at {
            wait_until(&wake, at);
            while let Ok(Some(_)) = reply_sub.receive() {}
        }
        bell.expect(tick, n);
        let published = now_ns();
        let pub_at = Instant::now();
        tick_pub
            .send_copy(tick)
            .map_err(|e| anyhow!("send tick: {e:?}"))?;
        bell.ring().map_err(|e| anyhow!("{e}"))?;
        let mut answered = 0;
        let mut last_in = published;
        loop {
            while let Ok(Some(s)) = reply_sub.receive() {
                let [i, t] = *s.payload();
                if t == tick && (i as usize) < n && got[i as usize] != tick {
                    got[i as usize] = tick;
                    answered += 1;
                    last_in = now_ns();
                    roundtrip.record_ns(last_in.saturating_sub(published));
                }
            }
            if answered == n {
                allin.record_ns(last_in.saturating_sub(published));
                break;
            }
            if pub_at.elapsed() >= deadline {
                misses += (n - answered) as u64;
                break;
            }
            let left = (pub_at + deadline).saturating_duration_since(Instant::now());
            bell.wait_answers(left).map_err(|e| anyhow!("{e}"))?;
        }
    }
    drop(below);
    for _ in 0..2 {
        let _ = tick_pub.send_copy(STOP);
        let _ = bell.ring();
    }
    reap(&mut children);
    let p = allin.percentiles();
    let v = serde_json::json!({
        "agents": n, "rate_hz": args.rate, "ticks": ticks,
        "allin_us": p, "roundtrip_us": roundtrip.percentiles(),
        "miss_rate": misses as f64 / (ticks as f64 * n as f64),
    });
    std::fs::write(&args.out, format!("{v:#}\n"))
        .with_context(|| format!("writing {}", args.out.display()))?;
    Ok(())
}

/// Waits for the next tick's time: on the listener (only hellos notify
/// it) while far from `until`, since its socket timeout is rounded up to
/// whole jiffies, and in short sleeps in the last few milliseconds.
fn wait_until(listener: &iceoryx2::port::listener::Listener<S>, until: Instant) {
    let left = until.saturating_duration_since(Instant::now());
    // At least a millisecond: a socket timeout below a microsecond reads as
    // zero, which means "wait forever".
    if left >= Duration::from_millis(10) {
        let _ = listener.timed_wait(
            |_| {},
            (left - Duration::from_millis(9)).min(Duration::from_millis(20)),
        );
    } else {
        std::thread::sleep(left.min(Duration::from_micros(200)));
    }
}

/// The agent side: answers every tick at once.
fn agent(args: &AgentArgs) -> Result<()> {
    let ns = Namespace::new(&args.run).map_err(|e| anyhow!("{e}"))?;
    let node = make_node(&ns, &format!("base-agent-{}", args.index))?;
    let tick_sub = node
        .service_builder(&name("base/tick")?)
        .publish_subscribe::<u64>()
        .open()
        .map_err(|e| anyhow!("base/tick: {e:?}"))?
        .subscriber_builder()
        .create()
        .map_err(|e| anyhow!("tick subscriber: {e:?}"))?;
    let reply_pub = node
        .service_builder(&name("base/reply")?)
        .publish_subscribe::<[u64; 2]>()
        .open()
        .map_err(|e| anyhow!("base/reply: {e:?}"))?
        .publisher_builder()
        .create()
        .map_err(|e| anyhow!("reply publisher: {e:?}"))?;
    let wake = node
        .service_builder(&name("base/wake")?)
        .event()
        .open()
        .map_err(|e| anyhow!("base/wake: {e:?}"))?
        .notifier_builder()
        .create()
        .map_err(|e| anyhow!("wake notifier: {e:?}"))?;
    // The world creates the doorbell before its services: found them, found it.
    let mut bell = Doorbell::open(&ns).map_err(|e| anyhow!("{e}"))?;
    let mut started = false;
    let mut last_heard = Instant::now();
    let mut last_hello: Option<Instant> = None;
    loop {
        if !started && last_hello.is_none_or(|t| t.elapsed() > Duration::from_millis(200)) {
            let _ = reply_pub.send_copy([args.index, HELLO]);
            let _ = wake.notify();
            last_hello = Some(Instant::now());
        }
        bell.wait(Duration::from_millis(100))
            .map_err(|e| anyhow!("{e}"))?;
        let mut latest = None;
        while let Ok(Some(s)) = tick_sub.receive() {
            latest = Some(*s.payload());
        }
        match latest {
            Some(STOP) => return Ok(()),
            Some(t) => {
                started = true;
                last_heard = Instant::now();
                reply_pub
                    .send_copy([args.index, t])
                    .map_err(|e| anyhow!("send reply: {e:?}"))?;
                bell.answered(t).map_err(|e| anyhow!("{e}"))?;
            }
            None if last_heard.elapsed() > Duration::from_secs(70) => {
                return Err(anyhow!(
                    "baseline agent {}: the world is silent",
                    args.index
                ));
            }
            None => {}
        }
    }
}
