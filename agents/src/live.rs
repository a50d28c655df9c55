//! A robot driven tick by tick by a program that pulls: [`Live::next`]
//! waits for the world's next snapshot and returns the robot's observation
//! (owned), [`Live::reply`] sends the command for it. The protocol is the
//! agent's (join with a token, ready twice, lockstep and realtime, world-gone
//! detection, a clean exit on the run's last snapshot or a termination
//! request): [`crate::run`], what `mrsim agent` runs, is [`drive`] over this,
//! a planner answering each observation.
//!
//! [`LiveAgent`] is the same over iceoryx2, joining a run by its id: what a
//! user's own program (or the Python package) drives a robot with.

use crate::guard::plan_checked;
use crate::seat::{Seat, join_seat};
use crate::{AgentError, AgentExit, AgentOptions};
use mrsim_planners::{
    Command, DesignatedPath, Observation, Params, Planner, Segment, SelfState, Sensed, Vec2,
    lidar::LaserScan,
};
use mrsim_proto::{BodyState, SnapshotHeader, now_ns};
use mrsim_transport::shm::ShmAgent;
use mrsim_transport::{AgentTransport, Namespace};
use std::sync::Arc;
use std::time::Duration;

/// How often (at most) the loop asks its transport whether the process is
/// to stop: 50 ms, so a stop is heard within that and one wait (100 ms).
pub(crate) const STOP_CHECK_EVERY_NS: u64 = 50_000_000;

/// A robot's observation of one tick, owned: what a planner's
/// [`Observation`] borrows, kept (sensing range, field of view, noise and
/// velocity estimation already applied). [`Self::view`] lends the
/// planners' form.
#[derive(Debug, Clone)]
pub struct OwnedObservation {
    /// Tick number.
    pub tick: u64,
    /// Simulated time, s.
    pub time: f64,
    /// Control period, s.
    pub dt: f64,
    /// The robot itself.
    pub me: SelfState,
    /// The robot's goal.
    pub goal: Vec2,
    /// Distance to the goal that counts as reached.
    pub goal_tolerance: f64,
    /// Consecutive ticks within `goal_tolerance` that count as arrival.
    pub goal_hold_ticks: u32,
    /// Bodies within sensing range and field of view.
    pub others: Vec<Sensed>,
    /// Static wall segments (the arena's included), shared for the run.
    pub walls: Arc<[Segment]>,
    /// The robot's designated path, if it has one.
    pub path: Option<Arc<DesignatedPath>>,
    /// The tick's deadline (CLOCK_MONOTONIC ns) in realtime; 0 in lockstep.
    pub deadline_ns: u64,
    /// The robot's laser scan this tick, if its scenario entry has a
    /// `sensor`.
    pub scan: Option<LaserScan>,
}

impl OwnedObservation {
    /// The observation as a [`Planner`] takes it.
    pub fn view(&self) -> Observation<'_> {
        Observation {
            tick: self.tick,
            time: self.time,
            dt: self.dt,
            me: self.me,
            goal: self.goal,
            goal_tolerance: self.goal_tolerance,
            goal_hold_ticks: self.goal_hold_ticks,
            others: &self.others,
            walls: &self.walls,
            path: self.path.as_deref(),
            scan: self.scan.as_ref(),
        }
    }
}

/// What [`Live::next`] (and [`LiveAgent::next`]) found.
#[derive(Debug, Clone)]
pub enum Next {
    /// A tick to answer with [`Live::reply`].
    Observation(Box<OwnedObservation>),
    /// Nothing within the timeout (the world is waiting for others, or
    /// has not started); ask again.
    Idle,
    /// The world ended the run.
    Finished,
    /// The world process is gone (it died or left without ending the run).
    WorldGone,
    /// This process was asked to terminate (SIGINT, SIGTERM).
    Interrupted,
}

/// A tick handed out and not answered yet.
#[derive(Debug, Clone, Copy)]
struct Pending {
    header: SnapshotHeader,
    /// When the agent woke for it, and when its observation began.
    woke: u64,
    began: u64,
}

