//! A robot's seat in a run: what joining gives an agent (its id and token,
//! its scenario entry, the static geometry, its observer and diagnostics;
//! built here from the run's setup that `join.rs` reads) and what every way
//! of driving the robot does with it each tick: observe a snapshot, turn a
//! command into the wire message, send it (through the fault injector in
//! tests), note a planner's failure, and, with a planner, all of these at
//! once ([`Seat::answer`]). The planner itself is not kept here: a
//! [`crate::Driver`] pairs a seat with one, a [`crate::Live`] drives seats
//! with planners or hands their observations to whatever program answers.

use crate::guard::{Halt, PlanFailure, PlanFault, plan_checked};
use crate::{AgentError, AgentExit, AgentOptions, diagnostics, fault, observe};
use mrsim_planners::{
    Command, DesignatedPath, Observation, Planner, Registry, Segment, Shape, Vec2,
};
use mrsim_proto::{BodyState, CommandMsg, JoinReply, SnapshotHeader, command_kind, now_ns};
use mrsim_scenario::timing::{CallStatus, Clerk, RecordedCall, Timing};
use mrsim_scenario::{RobotSpec, WorldConfig};
use mrsim_transport::TransportError;
use std::collections::{BTreeMap, VecDeque};
use std::sync::Arc;

/// One joined robot, without its planner.
pub(crate) struct Seat {
    pub(crate) me: usize,
    /// The robot id put in commands (another one only in fault tests).
    claim: u32,
    token: u64,
    robot_count: usize,
    pub(crate) capacity: usize,
    pub(crate) spec: RobotSpec,
    pub(crate) path: Option<Arc<DesignatedPath>>,
    /// What its route goes around (`route = "shortest"` only).
    route: Option<crate::route::RouteScene>,
    observer: observe::Observer,
    diag: Option<diagnostics::DiagnosticsWriter>,
    answered: Option<u64>,
    injector: Option<fault::Injector>,
    hung: bool,
    lockstep: bool,
    halt: Option<Halt>,
    /// The first failure of the planner in a realtime run (reported at
    /// the end; the run goes on, each failed tick a miss).
    failed: Option<PlanFailure>,
    /// The robot's timing model or recorded calls, if any.
    timed: Option<Timed>,
    /// Realtime under `[world.cpus]`: the scheduling policy its agent
    /// takes ([`crate::cores`]).
    pub(crate) policy: Option<mrsim_sys::policy::Policy>,
    /// Realtime: the calling thread's CPU clock when the current planner
    /// call began (taken by the command that answers it).
    call_cpu_ns: Option<u64>,
    /// Lockstep: the CPU of the current call as the model or the record
    /// has it (sent instead of a measurement, so the run's timing.csv is
    /// the same whatever the machine).
    model_cpu_ns: Option<u64>,
}

/// How timing drives one robot's planner (`mrsim_scenario::timing`).
struct Timed {
    how: TimedBy,
    /// The age of the state shown, in ticks, and the snapshots kept for it
    /// (the newest last).
    delay_ticks: u64,
    history: VecDeque<(SnapshotHeader, Vec<BodyState>)>,
}

/// Where a robot's timing comes from.
enum TimedBy {
    /// Lockstep: the clerk decides from the model.
    Modelled(Clerk),
    /// Realtime: the model is spent for real.
    Spent { timing: Timing, seed: u64 },
    /// Lockstep under `[world.cpus]`, CPU work: the world's model of the
    /// cores decides; the planner reads a snapshot that marks it
    /// ([`mrsim_proto::flags::PLANS`]) and the world takes the send time
    /// from the model.
    Cored { timing: Timing, seed: u64 },
    /// A recorded run's planner calls (`mrsim rerun`), by tick; `deadline_ns`
    /// after publication is the tick's deadline.
    Replayed {
        calls: BTreeMap<u64, RecordedCall>,
        deadline_ns: u64,
    },
}

