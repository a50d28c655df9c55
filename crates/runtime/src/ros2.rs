//! The ROS 2 agent (`mrsim ros2`): one agent process for a set of robots
//! with `planner = "ros2"`, joined to the world like any agent (over shared
//! memory or Zenoh) and, on the other side, a ROS 2 node on a Zenoh
//! session as rmw_zenoh makes one (`mrsim_ros2`). Per robot, under
//! `/<prefix><robot>/`: `cmd_vel` in (geometry_msgs/msg/Twist), `odom` and,
//! with a lidar, `scan` out; for all, `/tf` (odom to base_link), `/clock`
//! and, with a map, `/map`.
//!
//! Each tick: on the tick's first observation `/clock` is published (the
//! tick's simulated time), then per robot its odometry, tf and scan, then
//! its command is sent: in realtime the last `cmd_vel` (none yet, or none
//! for [`STALE_AFTER`]: brake); in lockstep the first `cmd_vel` that came
//! after this tick's `/clock`, waited for up to [`Ros2Request::wait`]
//! (then the robot brakes for the tick and the miss is counted).
//!
//! Bad input never stops anything: a `cmd_vel` that does not decode as a
//! Twist, one with a non-finite or absurd value, one of another type
//! published under the same name, and a flood (more than [`FLOOD`] in one
//! second) each make the robot brake, and are counted (the first of each
//! kind per robot is logged); the counts are written at the end
//! ([`Ros2Request::stats_out`]).

use crate::error::{Invalid, Refusal};
use mrsim_agents::{AgentExit, AgentOptions, Live, Next, OwnedObservation};
use mrsim_planners::ackermann::steering_for_turn_rate;
use mrsim_planners::{Command, Kinematics, SelfState, Vec2};
use mrsim_ros2::attachment::Attachment;
use mrsim_ros2::msgs::{
    Clock, Header, LaserScan, OccupancyGrid, Odometry, Quaternion, TfMessage, Time,
    TransformStamped, Twist, Vector3,
};
use mrsim_ros2::names::{self, Qos};
use mrsim_ros2::node::{Node, NodeError, NodeOptions, Publisher, Received, Subscription};
use mrsim_transport::shm::ShmAgent;
use mrsim_transport::zenoh::{ZenohAgent, ZenohOptions};
use mrsim_transport::{AgentTransport, Namespace, TransportError};
use serde::Serialize;
use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::{Arc, Condvar, Mutex};
use std::time::{Duration, Instant};

/// A `cmd_vel` component beyond this (m/s or rad/s) is absurd: the robot
/// brakes instead of the world clamping it.
pub const ABSURD: f64 = 1.0e3;

/// More `cmd_vel` samples than this for one robot within one second (of
/// wall time: a tick of lockstep may be far shorter) are a flood: the rest
/// of that second's, and every one of the next second's, are dropped and
/// the robot brakes; it takes commands again after a second of no flood.
pub const FLOOD: u64 = 200;

/// In realtime, a robot whose last `cmd_vel` is older than this brakes.
pub const STALE_AFTER: Duration = Duration::from_millis(500);

/// The counts file `mrsim run` has the ROS 2 agent write into the run
/// folder.
pub const STATS_FILE: &str = mrsim_runfolder::ROS2_STATS_FILE;

/// What `mrsim ros2` is asked to do.
#[derive(Debug, Clone, Default)]
pub struct Ros2Request {
    /// The robots (their planner `ros2`).
    pub robots: Vec<String>,
    /// The world's run id.
    pub run_id: String,
    /// How long to wait for the world and the join.
    pub timeout: Duration,
    /// Over Zenoh to the world instead of shared memory.
    pub zenoh: Option<ZenohOptions>,
    /// The ROS 2 side: domain, router, config.
    pub node: NodeOptions,
    /// Topic prefix before the robot's name (`sim` gives `/sim/a0/odom`).
    pub prefix: String,
    /// Lockstep: how long to wait for a robot's `cmd_vel` after the tick's
    /// `/clock` before it brakes for the tick.
    pub wait: Duration,
    /// The scenario's map (its YAML), published on `/map`.
    pub map: Option<PathBuf>,
    /// Write the counts here (JSON) at the end.
    pub stats_out: Option<PathBuf>,
}

