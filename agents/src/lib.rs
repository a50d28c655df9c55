//! One robot's agent: join the run, get the robot's setup from the world,
//! then each tick turn the snapshot into the planner's [`Observation`]
//! (sensing range and field of view applied), call the planner, and send
//! the command back before the deadline.
//!
//! The transport is injected ([`AgentTransport`]), so the same loop runs in
//! an agent process over iceoryx2, in a thread over crossbeam channels, or
//! in a test against a scripted fake world. The planner is pure and never
//! sees the transport or a clock; the agent measures its compute time.
#![warn(missing_docs)]

pub mod diagnostics;
pub mod fault;
pub mod group;
pub mod observe;

pub use group::{join_group, run_group};

use mrsim_planners::{Command, DesignatedPath, Planner, Segment, Vec2};
use mrsim_proto::{BodyState, CommandMsg, PROTOCOL_VERSION, SnapshotHeader, command_kind, now_ns};
use mrsim_scenario::RobotSpec;
use mrsim_transport::{AgentTransport, TransportError};
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

/// Builds the planner a robot's scenario entry asks for.
pub fn build_planner(spec: &RobotSpec) -> Result<Box<dyn Planner>, mrsim_planners::BuildError> {
    mrsim_planners::build(&spec.planner, &planner_params(spec))
}

/// How far from its centre robot `spec` senses other bodies' centres, less
/// their radius (its sensing range plus its own radius); `None` when
/// unlimited.
pub fn reach(spec: &RobotSpec) -> Option<f64> {
    let r = spec.sensing_range + spec.radius;
    r.is_finite().then_some(r)
}

/// How often (at most) [`run`] asks its transport whether the process is
/// to stop: 50 ms, so a stop is heard within that and one wait (100 ms).
const STOP_CHECK_EVERY_NS: u64 = 50_000_000;

/// Joins the run as `opts.robot` and drives it until the world ends the
/// run, the process is asked to stop, or something fails.
pub fn run(link: &mut dyn AgentTransport, opts: &AgentOptions) -> Result<AgentExit, AgentError> {
    group::run_group(link, std::slice::from_ref(opts))
}

/// Joins the run as `opts.robot` and reads the run's setup: the robot's
/// [`Driver`], ready for the first snapshot. `None` if the process was
/// asked to stop meanwhile.
pub fn join(
    link: &mut dyn AgentTransport,
    opts: &AgentOptions,
) -> Result<Option<Driver>, AgentError> {
    Ok(group::join_group(link, std::slice::from_ref(opts))?.and_then(|mut d| d.pop()))
}

/// The [`Driver`] of robot `me` of the run whose setup is `view`, joined
/// with `reply` under `opts`.
fn driver(
    view: &SetupView<'_>,
    walls: &std::sync::Arc<[Segment]>,
    reply: &mrsim_proto::JoinReply,
    opts: &AgentOptions,
) -> Result<Driver, AgentError> {
    let scenario = &view.scenario;
    let me = reply.robot_id as usize;
    let spec: RobotSpec = scenario
        .robots
        .get(me)
        .ok_or_else(|| AgentError::BadSetup(format!("no robot with id {me}")))
        .and_then(|raw| {
            serde_json::from_str(raw.get()).map_err(|e| AgentError::BadSetup(e.to_string()))
        })?;
    let planner = build_planner(&spec).map_err(|source| AgentError::Planner {
        robot: spec.name.clone(),
        source,
    })?;
    let path = (!spec.path.is_empty()).then(|| DesignatedPath {
        points: spec.path.iter().map(|p| Vec2::new(p[0], p[1])).collect(),
        boundary: spec.boundary.unwrap_or(f64::INFINITY),
    });
    let robot_count = scenario.robots.len();
    let capacity = robot_count + scenario.obstacles;
    let observer = observe::Observer::for_robot(&scenario.world, Some(&spec), me, capacity);
    // The planner's diagnostics go to a part file in the run's folder, when
    // the world's folder is reachable from here (same machine).
    let diag = view
        .out_dir
        .as_deref()
        .map(std::path::PathBuf::from)
        .filter(|d| d.is_dir())
        .and_then(
            |d| match diagnostics::DiagnosticsWriter::start(&d, me, &spec.name) {
                Ok(w) => Some(w),
                Err(e) => {
                    eprintln!("agent {}: no diagnostics: {e}", spec.name);
                    None
                }
            },
        );
    Ok(Driver {
        me,
        claim: opts.impersonate.unwrap_or(me as u32),
        token: reply.token,
        robot_count,
        capacity,
        spec,
        planner,
        walls: walls.clone(),
        path,
        observer,
        diag,
        answered: None,
        injector: opts.fault.map(fault::Injector::new),
        hung: false,
    })
}

/// The walls every robot of the run whose setup is `view` sees (its
/// `[[wall]]`s, map and arena), shared by the drivers of one process.
fn walls(view: &SetupView<'_>) -> std::sync::Arc<[Segment]> {
    mrsim_scenario::walls_and_arena(&view.scenario.walls, view.scenario.world.arena)
        .iter()
        .map(|w| Segment {
            a: Vec2::new(w[0][0], w[0][1]),
            b: Vec2::new(w[1][0], w[1][1]),
        })
        .collect()
}

