//! Pure motion planners for mrsim.
//!
//! Every planner is a function of an [`Observation`]: the robot's own state,
//! its goal, the bodies it senses and the static geometry. It returns a
//! [`Command`] (a force or a velocity; a unicycle's forward speed and
//! turn rate; a car's speed and steering angle). No planner sees IPC, a
//! clock or the physics engine, so each one can be unit-tested,
//! benchmarked and compared on its own, and the same code runs in an agent
//! process or in a thread.
//!
//! Why the crate is shaped as it is:
//!
//! - **Pure planners.** This crate depends on nalgebra, thiserror and the
//!   leaf `mrsim-shape` (the bodies' shapes) only: the agents bring the
//!   transport, the world brings rapier. What a planner
//!   does is decided by its observation and its own state alone, which is
//!   what makes the lockstep runs reproducible to the byte.
//! - **One module per method**, named after it, whose `//!` cites the paper
//!   and the equations it implements, so that the code can be read against
//!   the paper (`homing` is the smallest example). A method too long for one
//!   file becomes a folder split the way its reference implementation is:
//!   [`orca`] is the method in `mod.rs`, its linear programs and its static
//!   obstacles beside it, its tests in their own file. A test module longer
//!   than about 200 lines lives in `<method>/tests.rs` the same way, so that
//!   the method file reads like the paper; the states and observations the
//!   tests start from are the testkit's fixtures.
//! - **One table.** [`PLANNERS`] is the only list of planners: each entry
//!   has the scenario name, a one-line summary and the constructor, and
//!   both the listing (`mrsim --help`, error messages) and [`build`] read
//!   it, so a planner is added in one place. A [`Registry`] is that table
//!   plus [`EXTERNAL`] (a robot driven by the user's own program) plus
//!   planners a program registers by name (in-process runs).
//! - **The testkit is for tests.** `testkit` is a reference simulation with
//!   the world's actuator model (m r'' + b r' = f, the same limits and
//!   integration), in which the unit tests check each planner's behaviour
//!   in microseconds. It is compiled for this crate's tests and, with the
//!   `testkit` feature, for examples and other crates' tests; the product
//!   never builds it.
#![warn(missing_docs)]

mod params;
mod registry;

pub mod ackermann;
pub mod chung;
pub mod designated_path;
pub mod dwa;
pub mod estimate;
pub mod free_space;
pub mod homing;
pub mod hydro;
pub mod khatib;
pub mod lidar;
pub mod orca;
pub mod prediction;
pub mod social_force;
#[cfg(any(test, feature = "testkit"))]
pub mod testkit;
pub mod trajectory_guided;
pub mod unicycle;
pub mod vdf;

pub use lidar::LaserScan;
pub use mrsim_shape::{Placed, Polygon, Pose, Shape};
pub use params::{ParamError, ParamReader, ParamValue, Params};
pub use registry::{
    BuildError, EXTERNAL, Entry, Factory, FromParams, PLANNERS, PlannerInfo, ROS2, RegisterError,
    Registry, build,
};

/// 2-D vector, f64, in the scenario's units.
pub type Vec2 = nalgebra::Vector2<f64>;

/// What a sensed body is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BodyKind {
    /// Another robot, driven by its own agent.
    Robot,
    /// A scripted obstacle moved by the world.
    Obstacle,
    /// A person (pedestrian) moved by the world's crowd models, who may
    /// or may not make way for robots (the scenario's `sees_robots`).
    Person,
}

