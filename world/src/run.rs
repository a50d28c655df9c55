//! The tick loop: join, then each tick publish, collect, step, record.
//!
//! Lockstep waits for every live agent's command (or `stall_timeout`, after
//! which the agent is lost); realtime ticks on the wall clock and counts a
//! command that is not in by the deadline as a miss, after which the robot
//! holds its last command or brakes. Agents are identified by the token the
//! world hands out at join time: a command without the robot's current
//! token, for another tick, with non-finite values, or a second one in a
//! tick, is rejected, counted and logged, and never drives a robot.

use crate::live::LiveStats;
use crate::metrics::{
    DurationHistogram, RobotAccumulator, RobotMetrics, RunMetrics, TimingMetrics,
};
use crate::physics::{Applied, Contact, Owner, World};
use crate::record::Recorder;
use crate::timings::TimingRecorder;
use crate::tracking::Tracker;
use mrsim_proto::{
    CommandMsg, FixedStr, JoinReply, JoinRequest, PROTOCOL_VERSION, SnapshotHeader, StatsHeader,
    agent_state, command_kind, flags, now_ns, run_phase,
};
use mrsim_runfolder::{FileError, METRICS_FILE, SCENARIO_FILE, TRAJECTORY_FILE};
use mrsim_scenario::{MissPolicy, Mode};
use mrsim_sys::sched::BelowAgents;
use mrsim_sys::usage::{CpusTime, process_usage, thread_usage};
use mrsim_transport::{TransportError, WorldTransport};
use serde_json::json;
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// How a run is carried out.
#[derive(Debug, Clone)]
pub struct RunOptions {
    /// Folder for the outputs (must exist).
    pub out_dir: PathBuf,
    /// The run id, written into metrics.json.
    pub run_id: String,
    /// Transport name for metrics.json (`shm` or `inproc`).
    pub transport: String,
    /// How long to wait for every agent to join; None = forever.
    pub start_timeout: Option<Duration>,
    /// Print progress lines (joins, losses) to stderr.
    pub verbose: bool,
}

/// What a finished run returns.
#[derive(Debug, Clone)]
pub struct RunOutcome {
    /// Everything written to metrics.json.
    pub metrics: RunMetrics,
}

