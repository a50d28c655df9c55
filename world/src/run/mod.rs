//! The tick loop: join, then each tick publish, collect, step, record.
//!
//! Split by role, as rapier splits its pipeline: [`admission`] decides who
//! drives which robot and which commands count (verdicts and events, no
//! side effects beyond its own table), [`schedule`] when ticks start and
//! how long the world waits for answers, [`recording`] what is written,
//! counted and shown live. [`run`] wires them: it owns the world and the
//! transport, applies the verdicts (moving, braking and flagging robots),
//! logs, and is the only one that waits.
//!
//! Lockstep waits for every live agent's command (or `stall_timeout`, after
//! which the agent is lost); realtime ticks on the wall clock and counts a
//! command that is not in by the deadline as a miss, after which the robot
//! holds its last command or brakes. A command without the robot's current
//! token, for another tick, with non-finite values, or a second one in a
//! tick, is rejected, counted and logged, and never drives a robot.

pub mod admission;
pub mod episode;
#[cfg(test)]
mod fake;
mod options;
pub mod recording;
pub mod schedule;
#[cfg(test)]
mod tests;

use crate::metrics::TimingMetrics;
use crate::physics::{Applied, World};
use crate::record::Recorder;
use crate::timings::TimingRecorder;
use crate::tracking::Tracker;
use admission::{Admission, Agent, Event, TickWindow, Verdict};
use mrsim_proto::{
    CommandMsg, JoinRequest, SnapshotHeader, StatsHeader, command_kind, flags, now_ns, run_phase,
};
use mrsim_runfolder::timing::{Status, TIMING_FILE, TIMING_PARQUET_FILE, TimingSink};
use mrsim_runfolder::{FileError, METRICS_FILE, ROUTES_FILE, SCENARIO_FILE, TRAJECTORY_FILE};
use mrsim_scenario::cores::Contention;
use mrsim_scenario::timing::{Timing, s_to_ns};
use mrsim_scenario::{MissPolicy, Mode};
use mrsim_sys::sched::{BelowAgents, WORLD_PRIORITY};
use mrsim_sys::usage::{CpusTime, process_usage, thread_usage};
use mrsim_transport::{TransportError, WorldTransport};
use recording::{Recording, Stamp, Summary};
use schedule::{Clock, Schedule, SystemClock, Wait, wait_until};
use serde_json::json;
use std::time::{Duration, Instant};

pub use crate::metrics::RunMetrics;
use mrsim_sys::process::pid_alive;
use options::out_err;
pub use options::{Route, RunOptions, RunOutcome, WorldRunError};

/// The loop's state: the world and its transport, and one struct per role.
struct Loop<'a> {
    world: World,
    link: &'a mut dyn WorldTransport,
    clock: &'a dyn Clock,
    opts: RunOptions,
    admission: Admission,
    schedule: Schedule,
    recording: Recording,
    /// The tick being answered: its number, publish time and deadline.
    window: TickWindow,
    /// Latest receive time of a command accepted this tick.
    last_in_ns: u64,
    /// Commands taken from the transport, reused from drain to drain.
    inbox: Vec<(CommandMsg, u64)>,
    last_pid_check: Instant,
    pid_checks: u64,
    clock_start: Option<Instant>,
    /// What timing decides per robot: its model, and how the world judges
    /// and applies its commands (see [`Timed`]).
    timed: Timed,
    /// The robots' positions after the step, reused from tick to tick.
    positions: Vec<[f64; 2]>,
    /// The run counted as an episode (`[world] end_on`).
    episode: episode::Episode,
}

/// The world's side of the robots' timing models
/// (`mrsim_scenario::timing`): a robot with a model has its commands take
/// effect from the physics substep they arrive in (plus its actuation
/// delay) and misses only at the ticks of its period; in lockstep the world
/// judges a modelled or replayed command's send time against the deadline.
struct Timed {
    /// Each robot's model, if it has one.
    models: Vec<Option<Timing>>,
    /// Each robot replays a recorded run's planner calls.
    replayed: Vec<bool>,
    /// The tick, ns.
    dt_ns: u64,
    /// The deadline, ns after a tick's publication.
    deadline_ns: u64,
    substeps: u32,
    lockstep: bool,
    /// The run writes timing.csv: realtime, or some robot has a model.
    recorded: bool,
    /// Lockstep under `[world.cpus]`: the cores' model, which decides for
    /// the robots whose compute is CPU work when they read and send.
    cores: Option<Contention>,
    /// Per robot under the cores' model: when its answer to the current
    /// tick is sent, ns after publication, if its call ends within the tick.
    core_sent: Vec<Option<u64>>,
}