impl Timed {
    /// The timing of the robot `spec` (index `me`) in a run of `world`'s
    /// settings, if it has a model or replays a record.
    fn of(spec: &RobotSpec, me: usize, world: &WorldConfig) -> Option<Self> {
        let lockstep = world.mode == mrsim_scenario::Mode::Lockstep;
        let how = match (&spec.replay, &spec.timing) {
            (Some(calls), _) => TimedBy::Replayed {
                calls: calls.iter().map(|c| (c.tick, *c)).collect(),
                deadline_ns: mrsim_scenario::timing::s_to_ns(world.dt * world.deadline),
            },
            (None, Some(t)) if lockstep && t.cpu && world.cpus.is_some() => TimedBy::Cored {
                timing: t.clone(),
                seed: world.seed,
            },
            (None, Some(t)) if lockstep => {
                TimedBy::Modelled(Clerk::new(t.clone(), world.seed, me as u64, world.dt))
            }
            (None, Some(t)) => TimedBy::Spent {
                timing: t.clone(),
                seed: world.seed,
            },
            (None, None) => return None,
        };
        let delay_ticks = spec
            .timing
            .as_ref()
            .map_or(0, |t| t.observation_delay_ticks(world.dt));
        Some(Self {
            how,
            delay_ticks,
            history: VecDeque::new(),
        })
    }
}

/// What the planner does with one snapshot, timing considered.
enum Step {
    /// No timing: plan and send as soon as done.
    Plain,
    /// Not this tick (busy, off period, snapshot lost, not in the record):
    /// in lockstep answered with [`command_kind::NONE`].
    Skip,
    /// Plan; in lockstep the command is sent `start_ns` into the tick plus
    /// the modelled compute time.
    Modelled { start_ns: u64 },
    /// Plan; the command is sent as recorded.
    Replayed(RecordedCall),
    /// Plan, then spend the model's compute time for real (realtime).
    Spent,
    /// Plan; the world's model of the cores says when it is sent.
    Cored,
}

/// The walls every robot of the run whose setup is `view` sees (its
/// `[[wall]]`s, map and arena), shared by the seats of one process.
pub(crate) fn walls(view: &SetupView<'_>) -> Arc<[Segment]> {
    observe::walls_of(&view.scenario.walls, view.scenario.world.arena)
}

/// Every body's shape by id in the run whose setup is `view` (robots, then
/// obstacles), shared by the seats of one process; empty when all are
/// discs. Only the entries that name a `shape` are read again (a run of
/// discs reads none).
pub(crate) fn shapes(view: &SetupView<'_>) -> Result<Arc<[Shape]>, AgentError> {
    let s = &view.scenario;
    let bodies = || s.robots.iter().chain(&s.obstacles);
    // Any entry with a `shape` key has the word in its text (a disc's is
    // left out of the setup); the entries that do are parsed for it.
    if !bodies().any(|raw| raw.get().contains("\"shape\"")) {
        return Ok(Arc::new([]));
    }
    #[derive(serde::Deserialize)]
    struct Entry {
        #[serde(default)]
        radius: f64,
        #[serde(default)]
        shape: mrsim_scenario::ShapeSpec,
    }
    bodies()
        .map(|raw| {
            let e: Entry = serde_json::from_str(raw.get())
                .map_err(|e| AgentError::BadSetup(format!("a body's shape: {e}")))?;
            Ok(e.shape.shape(e.radius))
        })
        .collect()
}

/// The seat of the robot the world gave `reply` in the run whose setup is
/// `view`, joined under `opts`, among `walls` and the bodies' `shapes`.
pub(crate) fn seat_of(
    view: &SetupView<'_>,
    walls: &Arc<[Segment]>,
    shapes: &Arc<[Shape]>,
    reply: &JoinReply,
    opts: &AgentOptions,
) -> Result<Seat, AgentError> {
    let me = reply.robot_id as usize;
    let scenario = &view.scenario;
    let spec: RobotSpec = scenario
        .robots
        .get(me)
        .ok_or_else(|| AgentError::BadSetup(format!("no robot with id {me}")))
        .and_then(|raw| {
            serde_json::from_str(raw.get()).map_err(|e| AgentError::BadSetup(e.to_string()))
        })?;
    let path = (!spec.path.is_empty()).then(|| {
        Arc::new(DesignatedPath {
            points: spec.path.iter().map(|p| Vec2::new(p[0], p[1])).collect(),
            boundary: spec.boundary.unwrap_or(f64::INFINITY),
        })
    });
    let robot_count = scenario.robots.len();
    let capacity = robot_count + scenario.obstacles.len();
    let route = match spec.route {
        mrsim_scenario::Route::Direct => None,
        mrsim_scenario::Route::Shortest => {
            let obstacles = scenario
                .obstacles
                .iter()
                .map(|raw| serde_json::from_str(raw.get()))
                .collect::<Result<Vec<mrsim_scenario::ObstacleSpec>, _>>()
                .map_err(|e| AgentError::BadSetup(e.to_string()))?;
            let res = scenario
                .map
                .as_ref()
                .map(|m| m.resolution * scenario.length_unit.per_metre());
            Some(crate::route::RouteScene::from_segments(
                walls, &obstacles, res,
            ))
        }
    };
    let observer = observe::Observer::for_robot(
        &scenario.world,
        Some(&spec),
        me,
        capacity,
        walls.clone(),
        shapes.clone(),
    );
    let diag = start_diagnostics(view.out_dir.as_deref(), me, &spec.name);
    let timed = Timed::of(&spec, me, &scenario.world);
    let policy = policy_of(scenario, me)?;
    Ok(Seat {
        timed,
        policy,
        call_cpu_ns: None,
        model_cpu_ns: None,
        me,
        claim: opts.impersonate.unwrap_or(me as u32),
        token: reply.token,
        robot_count,
        capacity,
        lockstep: scenario.world.mode == mrsim_scenario::Mode::Lockstep,
        diag,
        spec,
        path,
        route,
        observer,
        answered: None,
        injector: opts.fault.map(fault::Injector::new),
        hung: false,
        halt: opts.halt.clone(),
        failed: None,
    })
}

