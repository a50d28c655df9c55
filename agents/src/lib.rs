//! One robot's agent: join the run, get the robot's setup from the world,
//! then each tick turn the snapshot into the planner's
//! [`Observation`](mrsim_planners::Observation) (sensing range and field of
//! view applied), call the planner, and send the command back before the
//! deadline.
//!
//! The transport is injected ([`AgentTransport`]), so the same loop runs in
//! an agent process over iceoryx2, in a thread over crossbeam channels, or
//! in a test against a scripted fake world. The planner is pure and never
//! sees the transport or a clock; the agent measures its compute time.
//!
//! Every way to drive a joined robot shares one seat (`seat`: observe,
//! send, fault injection, diagnostics; `join`: joining, one robot or
//! several) and, but for the in-process pool, one per-tick loop ([`Live`],
//! over one robot or a group): [`Live::next`] hands out each tick's
//! observation and [`Live::reply`] takes the answer (a user's own program,
//! [`LiveAgent`] over iceoryx2); [`drive`] answers with planners (what
//! [`run`] and [`run_group`], `mrsim agent`, run); a [`Driver`] pairs the
//! seat with a planner for the in-process pool, which plans for many robots
//! per snapshot. Every plan call goes through [`guard::plan_checked`].
#![warn(missing_docs)]

pub mod car_route;
pub mod cores;
pub mod diagnostics;
pub mod fault;
pub mod group;
pub mod guard;
mod join;
pub mod live;
pub mod observe;
pub mod passage;
pub mod route;
mod seat;

pub use group::{join_group, join_live, run_group};
pub use guard::{Halt, PlanFailure, PlanFault, plan_checked};
pub use live::{Live, LiveAgent, Next, OwnedObservation, drive};

use mrsim_planners::{Planner, Registry};
use mrsim_proto::{BodyState, CommandMsg, PROTOCOL_VERSION, SnapshotHeader};
use mrsim_scenario::RobotSpec;
use mrsim_transport::{AgentTransport, TransportError};
use seat::Seat;
use std::sync::Arc;
use std::time::Duration;

/// Why an agent stopped with an error.
#[derive(Debug, thiserror::Error)]
pub enum AgentError {
    /// The transport failed.
    #[error(transparent)]
    Transport(#[from] TransportError),
    /// The world refused to let this agent drive the robot.
    #[error("the world refused robot `{robot}`: {reason}")]
    Refused {
        /// The robot asked for.
        robot: String,
        /// The world's reason.
        reason: String,
    },
    /// No answer from the world in time.
    #[error(
        "no {what} from the world within {secs:.0} s (is `mrsim world` running with this run id?)"
    )]
    Timeout {
        /// What was awaited.
        what: &'static str,
        /// The timeout.
        secs: f64,
    },
    /// The world's setup could not be read.
    #[error("bad setup from the world: {0}")]
    BadSetup(String),
    /// The robot's planner could not be built.
    #[error("robot `{robot}`: {source}")]
    Planner {
        /// The robot.
        robot: String,
        /// Why.
        source: mrsim_planners::BuildError,
    },
    /// The world process is gone.
    #[error("the world is gone (its process died or left without ending the run)")]
    WorldGone,
    /// The robot's planner failed at a tick (panicked, or returned a
    /// non-finite command).
    #[error(transparent)]
    Plan(#[from] PlanFailure),
    /// A reply without a tick to answer (none handed out, or answered).
    #[error("no tick to answer: reply once to each observation `next` gives")]
    NothingToAnswer,
    /// The run id is not one a world can have.
    #[error("bad run id: {0}")]
    BadRunId(String),
    /// No world of that run id was found in time.
    #[error(
        "cannot reach the world of run `{run_id}` (is `mrsim world ... --run {run_id}` running?)"
    )]
    NoWorld {
        /// The run id.
        run_id: String,
        /// Why.
        #[source]
        source: TransportError,
    },
    /// The process was asked to stop before the robot had joined.
    #[error("interrupted before joining")]
    Interrupted,
    /// Realtime under `[world.cpus]`: the robot's agent could not take its
    /// scheduling policy (the kernel refused it, or the process drives
    /// several robots).
    #[error("robot `{robot}`: {why}")]
    Scheduling {
        /// The robot.
        robot: String,
        /// Why, with the kernel's reason.
        why: String,
    },
}

/// How an agent ended without error.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AgentExit {
    /// The world ended the run.
    Finished,
    /// The process was asked to terminate.
    Interrupted,
}