/// Realtime under `[world.cpus]`: puts the calling thread (the tick loop)
/// at SCHED_FIFO [`WORLD_PRIORITY`], above every agent's policy but
/// SCHED_DEADLINE's (which runs before any SCHED_FIFO task). `None` for
/// every other run; the kernel's refusal when it refuses (the launcher
/// probed it before the run, so only a world started by hand meets it).
fn above_agents(
    scenario: &mrsim_scenario::Scenario,
) -> Option<Result<(), mrsim_sys::policy::PolicyError>> {
    let real = scenario.world.mode == Mode::Realtime && scenario.world.cpus.is_some();
    real.then(|| {
        mrsim_sys::policy::set_policy(mrsim_sys::policy::Policy::Fifo {
            priority: WORLD_PRIORITY,
        })
    })
}

/// True if a run of `scenario` writes timing.csv: realtime, or some robot
/// has a timing model.
fn records_calls(scenario: &mrsim_scenario::Scenario) -> bool {
    scenario.world.mode != Mode::Lockstep || scenario.robots.iter().any(|r| r.timing.is_some())
}

impl Timed {
    fn new(scenario: &mrsim_scenario::Scenario) -> Self {
        let w = &scenario.world;
        Self {
            models: scenario.robots.iter().map(|r| r.timing.clone()).collect(),
            replayed: scenario.robots.iter().map(|r| r.replay.is_some()).collect(),
            dt_ns: s_to_ns(w.dt).max(1),
            deadline_ns: s_to_ns(w.dt * w.deadline),
            substeps: w.substeps,
            lockstep: w.mode == Mode::Lockstep,
            recorded: records_calls(scenario),
            // Checked by `run` before the loop is built.
            cores: Contention::of(scenario).unwrap_or(None),
            core_sent: vec![None; scenario.robots.len()],
        }
    }

    /// True if robot `i` is timed by the cores' model.
    fn cored(&self, i: usize) -> bool {
        self.cores.as_ref().is_some_and(|c| c.has(i))
    }

    /// True if robot `i`'s send times are judged here rather than by the
    /// clock: modelled or replayed, in lockstep.
    fn judged(&self, i: usize) -> bool {
        self.lockstep && (self.models[i].is_some() || self.replayed[i])
    }

    /// True if robot `i`'s planner runs at `tick` (else no answer is no miss).
    fn plans_at(&self, i: usize, tick: u64) -> bool {
        self.models[i].as_ref().is_none_or(|t| t.plans_at(tick))
    }

    /// True if the run writes timing.csv.
    fn recorded(&self) -> bool {
        self.recorded
    }
}

impl<'a> Loop<'a> {
    /// A loop over `world` and `link` with the outputs started in
    /// `opts.out_dir` (the recorder and timings threads).
    fn new(
        world: World,
        link: &'a mut dyn WorldTransport,
        clock: &'a dyn Clock,
        opts: RunOptions,
        rec: Recorder,
        timings: TimingRecorder,
    ) -> Self {
        let scenario = &world.scenario;
        let names = body_names(scenario);
        let n = scenario.robots.len();
        let robots = names[..n].to_vec();
        let schedule = Schedule::new(scenario);
        let timed = Timed::new(scenario);
        let episode = episode::Episode::new(scenario);
        Self {
            admission: Admission::new(robots, std::process::id()).with_room(opts.group_room),
            recording: Recording::new(rec, timings, names, n).with_people(scenario.people.len()),
            // Before the first tick nothing is late.
            window: TickWindow {
                tick: 0,
                published_ns: 0,
                deadline_ns: u64::MAX,
                realtime: schedule.realtime,
            },
            schedule,
            world,
            link,
            clock,
            opts,
            last_in_ns: 0,
            inbox: Vec::with_capacity(n),
            positions: Vec::with_capacity(n),
            episode,
            last_pid_check: clock.now(),
            pid_checks: 0,
            clock_start: None,
            timed,
        }
    }

    fn stamp(&self) -> Stamp {
        Stamp {
            tick: self.window.tick,
            time: self.world.time(),
        }
    }

    fn log(&self, msg: &str) {
        if self.opts.verbose {
            eprintln!("world: {msg}");
        }
    }

    /// Records and logs what admission did, and moves the robot: a lost
    /// robot brakes and is flagged lost, a (re)joined one is unflagged.
    fn apply(&mut self, e: Event) {
        self.recording.admitted(self.stamp(), &e);
        match e {
            Event::Joined { robot, pid } => {
                self.unflag_lost(robot);
                let name = self.recording.name(robot);
                self.log(&format!("agent for {name} joined (pid {pid})"));
            }
            Event::Rejoined {
                robot,
                pid,
                by_command,
            } => {
                self.unflag_lost(robot);
                let name = self.recording.name(robot);
                if by_command {
                    self.log(&format!("agent for {name} answered again and rejoined"));
                } else {
                    self.log(&format!("agent for {name} rejoined (pid {pid})"));
                }
            }
            Event::JoinRefused { reason, .. } => {
                self.log(&format!("refused a join: {reason}"));
            }
            Event::Lost { robot, reason, .. } => {
                self.world.clear_pending(robot);
                self.world.set_command(robot, Applied::BRAKE);
                let flags = self.world.states()[robot].flags | flags::LOST;
                self.world.set_flags(robot, flags);
                let name = self.recording.name(robot);
                self.log(&format!("lost the agent for {name}: {reason}"));
            }
        }
    }

