//! The agent's one per-tick loop, over the robots this process drives (a
//! group of one for `mrsim agent --robot`, [`LiveAgent`] and the Python
//! package; several for `mrsim agent --robots`): wait for the world's next
//! snapshot, ask every so often whether the process is to stop, notice a
//! world that is gone, say ready again until the first snapshot comes, end
//! on the run's last snapshot. What each snapshot is for is the caller's:
//!
//! - pull: [`Live::next`] returns a robot's observation (owned) and
//!   [`Live::reply`] sends the command for it (a user's own program;
//!   [`LiveAgent`] is this over iceoryx2, joining a run by its id);
//! - push: [`drive`] answers every robot's observation with its planner
//!   within the snapshot (what `mrsim agent` runs: [`crate::run`],
//!   [`crate::run_group`]).
//!
//! The observations of a group of more than one robot look only at the
//! bodies a neighbour grid (`mrsim-spatial`, one built per snapshot) puts
//! near each robot: the same bodies in the same order as a full scan, so
//! the commands are those of one process per robot.

use crate::join::join_seat;
use crate::seat::Seat;
use crate::{AgentError, AgentExit, AgentOptions};
use mrsim_planners::{
    Command, DesignatedPath, Observation, Params, Planner, Segment, SelfState, Sensed, Vec2,
    lidar::LaserScan,
};
use mrsim_proto::{BodyState, SnapshotHeader, now_ns};
use mrsim_spatial::NeighbourGrid;
use mrsim_transport::shm::ShmAgent;
use mrsim_transport::{AgentTransport, Namespace, SendFn};
use std::collections::VecDeque;
use std::sync::Arc;
use std::time::Duration;

/// How often (at most) the loop asks its transport whether the process is
/// to stop (over iceoryx2 the question takes a process-wide lock: asked
/// every few ticks, not every tick): 50 ms, so a stop is heard within that
/// and one wait (100 ms).
const STOP_CHECK_EVERY_NS: u64 = 50_000_000;

/// The longest single wait of the loop.
const WAIT_SLICE_NS: u64 = 100_000_000;

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

/// A tick handed out (or queued to be) and not answered yet.
#[derive(Debug, Clone, Copy)]
struct Pending {
    /// The robot's seat.
    seat: usize,
    header: SnapshotHeader,
    /// When the agent woke for it, and when its observation began.
    woke: u64,
    began: u64,
}

/// How one run of [`Ticks::listen`] ended.
enum Heard {
    /// The caller's snapshot handler has something for it.
    Tick,
    /// The timeout passed.
    Idle,
    /// The world ended the run.
    Finished,
    /// The world process is gone.
    WorldGone,
    /// The process was asked to terminate.
    Interrupted,
}

/// What [`Ticks::listen`] calls with each snapshot that is not the run's
/// last: the robots, the snapshot, when the agent woke for it, and a sender
/// of commands. True when the caller is to hear of it ([`Heard::Tick`]).
type OnSnapshot<'a> = dyn FnMut(
        &mut Seats,
        &SnapshotHeader,
        &[BodyState],
        u64,
        &mut SendFn<'_>,
    ) -> Result<bool, AgentError>
    + 'a;

/// The loop's own state, the same whatever the snapshots are for.
struct Ticks {
    /// Where a transport that cannot lend its snapshot copies it.
    scratch: (SnapshotHeader, Vec<BodyState>),
    /// When the last snapshot came (the clock read as the agent woke for
    /// it).
    last_heard: u64,
    /// A snapshot has come (after it, a wake-up without one is spurious).
    heard_one: bool,
    /// Silence after which the world's life is checked.
    check_after: u64,
    /// When the loop last asked whether it is to stop.
    asked_to_stop_at: u64,
    /// Before the first snapshot: when the robots last said they are
    /// ready, and how long a silent wait lasts before they say it again.
    ready_at: u64,
    ready_every: u64,
}

/// Before the first snapshot, the first pause after which robots that
/// heard nothing say they are ready again; it doubles each time, up to
/// [`READY_AGAIN_MAX_NS`].
const READY_AGAIN_NS: u64 = 1_000_000_000;

/// The longest pause between two "ready" of a robot that hears nothing.
const READY_AGAIN_MAX_NS: u64 = 8_000_000_000;

