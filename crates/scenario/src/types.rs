//! The resolved scenario: what the world and the agents use after loading,
//! defaults applied, `[generate]` expanded and everything validated.
//!
//! These types are also the start-up message the world sends every agent
//! (as JSON), so they derive both `Serialize` and `Deserialize`.

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// The unit of every length in a scenario file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum LengthUnit {
    /// Metres (default).
    #[default]
    M,
    /// Centimetres (Ko & Choi's cases).
    Cm,
    /// Millimetres.
    Mm,
}

impl LengthUnit {
    /// How many of this unit make a metre (rapier's `length_unit`).
    pub fn per_metre(self) -> f64 {
        match self {
            LengthUnit::M => 1.0,
            LengthUnit::Cm => 100.0,
            LengthUnit::Mm => 1000.0,
        }
    }
}

/// How the world keeps time.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Mode {
    /// Wait for every live agent each tick: deterministic.
    #[default]
    Lockstep,
    /// Tick on the wall clock; late commands are deadline misses.
    Realtime,
}

impl std::fmt::Display for Mode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Mode::Lockstep => "lockstep",
            Mode::Realtime => "realtime",
        })
    }
}

/// What a robot does when its command misses the deadline (realtime).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum MissPolicy {
    /// Keep applying the last command.
    #[default]
    Hold,
    /// Brake: force/velocity set to stop the robot.
    Brake,
}

/// An axis-aligned arena with walls all round.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Arena {
    /// Lower-left corner.
    pub min: [f64; 2],
    /// Upper-right corner.
    pub max: [f64; 2],
}

/// The `[world]` table.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WorldConfig {
    /// Tick = control period, s (default 0.1).
    pub dt: f64,
    /// Physics steps per tick (default 10).
    pub substeps: u32,
    /// Simulated time at most, s (default 60).
    pub duration: f64,
    /// Lockstep or realtime (default lockstep).
    pub mode: Mode,
    /// Policy on a deadline miss (default hold).
    pub on_deadline_miss: MissPolicy,
    /// Seed of every random process (default 1).
    pub seed: u64,
    /// Optional walls all round.
    pub arena: Option<Arena>,
    /// Deadline as a fraction of the tick, (0, 1] (default 1.0).
    pub deadline: f64,
    /// Lockstep: how long the world waits for an agent before it is lost,
    /// s (default 2.0).
    pub stall_timeout: f64,
    /// Robots each agent process of `mrsim run` drives (default 1; the
    /// last process takes the rest). Left out of the resolved scenario
    /// when 1, so files written before it existed read the same.
    #[serde(default = "one", skip_serializing_if = "is_one")]
    pub robots_per_agent: u32,
    /// Seconds without progress towards its goal after which a robot not
    /// at its goal is stuck (default [`DEFAULT_STUCK_AFTER`]; left out of
    /// the resolved scenario at the default).
    #[serde(
        default = "default_stuck_after",
        skip_serializing_if = "is_default_stuck_after"
    )]
    pub stuck_after: f64,
    /// End the run once every robot not at its goal is stuck (default
    /// false; left out of the resolved scenario when false).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub end_when_stuck: bool,
    /// What ends the run as a benchmark's episode ends (`[world] end_on`):
    /// a robot's first contact, the time limit. Left out of the resolved
    /// scenario when it names nothing.
    #[serde(default, skip_serializing_if = "EndOn::is_empty")]
    pub end_on: EndOn,
    /// The cores the agents' CPU work shares (`[world.cpus]`), if the
    /// scenario models them; `None`: CPU work has a core of its own per
    /// agent. Left out of the resolved scenario when `None`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cpus: Option<Cpus>,
}

/// `[world] end_on = ["collision", "timeout"]`: the run counted as an
/// episode of the crowd-navigation benchmarks (CrowdNav's `CrowdSim.step`),
/// each robot's outcome success, collision or timeout.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct EndOn {
    /// `"collision"`: the first contact of a robot not yet at its goal
    /// (with a robot, a person, an obstacle or a wall; never one among
    /// people or obstacles alone) ends the run at the tick it starts.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub collision: bool,
    /// `"timeout"`: the run's time limit (`[world] duration`) ends the
    /// episode, and the robots not at their goals then are timeouts.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub timeout: bool,
}

impl EndOn {
    /// The names `end_on` takes, in the order they are listed.
    pub const NAMES: [&'static str; 2] = ["collision", "timeout"];

    /// True if it names nothing: the run is counted as mrsim counts it,
    /// with no episode outcome.
    pub fn is_empty(&self) -> bool {
        !self.collision && !self.timeout
    }

    /// The names it holds, as written in a scenario file.
    pub fn names(&self) -> Vec<&'static str> {
        let on = [self.collision, self.timeout];
        Self::NAMES
            .iter()
            .zip(on)
            .filter(|(_, on)| *on)
            .map(|(n, _)| *n)
            .collect()
    }
}