/// Realtime under `[world.cpus]`: the policy of robot `me`'s agent
/// ([`crate::cores::policies`]); every robot's name and timing are read
/// only under `fifo`, where rate-monotonic ranks them all.
fn policy_of(
    scenario: &ScenarioView<'_>,
    me: usize,
) -> Result<Option<mrsim_sys::policy::Policy>, AgentError> {
    let Some(cpus) = scenario
        .world
        .cpus
        .filter(|_| crate::cores::real(&scenario.world))
    else {
        return Ok(None);
    };
    #[derive(serde::Deserialize)]
    struct Entry {
        name: String,
        #[serde(default)]
        timing: Option<Timing>,
    }
    let parse = |raw: &serde_json::value::RawValue| {
        serde_json::from_str::<Entry>(raw.get()).map_err(|e| AgentError::BadSetup(e.to_string()))
    };
    let entries: Vec<Entry> = match cpus.scheduler {
        mrsim_scenario::Scheduler::Fifo => scenario
            .robots
            .iter()
            .map(|r| parse(r))
            .collect::<Result<_, _>>()?,
        _ => {
            let raw = scenario
                .robots
                .get(me)
                .ok_or_else(|| AgentError::BadSetup(format!("no robot with id {me}")))?;
            vec![parse(raw)?]
        }
    };
    let mine = if entries.len() == 1 { 0 } else { me };
    let robots: Vec<(&str, Option<&Timing>)> = entries
        .iter()
        .map(|e| (e.name.as_str(), e.timing.as_ref()))
        .collect();
    Ok(crate::cores::policies(cpus.scheduler, &robots)
        .get(mine)
        .copied())
}

/// The planner's diagnostics go to a part file in the run's folder, when
/// the world's folder is reachable from here (same machine).
fn start_diagnostics(
    out_dir: Option<&str>,
    me: usize,
    robot: &str,
) -> Option<diagnostics::DiagnosticsWriter> {
    let dir = out_dir
        .map(std::path::PathBuf::from)
        .filter(|d| d.is_dir())?;
    match diagnostics::DiagnosticsWriter::start(&dir, me, robot) {
        Ok(w) => Some(w),
        Err(e) => {
            eprintln!("agent {robot}: no diagnostics: {e}");
            None
        }
    }
}

/// The part of the world's setup an agent reads. Only its own robot's
/// entry is parsed (the others are skipped as raw text, nothing built): a
/// thousand agents each building all thousand robots' specs cost O(n²) at
/// join, seconds on two cores.
#[derive(serde::Deserialize)]
pub(crate) struct SetupView<'a> {
    #[serde(borrow)]
    scenario: ScenarioView<'a>,
    #[serde(default)]
    out_dir: Option<String>,
}

/// [`mrsim_scenario::Scenario`] as an agent needs it.
#[derive(serde::Deserialize)]
pub(crate) struct ScenarioView<'a> {
    world: mrsim_scenario::WorldConfig,
    #[serde(borrow)]
    robots: Vec<&'a serde_json::value::RawValue>,
    /// Parsed only for a robot with a route (their number counts).
    #[serde(default, borrow)]
    obstacles: Vec<&'a serde_json::value::RawValue>,
    #[serde(default)]
    walls: Vec<mrsim_scenario::WallSpec>,
    #[serde(default)]
    map: Option<mrsim_scenario::MapInfo>,
    #[serde(default)]
    length_unit: mrsim_scenario::LengthUnit,
}