/// A joined robot answered tick by tick, over any [`AgentTransport`]
/// (given to each call, so the caller keeps the transport).
pub struct Live {
    seat: Seat,
    /// Where a transport that cannot lend its snapshot copies it.
    scratch: (SnapshotHeader, Vec<BodyState>),
    /// When the last snapshot came.
    last_heard: u64,
    /// A snapshot has come (after it, a wake-up without one is spurious).
    heard_one: bool,
    check_after: u64,
    /// When the loop last asked whether it is to stop.
    asked_to_stop_at: u64,
    pending: Option<Pending>,
}

impl Live {
    /// Joins the run over `link` as `opts.robot` and tells the world the
    /// robot is ready. `None` if the process was asked to stop meanwhile.
    pub fn join(
        link: &mut dyn AgentTransport,
        opts: &AgentOptions,
    ) -> Result<Option<Self>, AgentError> {
        match join_seat(link, opts)? {
            Some(seat) => Self::start(link, seat, opts).map(Some),
            None => Ok(None),
        }
    }

    pub(crate) fn start(
        link: &mut dyn AgentTransport,
        seat: Seat,
        opts: &AgentOptions,
    ) -> Result<Self, AgentError> {
        link.send_command(&seat.ready())?;
        link.joined();
        Ok(Self {
            scratch: (SnapshotHeader::default(), Vec::with_capacity(seat.capacity)),
            seat,
            last_heard: now_ns(),
            heard_one: false,
            check_after: u64::try_from(opts.world_check_after.as_nanos()).unwrap_or(u64::MAX),
            asked_to_stop_at: 0,
            pending: None,
        })
    }

    /// The robot's name.
    pub fn robot(&self) -> &str {
        &self.seat.spec.name
    }

    /// The robot's id (its index in the scenario).
    pub fn robot_id(&self) -> usize {
        self.seat.me
    }

    /// The robot's planner parameters as its scenario entry gives them
    /// (for a program that reads its own settings from the scenario).
    pub fn params(&self) -> Params {
        crate::planner_params(&self.seat.spec)
    }

    /// Waits up to `timeout` for the next tick to answer. A tick not
    /// answered before a newer one comes is skipped (in realtime a miss; in
    /// lockstep the world waits for the answer, so none comes).
    pub fn next(
        &mut self,
        link: &mut dyn AgentTransport,
        timeout: Duration,
    ) -> Result<Next, AgentError> {
        let until = now_ns().saturating_add(u64::try_from(timeout.as_nanos()).unwrap_or(u64::MAX));
        loop {
            let now = now_ns();
            if now.saturating_sub(self.asked_to_stop_at) >= STOP_CHECK_EVERY_NS {
                self.asked_to_stop_at = now;
                if link.termination_requested() {
                    return Ok(Next::Interrupted);
                }
            }
            let slice = Duration::from_nanos(until.saturating_sub(now).min(100_000_000));
            link.wait(slice)?;
            let woke = now_ns();
            let (mut finished, mut observed) = (false, None);
            let (seat, heard_one) = (&mut self.seat, &mut self.heard_one);
            let got = link.with_latest_snapshot(&mut self.scratch, &mut |header, bodies, _| {
                *heard_one = true;
                if header.finished != 0 {
                    finished = true;
                } else if seat.due(header, bodies.len()) {
                    let began = now_ns();
                    observed = Some((owned(seat, header, bodies), began));
                }
            })?;
            if !got {
                if woke.saturating_sub(self.last_heard) > self.check_after && !link.world_alive() {
                    return Ok(Next::WorldGone);
                }
                if !self.heard_one {
                    // Before the first snapshot a wake-up is the world's
                    // call to take up the tick's channels (this receive just
                    // did): say ready again, and the world starts the clock
                    // once every agent has.
                    link.send_command(&self.seat.ready())?;
                }
            } else {
                self.last_heard = woke;
                if finished {
                    return Ok(Next::Finished);
                }
                if let Some((obs, began)) = observed {
                    self.pending = Some(Pending {
                        header: header_of(&obs),
                        woke,
                        began,
                    });
                    return Ok(Next::Observation(Box::new(obs)));
                }
            }
            if woke >= until {
                return Ok(Next::Idle);
            }
        }
    }

