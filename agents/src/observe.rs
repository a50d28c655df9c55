//! From a snapshot to a planner's observation: the robot's own state, and
//! the other bodies it can sense (within `sensing_range`, measured surface
//! to surface, and within `field_of_view_deg` centred on its heading: the
//! direction of its velocity, or towards its goal while it stands still).
//!
//! Then, in this order, as a camera would give them (Zhu & Loh section 2):
//! the sensed positions get Gaussian noise of standard deviation
//! `position_noise` per axis (drawn from the robot's own stream of the
//! scenario's seed, so runs repeat), and with `velocity_source =
//! "differenced"` every sensed body's velocity and acceleration are
//! replaced by differences of its observed (noisy) positions, eqs 2.9-2.12
//! ([`VelocityEstimator`]). With `"truth"` the velocity is the snapshot's and
//! the acceleration zero.
//!
//! A unicycle robot's heading is its body's (the snapshot's `heading`), and
//! the observation says so ([`SelfState::heading`], `kinematics`). A robot
//! with a `sensor` gets a laser scan each tick ([`mrsim_lidar`]'s
//! [`Scanner::scan_robot`], the function the world's scan.csv calls too, so
//! the file repeats exactly what the planner saw): cast from its centre
//! along its heading (a holonomic robot's frame is the world's: heading 0)
//! against every other body of the snapshot (true positions, whatever the
//! sensing range) and every wall, with noise from a stream per robot and
//! tick.

use mrsim_lidar::{Scanner, Walls};
use mrsim_planners::estimate::VelocityEstimator;
use mrsim_planners::lidar::LaserScan;
use mrsim_planners::{
    BodyKind, DesignatedPath, Kinematics, Observation, Segment, SelfState, Sensed, Vec2,
};
use mrsim_proto::{BodyState, SnapshotHeader, body_kind};
use mrsim_scenario::rng::Rng;
use mrsim_scenario::{RobotSpec, Scenario, VelocitySource, WorldConfig};

/// Turns snapshots into observations for one robot; keeps the buffers.
pub struct Observer {
    me: usize,
    dt: f64,
    others: Vec<Sensed>,
    /// Differenced velocities (eqs 2.9-2.12), if the robot asks for them.
    estimator: Option<VelocityEstimator>,
    /// Standard deviation of the position noise (0 = none).
    noise: f64,
    rng: Rng,
    seed: u64,
    /// The last scan, if the robot has a lidar.
    scan: LaserScan,
    /// The scanner among the walls it was built for (their address and
    /// length: a run's walls are fixed), built at the first scan.
    scanner: Option<((usize, usize), Scanner)>,
}

impl Observer {
    /// An observer for robot `me` of `scenario`.
    pub fn new(scenario: &Scenario, me: usize) -> Self {
        Self::for_robot(
            &scenario.world,
            scenario.robots.get(me),
            me,
            scenario.robots.len() + scenario.obstacles.len(),
        )
    }

    /// An observer for robot `me` (its entry `spec`, if known) of a run
    /// with `world` and `bodies` bodies in each snapshot.
    pub fn for_robot(
        world: &WorldConfig,
        spec: Option<&RobotSpec>,
        me: usize,
        bodies: usize,
    ) -> Self {
        Self {
            me,
            dt: world.dt,
            // Grown to what the robot senses, not sized for every body: a
            // run of n robots would hold n such buffers.
            others: Vec::with_capacity(bodies.min(64)),
            estimator: spec
                .is_some_and(|r| r.velocity_source == VelocitySource::Differenced)
                .then(VelocityEstimator::new),
            noise: spec.map_or(0.0, |r| r.position_noise),
            rng: Rng::stream(world.seed, "position-noise", me as u64),
            seed: world.seed,
            scan: LaserScan::default(),
            scanner: None,
        }
    }