/// `[world.cpus]`: the cores the planners' CPU work (`compute = { ...,
/// cpu = true }`) contends for, and how they are shared.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Cpus {
    /// Cores the agents' CPU work shares, >= 1.
    pub count: u32,
    /// How the cores are shared among the runnable planners (default fair).
    pub scheduler: Scheduler,
    /// CPU the world itself takes on one of the cores at the start of
    /// every tick, above every agent, ms, >= 0 (default 0).
    pub world_ms: f64,
}

/// How the cores are shared (`[world.cpus] scheduler`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Scheduler {
    /// Processor sharing among the runnable planners, the idealised share
    /// of Linux's SCHED_OTHER (CFS/EEVDF).
    #[default]
    Fair,
    /// Global fixed-priority preemptive (SCHED_FIFO): each robot's
    /// `timing.priority`, rate-monotonic where it has none.
    Fifo,
    /// Global EDF over constant-bandwidth reservations (SCHED_DEADLINE):
    /// each robot's `timing.reservation`.
    Deadline,
}

impl Scheduler {
    /// The name as written in a scenario file.
    pub fn name(self) -> &'static str {
        match self {
            Scheduler::Fair => "fair",
            Scheduler::Fifo => "fifo",
            Scheduler::Deadline => "deadline",
        }
    }
}

/// `[world] stuck_after` when the file does not say, s.
pub const DEFAULT_STUCK_AFTER: f64 = 10.0;

fn default_stuck_after() -> f64 {
    DEFAULT_STUCK_AFTER
}

fn is_default_stuck_after(s: &f64) -> bool {
    *s == DEFAULT_STUCK_AFTER
}

fn one() -> u32 {
    1
}

fn is_one(k: &u32) -> bool {
    *k == 1
}

/// One planner parameter value (see `mrsim_planners::ParamValue`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum ParamValue {
    /// A boolean.
    Bool(bool),
    /// A number (integers included).
    Number(f64),
    /// A string.
    Text(String),
    /// A list of numbers.
    Numbers(Vec<f64>),
    /// A list of points.
    Points(Vec<[f64; 2]>),
}

/// Where a robot's sensed velocities come from (Zhu & Loh eqs 2.9-2.12).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum VelocitySource {
    /// The true velocity from the snapshot.
    #[default]
    Truth,
    /// Differenced from the last observed positions, as a camera gives it.
    Differenced,
}

/// How a robot moves (the `kinematics` robot key).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Kinematics {
    /// A disc driven by a force or a velocity in any direction (default).
    #[default]
    Holonomic,
    /// A differential drive: forward speed v along its heading and turn
    /// rate omega, never sideways.
    Unicycle,
    /// A car: the kinematic bicycle, a speed along the heading and a
    /// steering angle of the front wheels, within the limits of its
    /// [`Ackermann`] (`RobotSpec::ackermann`).
    Ackermann,
}

/// A car-like robot's geometry and steering limits (`kinematics =
/// "ackermann"`: the keys `wheelbase`, `max_steering_deg`,
/// `max_steering_rate_deg`, `max_reverse_speed`). The robot's pose names
/// the centre of its shape; the wheelbase is centred on it, so the rear
/// axle is `wheelbase / 2` behind the centre along the heading.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Ackermann {
    /// Distance between the axles, > 0.
    pub wheelbase: f64,
    /// Largest steering angle either way, rad, in (0, pi/2).
    pub max_steering: f64,
    /// Fastest change of the steering angle, rad/s, > 0.
    pub max_steering_rate: f64,
    /// Fastest speed backwards, >= 0 (0: the car never reverses).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub max_reverse_speed: f64,
}

/// Built-in `max_steering_deg`, degrees.
pub const DEFAULT_MAX_STEERING_DEG: f64 = 30.0;
/// Built-in `max_steering_rate_deg`, degrees per second.
pub const DEFAULT_MAX_STEERING_RATE_DEG: f64 = 60.0;
/// Built-in `goal_heading_tolerance_deg`, degrees.
pub const DEFAULT_GOAL_HEADING_TOLERANCE_DEG: f64 = 10.0;

impl Ackermann {
    /// The radius of the tightest circle the rear axle drives,
    /// `wheelbase / tan(max_steering)` (the centre's, L/2 ahead of the
    /// axle, is `sqrt(R^2 + (L/2)^2)`).
    pub fn min_turning_radius(&self) -> f64 {
        self.wheelbase / self.max_steering.tan()
    }
}

