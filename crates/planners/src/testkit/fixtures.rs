//! The states and observations the planners' unit tests start from.
//!
//! A test module fixes its robot once, as a [`RobotModel`] (size and
//! actuator limits), and builds every state from it; the bodies it senses
//! come from [`sensed`] (or [`robot`] and [`obstacle`]) and the observation
//! from [`observation`], changed with struct-update syntax where a test
//! needs another control period, tolerance, wall or path:
//!
//! ```text
//! let obs = Observation {
//!     goal_tolerance: 0.1,
//!     walls: &walls,
//!     ..observation(ROBOT.at(position, velocity), goal, &others)
//! };
//! ```

use crate::{BodyKind, Kinematics, Observation, SelfState, Sensed, Vec2};

/// A test robot's disc and actuator model (m r'' + b r' = f with its
/// limits): what stays the same for every state a test module builds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RobotModel {
    /// Disc radius.
    pub radius: f64,
    /// Mass m.
    pub mass: f64,
    /// Damping b.
    pub damping: f64,
    /// Speed limit.
    pub max_speed: f64,
    /// Acceleration limit.
    pub max_accel: f64,
}

impl RobotModel {
    /// The model most planner tests use: a disc of `radius`, mass 1, no
    /// damping, 1 m/s and 2 m/s².
    pub const fn unit(radius: f64) -> Self {
        Self {
            radius,
            mass: 1.0,
            damping: 0.0,
            max_speed: 1.0,
            max_accel: 2.0,
        }
    }

    /// The holonomic robot with id 0 at `position`, moving at `velocity`
    /// (heading 0, not turning).
    pub fn at(&self, position: Vec2, velocity: Vec2) -> SelfState {
        SelfState {
            id: 0,
            position,
            velocity,
            radius: self.radius,
            shape: crate::Shape::disc(self.radius),
            mass: self.mass,
            damping: self.damping,
            max_speed: self.max_speed,
            max_accel: self.max_accel,
            heading: 0.0,
            angular_velocity: 0.0,
            steering: 0.0,
            kinematics: Kinematics::Holonomic,
        }
    }

    /// The unicycle robot with id 0 at `position`, moving at `velocity`
    /// with heading `heading` and turn rate `angular_velocity`, within the
    /// turn-rate and angular-acceleration limits given.
    pub fn unicycle(
        &self,
        position: Vec2,
        velocity: Vec2,
        heading: f64,
        angular_velocity: f64,
        max_angular_speed: f64,
        max_angular_accel: f64,
    ) -> SelfState {
        SelfState {
            heading,
            angular_velocity,
            kinematics: Kinematics::Unicycle {
                max_angular_speed,
                max_angular_accel,
            },
            ..self.at(position, velocity)
        }
    }

    /// The car `car` (its geometry and steering limits; its speed limits
    /// are the model's) with id 0, its centre at `position`, heading
    /// `heading`, driving at `speed` along it with steering `steering`: its
    /// centre's velocity is v e + (L/2) theta' e_perp, theta' = v
    /// tan(steering) / L.
    pub fn car(
        &self,
        car: CarLimits,
        position: Vec2,
        heading: f64,
        speed: f64,
        steering: f64,
    ) -> SelfState {
        let (s, c) = heading.sin_cos();
        let omega = speed * steering.tan() / car.wheelbase;
        let velocity = Vec2::new(c, s) * speed + Vec2::new(-s, c) * (car.wheelbase / 2.0 * omega);
        SelfState {
            heading,
            angular_velocity: omega,
            steering,
            kinematics: Kinematics::Ackermann {
                wheelbase: car.wheelbase,
                max_steering: car.max_steering,
                max_steering_rate: car.max_steering_rate,
                max_reverse_speed: car.max_reverse_speed,
            },
            ..self.at(position, velocity)
        }
    }
}

/// A test car's geometry and steering limits ([`RobotModel::car`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CarLimits {
    /// Distance between the axles.
    pub wheelbase: f64,
    /// Steering limit, rad.
    pub max_steering: f64,
    /// Steering-rate limit, rad/s.
    pub max_steering_rate: f64,
    /// Fastest speed backwards.
    pub max_reverse_speed: f64,
}

/// A sensed body of `kind`, without acceleration (the truth's estimate).
pub fn sensed(id: u32, kind: BodyKind, position: Vec2, velocity: Vec2, radius: f64) -> Sensed {
    Sensed::disc(id, kind, position, velocity, radius)
}

/// A sensed robot (see [`sensed`]).
pub fn robot(id: u32, position: Vec2, velocity: Vec2, radius: f64) -> Sensed {
    sensed(id, BodyKind::Robot, position, velocity, radius)
}

/// A sensed obstacle (see [`sensed`]).
pub fn obstacle(id: u32, position: Vec2, velocity: Vec2, radius: f64) -> Sensed {
    sensed(id, BodyKind::Obstacle, position, velocity, radius)
}

/// The observation planner unit tests start from: tick 0, dt 0.1 s, goal
/// tolerance 0.05, goal held for 3 ticks, no walls, no path, no scan.
pub fn observation<'a>(me: SelfState, goal: Vec2, others: &'a [Sensed]) -> Observation<'a> {
    Observation {
        tick: 0,
        time: 0.0,
        dt: 0.1,
        me,
        goal,
        goal_tolerance: 0.05,
        goal_hold_ticks: 3,
        others,
        walls: &[],
        path: None,
        scan: None,
    }
}