    /// The observation of this tick.
    pub fn observe<'a>(
        &'a mut self,
        header: &SnapshotHeader,
        bodies: &[BodyState],
        spec: &RobotSpec,
        walls: &'a [Segment],
        path: Option<&'a DesignatedPath>,
    ) -> Observation<'a> {
        self.observe_among(header, bodies, None, spec, walls, path)
    }

    /// [`Self::observe`], looking only at the bodies of indices `near`
    /// (ascending, so the sensed bodies come in the same order) when given:
    /// a caller that knows which bodies can be within range (a grid built
    /// once per snapshot for many robots) saves the scan of all of them.
    /// `near` must hold every body within the sensing range.
    pub fn observe_among<'a>(
        &'a mut self,
        header: &SnapshotHeader,
        bodies: &[BodyState],
        near: Option<&[u32]>,
        spec: &RobotSpec,
        walls: &'a [Segment],
        path: Option<&'a DesignatedPath>,
    ) -> Observation<'a> {
        let s = &bodies[self.me];
        let position = Vec2::new(s.position[0], s.position[1]);
        let velocity = Vec2::new(s.velocity[0], s.velocity[1]);
        let goal = Vec2::new(spec.goal[0], spec.goal[1]);
        let unicycle = spec.kinematics == mrsim_scenario::Kinematics::Unicycle;
        let heading = if unicycle {
            Vec2::new(s.heading.cos(), s.heading.sin())
        } else if velocity.norm() > 1e-9 {
            velocity.normalize()
        } else if (goal - position).norm() > 1e-12 {
            (goal - position).normalize()
        } else {
            Vec2::new(1.0, 0.0)
        };
        let half_fov = (spec.field_of_view_deg.min(360.0) / 2.0).to_radians();
        let cos_half = half_fov.cos();
        self.others.clear();
        let count = near.map_or(bodies.len(), <[u32]>::len);
        for k in 0..count {
            let Some(b) = (match near {
                None => bodies.get(k),
                Some(near) => bodies.get(near[k] as usize),
            }) else {
                continue;
            };
            if b.id as usize == self.me {
                continue;
            }
            // Clearly out of range (centre distance squared well beyond the
            // range plus both radii): skipped without a square root. Bodies
            // near the limit go through the exact test below, so what is
            // sensed does not change.
            let (dx, dy) = (b.position[0] - position.x, b.position[1] - position.y);
            let reach = (spec.sensing_range + b.radius + spec.radius) * (1.0 + 1e-9) + 1e-9;
            if dx * dx + dy * dy > reach * reach {
                continue;
            }
            let p = Vec2::new(b.position[0], b.position[1]);
            let d = p - position;
            let dist = d.norm();
            // Sensing range, surface to surface.
            if dist - b.radius - spec.radius > spec.sensing_range {
                continue;
            }
            // Field of view around the heading (360 degrees sees all).
            if spec.field_of_view_deg < 360.0 && dist > 1e-12 && d.dot(&heading) / dist < cos_half {
                continue;
            }
            self.others.push(Sensed {
                id: b.id,
                kind: if b.kind == body_kind::ROBOT {
                    BodyKind::Robot
                } else {
                    BodyKind::Obstacle
                },
                position: p,
                velocity: Vec2::new(b.velocity[0], b.velocity[1]),
                acceleration: Vec2::zeros(),
                radius: b.radius,
            });
        }
        if self.noise > 0.0 {
            for o in &mut self.others {
                o.position.x += self.noise * self.rng.gaussian();
                o.position.y += self.noise * self.rng.gaussian();
            }
        }
        if let Some(e) = &mut self.estimator {
            e.apply(header.sim_time, &mut self.others);
        }
        let scanned = spec.sensor.is_some() && {
            let key = (walls.as_ptr() as usize, walls.len());
            let scanner = match &mut self.scanner {
                Some((k, s)) if *k == key => s,
                slot => {
                    &mut slot
                        .insert((key, Scanner::new(Walls::from_segments(walls))))
                        .1
                }
            };
            scanner.scan_robot(
                &mut self.scan,
                self.seed,
                header.tick,
                self.me,
                spec,
                bodies,
            )
        };
        Observation {
            tick: header.tick,
            time: header.sim_time,
            dt: self.dt,
            me: SelfState {
                id: self.me as u32,
                position,
                velocity,
                radius: spec.radius,
                mass: spec.mass,
                damping: spec.damping,
                max_speed: spec.max_speed,
                max_accel: spec.max_accel,
                heading: s.heading,
                angular_velocity: s.angular_velocity,
                kinematics: if unicycle {
                    Kinematics::Unicycle {
                        max_angular_speed: spec.max_angular_speed,
                        max_angular_accel: spec.max_angular_accel,
                    }
                } else {
                    Kinematics::Holonomic
                },
            },
            goal,
            goal_tolerance: spec.goal_tolerance,
            goal_hold_ticks: spec.goal_hold_ticks,
            others: &self.others,
            walls,
            path,
            scan: scanned.then_some(&self.scan),
        }
    }
}