/// The heading a robot must have at its goal (`goal_heading_deg`,
/// `goal_heading_tolerance_deg`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct GoalHeading {
    /// The heading, rad, counter-clockwise from +x.
    pub heading: f64,
    /// How far the robot's heading may be from it, rad, in (0, pi].
    pub tolerance: f64,
}

impl GoalHeading {
    /// Is `heading` (rad) within the tolerance of the goal heading (the
    /// difference taken the short way round)?
    pub fn holds(&self, heading: f64) -> bool {
        angle_between(heading, self.heading) <= self.tolerance
    }
}

/// The angle between two headings, rad, in [0, pi] (the short way round).
pub fn angle_between(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(std::f64::consts::TAU);
    d.min(std::f64::consts::TAU - d)
}

/// How a robot's planner is led to its goal (the `route` robot key).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Route {
    /// The planner is given the goal itself (default).
    #[default]
    Direct,
    /// The planner is given a waypoint ahead on the shortest way its disc
    /// fits through the walls and static obstacles (`mrsim-route`),
    /// computed at the start and again when the robot stops making progress.
    Shortest,
}

impl Route {
    /// Is this the default (left out of scenario.json)?
    pub fn is_direct(&self) -> bool {
        *self == Route::Direct
    }
}

/// Which side of a corridor a robot's route keeps to (the `lane` robot
/// key; only with `route = "shortest"`): the route is moved towards that
/// side of the way it is travelled where the walls leave room, so that
/// robots going opposite ways along a corridor wide enough for two pass
/// beside each other instead of meeting head-on (`mrsim-route`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Lane {
    /// The route as searched, through the middle of its way (default).
    #[default]
    None,
    /// Keep to the right of the direction of travel.
    Right,
    /// Keep to the left of the direction of travel.
    Left,
}

impl Lane {
    /// Is this the default (left out of scenario.json)?
    pub fn is_none(&self) -> bool {
        *self == Lane::None
    }
}

/// A robot's laser scanner (`sensor = { kind = "lidar", ... }`): `beams`
/// rays spread evenly over `fov_deg` centred on the robot's heading, each
/// giving the distance to the first surface within `range` (ROS
/// LaserScan's meanings).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Lidar {
    /// Rays per scan, >= 1.
    pub beams: u32,
    /// Angle covered, degrees in (0, 360].
    pub fov_deg: f64,
    /// Longest range, > 0; a ray that hits nothing reads +infinity.
    pub range: f64,
    /// Standard deviation of Gaussian noise on each hit's range (0 = none).
    pub noise: f64,
    /// Write every scan to scan.csv (default false).
    pub record: bool,
}