/// Another body as the robot senses it.
///
/// Its [`shape`](Self::shape) is given in its body frame (x along
/// [`heading`](Self::heading)), and [`radius`](Self::radius) is always the
/// radius of the disc around it, so a planner that takes every body for a
/// disc keeps working, conservatively, when some are rectangles or
/// polygons. [`Self::placed`] gives a polygon's corners in the world.
///
/// ```
/// use mrsim_planners::{BodyKind, Polygon, Sensed, Shape, Vec2};
/// // A disc (what every body was before shapes): heading 0.
/// let d = Sensed::disc(3, BodyKind::Robot, Vec2::new(1.0, 0.0), Vec2::zeros(), 0.25);
/// assert_eq!((d.radius, d.heading, d.shape), (0.25, 0.0, Shape::disc(0.25)));
/// assert!(d.placed().is_none());
/// // A 2 x 1 box turned a quarter turn: its radius is its half diagonal.
/// let rect = Shape::Polygon(Polygon::rectangle(2.0, 1.0).unwrap());
/// let b = Sensed::disc(4, BodyKind::Obstacle, Vec2::new(5.0, 0.0), Vec2::zeros(), 0.0)
///     .shaped(rect, std::f64::consts::FRAC_PI_2);
/// assert!((b.radius - 1.25f64.sqrt()).abs() < 1e-12);
/// let corners = b.placed().unwrap();
/// // Its length now lies along y: the first corner, (-1, -0.5) in its
/// // frame, is at (5.5, -1) in the world.
/// let c = corners.points()[0];
/// assert!((c[0] - 5.5).abs() < 1e-12 && (c[1] + 1.0).abs() < 1e-12);
/// // From (2, 0) its near side, x = 4.5, is 2.5 away; its disc's 2.38.
/// assert!((b.distance_to(Vec2::new(2.0, 0.0)) - 2.5).abs() < 1e-12);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sensed {
    /// The body's id in the world (stable for the run).
    pub id: u32,
    /// Robot, obstacle or person.
    pub kind: BodyKind,
    /// Position.
    pub position: Vec2,
    /// Velocity: the true one, or estimated from successive positions,
    /// depending on the robot's `velocity_source`.
    pub velocity: Vec2,
    /// Acceleration estimated from successive positions; zero when the
    /// velocity source is the truth.
    pub acceleration: Vec2,
    /// The radius of the disc the body fits in: a disc's own radius (0 for
    /// a point), a polygon's circumscribed radius (the farthest vertex
    /// from its position).
    pub radius: f64,
    /// The body's heading, rad counter-clockwise from +x: the direction of
    /// its shape's x axis (a unicycle's turns, an obstacle's is its
    /// scenario's `heading_deg`, a holonomic robot's stays at its start's).
    pub heading: f64,
    /// The body's shape in its body frame (origin at [`Self::position`],
    /// x along [`Self::heading`]): a disc, a rectangle or a convex polygon.
    pub shape: Shape,
}

impl Sensed {
    /// A disc of `radius` (0: a point) at `position` moving at `velocity`,
    /// with no acceleration and heading 0: how a body is sensed when it
    /// has no other shape.
    pub fn disc(id: u32, kind: BodyKind, position: Vec2, velocity: Vec2, radius: f64) -> Self {
        Self {
            id,
            kind,
            position,
            velocity,
            acceleration: Vec2::zeros(),
            radius,
            heading: 0.0,
            shape: Shape::disc(radius),
        }
    }

    /// The body with `shape` at `heading` (rad), its radius the shape's
    /// circumscribed one.
    pub fn shaped(self, shape: Shape, heading: f64) -> Self {
        Self {
            radius: shape.circumradius(),
            heading,
            shape,
            ..self
        }
    }

    /// The body's pose: its position and heading.
    pub fn pose(&self) -> Pose {
        Pose::new([self.position.x, self.position.y], self.heading)
    }

    /// A polygon's vertices in the world (counter-clockwise); `None` for a
    /// disc.
    pub fn placed(&self) -> Option<Placed> {
        self.shape.placed(self.pose())
    }

    /// The signed distance from point `p` to the body's surface, its true
    /// shape at its heading: positive outside, negative inside (a disc's is
    /// the distance to its centre less its radius). Less a robot's own
    /// radius, the gap between a disc robot at `p` and the body.
    pub fn distance_to(&self, p: Vec2) -> f64 {
        match self.shape {
            Shape::Disc { radius } => (p - self.position).norm() - radius,
            Shape::Polygon(_) => mrsim_shape::signed_distance(&self.shape, self.pose(), [p.x, p.y]),
        }
    }
}

/// How the robot moves: the world's model and its limits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Kinematics {
    /// Force or velocity in any direction (the disc model).
    Holonomic,
    /// Differential drive: forward speed along the heading and a turn rate
    /// ([`Command::Unicycle`]); `max_speed` and `max_accel` of
    /// [`SelfState`] bound the forward speed and its rate of change.
    Unicycle {
        /// Turn-rate limit, rad/s.
        max_angular_speed: f64,
        /// Angular-acceleration limit, rad/s².
        max_angular_accel: f64,
    },
    /// A car, the kinematic bicycle: a speed along the heading and a
    /// steering angle of the front wheels ([`Command::Ackermann`]). The
    /// position is the centre of the body, the rear axle `wheelbase / 2`
    /// behind it; the heading turns at the rate speed tan(steering) /
    /// wheelbase.
    /// `max_speed` and `max_accel` of [`SelfState`] bound the speed forward
    /// and its rate of change ([`ackermann`]).
    Ackermann {
        /// Distance between the axles, > 0.
        wheelbase: f64,
        /// Steering limit either way, rad, in (0, pi/2).
        max_steering: f64,
        /// Steering-rate limit, rad/s.
        max_steering_rate: f64,
        /// Fastest speed backwards, >= 0 (0: never reverses).
        max_reverse_speed: f64,
    },
}