/// Why a run could not be carried out.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The transport failed.
    #[error(transparent)]
    Transport(#[from] TransportError),
    /// An output could not be written.
    #[error("cannot write {what} in {dir}: {source}")]
    Output {
        /// Which file.
        what: &'static str,
        /// The output folder.
        dir: String,
        /// The I/O error.
        source: std::io::Error,
    },
    /// Not every agent joined in time.
    #[error("agents for {missing} did not join within {secs:.0} s")]
    StartTimeout {
        /// The first few robot names, comma-separated, and how many more.
        missing: String,
        /// The timeout.
        secs: f64,
    },
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Agent {
    Waiting,
    Live { pid: u32, token: u64 },
    Lost { pid: u32, token: u64 },
}

pub use mrsim_sys::process::pid_alive;

fn splitmix(mut x: u64) -> u64 {
    x = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    x = (x ^ (x >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    x ^ (x >> 31)
}

struct Loop<'a> {
    world: World,
    link: &'a mut dyn WorldTransport,
    rec: Recorder,
    opts: RunOptions,
    names: Vec<String>,
    agents: Vec<Agent>,
    acc: Vec<RobotAccumulator>,
    got: Vec<Option<CommandMsg>>,
    garbage: Vec<bool>,
    collisions_total: u64,
    agents_lost: u64,
    rejected: u64,
    rejected_unknown: u64,
    late: u64,
    tick: u64,
    published_ns: u64,
    /// The current tick's deadline (realtime; `u64::MAX` in lockstep). A
    /// command sent after it is late even if the world, itself late (a
    /// stall of the host, or agents of higher priority running), takes it
    /// in before it stops waiting for the tick.
    deadline_ns: u64,
    /// Latest receive time of a command accepted this tick.
    last_in_ns: u64,
    /// Every command's round trip, wake-up and compute, on their way to
    /// the histograms of their own thread.
    timings: TimingRecorder,
    /// Commands taken from the transport, reused from drain to drain.
    inbox: Vec<(CommandMsg, u64)>,
    last_pid_check: Instant,
    pid_checks: u64,
    /// Agents that have said they are ready (setup read, planner built).
    ready: Vec<bool>,
    live: LiveStats,
    clock_start: Option<Instant>,
}

impl Loop<'_> {
    fn time(&self) -> f64 {
        self.world.time()
    }

    fn event(&self, mut v: serde_json::Value) {
        if let Some(o) = v.as_object_mut() {
            o.insert("tick".into(), json!(self.tick));
            o.insert("time".into(), json!(self.time()));
        }
        self.rec.event(v);
    }

    fn log(&self, msg: &str) {
        if self.opts.verbose {
            eprintln!("world: {msg}");
        }
    }

    fn handle_join(&mut self, req: JoinRequest) -> Result<(), TransportError> {
        let name = req.robot.as_str().to_string();
        let refuse = |reason: String| JoinReply {
            nonce: req.nonce,
            accepted: 0,
            robot_id: u32::MAX,
            token: 0,
            protocol_version: PROTOCOL_VERSION,
            world_pid: std::process::id(),
            reason: FixedStr::new(&reason),
        };
        let accept = |i: usize, token: u64| JoinReply {
            nonce: req.nonce,
            accepted: 1,
            robot_id: i as u32,
            token,
            protocol_version: PROTOCOL_VERSION,
            world_pid: std::process::id(),
            reason: FixedStr::default(),
        };
        let idx = self.world.scenario.robot_index(&name);
        let reply = if req.protocol_version != PROTOCOL_VERSION {
            refuse(format!(
                "protocol version {} refused: this world speaks version {PROTOCOL_VERSION}",
                req.protocol_version
            ))
        } else if let Some(i) = idx {
            match self.agents[i] {
                Agent::Live { pid, .. } if pid != req.pid && pid_alive(pid) => {
                    refuse(format!("robot `{name}` is already driven by process {pid}"))
                }
                // The same process asking again (its first reply was slow
                // and it re-asked): the same answer, not a second token the
                // agent would never see.
                Agent::Live { pid, token } if pid == req.pid => accept(i, token),
                previous => {
                    // A new process for a robot whose agent died before the
                    // periodic liveness check noticed: record the loss first,
                    // so the events read lost, then rejoined.
                    let previous = match previous {
                        Agent::Live { pid, .. } => {
                            self.lose(i, format!("agent process {pid} died"));
                            self.link.cleanup_dead();
                            self.agents[i]
                        }
                        other => other,
                    };
                    let token =
                        splitmix(now_ns() ^ ((req.pid as u64) << 32) ^ i as u64 ^ req.nonce) | 1;
                    self.agents[i] = Agent::Live {
                        pid: req.pid,
                        token,
                    };
                    self.acc[i].agent_pid = Some(req.pid);
                    let flags = self.world.states()[i].flags & !flags::LOST;
                    self.world.set_flags(i, flags);
                    if matches!(previous, Agent::Lost { .. }) {
                        self.event(
                            json!({"type": "agent_rejoined", "robot": name, "pid": req.pid}),
                        );
                        self.log(&format!("agent for {name} rejoined (pid {})", req.pid));
                    } else {
                        self.event(json!({"type": "agent_joined", "robot": name, "pid": req.pid}));
                        self.log(&format!("agent for {name} joined (pid {})", req.pid));
                    }
                    accept(i, token)
                }
            }
        } else {
            let known: Vec<&str> = self
                .names
                .iter()
                .take(self.agents.len())
                .map(String::as_str)
                .collect();
            let list = if known.len() > 12 {
                format!("{}, ... ({} robots)", known[..12].join(", "), known.len())
            } else {
                known.join(", ")
            };
            refuse(format!(
                "no robot named `{name}` in this run (robots: {list})"
            ))
        };
        if reply.accepted == 0 {
            self.event(
                json!({"type": "join_refused", "robot": name, "pid": req.pid,
                              "reason": reply.reason.as_str()}),
            );
            self.log(&format!("refused a join: {}", reply.reason.as_str()));
        }
        self.link.reply_join(&reply)
    }

    fn reject(&mut self, cmd: &CommandMsg, reason: &str) {
        self.rejected += 1;
        let robot = match self.names.get(cmd.robot_id as usize) {
            Some(n) if (cmd.robot_id as usize) < self.agents.len() => {
                self.acc[cmd.robot_id as usize].rejected += 1;
                n.clone()
            }
            _ => {
                self.rejected_unknown += 1;
                format!("#{}", cmd.robot_id)
            }
        };
        self.event(
            json!({"type": "command_rejected", "robot": robot, "reason": reason,
                          "for_tick": cmd.tick}),
        );
    }

    fn handle_command(&mut self, cmd: CommandMsg, received_ns: u64, realtime: bool) {
        let i = cmd.robot_id as usize;
        if i >= self.agents.len() {
            return self.reject(&cmd, "no robot with this id");
        }
        let (owner_ok, was_lost, pid) = match self.agents[i] {
            Agent::Live { token, pid } => (token == cmd.token, false, pid),
            Agent::Lost { token, pid } => (token == cmd.token, true, pid),
            Agent::Waiting => (false, false, 0),
        };
        if !owner_ok {
            return self.reject(&cmd, "not sent by the agent that owns this robot");
        }
        if cmd.kind == command_kind::READY {
            self.ready[i] = true;
            return;
        }
        if cmd.tick > self.tick {
            return self.reject(&cmd, "command for a future tick");
        }
        if cmd.tick < self.tick {
            if realtime && cmd.tick + 1 == self.tick {
                // Answered the previous tick after its deadline: already a miss.
                self.late += 1;
                self.acc[i].late += 1;
                return;
            }
            return self.reject(&cmd, "command for a past tick");
        }
        if cmd.sent_ns < self.published_ns {
            // Named this tick before the tick existed: a guess, not an answer.
            return self.reject(
                &cmd,
                "command for a future tick (sent before it was published)",
            );
        }
        if self.got[i].is_some() {
            return self.reject(&cmd, "second command in one tick");
        }
        if cmd.sent_ns > self.deadline_ns {
            // Sent after this tick's deadline: a miss, however soon the
            // world looked.
            self.late += 1;
            self.acc[i].late += 1;
            return;
        }
        if cmd.kind != command_kind::FORCE && cmd.kind != command_kind::VELOCITY {
            self.garbage[i] = true;
            return self.reject(&cmd, "unknown command kind");
        }
        if !cmd.value.iter().all(|v| v.is_finite()) {
            self.garbage[i] = true;
            return self.reject(&cmd, "non-finite command value (robot brakes)");
        }
        if was_lost {
            self.agents[i] = Agent::Live {
                pid,
                token: cmd.token,
            };
            let flags = self.world.states()[i].flags & !flags::LOST;
            self.world.set_flags(i, flags);
            let name = self.names[i].clone();
            self.event(json!({"type": "agent_rejoined", "robot": name, "pid": pid}));
            self.log(&format!("agent for {name} answered again and rejoined"));
        }
        self.timings.record(
            i,
            received_ns.saturating_sub(self.published_ns),
            cmd.woke_ns.saturating_sub(self.published_ns),
            cmd.compute_ns,
        );
        self.got[i] = Some(cmd);
        self.last_in_ns = self.last_in_ns.max(received_ns);
    }

    fn lose(&mut self, i: usize, reason: String) {
        if let Agent::Live { pid, token } = self.agents[i] {
            self.agents[i] = Agent::Lost { pid, token };
            self.agents_lost += 1;
            self.acc[i].lost += 1;
            self.world.set_command(i, Applied::BRAKE);
            let flags = self.world.states()[i].flags | flags::LOST;
            self.world.set_flags(i, flags);
            let name = self.names[i].clone();
            self.log(&format!("lost the agent for {name}: {reason}"));
            self.event(json!({"type": "agent_lost", "robot": name, "pid": pid, "reason": reason}));
        }
    }

    fn check_pids(&mut self) {
        if self.last_pid_check.elapsed() < Duration::from_millis(100) {
            return;
        }
        self.last_pid_check = Instant::now();
        // Every 100 ms whether each agent's process exists (one syscall);
        // every second also whether it is a zombie its parent has not
        // reaped yet (a /proc read, five syscalls: at 256 agents and more,
        // doing that every time cost the world 5 % of a core).
        self.pid_checks += 1;
        let alive = if self.pid_checks.is_multiple_of(10) {
            pid_alive
        } else {
            mrsim_sys::process::pid_exists
        };
        // An agent in the world's own process (the in-process transport)
        // cannot die on its own: its thread's failure comes through the
        // transport. Reading /proc/self for each of them would walk every
        // thread of this process (1000 reads of a 1000-thread process: 8 %
        // of the world's time at 1000 robots).
        let own = std::process::id();
        let mut died = false;
        for i in 0..self.agents.len() {
            if let Agent::Live { pid, .. } = self.agents[i]
                && pid != own
                && !alive(pid)
            {
                self.lose(i, format!("agent process {pid} died"));
                died = true;
            }
        }
        if died {
            self.link.cleanup_dead();
        }
    }

    fn drain(&mut self, realtime: bool) -> Result<(), TransportError> {
        let mut joins = Vec::new();
        self.link.drain_joins(&mut |j| joins.push(j))?;
        let any = !joins.is_empty();
        for j in joins {
            self.handle_join(j)?;
        }
        if any {
            self.link.joins_answered()?;
        }
        self.drain_commands(realtime)
    }

    /// Takes in every command received so far.
    fn drain_commands(&mut self, realtime: bool) -> Result<(), TransportError> {
        let mut inbox = std::mem::take(&mut self.inbox);
        inbox.clear();
        let drained = self.link.drain_commands(&mut |c, t| inbox.push((c, t)));
        if drained.is_ok() {
            for (c, t) in inbox.drain(..) {
                self.handle_command(c, t, realtime);
            }
        }
        self.inbox = inbox;
        drained
    }

    /// One round of waiting before the clock starts: joins and ready
    /// commands taken in, pids checked, and the live statistics published
    /// (which also lets go of the join-time connections of agents that
    /// closed theirs: the world's peak RSS at 1000 robots).
    fn before_start(&mut self, wait: Duration) -> Result<(), TransportError> {
        self.link.wait(wait)?;
        self.drain(false)?;
        // Commands before the first tick are from nobody we know yet.
        self.got.iter_mut().for_each(|g| *g = None);
        self.check_pids();
        self.publish_stats(run_phase::JOINING, false);
        Ok(())
    }

    /// Every live agent has said it is ready.
    fn all_ready(&self) -> bool {
        self.agents
            .iter()
            .zip(&self.ready)
            .all(|(a, r)| !matches!(a, Agent::Live { .. }) || *r)
    }

    /// Every live agent has answered this tick: with a valid command, or
    /// with garbage (rejected; the robot brakes and the world moves on
    /// rather than waiting `stall_timeout` for an answer that came).
    fn all_answered(&self) -> bool {
        self.agents
            .iter()
            .zip(self.got.iter().zip(&self.garbage))
            .all(|(a, (g, bad))| !matches!(a, Agent::Live { .. }) || g.is_some() || *bad)
    }

    fn record_contacts(&mut self, contacts: &[Contact]) {
        for c in contacts {
            if !matches!(c.a, Owner::Robot(_)) && !matches!(c.b, Owner::Robot(_)) {
                continue;
            }
            self.collisions_total += 1;
            for o in [c.a, c.b] {
                if let Owner::Robot(i) = o {
                    self.acc[i].collisions += 1;
                    self.acc[i].min_contact_gap = self.acc[i].min_contact_gap.min(c.gap);
                }
            }
            let n = self.agents.len();
            let name = |o: Owner| match o {
                Owner::Robot(i) => self.names[i].clone(),
                Owner::Obstacle(k) => self.names[n + k].clone(),
                Owner::Wall(w) => format!("wall{w}"),
            };
            self.event(json!({"type": "collision", "a": name(c.a), "b": name(c.b),
                              "x": c.at[0], "y": c.at[1], "gap": c.gap}));
        }
    }

    /// The goal test after a step. The other metrics of the robots' motion
    /// come from the recorded states, off this loop ([`crate::tracking`]).
    fn update_goals(&mut self) {
        let time = self.time();
        let mut reached = Vec::new();
        let robots = self.world.states().iter().zip(&self.world.scenario.robots);
        for (i, ((s, spec), acc)) in robots.zip(&mut self.acc).enumerate() {
            // Goal test (Ko & Choi eq 22): within tolerance N ticks running.
            let d = (spec.goal[0] - s.position[0]).hypot(spec.goal[1] - s.position[1]);
            if d <= spec.goal_tolerance {
                if acc.hold == 0 {
                    acc.hold_start = time;
                }
                acc.hold += 1;
                if !acc.reached_goal && acc.hold >= spec.goal_hold_ticks.max(1) {
                    acc.reached_goal = true;
                    acc.time_to_goal = Some(acc.hold_start);
                    reached.push(i);
                }
            } else {
                acc.hold = 0;
            }
        }
        for i in reached {
            let flags = self.world.states()[i].flags | flags::AT_GOAL;
            self.world.set_flags(i, flags);
            let name = self.names[i].clone();
            let t = self.acc[i].time_to_goal;
            self.event(json!({"type": "goal_reached", "robot": name, "time_to_goal": t}));
        }
    }

    /// Publishes the live statistics for observers when due (or now, with
    /// `force`): no allocation, and a failure never stops the run.
    fn publish_stats(&mut self, phase: u32, force: bool) {
        let now = Instant::now();
        if !force && !self.live.due(now) {
            return;
        }
        let (acc, agents, rows) = (&self.acc, &self.agents, self.live.robots_mut());
        self.timings.live(|latency| {
            for (i, row) in rows.iter_mut().enumerate() {
                let l = latency.get(i).copied().unwrap_or_default();
                row.latency_p50_us = l.p50_us;
                row.latency_p99_us = l.p99_us;
                row.commands = l.commands;
            }
        });
        for (i, row) in rows.iter_mut().enumerate() {
            let acc = &acc[i];
            row.state = match agents[i] {
                Agent::Waiting => agent_state::WAITING,
                Agent::Live { .. } => agent_state::LIVE,
                Agent::Lost { .. } => agent_state::LOST,
            };
            row.reached_goal = u32::from(acc.reached_goal);
            row.agent_pid = acc.agent_pid.unwrap_or(0);
            row.deadline_misses = acc.deadline_misses;
            row.collisions = acc.collisions;
            row.commands_rejected = acc.rejected;
        }
        let wall = self.clock_start.map_or(0.0, |t| t.elapsed().as_secs_f64());
        let header = StatsHeader {
            tick: self.tick,
            max_ticks: self.world.scenario.max_ticks(),
            sim_time: self.time(),
            realtime_factor: if wall > 0.0 { self.time() / wall } else { 0.0 },
            published_ns: now_ns(),
            collisions_total: self.collisions_total,
            agents_lost: self.agents_lost,
            phase,
            realtime: u32::from(self.world.scenario.world.mode == Mode::Realtime),
            robot_count: self.agents.len() as u32,
            world_pid: std::process::id(),
        };
        let _ = self.live.publish(&mut *self.link, &header, now);
    }

    fn done(&self) -> bool {
        self.acc
            .iter()
            .zip(&self.agents)
            .all(|(a, g)| a.reached_goal || matches!(g, Agent::Lost { .. }))
    }
}

/// Waits for a wake-up from an agent or until `until`, whichever comes
/// first (the transports' waits are precise: iceoryx2's on a
/// high-resolution `ppoll`, in-process on a channel's timed receive).
fn wait_until(link: &mut dyn WorldTransport, until: Instant) -> Result<(), TransportError> {
    let left = until.saturating_duration_since(Instant::now());
    if left.is_zero() {
        return Ok(());
    }
    link.wait(left.min(Duration::from_millis(20)))
}

/// Runs `world` to the end over `link`, writing the outputs into
/// `opts.out_dir`.
pub fn run(
    world: World,
    link: &mut dyn WorldTransport,
    opts: RunOptions,
) -> Result<RunOutcome, RunError> {
    let dir = opts.out_dir.clone();
    let out_err = |what: &'static str| {
        let dir = dir.display().to_string();
        move |source: std::io::Error| RunError::Output { what, dir, source }
    };
    let scenario = world.scenario.clone();
    let n = scenario.robots.len();
    let names: Vec<String> = scenario
        .robots
        .iter()
        .map(|r| r.name.clone())
        .chain(scenario.obstacles.iter().map(|o| o.name.clone()))
        .collect();
    let scenario_json =
        serde_json::to_vec_pretty(&scenario).map_err(|e| out_err(SCENARIO_FILE)(e.into()))?;
    std::fs::write(dir.join(SCENARIO_FILE), &scenario_json).map_err(out_err(SCENARIO_FILE))?;
    // Absolute, so that an agent started from another folder writes its
    // diagnostics into this run's folder.
    let out_dir = std::fs::canonicalize(&dir).unwrap_or_else(|_| dir.clone());
    let setup = serde_json::to_vec(
        &json!({"run_id": opts.run_id, "out_dir": out_dir, "scenario": scenario}),
    )
    .map_err(|e| out_err("setup")(e.into()))?;
    let tracker = Tracker::new(&scenario, world.walls());
    let rec = Recorder::start(&dir, names.clone(), tracker).map_err(out_err(TRAJECTORY_FILE))?;
    link.publish_setup(&setup)?;

    let realtime = scenario.world.mode == Mode::Realtime;
    let mut lp = Loop {
        world,
        link,
        rec,
        opts,
        names,
        agents: vec![Agent::Waiting; n],
        acc: vec![
            RobotAccumulator {
                min_contact_gap: f64::INFINITY,
                ..Default::default()
            };
            n
        ],
        got: vec![None; n],
        garbage: vec![false; n],
        collisions_total: 0,
        agents_lost: 0,
        rejected: 0,
        rejected_unknown: 0,
        late: 0,
        tick: 0,
        published_ns: 0,
        deadline_ns: u64::MAX,
        last_in_ns: 0,
        timings: TimingRecorder::start(n).map_err(out_err(METRICS_FILE))?,
        inbox: Vec::with_capacity(n),
        last_pid_check: Instant::now(),
        pid_checks: 0,
        ready: vec![false; n],
        live: LiveStats::new(n),
        clock_start: None,
    };
    let mut jitter = DurationHistogram::default();
    let mut allin = DurationHistogram::default();
    let mut tick_cost = DurationHistogram::default();
    let mut physics = DurationHistogram::default();

    // Join: every robot's agent must be there before the clock starts.
    let join_start = Instant::now();
    let mut interrupted = false;
    lp.log(&format!(
        "waiting for {n} agents to join run {}",
        lp.opts.run_id
    ));
    // Then every one must be ready (setup read, planner built), so that the
    // first ticks are not lost to start-up in realtime, nor its time counted
    // as the first tick's latency in lockstep.
    while lp.agents.contains(&Agent::Waiting) || !lp.all_ready() {
        if lp.link.termination_requested() {
            interrupted = true;
            break;
        }
        if let Some(t) = lp.opts.start_timeout
            && join_start.elapsed() > t
        {
            let missing: Vec<&str> = lp
                .agents
                .iter()
                .enumerate()
                .filter(|(i, a)| **a == Agent::Waiting || !lp.ready[*i])
                .map(|(i, _)| lp.names[i].as_str())
                .collect();
            // Tell the agents that did join to stop.
            let header = SnapshotHeader {
                finished: 1,
                ..Default::default()
            };
            let _ = lp.link.publish_snapshot(&header, &[]);
            return Err(RunError::StartTimeout {
                missing: crate::names::first_few(&missing, 5),
                secs: t.as_secs_f64(),
            });
        }
        lp.before_start(Duration::from_millis(50))?;
    }
    lp.log("all agents joined; running");

    let dt = scenario.world.dt;
    let max_ticks = scenario.max_ticks();
    let deadline_after = Duration::from_secs_f64(dt * scenario.world.deadline);
    let stall = Duration::from_secs_f64(scenario.world.stall_timeout);
    // Tick 0 costs what any tick costs: the channels are connected, the
    // agents take up their side (and, over a transport that says so, each
    // says ready again once it has), and in realtime tick 0 comes one tick
    // after that.
    if lp.link.prepare_ticks()? {
        // The second ready commands wait in the transport until drained.
        lp.ready.fill(false);
        // A run that cannot wait starts anyway: an agent of this protocol
        // answers at once, and tick 0's deadline still holds for the rest.
        let limit = Duration::from_secs(2) + Duration::from_millis(5 * n as u64);
        let started = Instant::now();
        while !interrupted && !lp.all_ready() && started.elapsed() < limit {
            if lp.link.termination_requested() {
                interrupted = true;
                break;
            }
            lp.before_start(Duration::from_millis(20))?;
        }
        if !lp.all_ready() {
            lp.log("not every agent took up the tick's channels in time; starting anyway");
        }
    }
    let settle = if realtime {
        Duration::from_secs_f64(dt)
    } else {
        Duration::ZERO
    };
    let wall_start = Instant::now() + settle;
    lp.clock_start = Some(wall_start);
    // Under SCHED_FIFO (`--rt`) the world ticks one level below its
    // agents, and the agents its doorbell wakes preempt it while it
    // publishes: the publish's cost is then the thread's CPU time, not the
    // wall time.
    let below = BelowAgents::enter();
    let fifo = below.active();
    lp.publish_stats(run_phase::RUNNING, true);
    let (cpu_start, _) = process_usage();
    let cpus_start = CpusTime::now();
    let mut contacts = Vec::new();
    while !interrupted && lp.tick < max_ticks {
        if lp.link.termination_requested() {
            interrupted = true;
            break;
        }
        let mut scheduled = None;
        if realtime {
            let at = wall_start + Duration::from_secs_f64(lp.tick as f64 * dt);
            while Instant::now() < at {
                wait_until(lp.link, at)?;
                lp.drain(true)?;
            }
            scheduled = Some(at);
        }
        lp.got.iter_mut().for_each(|g| *g = None);
        lp.garbage.iter_mut().for_each(|g| *g = false);
        lp.last_in_ns = 0;
        let pub_instant = Instant::now();
        let pub_cpu = if fifo { thread_usage().0 } else { 0.0 };
        if let Some(at) = scheduled {
            // Tick jitter: actual start of the tick minus its scheduled time.
            jitter.record_ns(pub_instant.saturating_duration_since(at).as_nanos() as u64);
        }
        lp.published_ns = now_ns();
        if realtime {
            lp.deadline_ns = lp.published_ns + deadline_after.as_nanos() as u64;
        }
        let header = SnapshotHeader {
            tick: lp.tick,
            sim_time: lp.time(),
            published_ns: lp.published_ns,
            deadline_ns: if realtime { lp.deadline_ns } else { 0 },
            finished: 0,
            body_count: lp.world.states().len() as u32,
        };
        let live = lp
            .agents
            .iter()
            .filter(|a| matches!(a, Agent::Live { .. }))
            .count();
        lp.link.expect_answers(lp.tick, live);
        lp.link.publish_snapshot(&header, lp.world.states())?;
        lp.rec.tick(lp.tick, lp.time(), lp.world.states());
        let mut own = if fifo {
            Duration::from_secs_f64((thread_usage().0 - pub_cpu).max(0.0))
        } else {
            pub_instant.elapsed()
        };

        // Collect this tick's commands (taking them in is the world's own
        // work; waiting for them is not).
        loop {
            let drain_start = Instant::now();
            lp.drain(realtime)?;
            own += drain_start.elapsed();
            lp.check_pids();
            lp.rec.send_if_due();
            lp.timings.send_if_due();
            if lp.all_answered() || lp.link.termination_requested() {
                break;
            }
            let waited = pub_instant.elapsed();
            let limit = if realtime { deadline_after } else { stall };
            if waited >= limit {
                if !realtime {
                    for i in 0..n {
                        if matches!(lp.agents[i], Agent::Live { .. })
                            && lp.got[i].is_none()
                            && !lp.garbage[i]
                        {
                            lp.lose(
                                i,
                                format!(
                                    "no command for {:.1} s (stall_timeout)",
                                    stall.as_secs_f64()
                                ),
                            );
                        }
                    }
                }
                break;
            }
            if realtime {
                wait_until(lp.link, pub_instant + limit)?;
            } else {
                lp.link
                    .wait((limit - waited).min(Duration::from_millis(20)))?;
            }
        }
        // All in: published -> the last command in, on ticks where every
        // live agent answered in time.
        if lp.all_answered() && lp.got.iter().any(Option::is_some) {
            allin.record_ns(lp.last_in_ns.saturating_sub(lp.published_ns));
        }
        let work_start = Instant::now();

        // Apply: a valid command, or the policy for a miss, or brake.
        for i in 0..n {
            match (lp.agents[i], lp.got[i]) {
                (Agent::Live { .. }, Some(c)) => {
                    let applied = if c.kind == command_kind::VELOCITY {
                        Applied::Velocity(c.value)
                    } else {
                        Applied::Force(c.value)
                    };
                    lp.world.set_command(i, applied);
                }
                (Agent::Live { .. }, None) if lp.garbage[i] => {
                    lp.world.set_command(i, Applied::BRAKE)
                }
                (Agent::Live { .. }, None) => {
                    lp.acc[i].deadline_misses += 1;
                    let name = lp.names[i].clone();
                    lp.event(json!({"type": "deadline_miss", "robot": name}));
                    if scenario.world.on_deadline_miss == MissPolicy::Brake || lp.garbage[i] {
                        lp.world.set_command(i, Applied::BRAKE);
                    }
                }
                _ => lp.world.set_command(i, Applied::BRAKE),
            }
        }

        lp.world.step(&mut contacts);
        physics.record_ns(lp.world.physics_ns());
        lp.tick += 1;
        lp.record_contacts(&contacts);
        lp.update_goals();
        own += work_start.elapsed();
        tick_cost.record_ns(own.as_nanos() as u64);
        lp.publish_stats(run_phase::RUNNING, false);
        if lp.done() {
            break;
        }
    }
    drop(below);
    // Commands already on their way for the last tick (an agent that sent
    // two, a late one) are still counted and logged, not left unread.
    let _ = lp.drain_commands(realtime);
    // A termination request that came while the last tick ended the run
    // (its agents stopped with it) still makes the run an interrupted one.
    interrupted |= lp.link.termination_requested();
    lp.rec.tick(lp.tick, lp.time(), lp.world.states());
    let wall = wall_start.elapsed().as_secs_f64();
    let (cpu_end, maxrss_kb) = process_usage();
    // Every command's timings recorded (the live summary too).
    let mut timings = lp.timings.finish().map_err(out_err(METRICS_FILE))?;
    let cpus = cpus_start.zip(CpusTime::now()).map(|(a, b)| b.since(a));
    let timing = TimingMetrics {
        wall_s: wall,
        latency_us: timings.all[0].percentiles(),
        wake_us: timings.all[1].percentiles(),
        compute_us: timings.all[2].percentiles(),
        jitter_us: jitter.percentiles(),
        allin_us: allin.percentiles(),
        world_tick_us: tick_cost.percentiles(),
        physics_us: physics.percentiles(),
        process_cpu_s: (cpu_end - cpu_start).max(0.0),
        process_maxrss_kb: maxrss_kb,
        cpus_steal_s: cpus.map(|c| c.steal_s),
    };

    lp.publish_stats(run_phase::FINISHED, true);
    // Tell every agent the run is over (twice, in case one is mid-read).
    let header = SnapshotHeader {
        tick: lp.tick,
        sim_time: lp.time(),
        published_ns: now_ns(),
        deadline_ns: 0,
        finished: 1,
        body_count: lp.world.states().len() as u32,
    };
    lp.link.publish_snapshot(&header, lp.world.states())?;
    lp.link.publish_snapshot(&header, lp.world.states())?;
    if interrupted {
        lp.event(json!({"type": "interrupted"}));
    }

    // Every tick's states taken in: the motion metrics are complete.
    let tracker = lp.rec.finish().map_err(out_err(TRAJECTORY_FILE))?;
    let robots = scenario
        .robots
        .iter()
        .zip(&lp.acc)
        .zip(&mut timings.robots)
        .zip(tracker.robots())
        .map(|(((spec, a), t), m)| {
            let [latency, wake, compute] = t.histograms();
            let min_clearance = m.min_clearance.min(a.min_contact_gap);
            (
                spec.name.clone(),
                RobotMetrics {
                    planner: spec.planner.clone(),
                    reached_goal: a.reached_goal,
                    time_to_goal: a.time_to_goal,
                    path_length: m.path_length,
                    collisions: a.collisions,
                    min_clearance: min_clearance.is_finite().then_some(min_clearance),
                    max_speed: m.max_speed,
                    deadline_misses: a.deadline_misses,
                    latency_us: latency.percentiles(),
                    wake_us: wake.percentiles(),
                    compute_us: compute.percentiles(),
                    agent_pid: a.agent_pid,
                    lost: a.lost,
                    commands_rejected: a.rejected,
                    commands_late: a.late,
                    path_deviation: m.path.as_ref().map(|p| p.deviation()),
                    boundary_violations: m.path.as_ref().and_then(|p| p.boundary_violations()),
                },
            )
        })
        .collect();
    let reached = lp.acc.iter().filter(|a| a.reached_goal).count();
    let metrics = RunMetrics {
        scenario: scenario.name.clone(),
        robots,
        collisions_total: lp.collisions_total,
        success_rate: if n > 0 {
            reached as f64 / n as f64
        } else {
            0.0
        },
        ticks: lp.tick,
        sim_time: lp.time(),
        mode: scenario.world.mode.to_string(),
        realtime_factor: if wall > 0.0 { lp.time() / wall } else { 0.0 },
        agents_lost: lp.agents_lost,
        commands_rejected: lp.rejected,
        commands_late: lp.late,
        commands_rejected_unknown: lp.rejected_unknown,
        world_pid: std::process::id(),
        run_id: lp.opts.run_id.clone(),
        transport: lp.opts.transport.clone(),
        interrupted,
        timing,
    };
    mrsim_runfolder::write_metrics(&dir, &metrics).map_err(|e| match e {
        FileError::Io { source, .. } => out_err(METRICS_FILE)(source),
        FileError::Json { source, .. } => out_err(METRICS_FILE)(source.into()),
    })?;
    Ok(RunOutcome { metrics })
}