    /// Answers the tick [`Self::next`] last handed out with `cmd`. A
    /// non-finite command is sent as it is: the world refuses it, counts it
    /// (`commands_rejected`) and the robot brakes.
    pub fn reply(&mut self, link: &mut dyn AgentTransport, cmd: Command) -> Result<(), AgentError> {
        let p = self.pending.take().ok_or(AgentError::NothingToAnswer)?;
        let sent = now_ns();
        self.seat.send(
            &p.header,
            cmd,
            [sent.saturating_sub(p.began), p.woke, sent],
            &mut |m| link.send_command(m),
        )
    }

    /// Ends the robot's control: writes out its diagnostics.
    pub fn finish(mut self, exit: AgentExit) -> Result<AgentExit, AgentError> {
        self.seat.finish(exit)
    }
}

/// The observation of a snapshot, owned.
fn owned(seat: &mut Seat, header: &SnapshotHeader, bodies: &[BodyState]) -> OwnedObservation {
    let (walls, path) = (seat.walls.clone(), seat.path.clone());
    let o = seat.observe_among(header, bodies, None);
    OwnedObservation {
        tick: o.tick,
        time: o.time,
        dt: o.dt,
        me: o.me,
        goal: o.goal,
        goal_tolerance: o.goal_tolerance,
        goal_hold_ticks: o.goal_hold_ticks,
        others: o.others.to_vec(),
        walls,
        path,
        deadline_ns: header.deadline_ns,
        scan: o.scan.cloned(),
    }
}

/// What answering a tick needs of its snapshot's header.
fn header_of(o: &OwnedObservation) -> SnapshotHeader {
    SnapshotHeader {
        tick: o.tick,
        sim_time: o.time,
        deadline_ns: o.deadline_ns,
        ..Default::default()
    }
}

/// Answers every tick of `live` with `planner` until the run ends: the
/// loop of `mrsim agent`. A planner that panics or returns a non-finite
/// command fails the robot at that tick ([`crate::guard`]): in lockstep the
/// loop ends with that error, in realtime the tick is a miss and the first
/// failure is the error at the end.
pub fn drive(
    link: &mut dyn AgentTransport,
    live: &mut Live,
    planner: &mut dyn Planner,
) -> Result<AgentExit, AgentError> {
    loop {
        match live.next(link, Duration::from_millis(100))? {
            Next::Observation(obs) => match plan_checked(planner, &obs.view()) {
                Ok(cmd) => {
                    live.reply(link, cmd)?;
                    if live.seat.wants_diagnostics() {
                        live.seat
                            .diagnostics(obs.tick, obs.time, planner.diagnostics());
                    }
                }
                Err(what) => {
                    live.pending = None;
                    live.seat.failed(obs.tick, what)?;
                }
            },
            Next::Idle => {}
            Next::Finished => return Ok(AgentExit::Finished),
            Next::Interrupted => return Ok(AgentExit::Interrupted),
            Next::WorldGone => return Err(AgentError::WorldGone),
        }
    }
}

/// A robot of a running world driven by this program, over iceoryx2: what
/// `mrsim agent` does, with the planning left to the caller.
///
/// ```no_run
/// use mrsim_agents::{LiveAgent, Next};
/// use mrsim_planners::Command;
/// use std::time::Duration;
///
/// let mut agent = LiveAgent::join("lab1", "me", Duration::from_secs(30))?;
/// loop {
///     match agent.next(Duration::from_millis(100))? {
///         Next::Observation(obs) => {
///             let towards = obs.goal - obs.me.position;
///             agent.reply(Command::Velocity(towards.cap_magnitude(obs.me.max_speed)))?;
///         }
///         Next::Idle => {}
///         _ => break,
///     }
/// }
/// # Ok::<(), mrsim_agents::AgentError>(())
/// ```
pub struct LiveAgent {
    link: ShmAgent,
    live: Option<Live>,
}