impl Seat {
    /// Builds the robot's planner from `registry`.
    pub(crate) fn build_planner(
        &self,
        registry: &Registry,
    ) -> Result<Box<dyn Planner>, AgentError> {
        let fail = |source| AgentError::Planner {
            robot: self.spec.name.clone(),
            source,
        };
        let planner = crate::build_planner_in(registry, &self.spec).map_err(fail)?;
        let Some(scene) = &self.route else {
            return Ok(crate::fit_goal_heading(&self.spec, planner));
        };
        let planner = crate::route::fit_route(planner, &self.spec, scene).map_err(|e| {
            fail(mrsim_planners::BuildError::Other(format!(
                "route from start to goal: {e}"
            )))
        })?;
        Ok(crate::fit_goal_heading(&self.spec, planner))
    }

    /// The message telling the world this robot's agent is ready.
    pub(crate) fn ready(&self) -> CommandMsg {
        let now = now_ns();
        CommandMsg {
            // Its own robot even when impersonating (fault tests): the
            // world must start the run to see the forged commands.
            robot_id: self.me as u32,
            kind: command_kind::READY,
            token: self.token,
            tick: 0,
            value: [0.0, 0.0],
            compute_ns: 0,
            woke_ns: now,
            sent_ns: now,
            ..CommandMsg::default()
        }
    }

    /// True if this snapshot (not the run's last) is one to answer: not
    /// answered yet, with this robot in it, and the agent not hung (a
    /// fault test's process fault due at this tick runs here).
    pub(crate) fn due(&mut self, header: &SnapshotHeader, bodies: usize) -> bool {
        if self.hung || self.answered.is_some_and(|t| t >= header.tick) || self.me >= bodies {
            return false;
        }
        if let Some(inj) = self.injector.as_mut() {
            self.hung = inj.before_plan(header.tick) == fault::Before::Hang;
        }
        !self.hung
    }