impl Ticks {
    /// Waits for snapshots until one `on` wants the caller to hear of, the
    /// run ends, the world is gone, the process is to stop, or the clock
    /// passes `until` (CLOCK_MONOTONIC ns; `u64::MAX`: never).
    fn listen(
        &mut self,
        link: &mut dyn AgentTransport,
        seats: &mut Seats,
        until: u64,
        on: &mut OnSnapshot<'_>,
    ) -> Result<Heard, AgentError> {
        let mut now = now_ns();
        loop {
            if now.saturating_sub(self.asked_to_stop_at) >= STOP_CHECK_EVERY_NS {
                self.asked_to_stop_at = now;
                if link.termination_requested() {
                    return Ok(Heard::Interrupted);
                }
            }
            let slice = until.saturating_sub(now).min(WAIT_SLICE_NS);
            link.wait(Duration::from_nanos(slice))?;
            let woke = now_ns();
            // Woken before the wait's end: the world called (or, rarely,
            // a spurious wake-up).
            let called = woke.saturating_sub(now) < slice;
            now = woke;
            let (mut finished, mut handled) = (false, Ok(false));
            let heard_one = &mut self.heard_one;
            let got =
                link.with_latest_snapshot(&mut self.scratch, &mut |header, bodies, send| {
                    *heard_one = true;
                    if header.finished != 0 {
                        finished = true;
                    } else {
                        handled = on(seats, header, bodies, woke, send);
                    }
                })?;
            if !got {
                if woke.saturating_sub(self.last_heard) > self.check_after && !link.world_alive() {
                    return Ok(Heard::WorldGone);
                }
                if !self.heard_one
                    && (called || woke.saturating_sub(self.ready_at) >= self.ready_every)
                {
                    // Before the first snapshot a wake-up is the world's
                    // call to take up the tick's channels (this receive just
                    // did): say ready again, and the world starts the clock
                    // once every agent has (`WorldTransport::prepare_ticks`).
                    // A wait that only timed out is no call: the robots say
                    // it again only now and then, in case a call was missed.
                    // A thousand agents of a hundred robots each saying it
                    // every wait slice while a run of 100,000 robots
                    // joins flood the world with a million commands a
                    // second, and the joins never end.
                    if !called {
                        self.ready_every = (self.ready_every * 2).min(READY_AGAIN_MAX_NS);
                    }
                    self.ready_at = woke;
                    for s in &seats.seats {
                        link.send_command(&s.ready())?;
                    }
                }
            } else {
                self.last_heard = woke;
                if handled? {
                    return Ok(Heard::Tick);
                }
                if finished {
                    return Ok(Heard::Finished);
                }
            }
            if woke >= until {
                return Ok(Heard::Idle);
            }
        }
    }
}

/// The robots this process drives and, for more than one that all sense
/// within a finite reach, the neighbour grid their observations share.
struct Seats {
    seats: Vec<Seat>,
    /// The largest reach of the robots, when a grid is built at all.
    reach: Option<f64>,
    grid: NeighbourGrid,
    near: Vec<u32>,
    /// The bodies bucketed this snapshot, with their indices in it.
    named: Vec<(u32, [f64; 3])>,
}

impl Seats {
    fn new(seats: Vec<Seat>) -> Self {
        let reach = seats
            .iter()
            .map(|s| crate::reach(&s.spec))
            .try_fold(0.0_f64, |m, r| r.map(|r| m.max(r)))
            .filter(|_| seats.len() > 1);
        Self {
            seats,
            reach,
            grid: NeighbourGrid::default(),
            near: Vec::new(),
            named: Vec::new(),
        }
    }

    /// Builds the grid over this snapshot's bodies: true if there is one
    /// to look robots' neighbours up in. Of a large snapshot (a group of a
    /// few robots among many bodies), only the bodies that can come within
    /// reach of one of the group are bucketed: those near the box around
    /// the group's robots. Each keeps its index in the snapshot, so every
    /// robot's candidates hold every body within its reach as before, and
    /// the observations are the same.
    fn index(&mut self, bodies: &[BodyState]) -> bool {
        let Some(r) = self.reach else {
            return false;
        };
        let all = |b: &BodyState| [b.position[0], b.position[1], b.radius];
        if bodies.len() < 4 * self.seats.len() {
            return self.grid.build(bodies.iter().map(all), r);
        }
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for b in self.seats.iter().filter_map(|s| bodies.get(s.me)) {
            for k in 0..2 {
                // min and max pass over a NaN: that robot scans every body.
                lo[k] = lo[k].min(b.position[k]);
                hi[k] = hi[k].max(b.position[k]);
            }
        }
        if !(lo[0] <= hi[0] && lo[1] <= hi[1]) {
            return self.grid.build(bodies.iter().map(all), r);
        }
        // Within reach of a robot inside the box only if within reach plus
        // the body's radius of the box (with room for rounding). A centre
        // that is not finite fails every test and is kept: the grid then
        // refuses, as over all the bodies.
        let m = r * (1.0 + 1e-6) + 1e-6;
        self.named.clear();
        self.named.extend(
            bodies
                .iter()
                .enumerate()
                .filter(|(_, b)| {
                    let [x, y] = b.position;
                    let e = m + b.radius * (1.0 + 1e-6);
                    !(x + e < lo[0] || x - e > hi[0] || y + e < lo[1] || y - e > hi[1])
                })
                .map(|(j, b)| (j as u32, all(b))),
        );
        self.grid.build_named(&self.named, r)
    }

