//! Starting runs: the launcher (`mrsim run`), the world and the agent.

use crate::cli::{ModeArg, ScenarioArgs};
use anyhow::{Context, Result, anyhow};
use mrsim_scenario::Loaded;
use mrsim_transport::shm::{ShmAgent, ShmWorld};
use mrsim_transport::{Capacity, Namespace};
use std::path::PathBuf;
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::atomic::{AtomicI32, Ordering};
use std::time::{Duration, Instant};

/// A scenario or command line refused before anything started (exit 2).
#[derive(Debug)]
pub struct Invalid(pub String);

impl std::fmt::Display for Invalid {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for Invalid {}

fn invalid(msg: impl Into<String>) -> anyhow::Error {
    anyhow::Error::new(Invalid(msg.into()))
}

/// Loads and fully validates a scenario: the file, the overrides, every
/// robot's planner and parameters, and whether the world can run it.
pub fn load(args: &ScenarioArgs) -> Result<Loaded> {
    let mut overrides = Vec::new();
    for s in &args.set {
        let (k, v) = s
            .split_once('=')
            .ok_or_else(|| invalid(format!("--set {s}: expected KEY=VALUE")))?;
        let v = v.trim();
        // Bare words are strings: `--set planner=orca`.
        let looks_like_toml = v.parse::<f64>().is_ok()
            || v == "true"
            || v == "false"
            || v.starts_with(['[', '{', '"', '\'']);
        let v = if looks_like_toml {
            v.to_string()
        } else {
            format!("\"{v}\"")
        };
        overrides.push((k.trim().to_string(), v));
    }
    if let Some(mode) = args.mode {
        let m = match mode {
            ModeArg::Lockstep => "\"lockstep\"",
            ModeArg::Realtime => "\"realtime\"",
        };
        overrides.push(("world.mode".to_string(), m.to_string()));
    }
    let loaded = match &args.scenario {
        Some(path) => mrsim_scenario::load_with_overrides(path, &overrides),
        None if overrides.is_empty() => Ok(mrsim_scenario::demo()),
        None => {
            let demo = mrsim_scenario::demo();
            mrsim_scenario::parse_with_overrides(demo.source(), demo.origin(), &overrides)
        }
    }
    .map_err(|e| invalid(e.to_string()))?;
    for r in &loaded.scenario.robots {
        if let Err(e) = mrsim_agents::build_planner(r) {
            let key = match &e {
                mrsim_planners::BuildError::UnknownPlanner { .. } => {
                    format!("robot.{}.planner", r.name)
                }
                mrsim_planners::BuildError::Param(p) => {
                    format!("robot.{}.params.{}", r.name, p.key())
                }
            };
            return Err(invalid(loaded.error_at(&key, e.to_string()).to_string()));
        }
    }
    if let Err(e) = mrsim_world::World::new(&loaded.scenario) {
        let key = match &e {
            mrsim_world::WorldError::Motion { name, .. } => format!("obstacle.{name}.motion"),
        };
        return Err(invalid(loaded.error_at(&key, e.to_string()).to_string()));
    }
    Ok(loaded)
}

fn prepare_out(out: &Option<PathBuf>, name: &str) -> Result<PathBuf> {
    let dir = match out {
        Some(d) => d.clone(),
        None => {
            let secs = std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map(|d| d.as_secs())
                .unwrap_or(0);
            let safe: String = name
                .chars()
                .map(|c| {
                    if c.is_ascii_alphanumeric() || c == '-' {
                        c
                    } else {
                        '_'
                    }
                })
                .collect();
            let mut n = 0;
            loop {
                let d = PathBuf::from("runs").join(format!("{safe}-{secs}-{n}"));
                if !d.exists() {
                    break d;
                }
                n += 1;
            }
        }
    };
    std::fs::create_dir_all(&dir).map_err(|e| {
        invalid(format!(
            "output folder {}: cannot create it: {e}",
            dir.display()
        ))
    })?;
    let probe = dir.join(".mrsim-write-test");
    std::fs::write(&probe, b"ok").map_err(|e| {
        invalid(format!(
            "output folder {}: cannot write in it: {e}",
            dir.display()
        ))
    })?;
    let _ = std::fs::remove_file(&probe);
    Ok(dir)
}

static SIGNALLED: AtomicI32 = AtomicI32::new(0);

extern "C" fn on_signal(sig: libc::c_int) {
    SIGNALLED.store(sig, Ordering::SeqCst);
}

fn install_signal_handlers() {
    // SAFETY: the handler only stores into an atomic, which is
    // async-signal-safe.
    unsafe {
        libc::signal(libc::SIGINT, on_signal as *const () as libc::sighandler_t);
        libc::signal(libc::SIGTERM, on_signal as *const () as libc::sighandler_t);
    }
}

fn signal(child: &Child, sig: libc::c_int) {
    // SAFETY: sending a signal to a child we started.
    unsafe {
        libc::kill(child.id() as libc::pid_t, sig);
    }
}

fn describe(status: ExitStatus) -> String {
    use std::os::unix::process::ExitStatusExt;
    match (status.code(), status.signal()) {
        (Some(c), _) => format!("exited with status {c}"),
        (None, Some(s)) => format!("was killed by signal {s}"),
        _ => "ended".to_string(),
    }
}

/// `mrsim run`: the whole run.
pub fn run(args: &ScenarioArgs, run_id: Option<String>, quiet: bool) -> Result<i32> {
    let loaded = load(args)?;
    let scenario = &loaded.scenario;
    let dir = prepare_out(&args.out, &scenario.name)?;
    let run_id = run_id.unwrap_or_else(Namespace::fresh_run_id);
    let ns = Namespace::new(&run_id).map_err(|e| invalid(e.to_string()))?;
    let exe = std::env::current_exe().context("cannot find the mrsim executable")?;
    install_signal_handlers();

    let mut world_cmd = Command::new(&exe);
    world_cmd.arg("world");
    if let Some(s) = &args.scenario {
        world_cmd.arg(s);
    }
    for s in &args.set {
        world_cmd.arg("--set").arg(s);
    }
    if let Some(m) = args.mode {
        world_cmd.arg("--mode").arg(match m {
            ModeArg::Lockstep => "lockstep",
            ModeArg::Realtime => "realtime",
        });
    }
    // Hundreds of agent processes starting on two cores take a while to
    // join: the world and each agent wait a minute plus a second per
    // robot.
    let join_secs = format!("{}", 60.0 + scenario.robots.len() as f64);
    world_cmd
        .args([
            "--run",
            &run_id,
            "--start-timeout",
            &join_secs,
            "--launched",
            "--out",
        ])
        .arg(&dir)
        .stdin(Stdio::null());
    let mut world = world_cmd
        .spawn()
        .context("cannot start the world process")?;

    let mut agents: Vec<(String, Child)> = Vec::with_capacity(scenario.robots.len());
    for r in &scenario.robots {
        let child = Command::new(&exe)
            .args(["agent", "--robot", &r.name, "--run", &run_id])
            .args(["--timeout", &join_secs])
            .stdin(Stdio::null())
            .spawn()
            .with_context(|| format!("cannot start the agent process for {}", r.name))?;
        agents.push((r.name.clone(), child));
    }

    // Wait for the world; forward a signal to everything we started.
    let mut forwarded = false;
    let world_status = loop {
        if let Some(status) = world.try_wait().context("waiting for the world")? {
            break status;
        }
        let sig = SIGNALLED.load(Ordering::SeqCst);
        if sig != 0 && !forwarded {
            signal(&world, libc::SIGTERM);
            for (_, a) in &agents {
                signal(a, libc::SIGTERM);
            }
            forwarded = true;
        }
        for (_, a) in agents.iter_mut() {
            let _ = a.try_wait();
        }
        std::thread::sleep(Duration::from_millis(20));
    };

    // Agents end on the world's last snapshot; give them a moment, then stop them.
    let grace = Instant::now();
    let mut agent_failures = Vec::new();
    for (name, a) in agents.iter_mut() {
        let status = loop {
            if let Ok(Some(s)) = a.try_wait() {
                break s;
            }
            if grace.elapsed() > Duration::from_secs(3) {
                signal(a, libc::SIGTERM);
                std::thread::sleep(Duration::from_millis(100));
                if let Ok(Some(s)) = a.try_wait() {
                    break s;
                }
                let _ = a.kill();
                match a.wait() {
                    Ok(s) => break s,
                    Err(_) => break world_status,
                }
            }
            std::thread::sleep(Duration::from_millis(10));
        };
        if !status.success() && world_status.success() {
            agent_failures.push(format!("agent for {name} {}", describe(status)));
        }
    }
    let removed = ns.remove_leftovers();
    let _ = removed;

    if !world_status.success() {
        eprintln!(
            "error: the world process (pid {}) {}; outputs so far are in {}",
            world.id(),
            describe(world_status),
            dir.display()
        );
        return Ok(crate::cli::EXIT_FAILED);
    }
    for f in &agent_failures {
        eprintln!("note: {f} (see events.jsonl)");
    }
    let metrics = std::fs::read_to_string(dir.join("metrics.json"))
        .with_context(|| format!("reading {}", dir.join("metrics.json").display()))?;
    let metrics: serde_json::Value =
        serde_json::from_str(&metrics).context("parsing metrics.json")?;
    if let Err(e) = mrsim_report::render_all(&dir) {
        eprintln!("warning: cannot draw the run's plots and replay: {e}");
    }
    if !quiet {
        print!("{}", crate::table::summary(&metrics));
    }
    println!("run folder: {}", dir.display());
    if metrics["interrupted"].as_bool() == Some(true) {
        return Ok(130);
    }
    Ok(0)
}

/// `mrsim world`: the world process.
pub fn world(
    args: &ScenarioArgs,
    run_id: &str,
    start_timeout: Option<f64>,
    launched: bool,
) -> Result<i32> {
    let loaded = load(args)?;
    let scenario = loaded.scenario.clone();
    let dir = prepare_out(&args.out, &scenario.name)?;
    let ns = Namespace::new(run_id).map_err(|e| invalid(e.to_string()))?;
    if !launched {
        // A world started by hand owns its namespace: clear what a crashed
        // earlier world of the same run id left behind.
        ns.remove_leftovers();
    }
    let setup_len = serde_json::to_vec(&serde_json::json!({
        "run_id": run_id, "out_dir": dir, "scenario": scenario
    }))
    .map(|v| v.len())
    .unwrap_or(1 << 16);
    let bodies = scenario.robots.len() + scenario.obstacles.len();
    let mut link = ShmWorld::create(
        &ns,
        Capacity {
            robots: scenario.robots.len(),
        },
        bodies,
        setup_len,
    )
    .with_context(|| {
        format!("cannot create run `{run_id}` (is another world using this run id?)")
    })?;
    if !launched {
        eprintln!(
            "world: run `{run_id}`, {} robots; start each agent with\n  mrsim agent --run {run_id} --robot NAME\nfor NAME in: {}",
            scenario.robots.len(),
            scenario
                .robots
                .iter()
                .map(|r| r.name.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    let world = mrsim_world::World::new(&scenario).map_err(|e| invalid(e.to_string()))?;
    let opts = mrsim_world::RunOptions {
        out_dir: dir.clone(),
        run_id: run_id.to_string(),
        transport: "shm".to_string(),
        start_timeout: start_timeout.map(Duration::from_secs_f64),
        verbose: !launched || std::env::var_os("MRSIM_VERBOSE").is_some(),
    };
    let outcome = mrsim_world::run(world, &mut link, opts);
    drop(link);
    let outcome = outcome.map_err(|e| anyhow!("world: {e}"))?;
    if !launched {
        std::thread::sleep(Duration::from_millis(300));
        ns.remove_leftovers();
        if let Err(e) = mrsim_report::render_all(&dir) {
            eprintln!("warning: cannot draw the run's plots and replay: {e}");
        }
        let v = serde_json::to_value(&outcome.metrics).unwrap_or_default();
        print!("{}", crate::table::summary(&v));
        println!("run folder: {}", dir.display());
    }
    Ok(if outcome.metrics.interrupted { 130 } else { 0 })
}

/// `mrsim agent`: one robot's agent process.
pub fn agent(robot: &str, run_id: &str, timeout: f64, impersonate: Option<u32>) -> Result<i32> {
    let ns = Namespace::new(run_id).map_err(|e| invalid(e.to_string()))?;
    let node_name = format!("mrsim-agent-{robot}");
    let mut link = ShmAgent::connect(&ns, &node_name, Duration::from_secs_f64(timeout))
        .with_context(|| format!("agent {robot}: cannot reach the world of run `{run_id}`"))?;
    let mut opts = mrsim_agents::AgentOptions::new(robot);
    opts.join_timeout = Duration::from_secs_f64(timeout);
    opts.impersonate = impersonate;
    match mrsim_agents::run(&mut link, &opts) {
        Ok(_) => Ok(0),
        Err(e) => Err(anyhow!("agent {robot}: {e}")),
    }
}