/// Options of one agent.
#[derive(Debug, Clone)]
pub struct AgentOptions {
    /// The robot to drive.
    pub robot: String,
    /// How long to wait for the join reply and the setup.
    pub join_timeout: Duration,
    /// Silence after which the agent checks that the world still lives.
    pub world_check_after: Duration,
    /// Deliberately claim this robot id in commands instead of the one the
    /// world assigned (for fault-injection tests of ownership checks).
    pub impersonate: Option<u32>,
    /// Misbehave on purpose (fault-injection tests); None = honest.
    pub fault: Option<fault::Fault>,
    /// The protocol version announced when joining (tests of strangers
    /// set another one).
    pub protocol_version: u32,
    /// Where the robot's planner is built from (by the name its scenario
    /// entry gives): the built-in planners unless a program registered
    /// its own (in-process runs).
    pub registry: Arc<Registry>,
    /// In an in-process run: what stops the run when a planner fails in
    /// lockstep ([`Halt`]).
    pub halt: Option<Halt>,
}

impl AgentOptions {
    /// Defaults for driving `robot`.
    pub fn new(robot: &str) -> Self {
        Self {
            robot: robot.to_string(),
            join_timeout: Duration::from_secs(30),
            world_check_after: Duration::from_millis(300),
            impersonate: None,
            fault: None,
            protocol_version: PROTOCOL_VERSION,
            registry: Arc::new(Registry::builtin()),
            halt: None,
        }
    }
}

/// Converts a scenario parameter table into the planners' form.
pub fn planner_params(spec: &RobotSpec) -> mrsim_planners::Params {
    use mrsim_planners::ParamValue as P;
    use mrsim_scenario::ParamValue as S;
    spec.params
        .iter()
        .map(|(k, v)| {
            let v = match v {
                S::Bool(b) => P::Bool(*b),
                S::Number(x) => P::Number(*x),
                S::Text(s) => P::Text(s.clone()),
                S::Numbers(xs) => P::Numbers(xs.clone()),
                S::Points(ps) => P::Points(ps.clone()),
            };
            (k.clone(), v)
        })
        .collect()
}

/// Builds the planner a robot's scenario entry asks for, from the
/// built-in ones.
pub fn build_planner(spec: &RobotSpec) -> Result<Box<dyn Planner>, mrsim_planners::BuildError> {
    let planner = mrsim_planners::build(&spec.planner, &planner_params(spec))?;
    Ok(fit_kinematics(spec, planner))
}

/// Builds the planner a robot's scenario entry asks for, from `registry`.
pub fn build_planner_in(
    registry: &Registry,
    spec: &RobotSpec,
) -> Result<Box<dyn Planner>, mrsim_planners::BuildError> {
    let planner = registry.build(&spec.planner, &planner_params(spec))?;
    Ok(fit_kinematics(spec, planner))
}

/// On a unicycle robot the planner drives through the look-ahead point
/// controller (`mrsim_planners::unicycle`), which hands a planner that
/// plans (v, omega) itself (`Planner::native_unicycle`, dwa) the robot's
/// own observation and passes its command unchanged; on a car, through
/// the tracking controller (`mrsim_planners::ackermann`), which does the
/// same for a planner of cars (`Planner::native_ackermann`); a holonomic
/// robot's planner is used as built.
fn fit_kinematics(spec: &RobotSpec, planner: Box<dyn Planner>) -> Box<dyn Planner> {
    match spec.kinematics {
        mrsim_scenario::Kinematics::Holonomic => planner,
        mrsim_scenario::Kinematics::Unicycle => Box::new(mrsim_planners::unicycle::LookAhead::new(
            planner,
            spec.lookahead,
        )),
        mrsim_scenario::Kinematics::Ackermann => {
            Box::new(mrsim_planners::ackermann::Tracker::new(planner))
        }
    }
}

/// `planner` as robot `spec` ends its way: a unicycle with a goal heading
/// (`goal_heading_deg`) turns in place to it at its goal
/// (`mrsim_planners::unicycle::GoalHeading`), outside its route, so that
/// it turns at the goal itself; any other robot's planner unchanged (a
/// car's route ends at the heading; a holonomic robot never turns).
pub fn fit_goal_heading(spec: &RobotSpec, planner: Box<dyn Planner>) -> Box<dyn Planner> {
    match (spec.kinematics, spec.goal_heading) {
        (mrsim_scenario::Kinematics::Unicycle, Some(g)) => Box::new(
            mrsim_planners::unicycle::GoalHeading::new(planner, g.heading),
        ),
        _ => planner,
    }
}