    /// The observation of this snapshot, looking only at the bodies of
    /// indices `near` when given (see [`observe::Observer::observe_among`]).
    pub(crate) fn observe_among(
        &mut self,
        header: &SnapshotHeader,
        bodies: &[BodyState],
        near: Option<&[u32]>,
    ) -> Observation<'_> {
        self.observer
            .observe_among(header, bodies, near, &self.spec, self.path.as_deref())
    }

    /// The run's walls, all of them (an observation holds those within
    /// the sensing range).
    pub(crate) fn walls(&self) -> &Arc<[Segment]> {
        self.observer.walls()
    }

    /// Sends `cmd` as this robot's answer to `tick` (through the fault
    /// injector in fault tests) and notes the tick answered.
    pub(crate) fn send(
        &mut self,
        header: &SnapshotHeader,
        cmd: Command,
        times: [u64; 3],
        send: &mut dyn FnMut(&CommandMsg) -> Result<(), TransportError>,
    ) -> Result<(), AgentError> {
        self.send_as(header, cmd, times, false, send)
    }

    /// [`Seat::send`], as a command lost on its way when `lost`.
    fn send_as(
        &mut self,
        header: &SnapshotHeader,
        cmd: Command,
        times: [u64; 3],
        lost: bool,
        send: &mut dyn FnMut(&CommandMsg) -> Result<(), TransportError>,
    ) -> Result<(), AgentError> {
        let [compute_ns, woke_ns, sent_ns] = times;
        let (kind, v) = match cmd {
            _ if lost => (command_kind::LOST, cmd_value(cmd)),
            Command::Force(f) => (command_kind::FORCE, f),
            Command::Velocity(v) => (command_kind::VELOCITY, v),
            Command::Unicycle { v, omega } => (command_kind::UNICYCLE, Vec2::new(v, omega)),
            Command::Ackermann { speed, steering } => {
                (command_kind::ACKERMANN, Vec2::new(speed, steering))
            }
        };
        // Realtime: the CPU the planner call took on this thread, and
        // under SCHED_DEADLINE the overruns so far.
        let measured = self.call_cpu_ns.take().map_or(0, |start| {
            mrsim_sys::cpu::thread_cpu_ns().saturating_sub(start)
        });
        let cpu_ns = self.model_cpu_ns.take().unwrap_or(measured);
        let overruns = match self.policy {
            Some(mrsim_sys::policy::Policy::Deadline { .. }) => {
                u32::try_from(mrsim_sys::policy::overruns()).unwrap_or(u32::MAX)
            }
            _ => 0,
        };
        let msg = CommandMsg {
            robot_id: self.claim,
            kind,
            token: self.token,
            tick: header.tick,
            value: [v.x, v.y],
            compute_ns,
            woke_ns,
            sent_ns,
            cpu_ns,
            overruns,
            ..CommandMsg::default()
        };
        match &self.injector {
            Some(inj) => {
                for m in inj.corrupt(msg, self.robot_count, header.deadline_ns) {
                    send(&m)?;
                }
            }
            None => send(&msg)?,
        }
        self.answered = Some(header.tick);
        Ok(())
    }

    /// Plans with `planner` on one snapshot (not the run's last) and hands
    /// the command to `send`: what [`crate::Driver::on_snapshot_among`]
    /// documents (`near`, `woke`, `start` and the clock returned), for
    /// every robot driven by a planner.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn answer(
        &mut self,
        planner: &mut dyn Planner,
        header: &SnapshotHeader,
        bodies: &[BodyState],
        near: Option<&[u32]>,
        woke: u64,
        start: Option<u64>,
        send: &mut dyn FnMut(&CommandMsg) -> Result<(), TransportError>,
    ) -> Result<u64, AgentError> {
        if !self.due(header, bodies.len()) {
            return Ok(start.unwrap_or(woke));
        }
        let t0 = start.unwrap_or_else(now_ns);
        if !self.lockstep {
            self.call_cpu_ns = Some(mrsim_sys::cpu::thread_cpu_ns());
        }
        let step = self.step(header, bodies);
        if matches!(step, Step::Skip) {
            self.answered = Some(header.tick);
            if self.lockstep {
                send(&self.no_command(header))?;
            }
            return Ok(now_ns());
        }
        let obs = match self.timed.as_ref().filter(|t| t.delay_ticks > 0) {
            Some(t) => {
                // The newest at least `delay_ticks` old (or the run's
                // first).
                let (h, b) = &t.history[0];
                self.observer
                    .observe_among(h, b, None, &self.spec, self.path.as_deref())
            }
            None => {
                self.observer
                    .observe_among(header, bodies, near, &self.spec, self.path.as_deref())
            }
        };
        let sensed = obs.others.len();
        let cmd = match plan_checked(planner, &obs) {
            Ok(cmd) => cmd,
            Err(what) => {
                self.failed(header.tick, what)?;
                return Ok(now_ns());
            }
        };
        let t1 = now_ns();
        let (sent, lost) = self.sent(&step, header, t0, t1, sensed);
        self.send_as(header, cmd, [t1.saturating_sub(t0), woke, sent], lost, send)?;
        // After the command is out: off the tick's critical path (asking a
        // planner for its diagnostics costs it something).
        if let Some(d) = &mut self.diag {
            d.record(header.tick, header.sim_time, &*planner);
        }
        Ok(t1)
    }

    /// What the planner does with this snapshot, timing considered (and
    /// the snapshot kept for an observation delay).
    fn step(&mut self, header: &SnapshotHeader, bodies: &[BodyState]) -> Step {
        let Some(t) = self.timed.as_mut() else {
            return Step::Plain;
        };
        if t.delay_ticks > 0 {
            // Keep the newest snapshot at least `delay_ticks` old and those
            // after it: the first is the one shown.
            t.history.push_back((*header, bodies.to_vec()));
            let shown = header.tick.saturating_sub(t.delay_ticks);
            while t.history.len() > 1 && t.history[1].0.tick <= shown {
                t.history.pop_front();
            }
        }
        let tick = header.tick;
        let me = self.me as u64;
        match &t.how {
            TimedBy::Modelled(clerk) => match clerk.turn(tick) {
                mrsim_scenario::timing::Turn::Plan { start_ns } => Step::Modelled { start_ns },
                _ => Step::Skip,
            },
            TimedBy::Cored { .. } => {
                let marked = bodies
                    .get(self.me)
                    .is_some_and(|b| b.flags & mrsim_proto::flags::PLANS != 0);
                if marked { Step::Cored } else { Step::Skip }
            }
            TimedBy::Spent { timing, seed } => match timing.skips(*seed, me, tick) {
                Some(_) => Step::Skip,
                None => Step::Spent,
            },
            TimedBy::Replayed { calls, .. } => match calls.get(&tick) {
                Some(c) => Step::Replayed(*c),
                None => Step::Skip,
            },
        }
    }

    /// When the command of a planner call that began at `t0` and ended at
    /// `t1` (this clock) is sent, and whether it is lost: modelled,
    /// replayed, or now after spending the model's compute time.
    fn sent(
        &mut self,
        step: &Step,
        header: &SnapshotHeader,
        t0: u64,
        t1: u64,
        sensed: usize,
    ) -> (u64, bool) {
        let me = self.me as u64;
        let call_cpu_ns = self
            .call_cpu_ns
            .unwrap_or_else(mrsim_sys::cpu::thread_cpu_ns);
        match (step, self.timed.as_mut().map(|t| &mut t.how)) {
            (Step::Modelled { start_ns }, Some(TimedBy::Modelled(clerk))) => {
                let s = clerk.planned(header.tick, *start_ns, sensed);
                self.model_cpu_ns = Some(s.cpu_ns);
                (header.published_ns + s.sent_ns, s.lost)
            }
            (Step::Cored, Some(TimedBy::Cored { timing, seed })) => (
                header.published_ns,
                timing.command_lost(*seed, me, header.tick),
            ),
            (Step::Replayed(c), Some(TimedBy::Replayed { deadline_ns, .. })) => {
                // A late answer stays late, however soon it was sent (the
                // world may have closed the tick before it arrived).
                let sent = match c.status {
                    CallStatus::Late => c.sent_ns.max(*deadline_ns + 1),
                    _ => c.sent_ns,
                };
                self.model_cpu_ns = Some(c.cpu_ns);
                (header.published_ns + sent, c.status == CallStatus::Lost)
            }
            (Step::Spent, Some(TimedBy::Spent { timing, seed })) => {
                let drawn = timing.compute_ns(*seed, me, header.tick, sensed);
                if timing.cpu {
                    // CPU work: done when the thread has used the drawn
                    // time since the call began, the planner's own CPU
                    // included; preemption stretches it.
                    mrsim_sys::cpu::burn_until(call_cpu_ns, drawn);
                } else {
                    let due = t0 + drawn;
                    if due > t1 {
                        std::thread::sleep(std::time::Duration::from_nanos(due - t1));
                    }
                }
                (now_ns(), timing.command_lost(*seed, me, header.tick))
            }
            _ => (t1, false),
        }
    }

    /// The lockstep answer of a tick the planner does not plan on.
    fn no_command(&self, header: &SnapshotHeader) -> CommandMsg {
        CommandMsg {
            robot_id: self.claim,
            kind: command_kind::NONE,
            token: self.token,
            tick: header.tick,
            value: [0.0, 0.0],
            compute_ns: 0,
            woke_ns: header.published_ns,
            sent_ns: header.published_ns,
            ..CommandMsg::default()
        }
    }

    /// The planner failed at `tick`. Lockstep: the robot answers no more,
    /// the run's [`Halt`] (in-process) stops the run, and the error names
    /// the robot and the tick. Realtime: the tick goes unanswered (a miss,
    /// the scenario's `on_deadline_miss` applies) and the run goes on; the
    /// first failure is reported at the end.
    pub(crate) fn failed(&mut self, tick: u64, what: PlanFault) -> Result<(), AgentError> {
        let failure = PlanFailure {
            robot: self.spec.name.clone(),
            tick,
            what,
        };
        self.answered = Some(tick);
        if !self.lockstep {
            self.failed.get_or_insert(failure);
            return Ok(());
        }
        self.hung = true;
        if let Some(h) = &self.halt {
            h.raise(&failure);
        }
        Err(AgentError::Plan(failure))
    }

    /// Ends the robot's control: writes out its diagnostics; a planner
    /// that failed in a realtime run is reported now.
    pub(crate) fn finish(&mut self, exit: AgentExit) -> Result<AgentExit, AgentError> {
        if let Some(Err(e)) = self.diag.take().map(diagnostics::DiagnosticsWriter::finish) {
            eprintln!(
                "agent {}: diagnostics not fully written: {e}",
                self.spec.name
            );
        }
        match self.failed.take() {
            Some(f) => Err(AgentError::Plan(f)),
            None => Ok(exit),
        }
    }
}

/// A command's two numbers.
fn cmd_value(cmd: Command) -> Vec2 {
    match cmd {
        Command::Force(v) | Command::Velocity(v) => v,
        Command::Unicycle { v, omega } => Vec2::new(v, omega),
        Command::Ackermann { speed, steering } => Vec2::new(speed, steering),
    }
}