/// One robot, all defaults applied.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RobotSpec {
    /// Unique name; `mrsim agent --robot NAME` drives it.
    pub name: String,
    /// Start position.
    pub start: [f64; 2],
    /// Goal position.
    pub goal: [f64; 2],
    /// Planner name (checked against the planners crate by the launcher).
    pub planner: String,
    /// Planner parameters.
    pub params: BTreeMap<String, ParamValue>,
    /// Disc radius, >= 0 (0 = point robot); for another shape the radius
    /// of the smallest disc about its origin that holds it (what planners
    /// that see discs take it for).
    pub radius: f64,
    /// The body's shape (default a disc of `radius`).
    #[serde(default, skip_serializing_if = "ShapeSpec::is_disc")]
    pub shape: ShapeSpec,
    /// Mass, > 0.
    pub mass: f64,
    /// Linear damping b, >= 0.
    pub damping: f64,
    /// Speed limit enforced by the world, > 0.
    pub max_speed: f64,
    /// Acceleration limit enforced by the world, > 0.
    pub max_accel: f64,
    /// Time constant T of the velocity-command lag, s, >= 0 (0 = ideal).
    pub velocity_lag: f64,
    /// Sensing range, > 0.
    pub sensing_range: f64,
    /// Field of view, degrees in (0, 360], centred on the heading.
    pub field_of_view_deg: f64,
    /// Distance to the goal that counts as reached, > 0.
    pub goal_tolerance: f64,
    /// Ticks the robot must stay within tolerance (Ko & Choi eq 22's N).
    pub goal_hold_ticks: u32,
    /// True or differenced velocities of sensed bodies.
    pub velocity_source: VelocitySource,
    /// Standard deviation of Gaussian noise on sensed positions (0 = none).
    pub position_noise: f64,
    /// Designated path waypoints (Yamada), empty if none.
    pub path: Vec<[f64; 2]>,
    /// Half-width of the corridor around `path`.
    pub boundary: Option<f64>,
    /// Holonomic (default), unicycle or ackermann.
    #[serde(default)]
    pub kinematics: Kinematics,
    /// Ackermann: the car's geometry and steering limits; `Some` exactly
    /// when `kinematics` is [`Kinematics::Ackermann`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ackermann: Option<Ackermann>,
    /// The heading the robot must have at its goal, if any: it has
    /// arrived only when within `goal_tolerance` of the goal and within
    /// this heading's tolerance ([`RobotSpec::at_goal`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub goal_heading: Option<GoalHeading>,
    /// Unicycle: turn-rate limit enforced by the world, rad/s, > 0.
    #[serde(default = "default_angular_speed")]
    pub max_angular_speed: f64,
    /// Unicycle: angular-acceleration limit enforced by the world, rad/s²,
    /// > 0.
    #[serde(default = "default_angular_accel")]
    pub max_angular_accel: f64,
    /// Unicycle: distance ahead of the centre of the point a holonomic
    /// planner's velocity is applied to (the look-ahead controller,
    /// `mrsim_planners::unicycle`), > 0 and below `goal_tolerance` (by
    /// default [`default_lookahead_for`] the tolerance).
    #[serde(default = "default_lookahead")]
    pub lookahead: f64,
    /// How the planner is led to the goal (default direct).
    #[serde(default, skip_serializing_if = "Route::is_direct")]
    pub route: Route,
    /// Which side of a corridor its route keeps to (default none).
    #[serde(default, skip_serializing_if = "Lane::is_none")]
    pub lane: Lane,
    /// The robot's laser scanner, if it has one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sensor: Option<Lidar>,
    /// The robot's timing model (`[defaults.timing]`, `[robot.timing]`),
    /// if it has one (see [`crate::timing`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub timing: Option<crate::timing::Timing>,
    /// The planner calls of a recorded realtime run this robot replays
    /// (`mrsim rerun`): never from a file, set by the rerun itself.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub replay: Option<Vec<crate::timing::RecordedCall>>,
}

/// Built-in `max_angular_speed`, rad/s.
pub const DEFAULT_MAX_ANGULAR_SPEED: f64 = 2.0;
/// Built-in `max_angular_accel`, rad/s².
pub const DEFAULT_MAX_ANGULAR_ACCEL: f64 = 4.0;
/// Longest built-in `lookahead`, scenario units.
pub const DEFAULT_LOOKAHEAD: f64 = 0.2;

/// The `lookahead` of a unicycle robot that sets none:
/// [`DEFAULT_LOOKAHEAD`], or half of `goal_tolerance` when that is shorter.
/// The look-ahead point, not the centre, is brought to the goal, and the
/// planner is told `goal_tolerance - lookahead` so that the centre ends
/// within `goal_tolerance`: a look-ahead as long as the tolerance leaves
/// nothing, and half of it leaves the planner half.
pub fn default_lookahead_for(goal_tolerance: f64) -> f64 {
    DEFAULT_LOOKAHEAD.min(goal_tolerance / 2.0)
}

fn default_angular_speed() -> f64 {
    DEFAULT_MAX_ANGULAR_SPEED
}
fn default_angular_accel() -> f64 {
    DEFAULT_MAX_ANGULAR_ACCEL
}
fn default_lookahead() -> f64 {
    DEFAULT_LOOKAHEAD
}

/// How a scripted obstacle moves.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "model", rename_all = "kebab-case")]
pub enum Motion {
    /// Never moves.
    Static,
    /// Constant velocity (Zhu & Loh 2.13-2.15).
    ConstantVelocity {
        /// Velocity.
        velocity: [f64; 2],
    },
    /// Straight lines through `points` at `speed`.
    Waypoints {
        /// Points to visit in order (the start is not repeated).
        points: Vec<[f64; 2]>,
        /// Speed along the path.
        speed: f64,
        /// Start over from the first point after the last.
        #[serde(default)]
        r#loop: bool,
    },
    /// Random acceleration (Zhu & Loh 2.16-2.20).
    Random {
        /// `gaussian` or `uniform`.
        distribution: String,
        /// Standard deviation of the acceleration noise.
        accel_sigma: f64,
        /// AR coefficient on the previous acceleration.
        alpha1: f64,
        /// Gain on the fresh noise.
        beta1: f64,
        /// Speed cap.
        max_speed: f64,
    },
    /// Intentional motion (Zhu & Loh 2.21-2.23).
    Intentional {
        /// `pursue`, `avoid` or `goal`.
        behavior: String,
        /// Body pursued (`pursue`), or the only body avoided (`avoid`; without
        /// one, every other body).
        target: Option<String>,
        /// Goal (for `goal`).
        goal: Option<[f64; 2]>,
        /// Route (for `goal`).
        points: Vec<[f64; 2]>,
        /// Speed cap.
        max_speed: f64,
        /// Acceleration cap.
        max_accel: f64,
        /// Eq 2.23's alpha2.
        alpha2: f64,
        /// Eq 2.23's beta2.
        beta2: f64,
    },
}