/// Why the ROS 2 agent failed.
#[derive(Debug, thiserror::Error)]
pub enum Ros2Error {
    /// Refused before anything ran.
    #[error(transparent)]
    Invalid(#[from] Invalid),
    /// The world was not reached.
    #[error("ros2 agent: cannot reach the world of run `{run_id}`")]
    Connect {
        /// The run id.
        run_id: String,
        /// Why.
        #[source]
        source: TransportError,
    },
    /// The ROS 2 side failed.
    #[error("ros2 agent: {0}")]
    Node(#[from] NodeError),
    /// Joining or driving failed.
    #[error("ros2 agent: {0}")]
    Agent(#[from] mrsim_agents::AgentError),
    /// The map did not load.
    #[error("ros2 agent: map: {0}")]
    Map(String),
    /// The counts were not written.
    #[error("ros2 agent: cannot write {path}: {source}")]
    Stats {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
}

impl Refusal for Ros2Error {
    fn refused(&self) -> Option<&Invalid> {
        match self {
            Ros2Error::Invalid(i) => Some(i),
            _ => None,
        }
    }
}

/// What one robot's `cmd_vel` brought, counted.
#[derive(Debug, Clone, Default, Serialize, PartialEq, Eq)]
pub struct CmdCounts {
    /// Samples under the topic's name, of any type.
    pub received: u64,
    /// Twists taken as the robot's command.
    pub accepted: u64,
    /// Payloads that did not decode as a Twist.
    pub undecodable: u64,
    /// Twists with a NaN or infinite component.
    pub non_finite: u64,
    /// Twists with a component beyond [`ABSURD`].
    pub absurd: u64,
    /// Samples of another type under the same topic name.
    pub wrong_type: u64,
    /// Samples without a well-formed 33-byte attachment (taken anyway).
    pub bad_attachment: u64,
    /// Samples beyond [`FLOOD`] in one second, dropped.
    pub flooded: u64,
    /// Lockstep ticks with no `cmd_vel` after the tick's `/clock` within
    /// the wait (the robot braked).
    pub missed: u64,
    /// Realtime ticks whose last `cmd_vel` was stale or absent (braked).
    pub stale: u64,
    /// Ticks answered.
    pub ticks: u64,
}

/// One robot's `cmd_vel` state, shared with its subscriber's callback.
#[derive(Debug, Default)]
struct CmdState {
    /// The command to apply (a bad sample sets a brake).
    latest: Option<Twist>,
    /// When it came.
    at: Option<Instant>,
    /// Bumped on every sample that sets `latest` (good or bad).
    seq: u64,
    /// Samples in the current second, and when it began.
    this_second: u64,
    second_began: Option<Instant>,
    /// The second before this one was a flood: this one's samples are
    /// dropped too, so that a flood's tail never drives the robot.
    flood_held: bool,
    counts: CmdCounts,
    /// Kinds already logged.
    logged: u8,
}

struct Inbox {
    state: Mutex<Vec<CmdState>>,
    arrived: Condvar,
}

/// What a sample is, once judged.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Verdict {
    Take(Twist),
    Undecodable,
    NonFinite,
    Absurd,
    WrongType,
}

/// Judges one `cmd_vel` sample: its type (by key), its payload, its values.
fn judge(right_type: bool, payload: &[u8]) -> (Verdict, Option<String>) {
    if !right_type {
        return (Verdict::WrongType, None);
    }
    let t = match Twist::decode(payload) {
        Ok(t) => t,
        Err(e) => return (Verdict::Undecodable, Some(e.to_string())),
    };
    let all = [
        t.linear.x,
        t.linear.y,
        t.linear.z,
        t.angular.x,
        t.angular.y,
        t.angular.z,
    ];
    if all.iter().any(|v| !v.is_finite()) {
        return (Verdict::NonFinite, None);
    }
    if all.iter().any(|v| v.abs() > ABSURD) {
        return (Verdict::Absurd, None);
    }
    (Verdict::Take(t), None)
}

impl Inbox {
    fn on_sample(&self, robot: usize, name: &str, r: Received<'_>) {
        let Ok(mut all) = self.state.lock() else {
            return;
        };
        let Some(s) = all.get_mut(robot) else {
            return;
        };
        s.counts.received += 1;
        let now = Instant::now();
        if s.second_began
            .is_none_or(|t| now.duration_since(t) >= Duration::from_secs(1))
        {
            s.second_began = Some(now);
            s.flood_held = s.this_second > FLOOD;
            s.this_second = 0;
        }
        s.this_second += 1;
        if s.this_second > FLOOD || s.flood_held {
            s.counts.flooded += 1;
            s.latest = Some(Twist::default());
            s.at = Some(now);
            s.seq += 1;
            log_once(
                s,
                1,
                name,
                &format!(
                    "more than {FLOOD} cmd_vel in one second: a flood; braking, the rest dropped"
                ),
            );
            self.arrived.notify_all();
            return;
        }
        if r.attachment
            .as_deref()
            .map(Attachment::decode)
            .is_none_or(|a| a.is_err())
        {
            s.counts.bad_attachment += 1;
            log_once(
                s,
                2,
                name,
                "a cmd_vel without rmw_zenoh's 33-byte attachment (taken)",
            );
        }
        let (verdict, why) = judge(r.right_type, &r.payload);
        let brake = Twist::default();
        match verdict {
            Verdict::Take(t) => {
                s.counts.accepted += 1;
                s.latest = Some(t);
            }
            Verdict::Undecodable => {
                s.counts.undecodable += 1;
                s.latest = Some(brake);
                let why = why.unwrap_or_default();
                log_once(
                    s,
                    4,
                    name,
                    &format!("a cmd_vel that is not a geometry_msgs/msg/Twist ({why}): braking"),
                );
            }
            Verdict::NonFinite => {
                s.counts.non_finite += 1;
                s.latest = Some(brake);
                log_once(
                    s,
                    8,
                    name,
                    "a cmd_vel with a NaN or infinite value: braking",
                );
            }
            Verdict::Absurd => {
                s.counts.absurd += 1;
                s.latest = Some(brake);
                log_once(
                    s,
                    16,
                    name,
                    &format!("a cmd_vel with a value beyond {ABSURD}: braking"),
                );
            }
            Verdict::WrongType => {
                s.counts.wrong_type += 1;
                s.latest = Some(brake);
                log_once(
                    s,
                    32,
                    name,
                    &format!(
                        "a sample of another type under cmd_vel ({}): braking",
                        r.key
                    ),
                );
            }
        }
        s.at = Some(Instant::now());
        s.seq += 1;
        self.arrived.notify_all();
    }
}

fn log_once(s: &mut CmdState, bit: u8, robot: &str, what: &str) {
    if s.logged & bit == 0 {
        s.logged |= bit;
        eprintln!("ros2 agent: {robot}: {what} (further ones are counted, not logged)");
    }
}

/// The command a Twist means for the robot `me`: a holonomic robot takes
/// `linear.x`, `linear.y` as its velocity; a unicycle `linear.x` as its
/// forward speed and `angular.z` as its turn rate; a car takes them as
/// teb_local_planner's car-like mode publishes them (`linear.x` the speed,
/// `angular.z` the heading's rate), steering atan(L omega / v) so that the
/// bicycle turns at omega (at v = 0 no steering turns the car: it keeps
/// the steering it has, `me.steering`).
pub fn command_of(t: &Twist, me: &SelfState) -> Command {
    match me.kinematics {
        Kinematics::Unicycle { .. } => Command::Unicycle {
            v: t.linear.x,
            omega: t.angular.z,
        },
        Kinematics::Ackermann { wheelbase, .. } => Command::Ackermann {
            speed: t.linear.x,
            steering: steering_for_turn_rate(t.linear.x, t.angular.z, wheelbase, me.steering),
        },
        Kinematics::Holonomic => Command::Velocity(Vec2::new(t.linear.x, t.linear.y)),
    }
}

/// The frames of `robot`: (`<robot>/odom`, `<robot>/base_link`).
pub fn frames(robot: &str) -> (String, String) {
    (format!("{robot}/odom"), format!("{robot}/base_link"))
}

/// The odometry of an observation: the pose in the robot's odom frame
/// (the world's, as the simulation knows it), the velocity in its body
/// frame.
pub fn odometry_of(robot: &str, o: &OwnedObservation) -> Odometry {
    let (odom, base) = frames(robot);
    let (s, c) = o.me.heading.sin_cos();
    let v = o.me.velocity;
    Odometry {
        header: Header {
            stamp: Time::from_secs(o.time),
            frame_id: odom,
        },
        child_frame_id: base,
        position: Vector3 {
            x: o.me.position.x,
            y: o.me.position.y,
            z: 0.0,
        },
        orientation: Quaternion::from_yaw(o.me.heading),
        linear: Vector3 {
            x: c * v.x + s * v.y,
            y: -s * v.x + c * v.y,
            z: 0.0,
        },
        angular: Vector3 {
            x: 0.0,
            y: 0.0,
            z: o.me.angular_velocity,
        },
    }
}

/// The laser scan of an observation, in the robot's base_link frame.
pub fn scan_of(robot: &str, o: &OwnedObservation) -> Option<LaserScan> {
    let sc = o.scan.as_ref()?;
    let n = sc.ranges.len();
    Some(LaserScan {
        header: Header {
            stamp: Time::from_secs(o.time),
            frame_id: frames(robot).1,
        },
        angle_min: sc.angle_min as f32,
        angle_max: (sc.angle_min + sc.angle_increment * n.saturating_sub(1) as f64) as f32,
        angle_increment: sc.angle_increment as f32,
        time_increment: 0.0,
        scan_time: o.dt as f32,
        range_min: 0.0,
        range_max: sc.range_max as f32,
        ranges: sc.ranges.iter().map(|r| *r as f32).collect(),
    })
}

/// The map as an OccupancyGrid in frame `map`.
fn grid_of(yaml: &std::path::Path) -> Result<OccupancyGrid, Ros2Error> {
    let m = mrsim_scenario::map::load(yaml).map_err(|e| Ros2Error::Map(e.to_string()))?;
    let c = |n: usize| u32::try_from(n).map_err(|_| Ros2Error::Map(format!("{n} cells")));
    Ok(OccupancyGrid {
        header: Header {
            stamp: Time::default(),
            frame_id: "map".to_string(),
        },
        map_load_time: Time::default(),
        resolution: m.meta.resolution as f32,
        width: c(m.width)?,
        height: c(m.height)?,
        origin_position: Vector3 {
            x: m.meta.origin[0],
            y: m.meta.origin[1],
            z: 0.0,
        },
        origin_orientation: Quaternion::from_yaw(m.meta.origin[2]),
        data: m.values,
    })
}

/// One robot's ROS 2 side.
struct RobotSide {
    name: String,
    odom: Publisher,
    scan: Option<Publisher>,
    _cmd: Subscription,
    /// The inbox's `seq` when this tick's `/clock` went out.
    mark: u64,
}

/// What the node declared: every token and key, for the counts file.
struct Declared {
    domain: u32,
    tokens: Vec<String>,
    keys: Vec<String>,
}

impl Declared {
    /// Declares a publisher and notes its token and key.
    fn publisher(
        &mut self,
        node: &mut Node,
        topic: &str,
        ty: &names::MsgType,
        qos: Qos,
    ) -> Result<Publisher, Ros2Error> {
        let p = node.publisher(topic, ty, qos)?;
        self.tokens.push(p.token().to_string());
        if let Some(cache) = p.cache_key() {
            self.tokens.push(cache.to_string());
        }
        self.keys.push(names::topic_key(self.domain, topic, ty));
        Ok(p)
    }
}

/// The counts of the run, per robot, as written to
/// [`Ros2Request::stats_out`].
#[derive(Debug, Clone, Serialize)]
pub struct Ros2Stats {
    /// Per robot name.
    pub robots: std::collections::BTreeMap<String, CmdCounts>,
    /// The node's liveliness token and every publisher's and
    /// subscriber's (and a transient-local publisher's cache's), as
    /// declared.
    pub tokens: Vec<String>,
    /// The key expression of every topic, as published or subscribed.
    pub keys: Vec<String>,
}

/// Joins the world as `req.robots` and relays between it and ROS 2 until
/// the run ends.
pub fn run(req: &Ros2Request) -> Result<Ros2Stats, Ros2Error> {
    let ns = Namespace::new(&req.run_id).map_err(|e| Invalid(e.to_string()))?;
    for r in &req.robots {
        if !names::is_ros_token(r) {
            return Err(Invalid(format!(
                "robot `{r}`: not a ROS name (a letter or `_`, then letters, digits and `_`)"
            ))
            .into());
        }
    }
    let node_name = format!(
        "mrsim_{}",
        req.robots.first().map_or("ros2", String::as_str)
    );
    let mut link: Box<dyn AgentTransport> = match &req.zenoh {
        None => ShmAgent::connect(&ns, &format!("mrsim-ros2-{node_name}"), req.timeout)
            .map(|a| Box::new(a) as _),
        Some(z) => ZenohAgent::connect(&ns, z, req.timeout).map(|a| Box::new(a) as _),
    }
    .map_err(|source| Ros2Error::Connect {
        run_id: req.run_id.clone(),
        source,
    })?;
    let grid = req.map.as_deref().map(grid_of).transpose()?;

    // The ROS side first, so a ROS node sees the topics before the run
    // starts.
    let mut node = Node::open(&NodeOptions {
        name: node_name,
        ..req.node.clone()
    })?;
    let mut declared = Declared {
        domain: req.node.domain,
        tokens: vec![node.token()],
        keys: Vec::new(),
    };
    let mut clock = declared.publisher(
        &mut node,
        "/clock",
        &names::CLOCK,
        Qos {
            best_effort: true,
            transient_local: false,
            depth: 1,
        },
    )?;
    let mut tf = declared.publisher(&mut node, "/tf", &names::TF_MESSAGE, Qos::reliable(100))?;
    // Transient local: published once, kept in the publisher's cache for
    // the subscribers that come later (as rmw_zenoh's does).
    let _map_pub = match &grid {
        Some(g) => {
            let mut p = declared.publisher(
                &mut node,
                "/map",
                &names::OCCUPANCY_GRID,
                Qos {
                    best_effort: false,
                    transient_local: true,
                    depth: 1,
                },
            )?;
            p.put(g.encode())?;
            Some(p)
        }
        None => None,
    };
    let inbox = Arc::new(Inbox {
        state: Mutex::new((0..req.robots.len()).map(|_| CmdState::default()).collect()),
        arrived: Condvar::new(),
    });
    let mut sides = Vec::with_capacity(req.robots.len());
    for (i, r) in req.robots.iter().enumerate() {
        let topic = |t: &str| names::robot_topic(&req.prefix, r, t);
        let odom = declared.publisher(
            &mut node,
            &topic("odom"),
            &names::ODOMETRY,
            Qos::reliable(10),
        )?;
        let ib = inbox.clone();
        let who = r.clone();
        let cmd = node.subscribe(
            &topic("cmd_vel"),
            &names::TWIST,
            Qos::reliable(10),
            move |s| ib.on_sample(i, &who, s),
        )?;
        declared.tokens.push(cmd.token().to_string());
        declared.keys.push(names::topic_key(
            declared.domain,
            &topic("cmd_vel"),
            &names::TWIST,
        ));
        sides.push(RobotSide {
            name: r.clone(),
            odom,
            scan: None,
            _cmd: cmd,
            mark: 0,
        });
    }

    let opts: Vec<AgentOptions> = req
        .robots
        .iter()
        .map(|r| {
            let mut o = AgentOptions::new(r);
            o.join_timeout = req.timeout;
            o
        })
        .collect();
    let mut live: Live = mrsim_agents::join_live(link.as_mut(), &opts)?
        .ok_or(mrsim_agents::AgentError::Interrupted)?;
    let index: HashMap<usize, usize> = live
        .robots()
        .into_iter()
        .filter_map(|(id, name)| req.robots.iter().position(|r| *r == name).map(|i| (id, i)))
        .collect();

    let mut last_tick = None;
    let exit = loop {
        let obs = match live.next(link.as_mut(), Duration::from_millis(100))? {
            Next::Observation(o) => o,
            Next::Idle => continue,
            Next::Finished => break AgentExit::Finished,
            Next::Interrupted => break AgentExit::Interrupted,
            Next::WorldGone => return Err(mrsim_agents::AgentError::WorldGone.into()),
        };
        let Some(&i) = index.get(&(obs.me.id as usize)) else {
            continue;
        };
        if last_tick != Some(obs.tick) {
            last_tick = Some(obs.tick);
            // A cmd_vel counts for this tick only if it comes after this
            // /clock.
            if let Ok(mut all) = inbox.state.lock() {
                for (s, side) in all.iter_mut().zip(sides.iter_mut()) {
                    side.mark = s.seq;
                }
            }
            clock.put(
                Clock {
                    clock: Time::from_secs(obs.time),
                }
                .encode(),
            )?;
        }
        let side = &mut sides[i];
        let odom = odometry_of(&side.name, &obs);
        side.odom.put(odom.encode())?;
        tf.put(
            TfMessage {
                transforms: vec![TransformStamped {
                    header: odom.header.clone(),
                    child_frame_id: odom.child_frame_id.clone(),
                    translation: odom.position,
                    rotation: odom.orientation,
                }],
            }
            .encode(),
        )?;
        if let Some(scan) = scan_of(&side.name, &obs) {
            if side.scan.is_none() {
                let topic = names::robot_topic(&req.prefix, &side.name, "scan");
                side.scan = Some(declared.publisher(
                    &mut node,
                    &topic,
                    &names::LASER_SCAN,
                    Qos {
                        best_effort: true,
                        transient_local: false,
                        depth: 5,
                    },
                )?);
            }
            if let Some(p) = side.scan.as_mut() {
                p.put(scan.encode())?;
            }
        }
        let lockstep = obs.deadline_ns == 0;
        let twist = take_command(&inbox, i, side.mark, lockstep, req.wait);
        live.reply(link.as_mut(), command_of(&twist, &obs.me))?;
    };
    let finished = live.finish(exit);
    let robots = match inbox.state.lock() {
        Ok(all) => req
            .robots
            .iter()
            .zip(all.iter())
            .map(|(r, s)| (r.clone(), s.counts.clone()))
            .collect(),
        Err(_) => Default::default(),
    };
    let stats = Ros2Stats {
        robots,
        tokens: declared.tokens,
        keys: declared.keys,
    };
    if let Some(path) = &req.stats_out {
        let text = serde_json::to_string_pretty(&stats).unwrap_or_default();
        std::fs::write(path, text).map_err(|source| Ros2Error::Stats {
            path: path.clone(),
            source,
        })?;
    }
    finished?;
    Ok(stats)
}

/// The command of robot `i` for this tick: in lockstep the first sample
/// after `mark` (waited for up to `wait`, else a brake, counted missed);
/// in realtime the last one (a brake if none came within
/// [`STALE_AFTER`], counted stale).
fn take_command(inbox: &Inbox, i: usize, mark: u64, lockstep: bool, wait: Duration) -> Twist {
    let Ok(mut all) = inbox.state.lock() else {
        return Twist::default();
    };
    if lockstep {
        let until = Instant::now() + wait;
        while all.get(i).is_some_and(|s| s.seq <= mark) {
            let left = until.saturating_duration_since(Instant::now());
            if left.is_zero() {
                break;
            }
            all = match inbox.arrived.wait_timeout(all, left) {
                Ok((g, _)) => g,
                Err(_) => return Twist::default(),
            };
        }
    }
    let Some(s) = all.get_mut(i) else {
        return Twist::default();
    };
    s.counts.ticks += 1;
    let fresh = if lockstep {
        s.seq > mark
    } else {
        s.at.is_some_and(|t| t.elapsed() <= STALE_AFTER)
    };
    match (fresh, s.latest) {
        (true, Some(t)) => t,
        _ => {
            if lockstep {
                s.counts.missed += 1;
            } else {
                s.counts.stale += 1;
            }
            Twist::default()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_good_twist_is_taken_and_bad_ones_are_told_apart() {
        let t = Twist {
            linear: Vector3 {
                x: 0.3,
                y: 0.0,
                z: 0.0,
            },
            angular: Vector3::default(),
        };
        assert_eq!(judge(true, &t.encode()).0, Verdict::Take(t));
        assert_eq!(judge(false, &t.encode()).0, Verdict::WrongType);
        assert_eq!(judge(true, &[0, 1, 0, 0, 1]).0, Verdict::Undecodable);
        let mut nan = t;
        nan.angular.z = f64::NAN;
        assert_eq!(judge(true, &nan.encode()).0, Verdict::NonFinite);
        let mut big = t;
        big.linear.x = 1e9;
        assert_eq!(judge(true, &big.encode()).0, Verdict::Absurd);
    }

    #[test]
    fn a_unicycle_takes_forward_speed_and_turn_rate_a_holonomic_robot_x_and_y() {
        let t = Twist {
            linear: Vector3 {
                x: 0.5,
                y: 0.25,
                z: 0.0,
            },
            angular: Vector3 {
                x: 0.0,
                y: 0.0,
                z: -1.0,
            },
        };
        let uni = Kinematics::Unicycle {
            max_angular_speed: 1.0,
            max_angular_accel: 1.0,
        };
        assert_eq!(
            command_of(&t, &me(uni, 0.0)),
            Command::Unicycle {
                v: 0.5,
                omega: -1.0
            }
        );
        assert_eq!(
            command_of(&t, &me(Kinematics::Holonomic, 0.0)),
            Command::Velocity(Vec2::new(0.5, 0.25))
        );
    }

    /// A robot of `kinematics` at rest with steering `steering`.
    fn me(kinematics: Kinematics, steering: f64) -> SelfState {
        SelfState {
            id: 0,
            position: Vec2::zeros(),
            velocity: Vec2::zeros(),
            radius: 1.0,
            shape: mrsim_planners::Shape::disc(1.0),
            mass: 1.0,
            damping: 0.0,
            max_speed: 4.0,
            max_accel: 2.0,
            heading: 0.0,
            angular_velocity: 0.0,
            steering,
            kinematics,
        }
    }

    #[test]
    fn a_car_takes_teb_s_speed_and_turn_rate_as_the_steering_of_that_turn() {
        let car = Kinematics::Ackermann {
            wheelbase: 3.0,
            max_steering: 0.5,
            max_steering_rate: 1.0,
            max_reverse_speed: 1.0,
        };
        let twist = |v: f64, w: f64| Twist {
            linear: Vector3 {
                x: v,
                y: 0.7,
                z: 0.0,
            },
            angular: Vector3 {
                x: 0.0,
                y: 0.0,
                z: w,
            },
        };
        // v = 2 m/s, omega = 0.5 rad/s on L = 3: tan(delta) = 0.75, and
        // the bicycle then turns at v tan(delta) / L = 0.5 (linear.y, which
        // a car cannot follow, is ignored).
        let Command::Ackermann { speed, steering } = command_of(&twist(2.0, 0.5), &me(car, 0.1))
        else {
            panic!("a car's command");
        };
        assert_eq!(speed, 2.0);
        assert!((steering.tan() - 0.75).abs() < 1e-12, "{steering}");
        // Backwards, the same turn rate steers the other way.
        let Command::Ackermann { speed, steering } = command_of(&twist(-1.0, 0.5), &me(car, 0.1))
        else {
            panic!("a car's command");
        };
        assert_eq!(speed, -1.0);
        assert!((steering.tan() + 1.5).abs() < 1e-12, "{steering}");
        // At rest no steering turns the car: it keeps its own; a zero
        // Twist (what a missing cmd_vel brakes with) stops it so.
        assert_eq!(
            command_of(&twist(0.0, 0.5), &me(car, 0.1)),
            Command::Ackermann {
                speed: 0.0,
                steering: 0.1
            }
        );
        assert_eq!(
            command_of(&Twist::default(), &me(car, -0.2)),
            Command::Ackermann {
                speed: 0.0,
                steering: -0.2
            }
        );
    }

    #[test]
    fn lockstep_brakes_when_no_cmd_vel_came_after_the_clock() {
        let inbox = Inbox {
            state: Mutex::new(vec![CmdState::default()]),
            arrived: Condvar::new(),
        };
        let t = take_command(&inbox, 0, 0, true, Duration::from_millis(1));
        assert_eq!(t, Twist::default());
        let s = inbox.state.lock().unwrap();
        assert_eq!((s[0].counts.missed, s[0].counts.ticks), (1, 1));
    }
}