/// The robot's own state and physical limits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SelfState {
    /// The robot's id in the world.
    pub id: u32,
    /// Position.
    pub position: Vec2,
    /// Velocity.
    pub velocity: Vec2,
    /// Disc radius (0 for a point robot); for another shape the radius of
    /// the smallest disc about the robot's position that holds it.
    pub radius: f64,
    /// The robot's shape in its body frame (x along `heading`): a disc of
    /// `radius`, or a rectangle or convex polygon.
    pub shape: Shape,
    /// Mass m of m r'' + b r' = f.
    pub mass: f64,
    /// Damping b of m r'' + b r' = f.
    pub damping: f64,
    /// Speed limit the world enforces.
    pub max_speed: f64,
    /// Acceleration limit the world enforces.
    pub max_accel: f64,
    /// Heading, rad counter-clockwise from +x (a unicycle's body
    /// orientation; 0 for a holonomic robot, which has none).
    pub heading: f64,
    /// Turn rate, rad/s (0 for a holonomic robot).
    pub angular_velocity: f64,
    /// A car's steering angle, rad, counter-clockwise (0 for the others).
    pub steering: f64,
    /// The robot's motion model.
    pub kinematics: Kinematics,
}

impl SelfState {
    /// The velocity a force `f` held for `dt` brings the robot to, by its
    /// actuator model (m r'' + b r' = f, the acceleration within
    /// `max_accel`): what a force asks of a robot that takes velocities
    /// (the unicycle's and the car's controllers).
    pub fn velocity_after(&self, f: Vec2, dt: f64) -> Vec2 {
        let m = if self.mass > 0.0 { self.mass } else { 1.0 };
        let mut a = (f - self.velocity * self.damping) / m;
        if a.norm() > self.max_accel {
            a *= self.max_accel / a.norm();
        }
        self.velocity + a * dt
    }
}

/// A static wall segment.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Segment {
    /// One end.
    pub a: Vec2,
    /// The other end.
    pub b: Vec2,
}

impl Segment {
    /// The point of the segment closest to `p`.
    pub fn closest_point(&self, p: Vec2) -> Vec2 {
        let ab = self.b - self.a;
        let len2 = ab.norm_squared();
        if len2 <= f64::EPSILON {
            return self.a;
        }
        let t = ((p - self.a).dot(&ab) / len2).clamp(0.0, 1.0);
        self.a + ab * t
    }
}

/// A designated path (Yamada et al.): waypoints and the half-width of the
/// corridor the robot must stay in.
#[derive(Debug, Clone, PartialEq)]
pub struct DesignatedPath {
    /// Waypoints, first to last.
    pub points: Vec<Vec2>,
    /// Half-width of the allowed corridor around the path.
    pub boundary: f64,
}

/// Everything a planner may know at one control step.
#[derive(Debug, Clone, Copy)]
pub struct Observation<'a> {
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
    /// Consecutive ticks within `goal_tolerance` that count as arrival
    /// (the scenario's `goal_hold_ticks`; Ko & Choi eq 22's N).
    pub goal_hold_ticks: u32,
    /// Bodies within sensing range and field of view, robots and obstacles
    /// alike (every other robot is a moving obstacle).
    pub others: &'a [Sensed],
    /// Static wall segments (including the arena's, if any).
    pub walls: &'a [Segment],
    /// The robot's designated path, if its scenario entry has one.
    pub path: Option<&'a DesignatedPath>,
    /// This tick's laser scan, if the robot has a lidar.
    pub scan: Option<&'a LaserScan>,
}

/// A planner's output for one tick.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Command {
    /// A force applied for the whole tick (m r'' + b r' = f).
    Force(Vec2),
    /// A velocity set-point, tracked by the world's first-order lag.
    Velocity(Vec2),
    /// A unicycle robot's set-points: forward speed `v` and turn rate
    /// `omega` (rad/s), tracked within its limits.
    Unicycle {
        /// Forward speed along the heading.
        v: f64,
        /// Turn rate, rad/s, counter-clockwise.
        omega: f64,
    },
    /// A car's set-points ([`Kinematics::Ackermann`]): the speed of its
    /// rear axle along the heading (negative: backwards) and the steering
    /// angle of its front wheels, rad, counter-clockwise. The world brings
    /// the speed to it within `max_accel` (and the velocity lag) and the
    /// steering within `max_steering_rate`, and clamps them to [-
    /// `max_reverse_speed`, `max_speed`] and ±`max_steering`, whatever is
    /// asked. On a holonomic robot or a unicycle it brakes the robot.
    Ackermann {
        /// Speed along the heading.
        speed: f64,
        /// Steering angle, rad.
        steering: f64,
    },
}