/// One scripted obstacle.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ObstacleSpec {
    /// Unique name (shared namespace with robots).
    pub name: String,
    /// Start position.
    pub start: [f64; 2],
    /// Disc radius, >= 0; for another shape its circumscribed radius, as
    /// a robot's.
    pub radius: f64,
    /// The body's shape (default a disc of `radius`).
    #[serde(default, skip_serializing_if = "ShapeSpec::is_disc")]
    pub shape: ShapeSpec,
    /// Heading, rad (the `heading_deg` key): the body frame's x axis. An
    /// obstacle never turns (its motion moves it, not its heading).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub heading: f64,
    /// How it moves.
    pub motion: Motion,
}

/// How a person decides where to walk each tick.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "model", rename_all = "kebab-case")]
pub enum PersonMotion {
    /// ORCA among the people, as RVO2 (and CrowdNav's humans) run it.
    Orca {
        /// Largest centre distance at which another body is considered.
        neighbor_dist: f64,
        /// Most bodies considered, nearest first.
        max_neighbors: usize,
        /// Time horizon of the other bodies' velocity obstacles, s.
        time_horizon: f64,
        /// Time horizon of the walls' velocity obstacles, s.
        time_horizon_obst: f64,
        /// Padding of every disc when avoiding (CrowdNav pads 0.01).
        radius_margin: f64,
    },
    /// Helbing & Molnar's social forces as pedsim_ros weighs them, with
    /// Moussaid et al.'s interaction and pedsim's group forces.
    SocialForce(SocialForceParams),
}

/// The social force model's parameters (pedsim_ros's names and defaults:
/// `pedsim_simulator`'s config and libpedsim's agent).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SocialForceParams {
    /// Relaxation time of the desired force, s (0.5).
    pub relaxation_time: f64,
    /// Weight of the desired force (1.0).
    pub force_desired: f64,
    /// Weight of the social force (5.1).
    pub force_social: f64,
    /// Weight of the obstacle (wall) force (10.0).
    pub force_obstacle: f64,
    /// Range of the obstacle force, m (0.2).
    pub sigma_obstacle: f64,
    /// Weight of the group's gaze force (3.0).
    pub force_group_gaze: f64,
    /// Weight of the group's coherence force (2.0).
    pub force_group_coherence: f64,
    /// Weight of the group's repulsion force (1.0).
    pub force_group_repulsion: f64,
    /// Centre distance under which group members repel, m (0.5).
    pub group_overlap: f64,
    /// A robot's position difference is divided by this before the social
    /// force (libpedsim's `robotPosDiffScalingFactor`, 5).
    pub robot_scale: f64,
    /// Largest centre distance of a body that exerts a social force, m
    /// (libpedsim's neighbourhood range, 10).
    pub neighbor_dist: f64,
}

impl Default for SocialForceParams {
    fn default() -> Self {
        Self {
            relaxation_time: 0.5,
            force_desired: 1.0,
            force_social: 5.1,
            force_obstacle: 10.0,
            sigma_obstacle: 0.2,
            force_group_gaze: 3.0,
            force_group_coherence: 2.0,
            force_group_repulsion: 1.0,
            group_overlap: 0.5,
            robot_scale: 5.0,
            neighbor_dist: 10.0,
        }
    }
}

impl Default for PersonMotion {
    /// CrowdNav's ORCA humans: neighbour distance 10, 10 neighbours, time
    /// horizons 5 s, no padding.
    fn default() -> Self {
        PersonMotion::Orca {
            neighbor_dist: 10.0,
            max_neighbors: 10,
            time_horizon: 5.0,
            time_horizon_obst: 5.0,
            radius_margin: 0.0,
        }
    }
}