impl LiveAgent {
    /// Joins run `run_id` (the world's `--run`) as robot `robot`, waiting up
    /// to `timeout` for the world and for the join.
    pub fn join(run_id: &str, robot: &str, timeout: Duration) -> Result<Self, AgentError> {
        let mut opts = AgentOptions::new(robot);
        opts.join_timeout = timeout;
        Self::join_with(run_id, &opts)
    }

    /// [`Self::join`] with every option.
    pub fn join_with(run_id: &str, opts: &AgentOptions) -> Result<Self, AgentError> {
        let ns = Namespace::new(run_id).map_err(|e| AgentError::BadRunId(e.to_string()))?;
        let node = format!("mrsim-agent-{}", opts.robot);
        let mut link = ShmAgent::connect(&ns, &node, opts.join_timeout).map_err(|source| {
            AgentError::NoWorld {
                run_id: run_id.to_string(),
                source,
            }
        })?;
        let live = Live::join(&mut link, opts)?.ok_or(AgentError::Interrupted)?;
        Ok(Self {
            link,
            live: Some(live),
        })
    }

    /// The robot's name.
    pub fn robot(&self) -> &str {
        self.live.as_ref().map_or("", Live::robot)
    }

    /// The robot's planner parameters from its scenario entry.
    pub fn params(&self) -> Params {
        self.live.as_ref().map(Live::params).unwrap_or_default()
    }

    /// Waits up to `timeout` for the next tick to answer ([`Live::next`]).
    pub fn next(&mut self, timeout: Duration) -> Result<Next, AgentError> {
        let live = self.live.as_mut().ok_or(AgentError::NothingToAnswer)?;
        live.next(&mut self.link, timeout)
    }

    /// Answers the tick [`Self::next`] last handed out ([`Live::reply`]).
    pub fn reply(&mut self, cmd: Command) -> Result<(), AgentError> {
        let live = self.live.as_mut().ok_or(AgentError::NothingToAnswer)?;
        live.reply(&mut self.link, cmd)
    }

    /// Answers every tick with `planner` until the run ends, as `mrsim
    /// agent` does ([`drive`]), and ends the robot's control.
    pub fn drive(mut self, planner: &mut dyn Planner) -> Result<AgentExit, AgentError> {
        let mut live = self.live.take().ok_or(AgentError::NothingToAnswer)?;
        let exit = drive(&mut self.link, &mut live, planner);
        match exit {
            Ok(exit) => live.finish(exit),
            Err(e) => {
                let _ = live.finish(AgentExit::Finished);
                Err(e)
            }
        }
    }
}