impl Command {
    /// The command's vector, whatever its kind ((v, omega) for a unicycle
    /// command, (speed, steering) for a car's).
    pub fn vector(&self) -> Vec2 {
        match *self {
            Command::Force(v) | Command::Velocity(v) => v,
            Command::Unicycle { v, omega } => Vec2::new(v, omega),
            Command::Ackermann { speed, steering } => Vec2::new(speed, steering),
        }
    }
}

/// A named per-tick value a planner reports for plots (for example the
/// virtual distance to each obstacle for `vdf`).
#[derive(Debug, Clone, PartialEq)]
pub struct Diagnostic {
    /// Name, e.g. `vd_3` (virtual distance to body 3). A fixed name is
    /// borrowed (`"orca_lines".into()`), so reporting it allocates nothing.
    pub name: std::borrow::Cow<'static, str>,
    /// Value at this tick.
    pub value: f64,
}

/// One control step of a motion planner.
///
/// `plan` must be deterministic: the same observation and internal state
/// give the same command. Stateful planners (subgoal index, inherited
/// trajectory, carried-over terms) keep that state in `self`.
pub trait Planner: Send {
    /// One control step.
    fn plan(&mut self, obs: &Observation) -> Command;

    /// Named values from the last `plan` call, for diagnostics.csv.
    /// Planners with nothing to report keep the default.
    fn diagnostics(&self) -> Vec<Diagnostic> {
        Vec::new()
    }

    /// [`Planner::diagnostics`] appended to `out`: what an agent calls
    /// every tick, into a buffer it reuses. The default asks
    /// [`Planner::diagnostics`]; a planner that reports every tick
    /// overrides it to report without allocating (both must give the same
    /// values).
    fn diagnostics_into(&self, out: &mut Vec<Diagnostic>) {
        let values = self.diagnostics();
        if values.capacity() == 0 {
            // Nothing reported and nothing allocated: nothing to drop (a
            // drop is an out-of-line call on every agent's tick).
            std::mem::forget(values);
        } else {
            out.extend(values);
        }
    }

    /// True for a planner that plans a unicycle's (v, omega) from the
    /// robot's own state, not through the look-ahead point ([`unicycle`]):
    /// a [`Planner::native_unicycle`] one, and the look-ahead controller
    /// around one.
    fn plans_unicycle(&self) -> bool {
        self.native_unicycle()
    }

    /// True for a planner that plans a unicycle robot's (v, omega) itself
    /// (as [`dwa`] does): on a unicycle robot it then gets the robot's own
    /// observation and its command is applied unchanged, instead of
    /// driving through the look-ahead point ([`unicycle`]). The default,
    /// false, suits a planner that commands a force or a velocity.
    fn native_unicycle(&self) -> bool {
        false
    }

    /// True for a planner that plans a car's (speed, steering) itself,
    /// with the car's own footprint, not through the tracking controller
    /// ([`ackermann::Tracker`]): a [`Planner::native_ackermann`] one. The
    /// tracking controller around a planner answers for the planner it
    /// wraps (false for a holonomic one).
    fn plans_ackermann(&self) -> bool {
        self.native_ackermann()
    }

    /// True for a planner that plans a car's (speed, steering) itself: on
    /// a car it then gets the robot's own observation and its command is
    /// applied unchanged, instead of driving through the tracking
    /// controller ([`ackermann::Tracker`]). The default, false, suits a
    /// planner that commands a force or a velocity.
    fn native_ackermann(&self) -> bool {
        false
    }

    /// True for a planner that sees obstacles only through the robot's
    /// laser scan (dwa with `obstacles = "scan"`): a robot without a
    /// `sensor` is refused for it. The default, false, suits the rest.
    fn needs_scan(&self) -> bool {
        false
    }

    /// Told, before the first `plan`, that the planner drives a unicycle
    /// robot through its look-ahead point ([`unicycle::LookAhead`]): each
    /// observation of a unicycle robot is then of the point `lookahead`
    /// ahead of its centre along `me.heading`, and `me.radius` is enlarged
    /// by `lookahead` so that the disc covers the real one at any heading.
    /// A planner that can use the real disc where it is the nearer bound
    /// overrides this ([`orca`] keeps walls off the real disc); the
    /// default ignores it.
    fn drives_look_ahead(&mut self, _lookahead: f64) {}
}
