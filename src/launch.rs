//! Starting runs: the launcher (`mrsim run`), the world and the agent.

use crate::cli::{ModeArg, ScenarioArgs};
use anyhow::{Context, Result, anyhow};
use mrsim_scenario::Loaded;
use mrsim_transport::shm::{ShmAgent, ShmWorld};
use mrsim_transport::{Capacity, Namespace};
use std::path::PathBuf;
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::atomic::Ordering;
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

pub(crate) fn invalid(msg: impl Into<String>) -> anyhow::Error {
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

/// The output folder: `out`, or a fresh folder under `runs/` named after
/// `name`; created and checked writable.
pub(crate) fn prepare_out(out: &Option<PathBuf>, name: &str) -> Result<PathBuf> {
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
            let base = PathBuf::from("runs");
            std::fs::create_dir_all(&base).map_err(|e| {
                invalid(format!(
                    "output folder {}: cannot create it: {e}",
                    base.display()
                ))
            })?;
            // create_dir fails if the folder exists: two launchers started in
            // the same second never share a folder.
            let mut n = 0;
            loop {
                let d = base.join(format!("{safe}-{secs}-{n}"));
                match std::fs::create_dir(&d) {
                    Ok(()) => break d,
                    Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists && n < 10_000 => n += 1,
                    Err(e) => {
                        return Err(invalid(format!(
                            "output folder {}: cannot create it: {e}",
                            d.display()
                        )));
                    }
                }
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

fn signal(child: &Child, sig: i32) {
    mrsim_sys::process::kill(child.id(), sig);
}

fn describe(status: ExitStatus) -> String {
    use std::os::unix::process::ExitStatusExt;
    match (status.code(), status.signal()) {
        (Some(c), _) => format!("exited with status {c}"),
        (None, Some(s)) => format!("was killed by signal {s} ({})", mrsim_sys::signal::name(s)),
        _ => "ended".to_string(),
    }
}

/// How often `mrsim run --restart-agents` restarts one robot's agent at most.
pub const MAX_RESTARTS: u32 = 10;

fn spawn_agent(
    exe: &std::path::Path,
    robot: &str,
    run_id: &str,
    usage: &std::path::Path,
    join_secs: &str,
) -> Result<Child> {
    Command::new(exe)
        .args(["agent", "--robot", robot, "--run", run_id, "--usage-out"])
        .arg(usage)
        .args(["--timeout", join_secs])
        .stdin(Stdio::null())
        .spawn()
        .with_context(|| format!("cannot start the agent process for {robot}"))
}

/// Clears what a crashed earlier run with this id left behind, unless a
/// live world holds the run (then refuses: two worlds cannot share one).
fn claim_namespace(ns: &Namespace) -> Result<()> {
    match mrsim_transport::shm::world_running(ns) {
        Ok(true) => Err(invalid(format!(
            "run id `{}` is in use by a running world; choose another --run",
            ns.run_id()
        ))),
        _ => {
            ns.remove_leftovers();
            Ok(())
        }
    }
}

/// How `mrsim run` carries the run out, beyond the scenario.
#[derive(Debug, Clone, Default)]
pub struct RunHow {
    /// The transport between world and agents.
    pub transport: Transport,
    /// `--cpus`, `--rt`.
    pub sched: crate::sched::SchedArgs,
    /// Skip plot.svg/png and replay.html (the bench does not need them).
    pub no_report: bool,
    /// Restart an agent process that dies while the world runs.
    pub restart_agents: bool,
}

/// The transport between the world and its agents.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Transport {
    /// iceoryx2 shared memory, one process per agent.
    #[default]
    Shm,
    /// crossbeam channels, one thread per agent in one process.
    Inproc,
}

impl Transport {
    /// The name used on the command line and in metrics.json.
    pub fn name(self) -> &'static str {
        match self {
            Transport::Shm => "shm",
            Transport::Inproc => "inproc",
        }
    }
}

/// `mrsim run`: the whole run.
pub fn run(args: &ScenarioArgs, run_id: Option<String>, quiet: bool, how: &RunHow) -> Result<i32> {
    let loaded = load(args)?;
    let scenario = &loaded.scenario;
    let dir = prepare_out(&args.out, &scenario.name)?;
    let run_id = run_id.unwrap_or_else(Namespace::fresh_run_id);
    let ns = Namespace::new(&run_id).map_err(|e| invalid(e.to_string()))?;
    claim_namespace(&ns)?;
    crate::sched::apply(&how.sched).map_err(invalid)?;
    mrsim_sys::signal::catch_termination();
    if how.transport == Transport::Inproc {
        return run_inproc(scenario, &dir, &run_id, quiet, how);
    }
    let exe = std::env::current_exe().context("cannot find the mrsim executable")?;

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
        agents.push((
            r.name.clone(),
            spawn_agent(
                &exe,
                &r.name,
                &run_id,
                &usage_file(&dir, &r.name),
                &join_secs,
            )?,
        ));
    }
    let mut restarts = vec![0u32; agents.len()];

    // Wait for the world; forward a signal to everything we started.
    let mut forwarded: Option<Instant> = None;
    let mut watch = crate::watch::RunWatch::new(&ns, scenario.max_ticks());
    let world_status = loop {
        if let Some(status) = world.try_wait().context("waiting for the world")? {
            break status;
        }
        watch.update();
        // Stop the world first: it writes what it has and tells the agents
        // the run is over, so they end by themselves (the ones that do not
        // are stopped below); a world that does not end in 5 s is killed.
        if mrsim_sys::signal::received().is_some() && forwarded.is_none() {
            signal(&world, mrsim_sys::signal::SIGTERM);
            forwarded = Some(Instant::now());
        }
        if forwarded.is_some_and(|t| t.elapsed() > Duration::from_secs(5)) {
            signal(&world, mrsim_sys::signal::SIGKILL);
        }
        for ((name, a), n) in agents.iter_mut().zip(restarts.iter_mut()) {
            let Ok(Some(status)) = a.try_wait() else {
                continue;
            };
            if !how.restart_agents || forwarded.is_some() || status.success() || *n >= MAX_RESTARTS
            {
                continue;
            }
            *n += 1;
            eprintln!(
                "launcher: the agent for {name} (pid {}) {}; restarting it ({} of at most {MAX_RESTARTS})",
                a.id(),
                describe(status),
                *n
            );
            *a = spawn_agent(&exe, name, &run_id, &usage_file(&dir, name), &join_secs)?;
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    watch.finish();

    // Agents end on the world's last snapshot; give them a moment, then stop them.
    let grace = Instant::now();
    let mut agent_failures = Vec::new();
    for (name, a) in agents.iter_mut() {
        let status = loop {
            if let Ok(Some(s)) = a.try_wait() {
                break s;
            }
            if grace.elapsed() > Duration::from_secs(3) {
                signal(a, mrsim_sys::signal::SIGTERM);
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
    // Every agent has ended: join their diagnostics into diagnostics.csv.
    merge_diagnostics(&dir);

    // 130: the world was interrupted and wrote what it had (metrics.json).
    let interrupted = world_status.code() == Some(130);
    if !world_status.success() && !interrupted {
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
    let usage: Vec<_> = scenario
        .robots
        .iter()
        .filter_map(|r| {
            let f = usage_file(&dir, &r.name);
            let u = crate::usage::AgentUsage::read(&f);
            let _ = std::fs::remove_file(&f);
            u
        })
        .collect();
    write_usage(&dir, "shm", &usage)?;
    finish(&dir, quiet, how)
}

fn usage_file(dir: &std::path::Path, robot: &str) -> PathBuf {
    dir.join(format!(".usage-{robot}.json"))
}

/// Writes usage.json: what the agents used while the run ticked.
fn write_usage(
    dir: &std::path::Path,
    transport: &str,
    usage: &[crate::usage::AgentUsage],
) -> Result<()> {
    let v = serde_json::json!({
        "transport": transport,
        "agents_reported": usage.len(),
        "agents_cpu_s": usage.iter().map(|u| u.cpu_s).sum::<f64>(),
        // In-process agents share the world's process: no RSS of their own.
        "agent_maxrss_kb": (transport == "shm").then(|| usage.iter().map(|u| u.maxrss_kb).max()).flatten(),
    });
    std::fs::write(dir.join("usage.json"), format!("{v:#}\n"))
        .with_context(|| format!("writing {}", dir.join("usage.json").display()))
}

fn run_inproc(
    scenario: &mrsim_scenario::Scenario,
    dir: &std::path::Path,
    run_id: &str,
    quiet: bool,
    how: &RunHow,
) -> Result<i32> {
    let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let watch = stop.clone();
    let done = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let done_w = done.clone();
    // A signal to the launcher stops the in-process run as SIGTERM stops a
    // world process.
    let watcher = std::thread::spawn(move || {
        while !done_w.load(Ordering::SeqCst) {
            if mrsim_sys::signal::received().is_some() {
                watch.store(true, Ordering::SeqCst);
            }
            std::thread::sleep(Duration::from_millis(20));
        }
    });
    let outcome = crate::inproc::run_scenario(scenario, dir, run_id, stop);
    done.store(true, Ordering::SeqCst);
    let _ = watcher.join();
    let outcome = outcome.map_err(|e| anyhow!("{e}"))?;
    for (r, e) in scenario.robots.iter().zip(&outcome.agent_errors) {
        if let Some(e) = e {
            eprintln!("note: agent for {} failed: {e} (see events.jsonl)", r.name);
        }
    }
    write_usage(dir, "inproc", &outcome.agent_usage)?;
    finish(dir, quiet, how)
}

/// Reads metrics.json, draws the plots, prints the summary.
fn finish(dir: &std::path::Path, quiet: bool, how: &RunHow) -> Result<i32> {
    let metrics = std::fs::read_to_string(dir.join("metrics.json"))
        .with_context(|| format!("reading {}", dir.join("metrics.json").display()))?;
    let metrics: serde_json::Value =
        serde_json::from_str(&metrics).context("parsing metrics.json")?;
    if !how.no_report
        && let Err(e) = mrsim_report::render_all(dir)
    {
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
    // Absolute: the setup tells agents where to write their diagnostics.
    let dir = std::fs::canonicalize(&dir).unwrap_or(dir);
    let ns = Namespace::new(run_id).map_err(|e| invalid(e.to_string()))?;
    if !launched {
        // A world started by hand owns its namespace: clear what a crashed
        // earlier world of the same run id left behind.
        claim_namespace(&ns)?;
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
        wait_for_agents(&outcome.metrics, Duration::from_secs(3));
        merge_diagnostics(&dir);
        if let Err(e) = mrsim_report::render_all(&dir) {
            eprintln!("warning: cannot draw the run's plots and replay: {e}");
        }
        let v = serde_json::to_value(&outcome.metrics).unwrap_or_default();
        print!("{}", crate::table::summary(&v));
        println!("run folder: {}", dir.display());
    }
    Ok(if outcome.metrics.interrupted { 130 } else { 0 })
}

/// Deliberate misbehaviour of an agent, for fault-injection tests.
#[derive(Debug, Clone, Copy, Default)]
pub struct Misbehave {
    /// Put this robot id in every command.
    pub impersonate: Option<u32>,
    /// Misbehave this way.
    pub fault: Option<mrsim_agents::fault::Fault>,
    /// Announce this protocol version.
    pub protocol_version: Option<u32>,
}

/// `mrsim agent`: one robot's agent process.
/// With `usage_out`, it writes what it used (CPU while the run ticked,
/// peak RSS) there at the end.
pub fn agent(
    robot: &str,
    run_id: &str,
    timeout: f64,
    bad: Misbehave,
    usage_out: Option<&std::path::Path>,
) -> Result<i32> {
    let ns = Namespace::new(run_id).map_err(|e| invalid(e.to_string()))?;
    let node_name = format!("mrsim-agent-{robot}");
    let mut link = ShmAgent::connect(&ns, &node_name, Duration::from_secs_f64(timeout))
        .with_context(|| format!("agent {robot}: cannot reach the world of run `{run_id}`"))?;
    let mut opts = mrsim_agents::AgentOptions::new(robot);
    opts.join_timeout = Duration::from_secs_f64(timeout);
    opts.impersonate = bad.impersonate;
    opts.fault = bad.fault;
    if let Some(v) = bad.protocol_version {
        opts.protocol_version = v;
    }
    let mut metered = crate::usage::Metered::new(&mut link, crate::usage::Scope::Process);
    let result = mrsim_agents::run(&mut metered, &opts);
    if let Some(path) = usage_out
        && let Err(e) = metered.usage().write(path)
    {
        eprintln!(
            "warning: agent {robot}: cannot write {}: {e}",
            path.display()
        );
    }
    match result {
        Ok(_) => Ok(0),
        Err(e) => Err(anyhow!("agent {robot}: {e}")),
    }
}

/// Joins the agents' diagnostics part files in `dir` into diagnostics.csv
/// (a warning, not a failure, if that cannot be done).
fn merge_diagnostics(dir: &std::path::Path) {
    match mrsim_agents::diagnostics::merge(dir) {
        Ok(s) if s.skipped > 0 => eprintln!(
            "note: diagnostics: {} unfinished or malformed lines left out",
            s.skipped
        ),
        Ok(_) => {}
        Err(e) => eprintln!(
            "warning: cannot merge the agents' diagnostics in {}: {e}",
            dir.display()
        ),
    }
}

/// Waits (at most `limit`) until the agent processes of a hand-started run
/// have ended, so that their diagnostics are complete.
fn wait_for_agents(metrics: &mrsim_world::metrics::RunMetrics, limit: Duration) {
    let start = Instant::now();
    let pids: Vec<u32> = metrics
        .robots
        .values()
        .filter_map(|r| r.agent_pid)
        .collect();
    while start.elapsed() < limit && pids.iter().any(|&p| mrsim_world::run::pid_alive(p)) {
        std::thread::sleep(Duration::from_millis(20));
    }
}