    fn unflag_lost(&mut self, robot: usize) {
        let flags = self.world.states()[robot].flags & !flags::LOST;
        self.world.set_flags(robot, flags);
    }

    fn lose(&mut self, i: usize, reason: String) {
        if let Some(e) = self.admission.lose(i, reason) {
            self.apply(e);
        }
    }

    fn handle_join(&mut self, req: JoinRequest) -> Result<(), TransportError> {
        let link = &*self.link;
        let alive = |p| link.agent_alive(p).unwrap_or_else(|| pid_alive(p));
        let (reply, events) = self.admission.join(&req, now_ns(), alive);
        for e in events {
            let lost = matches!(e, Event::Lost { .. });
            self.apply(e);
            if lost {
                // The dead agent's leftovers freed before its successor
                // takes its place.
                self.link.cleanup_dead();
            }
        }
        self.link.reply_join(&reply)
    }

    /// Records one planner call's row of the timing file (realtime runs
    /// and runs with a timing model), written by the recording thread.
    fn call(&mut self, robot: usize, cmd: &CommandMsg, status: Status) {
        // A robot under the cores' model has its rows from the model
        // (`Loop::run_cores`).
        if !self.timed.recorded() || self.timed.cored(robot) {
            return;
        }
        let sent_ns = cmd.sent_ns.saturating_sub(self.window.published_ns);
        if cmd.overruns > 0 {
            let o = &mut self.recording.acc[robot].overruns;
            *o = Some(o.unwrap_or(0).max(cmd.overruns));
        }
        self.recording.call(crate::record::Call {
            tick: cmd.tick,
            robot: robot as u32,
            sent_ns,
            status,
            cpu_ns: cmd.cpu_ns,
        });
    }

    fn handle_command(&mut self, mut cmd: CommandMsg, received_ns: u64) {
        let cored = (cmd.robot_id as usize) < self.timed.core_sent.len()
            && self.timed.cored(cmd.robot_id as usize);
        if cored && cmd.tick == self.window.tick {
            // The cores' model says when it was sent: within the tick, or
            // after its deadline (its row is written when the model ends it).
            let sent = self.timed.core_sent[cmd.robot_id as usize]
                .unwrap_or(self.timed.deadline_ns.saturating_add(1));
            cmd.sent_ns = self.window.published_ns.saturating_add(sent);
        }
        match self.admission.command(&cmd, self.window) {
            Verdict::Accepted { robot, .. } if cmd.kind == command_kind::NONE => {
                let _ = robot;
            }
            Verdict::Accepted { robot, .. } if cmd.kind == command_kind::LOST => {
                self.call(robot, &cmd, Status::Lost);
            }
            Verdict::Accepted { robot, .. }
                if self.timed.judged(robot)
                    && cmd.sent_ns.saturating_sub(self.window.published_ns)
                        > self.timed.deadline_ns =>
            {
                // Modelled (or replayed) as sent after the deadline: late,
                // an answer that drives nothing.
                self.call(robot, &cmd, Status::Late);
                self.recording.late(robot);
                if let Some(g) = self.admission.got[robot].as_mut() {
                    g.kind = command_kind::NONE;
                }
            }
            Verdict::Accepted { robot, rejoined } => {
                self.call(robot, &cmd, Status::Accepted);
                if let Some(pid) = rejoined {
                    self.apply(Event::Rejoined {
                        robot,
                        pid,
                        by_command: true,
                    });
                }
                let published = self.window.published_ns;
                self.recording.timings.record(
                    robot,
                    received_ns.saturating_sub(published),
                    cmd.woke_ns.saturating_sub(published),
                    cmd.compute_ns,
                );
                self.last_in_ns = self.last_in_ns.max(received_ns);
            }
            Verdict::Ready { .. } => {}
            Verdict::Late { robot } => {
                self.call(robot, &cmd, Status::Late);
                self.recording.late(robot);
            }
            Verdict::Rejected {
                robot: Some(robot),
                reason,
            } if self.window.realtime
                && reason == admission::PAST_TICK
                && matches!(self.admission.agents()[robot], Agent::Live { token, .. } if token == cmd.token) =>
            {
                // Its owner's answer to a tick long gone: a planner call
                // like any other, late.
                self.call(robot, &cmd, Status::Late);
                let at = self.stamp();
                self.recording
                    .rejected(at, Some(robot), cmd.robot_id, reason, cmd.tick);
            }
            Verdict::Rejected { robot, reason } => {
                let at = self.stamp();
                self.recording
                    .rejected(at, robot, cmd.robot_id, reason, cmd.tick);
            }
        }
    }

