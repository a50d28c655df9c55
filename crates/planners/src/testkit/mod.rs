//! A tiny reference simulation for planner tests, without IPC or physics
//! engine: point-mass discs under m r'' + b r' = f (Chung eq 1) with the
//! world's actuator limits, integrated like the world does (semi-implicit
//! Euler, `substeps` per tick, force held for the tick, acceleration then
//! speed clamped), plus constant-velocity obstacles.
//!
//! It exists so that each planner's unit tests can check behaviour (a
//! crossing avoided, a goal reached) in microseconds. The end-to-end tests
//! run the same cases through the real world and agent processes.
//!
//! Compiled for the crate's own tests, and with the `testkit` feature for
//! examples and other crates' tests; the agents and the world never build
//! it. [`rvo2`] holds RVO2's own example scenes, [`fixtures`] the states,
//! bodies and observations the unit tests build.

pub mod fixtures;
pub mod rvo2;

pub use fixtures::{CarLimits, RobotModel, observation, obstacle, robot, sensed};

use crate::{
    BodyKind, Command, DesignatedPath, Observation, Planner, Segment, SelfState, Sensed, Vec2,
};

/// One robot of a [`Sim`].
pub struct SimRobot {
    /// Its planner.
    pub planner: Box<dyn Planner>,
    /// State and limits (position and velocity evolve).
    pub state: SelfState,
    /// Goal.
    pub goal: Vec2,
    /// Time constant of the velocity lag (0 = ideal).
    pub velocity_lag: f64,
    /// Command being applied.
    pub command: Command,
    /// Designated path passed to the planner (Yamada), if any.
    pub path: Option<DesignatedPath>,
}

/// A scripted constant-velocity obstacle.
#[derive(Debug, Clone, Copy)]
pub struct SimObstacle {
    /// Position.
    pub position: Vec2,
    /// Velocity.
    pub velocity: Vec2,
    /// Radius.
    pub radius: f64,
}

/// The reference simulation.
pub struct Sim {
    /// Control period.
    pub dt: f64,
    /// Physics steps per tick.
    pub substeps: u32,
    /// Robots.
    pub robots: Vec<SimRobot>,
    /// Obstacles.
    pub obstacles: Vec<SimObstacle>,
    /// Walls.
    pub walls: Vec<Segment>,
    /// Ticks done.
    pub tick: u64,
}

impl Sim {
    /// An empty world.
    pub fn new(dt: f64, substeps: u32) -> Self {
        Self {
            dt,
            substeps: substeps.max(1),
            robots: Vec::new(),
            obstacles: Vec::new(),
            walls: Vec::new(),
            tick: 0,
        }
    }

    /// Adds a robot at rest; returns its index.
    #[allow(clippy::too_many_arguments)]
    pub fn add_robot(
        &mut self,
        planner: Box<dyn Planner>,
        start: Vec2,
        goal: Vec2,
        radius: f64,
        mass: f64,
        damping: f64,
        max_speed: f64,
        max_accel: f64,
    ) -> usize {
        let id = self.robots.len() as u32;
        self.robots.push(SimRobot {
            planner,
            state: SelfState {
                id,
                position: start,
                velocity: Vec2::zeros(),
                radius,
                shape: crate::Shape::disc(radius),
                mass,
                damping,
                max_speed,
                max_accel,
                heading: 0.0,
                angular_velocity: 0.0,
                steering: 0.0,
                kinematics: crate::Kinematics::Holonomic,
            },
            goal,
            velocity_lag: 0.0,
            command: Command::Force(Vec2::zeros()),
            path: None,
        });
        self.robots.len() - 1
    }

    /// Adds a constant-velocity obstacle.
    pub fn add_obstacle(&mut self, position: Vec2, velocity: Vec2, radius: f64) {
        self.obstacles.push(SimObstacle {
            position,
            velocity,
            radius,
        });
    }

    /// What robot `i` senses: every other body (no range limit).
    pub fn sensed(&self, i: usize) -> Vec<Sensed> {
        let n = self.robots.len() as u32;
        let robots = self
            .robots
            .iter()
            .enumerate()
            .filter(|(j, _)| *j != i)
            .map(|(_, r)| {
                Sensed::disc(
                    r.state.id,
                    BodyKind::Robot,
                    r.state.position,
                    r.state.velocity,
                    r.state.radius,
                )
            });
        let obstacles = self.obstacles.iter().enumerate().map(|(k, o)| {
            Sensed::disc(
                n + k as u32,
                BodyKind::Obstacle,
                o.position,
                o.velocity,
                o.radius,
            )
        });
        robots.chain(obstacles).collect()
    }

    /// One tick: every robot plans on the same snapshot, then physics.
    pub fn step(&mut self) {
        let time = self.tick as f64 * self.dt;
        for i in 0..self.robots.len() {
            let others = self.sensed(i);
            let r = &mut self.robots[i];
            let obs = Observation {
                tick: self.tick,
                time,
                dt: self.dt,
                me: r.state,
                goal: r.goal,
                goal_tolerance: 1e-3,
                goal_hold_ticks: 3,
                others: &others,
                walls: &self.walls,
                path: r.path.as_ref(),
                scan: None,
            };
            let cmd = r.planner.plan(&obs);
            r.command = cmd;
        }
        let h = self.dt / self.substeps as f64;
        for _ in 0..self.substeps {
            for r in &mut self.robots {
                let s = &mut r.state;
                let mut a = match r.command {
                    Command::Force(f) => f / s.mass - s.velocity * (s.damping / s.mass),
                    Command::Velocity(v) => {
                        if r.velocity_lag > 0.0 {
                            (v - s.velocity) / r.velocity_lag
                        } else {
                            (v - s.velocity) / h
                        }
                    }
                    // The testkit's robots are holonomic: a unicycle or
                    // a car's command brakes them (the world's rule).
                    Command::Unicycle { .. } | Command::Ackermann { .. } => -s.velocity / h,
                };
                if a.norm() > s.max_accel {
                    a *= s.max_accel / a.norm();
                }
                s.velocity += a * h;
                if s.velocity.norm() > s.max_speed {
                    s.velocity *= s.max_speed / s.velocity.norm();
                }
                s.position += s.velocity * h;
            }
            for o in &mut self.obstacles {
                o.position += o.velocity * h;
            }
        }
        self.tick += 1;
    }

    /// Runs `ticks` ticks and returns, per tick, every robot's position.
    pub fn run(&mut self, ticks: u64) -> Vec<Vec<Vec2>> {
        (0..ticks)
            .map(|_| {
                self.step();
                self.robots.iter().map(|r| r.state.position).collect()
            })
            .collect()
    }

    /// Smallest surface-to-surface distance between robot `i` and any other
    /// body right now (negative = overlap).
    pub fn clearance(&self, i: usize) -> f64 {
        let me = &self.robots[i].state;
        self.sensed(i)
            .iter()
            .map(|o| (o.position - me.position).norm() - o.radius - me.radius)
            .fold(f64::INFINITY, f64::min)
    }
}