/// How a person reacts to a robot it perceives: HuNavSim's six behaviours
/// (Pérez-Higueras et al., RA-L 2023; `hunav_agent_manager`'s
/// `agent_manager.cpp`, `bt_functions.cpp` and behaviour trees, with
/// `hunav_loader.cpp`'s defaults). Every reacting behaviour (not regular,
/// not impassive) acts while the nearest robot is within `detect_dist` and
/// in the person's field of view, for `duration` seconds of such ticks;
/// then the person walks as a regular one (again after the next
/// `duration` unless `once`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum Behavior {
    /// Walks to its goal, avoiding robots as it avoids people.
    #[default]
    Regular,
    /// Takes robots for obstacles, not for people: it does not make way
    /// for them, only keeps off their discs.
    Impassive,
    /// Stops and turns to face the robot.
    Surprised(Reaction),
    /// Slows to `vel` and is pushed away from the robot by an extra force
    /// of weight `other_force_factor`.
    Scared {
        /// When and how long it reacts.
        reaction: Reaction,
        /// Its speed while scared, m/s (0.6).
        vel: f64,
        /// Weight of the robot's repulsion (HuNavSim's
        /// `other_force_factor`, 20).
        other_force_factor: f64,
    },
    /// Walks up to the robot, slowing as it nears, stops `stop_dist` from
    /// it and looks at it.
    Curious {
        /// When and how long it reacts.
        reaction: Reaction,
        /// Its speed at HuNavSim's view distance (10 m), m/s (the
        /// person's `preferred_speed`).
        vel: f64,
        /// Centre distance at which it stops, m (1.5).
        stop_dist: f64,
    },
    /// Walks to the point `front_dist` ahead of the robot, in its way.
    Threatening {
        /// When and how long it reacts.
        reaction: Reaction,
        /// Its speed while threatening, m/s (2.0).
        vel: f64,
        /// How far ahead of the robot it aims, m (1.4).
        front_dist: f64,
    },
}

/// When a behaviour acts: HuNavSim's `IsRobotVisible` distance and its
/// `TimeExpiredCondition`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Reaction {
    /// Largest centre distance of a robot that sets it off, m.
    pub detect_dist: f64,
    /// Seconds of reacting (counted over the ticks the robot is seen)
    /// before the person walks on as a regular one.
    pub duration: f64,
    /// After `duration`, never again (else the count starts over).
    pub once: bool,
}

impl Behavior {
    /// The scenario's spelling.
    pub fn name(self) -> &'static str {
        match self {
            Behavior::Regular => "regular",
            Behavior::Impassive => "impassive",
            Behavior::Surprised(_) => "surprised",
            Behavior::Scared { .. } => "scared",
            Behavior::Curious { .. } => "curious",
            Behavior::Threatening { .. } => "threatening",
        }
    }

    /// When a reacting behaviour acts (none for regular and impassive).
    pub fn reaction(self) -> Option<Reaction> {
        match self {
            Behavior::Regular | Behavior::Impassive => None,
            Behavior::Surprised(r)
            | Behavior::Scared { reaction: r, .. }
            | Behavior::Curious { reaction: r, .. }
            | Behavior::Threatening { reaction: r, .. } => Some(r),
        }
    }
}

/// One person (pedestrian): a disc the world moves towards its goal or
/// along its waypoints, by a crowd model.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PersonSpec {
    /// Unique name (shared namespace with robots and obstacles).
    pub name: String,
    /// Start position.
    pub start: [f64; 2],
    /// The points walked to in order (a `goal` is the one point).
    pub waypoints: Vec<[f64; 2]>,
    /// After the last point, the first again.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub cyclic: bool,
    /// Disc radius, > 0.
    pub radius: f64,
    /// Walking speed, and the speed limit, > 0.
    pub preferred_speed: f64,
    /// Does the person make way for robots? False: robots are not there
    /// for it (CrowdNav's invisible robot).
    pub sees_robots: bool,
    /// Its reaction to robots.
    #[serde(default)]
    pub behavior: Behavior,
    /// The group it walks with, if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub group: Option<String>,
    /// Its crowd model.
    pub motion: PersonMotion,
}

fn is_zero(x: &f64) -> bool {
    *x == 0.0
}

/// A body's shape as the scenario gives it (`shape = { kind = ... }`),
/// in the body frame: x along the heading.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum ShapeSpec {
    /// A disc of the body's `radius` (default).
    #[default]
    Disc,
    /// A rectangle centred on the body's position, `length` along the
    /// heading and `width` across it.
    Rectangle {
        /// Along the heading, > 0.
        length: f64,
        /// Across the heading, > 0.
        width: f64,
    },
    /// A convex polygon: 3 to 8 points, counter-clockwise, in the body
    /// frame (non-convex ones are refused).
    Polygon {
        /// The vertices.
        points: Vec<[f64; 2]>,
    },
}

impl ShapeSpec {
    /// Is it the default disc (left out of scenario.json)?
    pub fn is_disc(&self) -> bool {
        matches!(self, ShapeSpec::Disc)
    }

