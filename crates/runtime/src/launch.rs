//! A whole run (`mrsim run`): the world and one agent per robot, as
//! processes over iceoryx2 or in this process ([`crate::inproc`]), then
//! [`crate::finish`].
//!
//! [`prepare`] claims everything the run needs before anything starts (the
//! output folder, the run id's namespace, the scheduling, the termination
//! signals) so that a refusal comes before any process; [`Prepared::start`]
//! runs it. The processes are this same executable's `world` and `agent`
//! subcommands; a termination signal to the launcher is forwarded to the
//! world, which writes what it has and tells its agents the run is over.

use crate::error::{Invalid, Refusal};
use crate::finish::{AgentFailure, Ending, FinishError, Outcome, WorldFailure};
use crate::inproc::InprocError;
use crate::sched::{Applied, Sched};
use crate::usage::AgentUsage;
use crate::validate::{ScenarioSource, Validated};
use mrsim_transport::Namespace;
use mrsim_transport::zenoh::ZenohOptions;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// How often `--restart-agents` restarts one robot's agent at most.
pub const MAX_RESTARTS: u32 = 10;

/// The transport between the world and its agents.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Transport {
    /// iceoryx2 shared memory, one process per agent.
    #[default]
    Shm,
    /// crossbeam channels, the agents in a pool of threads of one process.
    Inproc,
    /// Zenoh over TCP, one process per agent (here on loopback; by hand,
    /// agents on other machines).
    Zenoh,
}

impl Transport {
    /// The name used on the command line and in metrics.json.
    pub fn name(self) -> &'static str {
        match self {
            Transport::Shm => "shm",
            Transport::Inproc => "inproc",
            Transport::Zenoh => "zenoh",
        }
    }
}

/// How to carry a run out, beyond its scenario.
#[derive(Debug, Clone, Default)]
pub struct RunRequest {
    /// The run id (iceoryx2 namespace); `None`: a fresh one.
    pub run_id: Option<String>,
    /// The output folder; `None`: a fresh folder under `runs/`.
    pub out: Option<PathBuf>,
    /// The transport between world and agents.
    pub transport: Transport,
    /// CPU affinity and SCHED_FIFO.
    pub sched: Sched,
    /// Draw plot.svg/png and replay.html at the end.
    pub render: bool,
    /// Restart an agent process that dies while the world runs (at most
    /// [`MAX_RESTARTS`] times per robot).
    pub restart_agents: bool,
    /// With [`Transport::Zenoh`]: where the world listens (`None`: a free
    /// loopback port) and the Zenoh config file, if any.
    pub zenoh: ZenohOptions,
    /// With [`Transport::Inproc`] in lockstep: the longest one robot's
    /// answer (observe, plan, send) may take before the run stops with
    /// [`RunError::Planner`] naming the robot and the tick, the outputs so
    /// far written. `None`: no limit (a planner that never returns holds
    /// the run).
    pub plan_timeout: Option<Duration>,
    /// Robots with planner `ros2`: how the ROS 2 agent reaches ROS 2.
    pub ros2: Ros2Side,
}

/// Where the ROS 2 agent (`mrsim ros2`) that `mrsim run` starts for the
/// robots with planner `ros2` finds the ROS 2 nodes.
#[derive(Debug, Clone, Default)]
pub struct Ros2Side {
    /// The Zenoh router of the ROS 2 side (`None`: tcp/localhost:7447).
    pub connect: Option<String>,
    /// The ROS domain id.
    pub domain: u32,
}

/// What happens while a run goes on, for a caller that shows it.
#[derive(Debug)]
pub enum Event<'a> {
    /// The launcher is waiting for its world (about every 20 ms): a moment
    /// to show progress.
    Waiting,
    /// The same for an in-process run, with an observer of its live
    /// statistics (a world process is observed over iceoryx2 instead).
    WaitingInproc(Observing<'a>),
    /// The world process has ended.
    WorldEnded,
    /// An agent process died and was started again.
    AgentRestarted {
        /// Its robot.
        robot: &'a str,
        /// The process that died.
        pid: u32,
        /// How it ended.
        how: String,
        /// This robot's restarts so far, this one included.
        restart: u32,
    },
}