    fn check_pids(&mut self) {
        let now = self.clock.now();
        if now.saturating_duration_since(self.last_pid_check) < Duration::from_millis(100) {
            return;
        }
        self.last_pid_check = now;
        // Every 100 ms whether each agent's process exists (one syscall);
        // every second also whether it is a zombie its parent has not
        // reaped yet (a /proc read: too dear to do every time).
        self.pid_checks += 1;
        let local = if self.pid_checks.is_multiple_of(10) {
            pid_alive
        } else {
            mrsim_sys::process::pid_exists
        };
        let link = &*self.link;
        let alive = |p| link.agent_alive(p).unwrap_or_else(|| local(p));
        // An agent in the world's own process (the in-process transport)
        // cannot die on its own: its thread's failure comes through the
        // transport, and reading /proc/self for each would walk every
        // thread of this process.
        let dead = self.admission.dead(alive, std::process::id());
        for &i in &dead {
            let Agent::Live { pid, .. } = self.admission.agents()[i] else {
                continue;
            };
            self.lose(i, format!("agent process {pid} died"));
        }
        if !dead.is_empty() {
            self.link.cleanup_dead();
        }
    }

    fn drain(&mut self) -> Result<(), TransportError> {
        let mut joins = Vec::new();
        self.link.drain_joins(&mut |j| joins.push(j))?;
        let any = !joins.is_empty();
        for j in joins {
            self.handle_join(j)?;
        }
        if any {
            self.link.joins_answered()?;
        }
        self.drain_commands()
    }

    /// Takes in every command received so far.
    fn drain_commands(&mut self) -> Result<(), TransportError> {
        let mut inbox = std::mem::take(&mut self.inbox);
        inbox.clear();
        let drained = self.link.drain_commands(&mut |c, t| inbox.push((c, t)));
        if drained.is_ok() {
            for (c, t) in inbox.drain(..) {
                self.handle_command(c, t);
            }
        }
        self.inbox = inbox;
        drained
    }

    /// One round of waiting before the clock starts: joins and ready
    /// commands taken in, pids checked, and the live statistics published
    /// (which also lets go of the join-time connections of agents that
    /// closed theirs).
    fn before_start(&mut self, wait: Duration) -> Result<(), TransportError> {
        self.link.wait(wait)?;
        // Before the first tick a late answer is no miss.
        let realtime = std::mem::replace(&mut self.window.realtime, false);
        let drained = self.drain();
        self.window.realtime = realtime;
        drained?;
        // Commands before the first tick are from nobody we know yet.
        self.admission.got.iter_mut().for_each(|g| *g = None);
        self.check_pids();
        // The joins' events reach events.jsonl while the world waits.
        self.recording.rec.send_if_due();
        self.publish_stats(run_phase::JOINING, false);
        Ok(())
    }

    /// Publishes the live statistics for observers when due (or now, with
    /// `force`).
    fn publish_stats(&mut self, phase: u32, force: bool) {
        let (world, clock, clock_start) = (&self.world, self.clock, self.clock_start);
        let (tick, agents) = (self.window.tick, self.admission.agents());
        let header = || {
            let wall = clock_start.map_or(0.0, |t| {
                clock.now().saturating_duration_since(t).as_secs_f64()
            });
            let time = world.time();
            StatsHeader {
                tick,
                max_ticks: world.scenario.max_ticks(),
                sim_time: time,
                realtime_factor: if wall > 0.0 { time / wall } else { 0.0 },
                published_ns: now_ns(),
                collisions_total: 0,
                agents_lost: 0,
                phase,
                realtime: u32::from(world.scenario.world.mode == Mode::Realtime),
                robot_count: agents.len() as u32,
                world_pid: std::process::id(),
            }
        };
        self.recording
            .publish_stats(&mut *self.link, agents, header, force);
    }

    /// Waits until every robot has an agent and every agent is ready (or
    /// the start timeout, or a termination request: then true).
    fn join_phase(&mut self) -> Result<bool, WorldRunError> {
        let join_start = self.clock.now();
        while self.admission.any_waiting() || !self.admission.all_ready() {
            if self.link.termination_requested() {
                return Ok(true);
            }
            if let Some(t) = self.opts.start_timeout
                && self.clock.now().saturating_duration_since(join_start) > t
            {
                let missing: Vec<&str> = self
                    .admission
                    .not_ready()
                    .into_iter()
                    .map(|i| self.recording.name(i))
                    .collect();
                let missing = crate::names::first_few(&missing, 5);
                // Tell the agents that did join to stop.
                let header = SnapshotHeader {
                    finished: 1,
                    ..Default::default()
                };
                let _ = self.link.publish_snapshot(&header, &[]);
                return Err(WorldRunError::StartTimeout {
                    missing,
                    secs: t.as_secs_f64(),
                });
            }
            self.before_start(Duration::from_millis(50))?;
        }
        Ok(false)
    }