impl Drop for LiveAgent {
    fn drop(&mut self) {
        if let Some(live) = self.live.take() {
            let _ = live.finish(AgentExit::Finished);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mrsim_proto::{JoinReply, PROTOCOL_VERSION, command_kind};
    use mrsim_transport::WorldTransport;
    use mrsim_transport::inproc::{InprocAgent, InprocWorld};
    use std::sync::atomic::AtomicBool;

    /// A world side with one robot `a` (planner `external`) and its
    /// agent's side, the setup published.
    fn world() -> (InprocWorld, InprocAgent) {
        let scenario = mrsim_scenario::parse(
            r#"
            name = "live"
            [world]
            arena = { min = [0.0, 0.0], max = [10.0, 10.0] }
            [[robot]]
            name = "a"
            start = [1.0, 5.0]
            goal = [9.0, 5.0]
            planner = "external"
            params = { gain = 2.0 }
            "#,
            "live.toml",
        )
        .expect("scenario")
        .scenario;
        let (mut world, mut sides) =
            mrsim_transport::inproc::channels(1, Arc::new(AtomicBool::new(false)));
        let setup = serde_json::json!({"run_id": "live", "out_dir": null, "scenario": scenario});
        world
            .publish_setup(setup.to_string().as_bytes())
            .expect("setup");
        let side = sides.pop().expect("one side");
        (world, side)
    }

    /// Answers the first join request with token 7.
    fn admit(world: &mut InprocWorld) {
        let mut asked = None;
        while asked.is_none() {
            world.wait(Duration::from_millis(10)).expect("wait");
            world.drain_joins(&mut |r| asked = Some(r)).expect("joins");
        }
        let asked = asked.expect("a join request");
        world
            .reply_join(&JoinReply {
                nonce: asked.nonce,
                accepted: 1,
                robot_id: 0,
                token: 7,
                protocol_version: PROTOCOL_VERSION,
                world_pid: std::process::id(),
                reason: Default::default(),
            })
            .expect("reply");
    }

    fn commands(world: &mut InprocWorld) -> Vec<mrsim_proto::CommandMsg> {
        let mut got = Vec::new();
        world
            .drain_commands(&mut |c, _| got.push(c))
            .expect("drain");
        got
    }

    #[test]
    fn a_live_robot_gets_each_tick_owned_and_answers_it_once_with_its_token() {
        let (mut world, mut side) = world();
        let agent = std::thread::spawn(move || {
            let mut live = Live::join(&mut side, &AgentOptions::new("a"))
                .expect("join")
                .expect("not interrupted");
            assert_eq!(live.robot(), "a");
            assert!(live.params().contains_key("gain"));
            let mut seen = Vec::new();
            loop {
                match live.next(&mut side, Duration::from_secs(5)).expect("next") {
                    Next::Observation(obs) => {
                        let view = obs.view();
                        assert_eq!((view.goal.x, view.goal.y), (9.0, 5.0));
                        assert_eq!(view.walls.len(), 4, "the arena's walls");
                        seen.push(obs.tick);
                        live.reply(&mut side, Command::Velocity(Vec2::new(1.0, 0.0)))
                            .expect("reply");
                        assert!(matches!(
                            live.reply(&mut side, Command::Velocity(Vec2::zeros())),
                            Err(AgentError::NothingToAnswer)
                        ));
                    }
                    Next::Idle => {}
                    Next::Finished => break,
                    other => panic!("{other:?}"),
                }
            }
            live.finish(AgentExit::Finished).expect("finish");
            seen
        });
        admit(&mut world);
        world.joins_answered().expect("answered");
        // The ready command, then one answer per tick.
        let mut ready = Vec::new();
        while ready.is_empty() {
            world.wait(Duration::from_millis(10)).expect("wait");
            ready = commands(&mut world);
        }
        assert_eq!(ready[0].kind, command_kind::READY);
        let bodies = [BodyState {
            position: [1.0, 5.0],
            ..Default::default()
        }];
        for tick in 0..3 {
            let header = SnapshotHeader {
                tick,
                ..Default::default()
            };
            world.publish_snapshot(&header, &bodies).expect("snapshot");
            let mut got = Vec::new();
            while got
                .iter()
                .all(|c: &mrsim_proto::CommandMsg| c.tick != tick || c.kind == command_kind::READY)
            {
                world.wait(Duration::from_millis(10)).expect("wait");
                got.extend(commands(&mut world));
            }
            let answer = got
                .iter()
                .find(|c| c.kind == command_kind::VELOCITY)
                .expect("answer");
            assert_eq!(
                (answer.tick, answer.token, answer.value),
                (tick, 7, [1.0, 0.0])
            );
        }
        let end = SnapshotHeader {
            finished: 1,
            ..Default::default()
        };
        world.publish_snapshot(&end, &[]).expect("the end");
        assert_eq!(agent.join().expect("agent thread"), [0, 1, 2]);
    }
}