/// The part of the world's setup an agent reads. Only its own robot's
/// entry is parsed (the others are skipped as raw text, nothing built): a
/// thousand agents each building all thousand robots' specs cost O(n²) at
/// join, seconds on two cores.
#[derive(serde::Deserialize)]
struct SetupView<'a> {
    #[serde(borrow)]
    scenario: ScenarioView<'a>,
    #[serde(default)]
    out_dir: Option<String>,
}

/// [`Scenario`] as an agent needs it.
#[derive(serde::Deserialize)]
struct ScenarioView<'a> {
    world: mrsim_scenario::WorldConfig,
    #[serde(borrow)]
    robots: Vec<&'a serde_json::value::RawValue>,
    /// Only counted.
    #[serde(default, deserialize_with = "count")]
    obstacles: usize,
    #[serde(default)]
    walls: Vec<mrsim_scenario::WallSpec>,
}

/// The length of a sequence, its items skipped.
fn count<'de, D: serde::Deserializer<'de>>(d: D) -> Result<usize, D::Error> {
    struct Count;
    impl<'de> serde::de::Visitor<'de> for Count {
        type Value = usize;
        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            f.write_str("a sequence")
        }
        fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut seq: A) -> Result<usize, A::Error> {
            let mut n = 0;
            while seq.next_element::<serde::de::IgnoredAny>()?.is_some() {
                n += 1;
            }
            Ok(n)
        }
    }
    d.deserialize_seq(Count)
}

/// One joined robot's control: from each snapshot to its command. It holds
/// no transport and no clock of its own, so the same driver runs in an
/// agent process ([`run`]) or among many in a thread of an in-process run.
pub struct Driver {
    me: usize,
    /// The robot id put in commands (another one only in fault tests).
    claim: u32,
    token: u64,
    robot_count: usize,
    capacity: usize,
    spec: RobotSpec,
    planner: Box<dyn Planner>,
    walls: std::sync::Arc<[Segment]>,
    path: Option<DesignatedPath>,
    observer: observe::Observer,
    diag: Option<diagnostics::DiagnosticsWriter>,
    answered: Option<u64>,
    injector: Option<fault::Injector>,
    hung: bool,
}

impl Driver {
    /// The robot's index in the scenario.
    pub fn robot_id(&self) -> usize {
        self.me
    }

    /// The message telling the world this robot's agent is ready (sent
    /// once, right after [`join`]).
    pub fn ready(&self) -> CommandMsg {
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
        }
    }

    /// Bodies a snapshot of this run holds (robots and obstacles).
    pub fn capacity(&self) -> usize {
        self.capacity
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
        reach(&self.spec)
    }

    /// The robot's position in `bodies`.
    pub fn position(&self, bodies: &[BodyState]) -> Option<[f64; 2]> {
        bodies.get(self.me).map(|b| b.position)
    }

    /// [`Self::on_snapshot`], the observation looking only at the bodies of
    /// indices `near` when given (ascending; every body within this robot's
    /// [`Self::reach`] plus its own radius must be among them), and its
    /// compute time counted from `start` when given (a worker that plans
    /// for many robots reads the clock once per robot: the end of one is
    /// the start of the next). Returns the clock at the end of its work
    /// (`start`, or `woke`, if there was none to do).
    pub fn on_snapshot_among(
        &mut self,
        header: &SnapshotHeader,
        bodies: &[BodyState],
        near: Option<&[u32]>,
        woke: u64,
        start: Option<u64>,
        send: &mut dyn FnMut(&CommandMsg) -> Result<(), TransportError>,
    ) -> Result<u64, AgentError> {
        let idle = start.unwrap_or(woke);
        if self.hung || self.answered.is_some_and(|t| t >= header.tick) || self.me >= bodies.len() {
            return Ok(idle);
        }
        if let Some(inj) = self.injector.as_mut() {
            self.hung = inj.before_plan(header.tick) == fault::Before::Hang;
            if self.hung {
                return Ok(idle);
            }
        }
        let t0 = start.unwrap_or_else(now_ns);
        let obs = self.observer.observe_among(
            header,
            bodies,
            near,
            &self.spec,
            &self.walls,
            self.path.as_ref(),
        );
        let cmd = self.planner.plan(&obs);
        let t1 = now_ns();
        let compute_ns = t1.saturating_sub(t0);
        let (kind, v) = match cmd {
            Command::Force(f) => (command_kind::FORCE, f),
            Command::Velocity(v) => (command_kind::VELOCITY, v),
        };
        let msg = CommandMsg {
            robot_id: self.claim,
            kind,
            token: self.token,
            tick: header.tick,
            value: [v.x, v.y],
            compute_ns,
            woke_ns: woke,
            sent_ns: t1,
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
        // After the command is out: off the tick's critical path.
        if let Some(d) = &mut self.diag {
            d.push(header.tick, header.sim_time, self.planner.diagnostics());
        }
        Ok(t1)
    }

    /// Ends the robot's control: writes out its diagnostics.
    pub fn finish(mut self, exit: AgentExit) -> Result<AgentExit, AgentError> {
        if let Some(Err(e)) = self.diag.take().map(diagnostics::DiagnosticsWriter::finish) {
            eprintln!(
                "agent {}: diagnostics not fully written: {e}",
                self.spec.name
            );
        }
        Ok(exit)
    }
}