    /// Connects the tick's channels and, over a transport that says so,
    /// waits (a bounded time, not at all if `interrupted`) for each agent
    /// to have taken up its side. True if the run is interrupted.
    fn prepare_ticks(&mut self, interrupted: bool) -> Result<bool, WorldRunError> {
        if !self.link.prepare_ticks()? {
            return Ok(interrupted);
        }
        // The second ready commands wait in the transport until drained.
        self.admission.ready.fill(false);
        // A run that cannot wait starts anyway: an agent of this protocol
        // answers at once, and tick 0's deadline still holds for the rest.
        let n = self.admission.agents().len();
        let limit = Duration::from_secs(2) + Duration::from_millis(5 * n as u64);
        let started = self.clock.now();
        while !interrupted
            && !self.admission.all_ready()
            && self.clock.now().saturating_duration_since(started) < limit
        {
            if self.link.termination_requested() {
                return Ok(true);
            }
            self.before_start(Duration::from_millis(20))?;
        }
        if !self.admission.all_ready() {
            self.log("not every agent took up the tick's channels in time; starting anyway");
        }
        Ok(interrupted)
    }

    /// Takes in this tick's commands until every live agent has answered
    /// or time is up (lockstep: the silent agents are then lost). Returns
    /// the time spent taking them in (the world's own work; waiting for
    /// them is not).
    fn collect(&mut self, published: Instant) -> Result<Duration, TransportError> {
        let mut own = Duration::ZERO;
        loop {
            let drain_start = self.clock.now();
            self.drain()?;
            own += self.clock.now().saturating_duration_since(drain_start);
            // All in: nothing else before the tick goes on (the caller
            // checks the agents' processes and sends the batches, off the
            // path from the last answer to its taking in).
            if self.admission.all_answered() || self.link.termination_requested() {
                return Ok(own);
            }
            self.check_pids();
            self.recording.rec.send_if_due();
            self.recording.timings.send_if_due();
            if self.admission.all_answered() {
                return Ok(own);
            }
            let waited = self.clock.now().saturating_duration_since(published);
            match self.schedule.next_wait(published, waited) {
                Wait::TimedOut => {
                    if !self.schedule.realtime {
                        for i in self.admission.silent() {
                            self.lose(i, self.schedule.stall_reason());
                        }
                    }
                    return Ok(own);
                }
                Wait::Until(at) => wait_until(self.link, self.clock, at)?,
                Wait::For(d) => self.link.wait(d)?,
            }
        }
    }

    /// Applies this tick's answers: a valid command, or the policy for a
    /// miss, or brake.
    fn apply_commands(&mut self) {
        let brake_on_miss = self.world.scenario.world.on_deadline_miss == MissPolicy::Brake;
        for i in 0..self.admission.agents().len() {
            let (agent, got, garbage) = (
                self.admission.agents()[i],
                self.admission.got[i],
                self.admission.garbage[i],
            );
            match (agent, got) {
                (Agent::Live { .. }, Some(c))
                    if !matches!(c.kind, command_kind::NONE | command_kind::LOST) =>
                {
                    let applied = match c.kind {
                        command_kind::VELOCITY => Applied::Velocity(c.value),
                        command_kind::UNICYCLE => Applied::Unicycle(c.value),
                        command_kind::ACKERMANN => Applied::Ackermann(c.value),
                        _ => Applied::Force(c.value),
                    };
                    match &self.timed.models[i] {
                        Some(t) => {
                            let sent = c.sent_ns.saturating_sub(self.window.published_ns);
                            let at = t.effect_substep(
                                self.window.tick,
                                sent,
                                self.timed.dt_ns,
                                self.timed.substeps,
                            );
                            self.world.set_command_at(i, at, applied);
                        }
                        None => self.world.set_command(i, applied),
                    }
                }
                (Agent::Live { .. }, None) if garbage => self.world.set_command(i, Applied::BRAKE),
                // Not a tick its planner runs on: the command holds.
                (Agent::Live { .. }, _) if !self.timed.plans_at(i, self.window.tick) => {}
                (Agent::Live { .. }, _) => {
                    let at = self.stamp();
                    self.recording.miss(at, i);
                    if brake_on_miss {
                        self.world.set_command(i, Applied::BRAKE);
                    }
                }
                _ => self.world.set_command(i, Applied::BRAKE),
            }
        }
    }