/// An observer of a running in-process world.
pub struct Observing<'a>(pub &'a mut dyn mrsim_transport::ObserverTransport);

impl std::fmt::Debug for Observing<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Observing(..)")
    }
}

/// Why a run failed.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// Refused before anything started: the output folder, the run id, the
    /// CPU list.
    #[error(transparent)]
    Invalid(#[from] Invalid),
    /// The running executable (the world's and agents' program) is not
    /// known.
    #[error("cannot find the mrsim executable")]
    Exe(#[source] std::io::Error),
    /// The world process could not be started.
    #[error("cannot start the world process")]
    SpawnWorld(#[source] std::io::Error),
    /// An agent process could not be started.
    #[error("cannot start the agent process for {robot}")]
    SpawnAgent {
        /// Its robot.
        robot: String,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// Waiting for the world process failed.
    #[error("waiting for the world")]
    Wait(#[source] std::io::Error),
    /// The in-process run failed.
    #[error(transparent)]
    Inproc(#[from] InprocError),
    /// A robot's planner failed in an in-process lockstep run (panicked, or
    /// returned a non-finite command): the run stopped at that tick; the
    /// outputs so far are in `dir`.
    #[error("{failure}; the run stopped there, outputs so far are in {}", dir.display())]
    Planner {
        /// Which robot, which tick, how.
        failure: mrsim_agents::PlanFailure,
        /// The run folder.
        dir: PathBuf,
    },
    /// The run ended but could not be finished.
    #[error(transparent)]
    Finish(#[from] FinishError),
}

impl Refusal for RunError {
    fn refused(&self) -> Option<&Invalid> {
        match self {
            RunError::Invalid(i) => Some(i),
            _ => None,
        }
    }
}

/// A run ready to start: its folder, namespace and scheduling are claimed.
#[derive(Debug)]
pub struct Prepared {
    validated: Validated,
    request: RunRequest,
    dir: PathBuf,
    ns: Namespace,
    applied: Applied,
}

/// Claims what the run needs: the output folder (created, writable), the
/// run id's namespace (what a crashed earlier run left is cleared; a live
/// world's is refused), the scheduling of this process and its children,
/// and the termination signals (from now on they stop the run instead of
/// this process).
pub fn prepare(validated: Validated, request: RunRequest) -> Result<Prepared, RunError> {
    check_transport(&validated, request.transport)?;
    check_memory(&validated, request.transport)?;
    let dir = crate::out::prepare(request.out.as_deref(), &validated.scenario().name)?;
    write_source(&dir, validated.source())?;
    let run_id = request
        .run_id
        .clone()
        .unwrap_or_else(Namespace::fresh_run_id);
    let ns = Namespace::new(&run_id).map_err(|e| Invalid(e.to_string()))?;
    claim_namespace(&ns)?;
    let applied = crate::sched::apply(&request.sched)?;
    mrsim_sys::signal::catch_termination();
    let mut request = request;
    if request.transport == Transport::Zenoh && request.zenoh.endpoint.is_none() {
        // Chosen now, so that the launcher's own observer knows where to
        // look before the world is up.
        request.zenoh.endpoint = Some(free_loopback_endpoint()?);
    }
    Ok(Prepared {
        validated,
        request,
        dir,
        ns,
        applied,
    })
}

/// A run in this process, headless: what a program that brings its own
/// planners asks for ([`run_in_process`]).
#[derive(Debug, Clone, Default)]
pub struct InProcess {
    /// The scenario file and its overrides.
    pub scenario: ScenarioSource,
    /// The planners the robots' names are looked up in: the built-in ones
    /// and the program's own ([`mrsim_planners::Registry::register`]).
    pub registry: Arc<mrsim_planners::Registry>,
    /// The output folder; `None`: a fresh folder under `runs/`.
    pub out: Option<PathBuf>,
    /// Draw plot.svg/png and replay.html at the end.
    pub render: bool,
    /// In lockstep: the longest one robot's answer may take before the run
    /// stops with [`RunError::Planner`] ([`RunRequest::plan_timeout`]).
    pub plan_timeout: Option<Duration>,
}

/// What a finished in-process run gives back.
#[derive(Debug, Clone)]
pub struct RunResult {
    /// The run folder (trajectory.csv, events.jsonl, metrics.json, ...).
    pub dir: PathBuf,
    /// metrics.json, typed.
    pub metrics: mrsim_runfolder::RunMetrics,
    /// Agents that ended badly while the world ran to its end.
    pub agent_failures: Vec<AgentFailure>,
}

/// Runs a scenario in this process (the world in the calling thread, the
/// robots' planners in a pool of threads, as `--transport inproc`), its
/// robots' planners built from `req.registry`. Unlike `mrsim run` it takes
/// no termination signals over (the calling program keeps its own) and
/// claims no shared memory. A refusal ([`RunError::Invalid`]) comes before
/// anything ran; a planner that fails in lockstep stops the run
/// ([`RunError::Planner`], the outputs so far written).
pub fn run_in_process(req: &InProcess) -> Result<RunResult, RunError> {
    let validated = Validated::with_registry(req.scenario.clone(), req.registry.clone())?;
    run_validated_in_process(validated, req.out.clone(), req.render, req.plan_timeout)
}

/// [`run_in_process`] of a scenario already validated.
pub(crate) fn run_validated_in_process(
    validated: Validated,
    out: Option<PathBuf>,
    render: bool,
    plan_timeout: Option<Duration>,
) -> Result<RunResult, RunError> {
    let request = RunRequest {
        out,
        transport: Transport::Inproc,
        render,
        plan_timeout,
        ..Default::default()
    };
    check_transport(&validated, request.transport)?;
    check_memory(&validated, request.transport)?;
    let dir = crate::out::prepare(request.out.as_deref(), &validated.scenario().name)?;
    write_source(&dir, validated.source())?;
    let ns = Namespace::new(&Namespace::fresh_run_id()).map_err(|e| Invalid(e.to_string()))?;
    let prepared = Prepared {
        validated,
        request,
        dir,
        ns,
        applied: Applied::default(),
    };
    let outcome = prepared.run_inproc(&mut |_| {})?;
    let metrics = outcome.metrics.ok_or_else(|| {
        RunError::Finish(FinishError::ReadMetrics {
            path: outcome.dir.join(mrsim_runfolder::METRICS_FILE),
            source: std::io::Error::other("the run wrote no metrics"),
        })
    })?;
    Ok(RunResult {
        dir: outcome.dir,
        metrics,
        agent_failures: outcome.agent_failures,
    })
}

/// Writes the run folder's source.json: how `mrsim rerun` loads the
/// scenario again (the file made absolute).
fn write_source(dir: &Path, source: &crate::ScenarioSource) -> Result<(), Invalid> {
    let doc = mrsim_runfolder::SourceDoc {
        file: source
            .path
            .as_ref()
            .map(|p| std::fs::canonicalize(p).unwrap_or_else(|_| p.clone())),
        set: source.set.clone(),
        mode: source
            .mode
            .map(|m| crate::validate::mode_name(m).to_string()),
    };
    mrsim_runfolder::write_source(dir, &doc)
        .map_err(|e| Invalid(format!("cannot write the run folder: {e}")))
}

/// Refuses a transport the scenario's robots cannot run over: an
/// in-process run has no way in for an `external` robot's program, and an
/// agent process knows only the built-in planners, not a program's own.
fn check_transport(validated: &Validated, transport: Transport) -> Result<(), Invalid> {
    let (robots, why) = match transport {
        Transport::Inproc => (
            [validated.external_robots(), validated.ros2_robots()].concat(),
            "has planner = \"external\" or \"ros2\": its own program (or the ROS 2 agent) \
             joins the run over shared memory or Zenoh, which an in-process run (--transport \
             inproc) does not offer; run it without --transport inproc, or register the \
             program's planner for an in-process run",
        ),
        Transport::Shm | Transport::Zenoh => (
            validated.robots_with_own_planners(),
            "has a planner registered in this program only: agent processes know the \
             built-in planners alone; run it in-process",
        ),
    };
    if robots.is_empty() {
        return Ok(());
    }
    let quoted: Vec<String> = robots.iter().map(|r| format!("`{r}`")).collect();
    Err(Invalid(format!(
        "{}: robot {} {why}",
        validated.origin(),
        mrsim_world::names::first_few(&quoted, 5)
    )))
}

/// Refuses a run that would not fit in the memory available now
/// ([`crate::memory`]).
fn check_memory(validated: &Validated, transport: Transport) -> Result<(), Invalid> {
    crate::memory::check(
        validated.origin(),
        validated.scenario(),
        transport,
        mrsim_sys::memory::available_bytes(),
    )
}

/// Clears what a crashed earlier run with this id left behind, unless a
/// live world holds the run (then refuses: two worlds cannot share one).
pub(crate) fn claim_namespace(ns: &Namespace) -> Result<(), Invalid> {
    match mrsim_transport::shm::world_running(ns) {
        Ok(true) => Err(Invalid(format!(
            "run id `{}` is in use by a running world; choose another --run",
            ns.run_id()
        ))),
        _ => {
            ns.remove_leftovers();
            Ok(())
        }
    }
}

/// How a child process ended, in words.
pub fn describe(status: ExitStatus) -> String {
    use std::os::unix::process::ExitStatusExt;
    match (status.code(), status.signal()) {
        (Some(c), _) => format!("exited with status {c}"),
        (None, Some(s)) => format!("was killed by signal {s} ({})", mrsim_sys::signal::name(s)),
        _ => "ended".to_string(),
    }
}

impl Prepared {
    /// The scenario to run.
    pub fn validated(&self) -> &Validated {
        &self.validated
    }

    /// The run folder.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The run's namespace (where an observer finds its world).
    pub fn namespace(&self) -> &Namespace {
        &self.ns
    }

    /// Over Zenoh, how an observer on this machine reaches the world (as
    /// its agents do); `None` with another transport.
    pub fn zenoh_observer(&self) -> Option<ZenohOptions> {
        let opts = &self.request.zenoh;
        (self.request.transport == Transport::Zenoh).then(|| ZenohOptions {
            endpoint: opts.endpoint.as_deref().map(loopback_of),
            config_file: opts.config_file.clone(),
        })
    }

    /// What the scheduling request gave.
    pub fn applied(&self) -> &Applied {
        &self.applied
    }

    /// Runs to the end and finishes; `on_event` hears what happens on the
    /// way.
    pub fn start(self, on_event: &mut dyn FnMut(Event<'_>)) -> Result<Outcome, RunError> {
        match self.request.transport {
            Transport::Inproc => self.run_inproc(on_event),
            Transport::Shm | Transport::Zenoh => self.run_processes(on_event),
        }
    }

    fn run_inproc(self, on_event: &mut dyn FnMut(Event<'_>)) -> Result<Outcome, RunError> {
        let Prepared {
            validated,
            request,
            dir,
            ns,
            ..
        } = self;
        let registry = validated.registry().clone();
        let (scenario, world) = validated.into_world();
        let stop = Arc::new(AtomicBool::new(false));
        // A planner that fails in lockstep stops the run as a signal would.
        let halt = mrsim_agents::Halt::new(stop.clone());
        let mut agents = mrsim_agents::AgentOptions::new("");
        agents.registry = registry;
        agents.halt = Some(halt.clone());
        let done = Arc::new(AtomicBool::new(false));
        // A signal to the launcher stops the in-process run as SIGTERM stops
        // a world process.
        let watcher = {
            let (stop, done) = (stop.clone(), done.clone());
            std::thread::spawn(move || {
                while !done.load(Ordering::SeqCst) {
                    if mrsim_sys::signal::received().is_some() {
                        stop.store(true, Ordering::SeqCst);
                    }
                    std::thread::sleep(Duration::from_millis(20));
                }
            })
        };
        let outcome = crate::inproc::run_scenario(
            &scenario,
            world,
            &dir,
            ns.run_id(),
            stop,
            &agents,
            request.plan_timeout,
            &mut |obs| on_event(Event::WaitingInproc(Observing(obs))),
        );
        on_event(Event::WorldEnded);
        done.store(true, Ordering::SeqCst);
        let _ = watcher.join();
        let outcome = outcome?;
        let agent_failures = alike(
            scenario
                .robots
                .iter()
                .zip(&outcome.agent_errors)
                .filter_map(|(r, e)| Some((r.name.as_str(), format!("failed: {}", e.as_ref()?)))),
        );
        let finished = crate::finish::finish(Ending {
            dir: &dir,
            world_failure: None,
            agent_failures,
            usage: Some((Transport::Inproc.name(), &outcome.agent_usage)),
            render: request.render,
        })?;
        match halt.failure() {
            Some(failure) => Err(RunError::Planner { failure, dir }),
            None => Ok(finished),
        }
    }

    fn run_processes(self, on_event: &mut dyn FnMut(Event<'_>)) -> Result<Outcome, RunError> {
        let exe = std::env::current_exe().map_err(RunError::Exe)?;
        // The world runs in its own process: this one's copy goes.
        let (source, scenario) = self.validated.into_scenario();
        let (dir, run_id) = (&self.dir, self.ns.run_id());
        // Hundreds of agent processes starting on two cores take a while to
        // join: the world and each agent wait a minute plus a second per
        // robot.
        let join_secs = format!("{}", 60.0 + scenario.robots.len() as f64);
        let transport = self.request.transport;
        // Over Zenoh the world listens where asked (a free loopback port by
        // default) and the agents, on this machine, connect there.
        let (world_net, agent_net) = match transport {
            Transport::Zenoh => zenoh_args(&self.request.zenoh)?,
            _ => (Vec::new(), Vec::new()),
        };
        // An `external` robot's program is started by its user, whenever:
        // then the world waits for its agents without a limit (a signal
        // ends the wait).
        let external = scenario
            .robots
            .iter()
            .any(|r| r.planner == mrsim_planners::EXTERNAL);
        let start_timeout: &[&str] = if external {
            &[]
        } else {
            &["--start-timeout", &join_secs]
        };
        let mut world = Command::new(&exe)
            .arg("world")
            .args(source.to_args())
            .args(["--run", run_id])
            .args(start_timeout)
            .args(["--launched", "--out"])
            .arg(dir)
            .args(&world_net)
            .stdin(Stdio::null())
            .spawn()
            .map_err(RunError::SpawnWorld)?;
        // One process per group of `robots_per_agent` robots (the last
        // takes the rest), named after the group's first robot.
        // An `external` robot's agent is its user's program: none is started.
        let names: Vec<&str> = scenario
            .robots
            .iter()
            .filter(|r| r.planner != mrsim_planners::EXTERNAL && r.planner != mrsim_planners::ROS2)
            .map(|r| r.name.as_str())
            .collect();
        let k = (scenario.world.robots_per_agent as usize).max(1);
        let groups: Vec<&[&str]> = names.chunks(k).collect();
        let spawn = |group: &[&str]| -> Result<Child, RunError> {
            let first = group.first().copied().unwrap_or_default();
            let mut cmd = Command::new(&exe);
            cmd.arg("agent");
            if let [one] = group {
                cmd.args(["--robot", one]);
            } else {
                cmd.arg("--robots").arg(group.join(","));
            }
            cmd.args(["--run", run_id, "--usage-out"])
                .arg(usage_file(dir, first))
                .args(["--timeout", &join_secs])
                .args(&agent_net)
                .stdin(Stdio::null())
                .spawn()
                .map_err(|source| RunError::SpawnAgent {
                    robot: group_name(group),
                    source,
                })
        };
        let mut agents: Vec<(String, Child)> = Vec::with_capacity(groups.len());
        for g in &groups {
            agents.push((group_name(g), spawn(g)?));
        }
        // The robots with planner `ros2` share one ROS 2 agent (not
        // restarted: after `groups`, out of the restart loop's reach).
        let ros2: Vec<&str> = scenario
            .robots
            .iter()
            .filter(|r| r.planner == mrsim_planners::ROS2)
            .map(|r| r.name.as_str())
            .collect();
        let mut restarts = vec![0u32; agents.len()];
        if !ros2.is_empty() {
            // In lockstep the ROS 2 agent waits for a cmd_vel for less
            // than the world waits for it, so the world never loses it.
            let wait = (0.5 * scenario.world.stall_timeout).min(1.0);
            let mut cmd = Command::new(&exe);
            cmd.arg("ros2")
                .arg("--robots")
                .arg(ros2.join(","))
                .args(["--run", run_id, "--timeout", &join_secs])
                .args(["--domain", &self.request.ros2.domain.to_string()])
                .args(["--wait", &wait.to_string(), "--stats-out"])
                .arg(dir.join(crate::ros2::STATS_FILE));
            if let Some(c) = &self.request.ros2.connect {
                cmd.args(["--ros2-connect", c]);
            }
            if let Some(m) = &scenario.map {
                cmd.arg("--map").arg(&m.file);
            }
            let child = cmd
                .args(&agent_net)
                .stdin(Stdio::null())
                .spawn()
                .map_err(|source| RunError::SpawnAgent {
                    robot: group_name(&ros2),
                    source,
                })?;
            agents.push((format!("ros2 agent ({})", ros2.join(",")), child));
        }

        // Wait for the world; forward a signal to everything we started.
        let mut forwarded: Option<Instant> = None;
        let world_status = loop {
            if let Some(status) = world.try_wait().map_err(RunError::Wait)? {
                break status;
            }
            on_event(Event::Waiting);
            // Stop the world first: it writes what it has and tells the
            // agents the run is over, so they end by themselves (the ones
            // that do not are stopped below); a world that does not end in
            // 5 s is killed.
            if mrsim_sys::signal::received().is_some() && forwarded.is_none() {
                mrsim_sys::process::kill(world.id(), mrsim_sys::signal::SIGTERM);
                forwarded = Some(Instant::now());
            }
            if forwarded.is_some_and(|t| t.elapsed() > Duration::from_secs(5)) {
                mrsim_sys::process::kill(world.id(), mrsim_sys::signal::SIGKILL);
            }
            // One system call a round while no agent has ended (asking
            // each of hundreds would be as many, at the agents' priority).
            let ended = mrsim_sys::process::a_child_ended();
            for (((name, a), n), g) in agents.iter_mut().zip(restarts.iter_mut()).zip(&groups) {
                if !ended {
                    break;
                }
                let Ok(Some(status)) = a.try_wait() else {
                    continue;
                };
                if !self.request.restart_agents
                    || forwarded.is_some()
                    || status.success()
                    || *n >= MAX_RESTARTS
                {
                    continue;
                }
                *n += 1;
                on_event(Event::AgentRestarted {
                    robot: name,
                    pid: a.id(),
                    how: describe(status),
                    restart: *n,
                });
                // A group's robots rejoin together, in one new process.
                *a = spawn(g)?;
            }
            std::thread::sleep(Duration::from_millis(20));
        };
        on_event(Event::WorldEnded);

        let agent_failures = alike(
            reap_agents(&mut agents, world_status)
                .iter()
                .map(|f| (f.robot.as_str(), f.what.clone())),
        );
        self.ns.remove_leftovers();
        // 130: the world was interrupted and wrote what it had (metrics.json).
        let interrupted = world_status.code() == Some(130);
        let world_failure = (!world_status.success() && !interrupted).then(|| WorldFailure {
            pid: world.id(),
            how: describe(world_status),
        });
        // A group's process used what its robots used together: each
        // robot is given an equal share of its CPU time.
        let usage: Vec<AgentUsage> = groups
            .iter()
            .filter_map(|g| {
                let f = usage_file(dir, g.first()?);
                let u = crate::usage::read_agent(&f);
                let _ = std::fs::remove_file(&f);
                u.map(|u| (g.len(), u))
            })
            .flat_map(|(len, u)| {
                let share = AgentUsage {
                    cpu_s: u.cpu_s / len as f64,
                    ..u
                };
                std::iter::repeat_n(share, len)
            })
            .collect();
        Ok(crate::finish::finish(Ending {
            dir,
            world_failure,
            agent_failures,
            usage: Some((transport.name(), &usage)),
            render: self.request.render,
        })?)
    }
}

/// Agents end on the world's last snapshot: gives them a moment, then stops
/// them. Returns the ones that ended badly while the world did not.
fn reap_agents(agents: &mut [(String, Child)], world_status: ExitStatus) -> Vec<AgentFailure> {
    let grace = Instant::now();
    let mut failures = Vec::new();
    for (name, a) in agents.iter_mut() {
        let status = loop {
            if let Ok(Some(s)) = a.try_wait() {
                break s;
            }
            if grace.elapsed() > Duration::from_secs(3) {
                mrsim_sys::process::kill(a.id(), mrsim_sys::signal::SIGTERM);
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
            failures.push(AgentFailure {
                robot: name.clone(),
                what: describe(status),
            });
        }
    }
    failures
}

/// Failures of robots (or groups) that failed alike (every robot when the
/// world went, say) as one failure naming the first few: a run of 10,000
/// robots prints a line, not 10,000.
fn alike<'a>(failures: impl Iterator<Item = (&'a str, String)>) -> Vec<AgentFailure> {
    let mut alike: Vec<(String, Vec<&str>)> = Vec::new();
    let mut index = std::collections::HashMap::new();
    for (name, what) in failures {
        let k = *index.entry(what.clone()).or_insert_with(|| {
            alike.push((what, Vec::new()));
            alike.len() - 1
        });
        alike[k].1.push(name);
    }
    alike
        .into_iter()
        .map(|(what, names)| AgentFailure {
            robot: group_name(&names),
            what,
        })
        .collect()
}

/// A group's robots as messages name them: the first few and a count.
fn group_name(group: &[&str]) -> String {
    mrsim_world::names::first_few(group, 3)
}

/// Where the agent of `robot` (of the group it is first of) writes what
/// it used.
fn usage_file(dir: &Path, robot: &str) -> PathBuf {
    dir.join(mrsim_runfolder::agent_usage_file(robot))
}

/// A loopback endpoint on a port free a moment ago.
fn free_loopback_endpoint() -> Result<String, RunError> {
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .map_err(|e| Invalid(format!("cannot find a free loopback port for zenoh: {e}")))?
        .port();
    Ok(format!("tcp/127.0.0.1:{port}"))
}

/// Where a process on this machine connects to reach a world listening on
/// `listen` (loopback when it listens on every address).
fn loopback_of(listen: &str) -> String {
    listen
        .replace("0.0.0.0", "127.0.0.1")
        .replace("[::]", "[::1]")
}

/// The world's and the agents' extra arguments of a Zenoh run started
/// here: `--transport zenoh`, the world's `--listen` (a free loopback port
/// unless given) and the agents' `--connect` to the same place (loopback
/// when the world listens on every address), and the config file.
fn zenoh_args(opts: &ZenohOptions) -> Result<(Vec<String>, Vec<String>), RunError> {
    let listen = match &opts.endpoint {
        Some(e) => e.clone(),
        None => free_loopback_endpoint()?,
    };
    let connect = loopback_of(&listen);
    let mut world = vec![
        "--transport".into(),
        "zenoh".into(),
        "--listen".into(),
        listen,
    ];
    let mut agent = vec![
        "--transport".into(),
        "zenoh".into(),
        "--connect".into(),
        connect,
    ];
    if let Some(f) = &opts.config_file {
        for side in [&mut world, &mut agent] {
            side.push("--zenoh-config".into());
            side.push(f.to_string_lossy().into_owned());
        }
    }
    Ok((world, agent))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn robots_that_failed_alike_are_one_failure_naming_the_first_few() {
        let names: Vec<String> = (0..1000).map(|i| format!("g{i}")).collect();
        let failures = alike(
            names
                .iter()
                .map(|n| (n.as_str(), "failed: the world is gone".to_string()))
                .chain([("odd", "exited with status 1".to_string())]),
        );
        assert_eq!(failures.len(), 2);
        assert_eq!(
            failures[0].to_string(),
            "agent for g0, g1, g2 and 997 more failed: the world is gone"
        );
        assert_eq!(
            failures[1].to_string(),
            "agent for odd exited with status 1"
        );
    }
}