    /// Seat `i` and, when `gridded`, the indices of the bodies near it
    /// (`None`: it looks at every body).
    fn near(
        &mut self,
        i: usize,
        gridded: bool,
        bodies: &[BodyState],
    ) -> (&mut Seat, Option<&[u32]>) {
        let seat = &mut self.seats[i];
        let among = gridded
            && match (
                crate::reach(&seat.spec),
                bodies.get(seat.me).map(|b| b.position),
            ) {
                (Some(r), Some(p)) => self.grid.near(p, r, &mut self.near),
                _ => false,
            };
        (seat, among.then_some(self.near.as_slice()))
    }
}

/// Joined robots answered tick by tick over any [`AgentTransport`] (given
/// to each call, so the caller keeps the transport): one robot when
/// [`Self::join`] made it, several (`mrsim agent --robots`) in
/// [`crate::run_group`].
pub struct Live {
    seats: Seats,
    ticks: Ticks,
    /// Observations of the last snapshot not handed out yet (a group's).
    queued: VecDeque<(Pending, Box<OwnedObservation>)>,
    /// The tick [`Self::next`] handed out last, until answered.
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
            Some(seat) => Self::start(link, vec![seat], opts.world_check_after).map(Some),
            None => Ok(None),
        }
    }

    /// Tells the world every robot of `seats` is ready, and closes the
    /// join-time ports; `world_check_after` is the silence after which the
    /// world's life is checked.
    pub(crate) fn start(
        link: &mut dyn AgentTransport,
        seats: Vec<Seat>,
        world_check_after: Duration,
    ) -> Result<Self, AgentError> {
        for s in &seats {
            link.send_command(&s.ready())?;
        }
        link.joined();
        let capacity = seats.first().map_or(0, |s| s.capacity);
        Ok(Self {
            seats: Seats::new(seats),
            ticks: Ticks {
                scratch: (SnapshotHeader::default(), Vec::with_capacity(capacity)),
                last_heard: now_ns(),
                heard_one: false,
                check_after: u64::try_from(world_check_after.as_nanos()).unwrap_or(u64::MAX),
                asked_to_stop_at: 0,
                ready_at: now_ns(),
                ready_every: READY_AGAIN_NS,
            },
            queued: VecDeque::new(),
            pending: None,
        })
    }

    fn first(&self) -> Option<&Seat> {
        self.seats.seats.first()
    }

    /// The robot's name (of a group, the first robot's).
    pub fn robot(&self) -> &str {
        self.first().map_or("", |s| &s.spec.name)
    }

    /// The robot's id, its index in the scenario (of a group, the first
    /// robot's).
    pub fn robot_id(&self) -> usize {
        self.first().map_or(0, |s| s.me)
    }

    /// Every joined robot: its id (index in the scenario, `me.id` of its
    /// observations) and its name, in join order.
    pub fn robots(&self) -> Vec<(usize, String)> {
        self.seats
            .seats
            .iter()
            .map(|s| (s.me, s.spec.name.clone()))
            .collect()
    }

    /// The robot's planner parameters as its scenario entry gives them
    /// (for a program that reads its own settings from the scenario).
    pub fn params(&self) -> Params {
        self.first()
            .map(|s| crate::planner_params(&s.spec))
            .unwrap_or_default()
    }

    /// Waits up to `timeout` for the next tick to answer (of a group, the
    /// next robot's: `me.id` says whose). A tick not answered before a
    /// newer one comes is skipped (in realtime a miss; in lockstep the
    /// world waits for the answer, so none comes).
    pub fn next(
        &mut self,
        link: &mut dyn AgentTransport,
        timeout: Duration,
    ) -> Result<Next, AgentError> {
        if self.queued.is_empty() {
            let until =
                now_ns().saturating_add(u64::try_from(timeout.as_nanos()).unwrap_or(u64::MAX));
            let queued = &mut self.queued;
            let heard = self.ticks.listen(
                link,
                &mut self.seats,
                until,
                &mut |seats, header, bodies, woke, _| {
                    let gridded = seats.index(bodies);
                    for i in 0..seats.seats.len() {
                        let (seat, near) = seats.near(i, gridded, bodies);
                        if seat.due(header, bodies.len()) {
                            let began = now_ns();
                            let obs = owned(seat, header, bodies, near);
                            let p = Pending {
                                seat: i,
                                header: *header,
                                woke,
                                began,
                            };
                            queued.push_back((p, Box::new(obs)));
                        }
                    }
                    Ok(!queued.is_empty())
                },
            )?;
            match heard {
                Heard::Tick => {}
                Heard::Idle => return Ok(Next::Idle),
                Heard::Finished => return Ok(Next::Finished),
                Heard::WorldGone => return Ok(Next::WorldGone),
                Heard::Interrupted => return Ok(Next::Interrupted),
            }
        }
        match self.queued.pop_front() {
            Some((p, obs)) => {
                self.pending = Some(p);
                Ok(Next::Observation(obs))
            }
            None => Ok(Next::Idle),
        }
    }

    /// Answers the tick [`Self::next`] last handed out with `cmd`. A
    /// non-finite command is sent as it is: the world refuses it, counts it
    /// (`commands_rejected`) and the robot brakes.
    pub fn reply(&mut self, link: &mut dyn AgentTransport, cmd: Command) -> Result<(), AgentError> {
        let p = self.pending.take().ok_or(AgentError::NothingToAnswer)?;
        let seat = self
            .seats
            .seats
            .get_mut(p.seat)
            .ok_or(AgentError::NothingToAnswer)?;
        let sent = now_ns();
        seat.send(
            &p.header,
            cmd,
            [sent.saturating_sub(p.began), p.woke, sent],
            &mut |m| link.send_command(m),
        )
    }

    /// Ends the robots' control: writes out their diagnostics. The first
    /// robot's error (a planner that failed in a realtime run), if any.
    pub fn finish(self, exit: AgentExit) -> Result<AgentExit, AgentError> {
        let mut result = Ok(exit);
        for mut s in self.seats.seats {
            let r = s.finish(exit);
            if result.is_ok() {
                result = r;
            }
        }
        result
    }
}