    /// One tick: wait for its time (realtime), publish, collect, apply,
    /// step, record. True when the run is over.
    fn tick(
        &mut self,
        wall_start: Instant,
        fifo: bool,
        contacts: &mut Vec<crate::physics::Contact>,
    ) -> Result<bool, TransportError> {
        let tick = self.window.tick;
        let scheduled = self.schedule.due(wall_start, tick);
        if let Some(at) = scheduled {
            while self.clock.now() < at {
                wait_until(self.link, self.clock, at)?;
                self.drain()?;
            }
        }
        self.admission.new_tick();
        self.last_in_ns = 0;
        let pub_instant = self.clock.now();
        let pub_cpu = if fifo { thread_usage().0 } else { 0.0 };
        if let Some(at) = scheduled {
            // Tick jitter: actual start of the tick minus its scheduled time.
            self.recording
                .costs
                .jitter
                .record_ns(pub_instant.saturating_duration_since(at).as_nanos() as u64);
        }
        // The bodies as they are about to be published, recorded before
        // the publish (after it the world would do it only once the agents
        // it wakes are done, see below).
        self.recording
            .rec
            .tick(tick, self.world.time(), self.world.states());
        self.window = self.schedule.window(tick, now_ns());
        if self.timed.cores.is_some() {
            self.run_cores(tick);
        }
        let header = SnapshotHeader {
            tick,
            sim_time: self.world.time(),
            published_ns: self.window.published_ns,
            deadline_ns: if self.schedule.realtime {
                self.window.deadline_ns
            } else {
                0
            },
            finished: 0,
            body_count: self.world.states().len() as u32,
        };
        self.link.expect_answers(tick, self.admission.live());
        self.link.publish_snapshot(&header, self.world.states())?;
        // Straight to the answers. Under SCHED_FIFO the agents the doorbell
        // wakes preempt the world as it rings, so whatever it did between
        // the ring and the collecting would wait for them and then delay
        // the taking in of the last answer; the cost of the publish is then
        // the thread's CPU time over the publish and the collecting (the
        // waits' sleep is no CPU time), read once they are over.
        let published = (!fifo).then(|| self.clock.now().saturating_duration_since(pub_instant));
        let collected = self.collect(pub_instant)?;
        let mut own = match published {
            Some(publish) => publish + collected,
            None => Duration::from_secs_f64((thread_usage().0 - pub_cpu).max(0.0)),
        };
        // All in: published -> the last command in, on ticks where every
        // live agent answered in time.
        if self.admission.all_answered() && self.admission.got.iter().any(Option::is_some) {
            let allin = self.last_in_ns.saturating_sub(self.window.published_ns);
            self.recording.costs.allin.record_ns(allin);
        }
        let work_start = self.clock.now();
        self.check_pids();
        self.recording.rec.send_if_due();
        self.recording.timings.send_if_due();
        self.apply_commands();
        self.world.step(contacts);
        self.recording
            .costs
            .physics
            .record_ns(self.world.physics_ns());
        self.window.tick += 1;
        let at = self.stamp();
        self.recording.contacts(at, contacts);
        let acc = &self.recording.acc;
        let ended_on_contact = self
            .episode
            .contacts(at.time, contacts, |i| acc[i].reached_goal);
        let poses = self.world.states().iter().map(|s| (s.position, s.heading));
        let scenario = &self.world.scenario;
        let reached = self.recording.goals(at, scenario, poses);
        for i in reached {
            let flags = self.world.states()[i].flags | flags::AT_GOAL;
            self.world.set_flags(i, flags);
        }
        self.positions.clear();
        let robots = self.world.scenario.robots.len();
        self.positions
            .extend(self.world.states().iter().take(robots).map(|s| s.position));
        let all_stuck = self
            .recording
            .stuck(at, &self.world.scenario, &self.positions);
        own += self.clock.now().saturating_duration_since(work_start);
        self.recording
            .costs
            .tick_cost
            .record_ns(own.as_nanos() as u64);
        self.publish_stats(run_phase::RUNNING, false);
        let acc = &self.recording.acc;
        Ok(ended_on_contact || all_stuck || self.admission.done(|i| acc[i].reached_goal))
    }
}

impl Loop<'_> {
    /// Lockstep under `[world.cpus]`: runs the cores' model over tick
    /// `tick`, marks the robots that read its snapshot
    /// ([`flags::PLANS`]), notes when their answers to it are sent, and
    /// writes the rows of the calls the model ended within the tick.
    /// `u64::MAX`: the run is over, the calls still running are run to
    /// their end and written.
    fn run_cores(&mut self, tick: u64) {
        let Some(cores) = self.timed.cores.as_mut() else {
            return;
        };
        let (states, scenario) = (self.world.states(), &self.world.scenario);
        match tick {
            u64::MAX => cores.drain(),
            _ => cores.tick(tick, |robot| {
                crate::sensed::count(states, robot, &scenario.robots[robot])
            }),
        }
        self.timed.core_sent.fill(None);
        let deadline = self.timed.deadline_ns;
        for c in cores.sends() {
            if c.tick == tick && c.sent_ns <= self.timed.dt_ns {
                self.timed.core_sent[c.robot] = Some(c.sent_ns);
            }
            if self.timed.recorded {
                let status = if c.lost {
                    Status::Lost
                } else if c.tick < tick || c.sent_ns > deadline {
                    Status::Late
                } else {
                    Status::Accepted
                };
                self.recording.call(crate::record::Call {
                    tick: c.tick,
                    robot: c.robot as u32,
                    sent_ns: c.sent_ns,
                    status,
                    cpu_ns: c.cpu_ns,
                });
            }
        }
        for i in 0..self.timed.core_sent.len() {
            if !cores.has(i) {
                continue;
            }
            let f = self.world.states()[i].flags;
            let f = if cores.reads(i) {
                f | flags::PLANS
            } else {
                f & !flags::PLANS
            };
            self.world.set_flags(i, f);
        }
    }
}