/// How far from its centre robot `spec` senses other bodies' centres, less
/// their radius (its sensing range plus its own radius); `None` when
/// unlimited.
pub fn reach(spec: &RobotSpec) -> Option<f64> {
    let r = spec.sensing_range + spec.radius;
    r.is_finite().then_some(r)
}

/// Joins the run as `opts.robot` and drives it with the planner its
/// scenario entry names (built from `opts.registry`) until the world ends
/// the run, the process is asked to stop, or something fails: [`drive`]
/// over a [`Live`] robot.
pub fn run(link: &mut dyn AgentTransport, opts: &AgentOptions) -> Result<AgentExit, AgentError> {
    let Some(seat) = join::join_seat(link, opts)? else {
        return Ok(AgentExit::Interrupted);
    };
    let mut planner = seat.build_planner(&opts.registry)?;
    let mut live = Live::start(link, vec![seat], opts.world_check_after)?;
    let exit = drive(link, &mut live, planner.as_mut())?;
    live.finish(exit)
}

/// Joins the run as `opts.robot` and reads the run's setup: the robot's
/// [`Driver`] (its planner built from `opts.registry`), ready for the
/// first snapshot. `None` if the process was asked to stop meanwhile.
pub fn join(
    link: &mut dyn AgentTransport,
    opts: &AgentOptions,
) -> Result<Option<Driver>, AgentError> {
    let Some(seat) = join::join_seat(link, opts)? else {
        return Ok(None);
    };
    let planner = seat.build_planner(&opts.registry)?;
    Ok(Some(Driver { seat, planner }))
}

/// One joined robot's control: from each snapshot to its command. It holds
/// no transport and no clock of its own, so the same driver runs in an
/// agent process ([`run`]) or among many in a thread of an in-process run.
pub struct Driver {
    seat: Seat,
    planner: Box<dyn Planner>,
}

impl Driver {
    /// The robot's index in the scenario.
    pub fn robot_id(&self) -> usize {
        self.seat.me
    }

    /// The message telling the world this robot's agent is ready (sent
    /// once, right after [`join`]).
    pub fn ready(&self) -> CommandMsg {
        self.seat.ready()
    }

    /// Bodies a snapshot of this run holds (robots and obstacles).
    pub fn capacity(&self) -> usize {
        self.seat.capacity
    }

    /// Plans on one snapshot (not the run's last) and hands the command to
    /// `send`; `woke` is when the agent woke for it (CLOCK_MONOTONIC ns).
    /// A tick already answered, or a snapshot without this robot, is
    /// skipped.
    pub fn on_snapshot(
        &mut self,
        header: &SnapshotHeader,
        bodies: &[BodyState],
        woke: u64,
        send: &mut dyn FnMut(&CommandMsg) -> Result<(), TransportError>,
    ) -> Result<(), AgentError> {
        self.on_snapshot_among(header, bodies, None, woke, None, send)
            .map(|_| ())
    }

    /// This robot's [`reach`].
    pub fn reach(&self) -> Option<f64> {
        reach(&self.seat.spec)
    }

    /// The robot's position in `bodies`.
    pub fn position(&self, bodies: &[BodyState]) -> Option<[f64; 2]> {
        bodies.get(self.seat.me).map(|b| b.position)
    }

    /// [`Self::on_snapshot`], the observation looking only at the bodies of
    /// indices `near` when given (ascending; every body within this robot's
    /// [`Self::reach`] plus its own radius must be among them), and its
    /// compute time counted from `start` when given (a worker that plans
    /// for many robots reads the clock once per robot: the end of one is
    /// the start of the next). Returns the clock at the end of its work
    /// (`start`, or `woke`, if there was none to do). A planner that
    /// panics or returns a non-finite command fails the robot at this tick
    /// ([`guard`]; in lockstep an error naming the robot and the tick).
    pub fn on_snapshot_among(
        &mut self,
        header: &SnapshotHeader,
        bodies: &[BodyState],
        near: Option<&[u32]>,
        woke: u64,
        start: Option<u64>,
        send: &mut dyn FnMut(&CommandMsg) -> Result<(), TransportError>,
    ) -> Result<u64, AgentError> {
        self.seat.answer(
            self.planner.as_mut(),
            header,
            bodies,
            near,
            woke,
            start,
            send,
        )
    }

    /// Ends the robot's control: writes out its diagnostics (and reports a
    /// planner that failed in a realtime run).
    pub fn finish(mut self, exit: AgentExit) -> Result<AgentExit, AgentError> {
        self.seat.finish(exit)
    }
}