/// The observation of a snapshot, owned.
fn owned(
    seat: &mut Seat,
    header: &SnapshotHeader,
    bodies: &[BodyState],
    near: Option<&[u32]>,
) -> OwnedObservation {
    let (all_walls, path) = (seat.walls().clone(), seat.path.clone());
    let o = seat.observe_among(header, bodies, near);
    // The walls the observation holds: all of them (shared), or those
    // within the sensing range when it is short of the walls' extent.
    let walls = if o.walls.len() == all_walls.len() {
        all_walls
    } else {
        Arc::from(o.walls)
    };
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

/// Answers every tick of `live`, a robot, with `planner` until the run
/// ends: the loop of `mrsim agent` ([`crate::run`]). A planner that panics
/// or returns a non-finite command fails the robot at that tick
/// ([`crate::guard`]): in lockstep the loop ends with that error, in
/// realtime the tick is a miss and the first failure is the error at the
/// end ([`Live::finish`]).
pub fn drive(
    link: &mut dyn AgentTransport,
    live: &mut Live,
    planner: &mut dyn Planner,
) -> Result<AgentExit, AgentError> {
    drive_each(link, live, &mut [planner])
}

/// [`drive`] for every robot of `live`, each with its planner (in the
/// robots' order; a robot without one is not answered): the first robot's
/// failure in lockstep ends the group (its process is one agent).
pub(crate) fn drive_each(
    link: &mut dyn AgentTransport,
    live: &mut Live,
    planners: &mut [&mut dyn Planner],
) -> Result<AgentExit, AgentError> {
    let mut answer = |seats: &mut Seats,
                      header: &SnapshotHeader,
                      bodies: &[BodyState],
                      woke: u64,
                      send: &mut SendFn<'_>| {
        let gridded = seats.index(bodies);
        // One clock read per robot: its work is counted from the wake-up
        // (the first) or from the end of the robot before it, as the
        // in-process pool counts it ([`crate::Driver::on_snapshot_among`]).
        let mut start = woke;
        for (i, planner) in planners.iter_mut().enumerate().take(seats.seats.len()) {
            let (seat, near) = seats.near(i, gridded, bodies);
            start = seat.answer(
                &mut **planner,
                header,
                bodies,
                near,
                woke,
                Some(start),
                send,
            )?;
        }
        Ok(false)
    };
    loop {
        match live
            .ticks
            .listen(link, &mut live.seats, u64::MAX, &mut answer)?
        {
            Heard::Tick | Heard::Idle => {}
            Heard::Finished => return Ok(AgentExit::Finished),
            Heard::Interrupted => return Ok(AgentExit::Interrupted),
            Heard::WorldGone => return Err(AgentError::WorldGone),
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
mod tests;