/// Every body's name: the robots, the obstacles, the people.
fn body_names(scenario: &mrsim_scenario::Scenario) -> Vec<String> {
    scenario.body_names()
}

/// Writes routes.csv: the route of each robot that has one, in scenario
/// order; nothing when none has.
fn write_routes(
    dir: &std::path::Path,
    scenario: &mrsim_scenario::Scenario,
    routes: &std::collections::BTreeMap<String, Route>,
) -> std::io::Result<()> {
    if routes.is_empty() {
        return Ok(());
    }
    let mut csv = String::from("robot,seq,x,y\n");
    for r in &scenario.robots {
        let Some(route) = routes.get(&r.name) else {
            continue;
        };
        for (k, p) in route.points.iter().enumerate() {
            csv.push_str(&format!("{},{k},{},{}\n", r.name, p[0], p[1]));
        }
    }
    std::fs::write(dir.join(ROUTES_FILE), csv)
}

/// Runs `world` to the end over `link`, writing the outputs into
/// `opts.out_dir`.
pub fn run(
    world: World,
    link: &mut dyn WorldTransport,
    opts: RunOptions,
) -> Result<RunOutcome, WorldRunError> {
    run_with_clock(world, link, opts, &SystemClock)
}

/// [`run`] on the time of `clock`.
fn run_with_clock(
    world: World,
    link: &mut dyn WorldTransport,
    opts: RunOptions,
    clock: &dyn Clock,
) -> Result<RunOutcome, WorldRunError> {
    Contention::of(&world.scenario)?;
    let dir = opts.out_dir.clone();
    let out_err = |what| out_err(&dir, what);
    let scenario = world.scenario.clone();
    let n = scenario.robots.len();
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
    let tracker = Tracker::new(&scenario, world.walls())
        .along_routes(&scenario, |name| opts.routes.get(name).map(|r| r.length));
    let mut extras =
        crate::record::Extras::of(&dir, &scenario).map_err(out_err(TRAJECTORY_FILE))?;
    if records_calls(&scenario) {
        let parquet = scenario.output.trajectory == mrsim_scenario::TrajectoryFormat::Parquet;
        let name = if parquet {
            TIMING_PARQUET_FILE
        } else {
            TIMING_FILE
        };
        extras.calls = Some(TimingSink::create(&dir, parquet).map_err(|e| match e {
            mrsim_runfolder::timing::TimingFileError::Io { source, .. } => out_err(name)(source),
            other => out_err(name)(std::io::Error::other(other.to_string())),
        })?);
    }
    let rec = Recorder::start_with(
        &dir,
        body_names(&scenario),
        tracker,
        scenario.output,
        extras,
    )
    .map_err(out_err(TRAJECTORY_FILE))?;
    link.publish_setup(&setup)?;
    let timings = TimingRecorder::start(n).map_err(out_err(METRICS_FILE))?;
    let mut lp = Loop::new(world, link, clock, opts, rec, timings);

    // Join: every robot's agent must be there, then ready (setup read,
    // planner built), before the clock starts, so that the first ticks are
    // not lost to start-up in realtime, nor its time counted as the first
    // tick's latency in lockstep.
    lp.log(&format!(
        "waiting for {n} agents to join run {}",
        lp.opts.run_id
    ));
    let mut interrupted = lp.join_phase()?;
    lp.log("all agents joined; running");
    // Tick 0 costs what any tick costs: the channels are connected, the
    // agents take up their side, and in realtime tick 0 comes one tick
    // after that.
    interrupted = lp.prepare_ticks(interrupted)?;
    let wall_start = clock.now() + lp.schedule.settle();
    lp.clock_start = Some(wall_start);
    // Realtime under `[world.cpus]`: the world ticks above every agent
    // (SCHED_FIFO 99; each agent takes its own policy). Otherwise, under
    // SCHED_FIFO (`--rt`), one level below its agents.
    let above = above_agents(&scenario);
    if let Some(Err(e)) = &above {
        lp.log(&format!(
            "the world cannot tick above its agents ({e}); it ticks at the policy it has"
        ));
    }
    let below = match above {
        Some(_) => BelowAgents::inactive(),
        None => BelowAgents::enter(),
    };
    let fifo = below.active();
    lp.publish_stats(run_phase::RUNNING, true);
    let (cpu_start, _) = process_usage();
    let cpus_start = CpusTime::now();
    let max_ticks = scenario.max_ticks();
    let mut contacts = Vec::new();
    while !interrupted && lp.window.tick < max_ticks {
        if lp.link.termination_requested() {
            interrupted = true;
            break;
        }
        if lp.tick(wall_start, fifo, &mut contacts)? {
            break;
        }
    }
    drop(below);
    // Commands already on their way for the last tick (an agent that sent
    // two, a late one) are still counted and logged, not left unread.
    let _ = lp.drain_commands();
    // The calls still on the cores end (late) after the last tick.
    lp.run_cores(u64::MAX);
    // A termination request that came while the last tick ended the run
    // (its agents stopped with it) still makes the run an interrupted one.
    interrupted |= lp.link.termination_requested();
    let (tick, time) = (lp.window.tick, lp.world.time());
    lp.recording.rec.tick(tick, time, lp.world.states());
    let wall = clock
        .now()
        .saturating_duration_since(wall_start)
        .as_secs_f64();
    let (cpu_end, maxrss_kb) = process_usage();
    finish(
        lp,
        interrupted,
        wall,
        cpu_end - cpu_start,
        maxrss_kb,
        cpus_start,
    )
}