    /// The shape for geometry, a disc taking `radius`. A spec that does
    /// not make a polygon (never one the scenario validated) is taken for
    /// the disc of `radius`, which holds it.
    pub fn shape(&self, radius: f64) -> mrsim_shape::Shape {
        use mrsim_shape::{Polygon, Shape};
        match self {
            ShapeSpec::Disc => Shape::disc(radius),
            ShapeSpec::Rectangle { length, width } => {
                Polygon::rectangle(*length, *width).map_or(Shape::disc(radius), Shape::Polygon)
            }
            ShapeSpec::Polygon { points } => {
                Polygon::new(points).map_or(Shape::disc(radius), Shape::Polygon)
            }
        }
    }
}

impl RobotSpec {
    /// The robot's shape for geometry.
    pub fn body_shape(&self) -> mrsim_shape::Shape {
        self.shape.shape(self.radius)
    }

    /// The robot's heading at its start, rad: a unicycle or a car faces
    /// its goal (0 if they coincide); a holonomic robot has heading 0 (its
    /// body never turns).
    pub fn start_heading(&self) -> f64 {
        let d = [self.goal[0] - self.start[0], self.goal[1] - self.start[1]];
        if self.turns() && (d[0] != 0.0 || d[1] != 0.0) {
            d[1].atan2(d[0])
        } else {
            0.0
        }
    }

    /// Does the robot's body turn (a unicycle or a car)?
    pub fn turns(&self) -> bool {
        matches!(
            self.kinematics,
            Kinematics::Unicycle | Kinematics::Ackermann
        )
    }

    /// Has a robot at `position` with heading `heading` (rad) arrived, for
    /// one tick: within `goal_tolerance` of the goal and, with a
    /// `goal_heading`, within its tolerance of it (the world's goal test,
    /// which also asks `goal_hold_ticks` such ticks running).
    pub fn at_goal(&self, position: [f64; 2], heading: f64) -> bool {
        let d = (self.goal[0] - position[0]).hypot(self.goal[1] - position[1]);
        d <= self.goal_tolerance && self.goal_heading.is_none_or(|g| g.holds(heading))
    }
}

impl Scenario {
    /// Every body's shape, robots first, then obstacles, then people (the
    /// world's body ids).
    pub fn body_shapes(&self) -> Vec<mrsim_shape::Shape> {
        let robots = self.robots.iter().map(RobotSpec::body_shape);
        robots
            .chain(self.obstacles.iter().map(ObstacleSpec::body_shape))
            .chain(
                self.people
                    .iter()
                    .map(|p| mrsim_shape::Shape::disc(p.radius)),
            )
            .collect()
    }

    /// How many bodies a snapshot holds: robots, obstacles and people.
    pub fn body_count(&self) -> usize {
        self.robots.len() + self.obstacles.len() + self.people.len()
    }

    /// Every body's name by body id: robots, obstacles, people.
    pub fn body_names(&self) -> Vec<String> {
        let robots = self.robots.iter().map(|r| r.name.clone());
        robots
            .chain(self.obstacles.iter().map(|o| o.name.clone()))
            .chain(self.people.iter().map(|p| p.name.clone()))
            .collect()
    }

    /// Do the bodies' headings matter, so that trajectory.csv carries
    /// them (`theta`)? When some robot turns (a unicycle or a car) or
    /// some body is not a disc (a turned rectangle is not the same body).
    pub fn has_headings(&self) -> bool {
        self.robots.iter().any(RobotSpec::turns) || self.has_shapes()
    }

    /// Is some body not a disc?
    pub fn has_shapes(&self) -> bool {
        self.robots.iter().any(|r| !r.shape.is_disc())
            || self.obstacles.iter().any(|o| !o.shape.is_disc())
    }
}

impl ObstacleSpec {
    /// The obstacle's shape for geometry.
    pub fn body_shape(&self) -> mrsim_shape::Shape {
        self.shape.shape(self.radius)
    }
}

/// A static wall segment.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct WallSpec {
    /// The segment's two ends.
    pub segment: [[f64; 2]; 2],
}

/// What an unknown cell of a map (neither occupied nor free) is for the
/// simulation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum UnknownCells {
    /// A wall (the default): nobody has seen what is there, so no robot
    /// goes there.
    #[default]
    Occupied,
    /// Free space.
    Free,
}

/// The `[map]` a scenario's walls were traced from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MapInfo {
    /// The map's YAML file, as found from the scenario's folder.
    pub file: String,
    /// The map's image.
    pub image: String,
    /// Cells across and up.
    pub size: [usize; 2],
    /// Metres a cell.
    pub resolution: f64,
    /// Pose of the lower-left cell: x, y (metres), yaw (radians).
    pub origin: [f64; 3],
    /// What unknown cells were taken as.
    pub unknown: UnknownCells,
    /// How many of [`Scenario::walls`], the last ones, are the map's.
    pub walls: usize,
}