/// Tells the agents the run is over and writes metrics.json.
fn finish(
    mut lp: Loop<'_>,
    interrupted: bool,
    wall: f64,
    cpu_s: f64,
    maxrss_kb: u64,
    cpus_start: Option<CpusTime>,
) -> Result<RunOutcome, WorldRunError> {
    let dir = lp.opts.out_dir.clone();
    let out_err = |what| out_err(&dir, what);
    // Every command's timings recorded (the live summary too).
    let mut timings = lp
        .recording
        .timings
        .finish()
        .map_err(out_err(METRICS_FILE))?;
    let cpus = cpus_start.zip(CpusTime::now()).map(|(a, b)| b.since(a));
    let costs = &lp.recording.costs;
    let timing = TimingMetrics {
        wall_s: wall,
        latency_us: timings.all[0].percentiles(),
        wake_us: timings.all[1].percentiles(),
        compute_us: timings.all[2].percentiles(),
        jitter_us: costs.jitter.percentiles(),
        allin_us: costs.allin.percentiles(),
        world_tick_us: costs.tick_cost.percentiles(),
        physics_us: costs.physics.percentiles(),
        process_cpu_s: cpu_s.max(0.0),
        process_maxrss_kb: maxrss_kb,
        cpus_steal_s: cpus.map(|c| c.steal_s),
    };

    lp.publish_stats(run_phase::FINISHED, true);
    // Tell every agent the run is over (twice, in case one is mid-read).
    let header = SnapshotHeader {
        tick: lp.window.tick,
        sim_time: lp.world.time(),
        published_ns: now_ns(),
        deadline_ns: 0,
        finished: 1,
        body_count: lp.world.states().len() as u32,
    };
    lp.link.publish_snapshot(&header, lp.world.states())?;
    lp.link.publish_snapshot(&header, lp.world.states())?;
    if interrupted {
        lp.recording
            .event(lp.stamp(), json!({"type": "interrupted"}));
    }

    // Every tick's states taken in: the motion metrics are complete.
    let Recording {
        mut rec,
        acc,
        counts,
        deadlocks,
        ended_stuck,
        ..
    } = lp.recording;
    let tracker = rec.finish().map_err(out_err(TRAJECTORY_FILE))?;
    let mut metrics = Summary {
        scenario: &lp.world.scenario,
        ticks: lp.window.tick,
        sim_time: lp.world.time(),
        wall_s: wall,
        run_id: lp.opts.run_id.clone(),
        transport: lp.opts.transport.clone(),
        interrupted,
        timing,
        deadlocks,
        ended_stuck,
    }
    .metrics(counts, &acc, &mut timings.robots, &tracker);
    if let Some(c) = lp.link.network_counts() {
        recording::add_network_counts(&mut metrics, c);
    }
    let names = body_names(&lp.world.scenario);
    lp.episode.fill(
        &mut metrics,
        &lp.world.scenario,
        &names,
        lp.window.tick,
        lp.world.time(),
    );
    write_routes(&lp.opts.out_dir, &lp.world.scenario, &lp.opts.routes)
        .map_err(out_err(ROUTES_FILE))?;
    mrsim_runfolder::write_metrics(&lp.opts.out_dir, &metrics).map_err(|e| match e {
        FileError::Io { source, .. } => out_err(METRICS_FILE)(source),
        FileError::Json { source, .. } => out_err(METRICS_FILE)(source.into()),
    })?;
    Ok(RunOutcome { metrics })
}