/// A fully resolved, validated scenario.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Scenario {
    /// Scenario name.
    pub name: String,
    /// Free text: where it comes from, what it shows.
    pub description: String,
    /// Unit of every length.
    pub length_unit: LengthUnit,
    /// The `[world]` table.
    pub world: WorldConfig,
    /// Robots, in file order, then generated ones.
    pub robots: Vec<RobotSpec>,
    /// Scripted obstacles, in file order.
    pub obstacles: Vec<ObstacleSpec>,
    /// People, in file order (left out of the JSON when there are none,
    /// so a scenario without people writes what it always wrote).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub people: Vec<PersonSpec>,
    /// Walls (not including the arena's): the file's, then the map's.
    pub walls: Vec<WallSpec>,
    /// The map the last walls come from, if the scenario has one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub map: Option<MapInfo>,
    /// The `[output]` table (left out of the JSON when it is the default,
    /// so a default run's scenario.json is what it always was).
    #[serde(default, skip_serializing_if = "OutputConfig::is_default")]
    pub output: OutputConfig,
}

/// The trajectory file a run writes (`[output] trajectory`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum TrajectoryFormat {
    /// `trajectory.csv` (default).
    #[default]
    Csv,
    /// `trajectory.parquet`: the same columns, typed.
    Parquet,
    /// No trajectory file (metrics.json and events.jsonl still complete).
    None,
}

/// The `[output]` table: what the world writes of the trajectory. The
/// metrics (metrics.json) see every tick and every robot whatever it says.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct OutputConfig {
    /// The trajectory's file format (default csv).
    pub trajectory: TrajectoryFormat,
    /// Record every `every`-th tick (ticks 0, K, 2K, ... and the last);
    /// default 1, every tick.
    pub every: u32,
    /// Also write `run.mcap` (Foxglove's schemas, simulated time) at the
    /// end of the run (default false).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub mcap: bool,
    /// Two bodies whose surfaces come nearer than this meet: one row of
    /// encounters.csv (default [`DEFAULT_ENCOUNTER_GAP`]; left out of the
    /// resolved scenario at the default).
    #[serde(skip_serializing_if = "is_default_encounter_gap")]
    pub encounter_gap: f64,
}

/// `[output] encounter_gap` when the file does not say.
pub const DEFAULT_ENCOUNTER_GAP: f64 = 1.0;

fn is_default_encounter_gap(g: &f64) -> bool {
    *g == DEFAULT_ENCOUNTER_GAP
}

impl Default for OutputConfig {
    fn default() -> Self {
        Self {
            trajectory: TrajectoryFormat::Csv,
            every: 1,
            mcap: false,
            encounter_gap: DEFAULT_ENCOUNTER_GAP,
        }
    }
}

impl OutputConfig {
    /// Every field at its default.
    pub fn is_default(&self) -> bool {
        *self == Self::default()
    }

    /// Is tick `tick` one the trajectory records (the run's last tick
    /// aside, which it always does)?
    pub fn records(&self, tick: u64) -> bool {
        tick.is_multiple_of(u64::from(self.every.max(1)))
    }
}

impl Scenario {
    /// Every wall segment, the arena's four sides included.
    pub fn all_walls(&self) -> Vec<[[f64; 2]; 2]> {
        walls_and_arena(&self.walls, self.world.arena)
    }

    /// Number of ticks the run lasts at most.
    pub fn max_ticks(&self) -> u64 {
        (self.world.duration / self.world.dt).round() as u64
    }

    /// Index of a robot by name.
    pub fn robot_index(&self, name: &str) -> Option<usize> {
        self.robots.iter().position(|r| r.name == name)
    }
}

/// The segments of `walls` and, with an `arena`, its four sides (as
/// [`Scenario::all_walls`]).
pub fn walls_and_arena(walls: &[WallSpec], arena: Option<Arena>) -> Vec<[[f64; 2]; 2]> {
    let mut out: Vec<[[f64; 2]; 2]> = walls.iter().map(|w| w.segment).collect();
    if let Some(a) = arena {
        let (x0, y0, x1, y1) = (a.min[0], a.min[1], a.max[0], a.max[1]);
        out.push([[x0, y0], [x1, y0]]);
        out.push([[x1, y0], [x1, y1]]);
        out.push([[x1, y1], [x0, y1]]);
        out.push([[x0, y1], [x0, y0]]);
    }
    out
}
