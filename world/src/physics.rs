//! The world as data plus a step: rapier2d bodies for robots, obstacles and
//! walls, the robots' actuator model, and collision detection.
//!
//! Robot dynamics are m r'' + b r' = f (Chung eq 1), integrated by
//! semi-implicit Euler with `substeps` steps per tick: each substep the
//! world turns the robot's command into an acceleration (force: f/m - b v/m;
//! velocity: first-order lag (v_cmd - v)/T, or ideal tracking when T = 0),
//! clamps it to `max_accel`, updates the velocity, clamps it to `max_speed`,
//! and lets rapier move the disc and resolve contacts. Doing the actuator
//! model ourselves (rather than with rapier's damping) keeps the limits
//! exact and the same as the planners' reference testkit.
//!
//! A unicycle robot (`kinematics = "unicycle"`) keeps a heading theta and a
//! turn rate omega as world state (its collider does not rotate: a disc is
//! the same at any angle). Each substep the world takes its forward speed
//! as the velocity's component along the heading (any sideways velocity a
//! contact gave it is dropped: wheels do not slip), moves v and omega
//! towards the command's (v, omega) by the same first-order lag as a
//! velocity command (ideal when `velocity_lag` = 0), clamps the
//! accelerations to `max_accel` and `max_angular_accel`, then v to
//! ±`max_speed` and omega to ±`max_angular_speed`, integrates
//! theta += omega h, and gives rapier the velocity v (cos theta, sin theta)
//! (semi-implicit Euler, like the holonomic model). A force command on a
//! unicycle pushes along the heading only (a = (f.e - b v) / m, omega brought
//! to 0), a velocity command u asks v = u.e and omega = 0 (e the heading's
//! unit vector); a unicycle command on a holonomic robot brakes it. A
//! unicycle starts facing its goal.
//!
//! A car (`kinematics = "ackermann"`) is the kinematic bicycle
//! (`mrsim_planners::ackermann`, whose `bicycle_step` the world calls, so
//! that the tracking controller predicts what the world does): the pose
//! names the centre of the body's shape, and the wheelbase L is centred
//! on it, so the rear axle is L/2 behind the centre along the heading. The
//! rear axle moves at speed v along the heading and the heading turns at v
//! tan(delta) / L (delta the steering angle). The world keeps each car's v
//! and delta; each substep it moves delta towards the command's steering,
//! clamped to ±`max_steering`, by at most `max_steering_rate` h, and v
//! towards the command's speed by the velocity lag (ideal when
//! `velocity_lag` = 0), its change clamped to `max_accel` h and v to
//! [-`max_reverse_speed`, `max_speed`]; then, with the new v and delta, it
//! moves the rear axle along the arc they drive in the substep (exactly,
//! by its chord), places the centre L/2 ahead of it and gives rapier the
//! velocity that takes the centre there, the collider turned to the new
//! heading (a car's heading rate, published as its angular velocity, is v
//! tan(delta) / L). A contact changes that velocity; of the change only its
//! component along the heading changes v (the wheels do not slip: the
//! sideways part is dropped), as for a unicycle. A car's published
//! velocity is its centre's at the end of the tick, v e + (v tan(delta) /
//! 2) e_perp, plus what a contact changed of the velocity given in the
//! last substep (rapier's own is the chord of the substep's arc, a little
//! off the heading's end). A force or velocity command that reaches a car
//! brakes it (v brought to 0 as above, the wheels held): a holonomic
//! planner drives a car through the agents' tracking controller, which
//! turns its velocity into a car's command before it is sent. A car's
//! command on a holonomic robot or a unicycle brakes it. A car starts
//! facing its goal, its wheels straight.

use crate::motion::{Body, MotionError, MotionSetup, MotionState};
use crate::people::Crowd;
use mrsim_planners::Vec2;
use mrsim_planners::ackermann::{Car, CarState, bicycle_step, centre_velocity};
use mrsim_proto::{BodyState, body_kind};
use mrsim_scenario::{Kinematics, RobotSpec, Scenario, ShapeSpec};
use rapier2d::prelude::*;

/// A command as the world applies it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Applied {
    /// Force held for the tick.
    Force([f64; 2]),
    /// Velocity set-point.
    Velocity([f64; 2]),
    /// A unicycle's forward speed and turn rate set-points.
    Unicycle([f64; 2]),
    /// A car's speed and steering angle (rad) set-points.
    Ackermann([f64; 2]),
}

impl Applied {
    /// Stop as fast as the limits allow.
    pub const BRAKE: Applied = Applied::Velocity([0.0, 0.0]);
}

/// Why a world could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum WorldError {
    /// An obstacle's motion model cannot be run.
    #[error("obstacle `{name}`: {source}")]
    Motion {
        /// The obstacle.
        name: String,
        /// Why.
        source: MotionError,
    },
}

/// What a body's collider belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Owner {
    /// Robot index.
    Robot(usize),
    /// Obstacle index.
    Obstacle(usize),
    /// Person index.
    Person(usize),
    /// Wall index (arena walls included).
    Wall(usize),
}

/// A contact that started during a tick.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Contact {
    /// One side.
    pub a: Owner,
    /// The other side.
    pub b: Owner,
    /// Midpoint of the two bodies' positions (walls: the body's position).
    pub at: [f64; 2],
    /// Surface-to-surface distance when the contact started (at most the
    /// touch tolerance; negative = overlap).
    pub gap: f64,
}

/// What the actuator model reads of a robot each substep, packed (a
/// [`RobotSpec`] is hundreds of bytes of names, parameters and paths: at
/// 100,000 robots reading the few numbers out of it touched a cache line
/// or more per robot per substep).
#[derive(Debug, Clone, Copy)]
struct Actuator {
    mass: f64,
    damping: f64,
    velocity_lag: f64,
    max_accel: f64,
    max_speed: f64,
    kinematics: Kinematics,
}

impl Actuator {
    fn of(spec: &RobotSpec) -> Self {
        Self {
            mass: spec.mass,
            damping: spec.damping,
            velocity_lag: spec.velocity_lag,
            max_accel: spec.max_accel,
            max_speed: spec.max_speed,
            kinematics: spec.kinematics,
        }
    }
}

/// What the world keeps of a car between substeps.
#[derive(Debug, Clone, Copy)]
struct Wheels {
    /// The car's geometry and limits.
    car: Car,
    /// Speed of the rear axle along the heading.
    speed: f64,
    /// Steering angle, rad.
    steering: f64,
    /// The velocity last given to rapier, as rapier holds it: what a
    /// contact changed of it is the contact's.
    given: [f32; 2],
}

/// The car of `spec`, if it is one.
pub fn car_of(spec: &RobotSpec) -> Option<Car> {
    let a = spec.ackermann?;
    (spec.kinematics == Kinematics::Ackermann).then_some(Car {
        wheelbase: a.wheelbase,
        max_steering: a.max_steering,
        max_steering_rate: a.max_steering_rate,
        max_reverse_speed: a.max_reverse_speed,
        max_speed: spec.max_speed,
        max_accel: spec.max_accel,
    })
}

/// The simulated world.
pub struct World {
    /// The scenario it was built from.
    pub scenario: Scenario,
    phys: PhysicsWorld,
    robots: Vec<RigidBodyHandle>,
    /// Each robot's actuator model, by robot index.
    actuators: Vec<Actuator>,
    obstacles: Vec<RigidBodyHandle>,
    motions: Vec<MotionState>,
    /// The people's rapier bodies, by person index.
    people: Vec<RigidBodyHandle>,
    /// Which of the people's bodies are enabled in rapier: those who may
    /// touch a robot this tick ([`World::people_in_reach`]).
    people_live: Vec<bool>,
    /// Scratch of [`World::people_in_reach`].
    people_near: Vec<bool>,
    near_scratch: Vec<u32>,
    /// The fastest any robot may go (forwards or backwards).
    robot_top_speed: f64,
    crowd: Crowd,
    bodies: Vec<Body>,
    /// Each collider's owner, by the collider's arena index (colliders are
    /// never removed, so the index alone names one).
    owners: Vec<Option<Owner>>,
    commands: Vec<Applied>,
    /// Commands that take effect at a later physics substep (counted from
    /// the run's start), per robot, in the order they take effect (a
    /// timing model's compute time and actuation delay).
    pending: Vec<std::collections::VecDeque<(u64, Applied)>>,
    /// True while some robot has a pending command.
    any_pending: bool,
    /// Each robot's heading, rad (unicycles turn it; 0 for the others).
    headings: Vec<f64>,
    /// Each robot's turn rate, rad/s.
    turn_rates: Vec<f64>,
    /// Each robot's wheels, `Some` for a car.
    wheels: Vec<Option<Wheels>>,
    /// Every body's shape by body id (robots, then obstacles).
    shapes: Vec<mrsim_shape::Shape>,
    states: Vec<BodyState>,
    /// Pairs in contact after the last substep, sorted.
    touching: Vec<(Owner, Owner)>,
    /// The next substep's `touching`, built beside it.
    touching_next: Vec<(Owner, Owner)>,
    touch_tolerance: f64,
    walls: Vec<[[f64; 2]; 2]>,
    tick: u64,
    /// Time spent in rapier's own step during the last tick, ns.
    physics_ns: u64,
}

/// `v` shortened to length `max` if longer, keeping its direction, also
/// when its length overflows (a command of 1e300 divided by a small mass):
/// then the direction comes from the infinite components, or from `v`
/// rescaled by its largest component. A NaN component gives zero (the
/// world never lets NaN reach a command, this is a last line).
pub fn clamp_norm(v: [f64; 2], max: f64) -> [f64; 2] {
    if v.iter().any(|c| c.is_nan()) {
        return [0.0, 0.0];
    }
    // The plain root of the sum of squares, and `hypot` (slow) only where
    // that overflows or underflows.
    let n2 = v[0] * v[0] + v[1] * v[1];
    let n = if n2.is_finite() && n2 > f64::MIN_POSITIVE {
        n2.sqrt()
    } else {
        v[0].hypot(v[1])
    };
    if n <= max {
        return v;
    }
    let dir = if n.is_finite() {
        [v[0] / n, v[1] / n]
    } else {
        let u = if v.iter().any(|c| c.is_infinite()) {
            v.map(|c| if c.is_infinite() { c.signum() } else { 0.0 })
        } else {
            let m = v[0].abs().max(v[1].abs());
            [v[0] / m, v[1] / m]
        };
        let un = u[0].hypot(u[1]);
        [u[0] / un, u[1] / un]
    };
    [dir[0] * max, dir[1] * max]
}

/// The motion setup of obstacle `i`: its noise stream, its body index
/// (robots come first) and its target's.
fn motion_setup(scenario: &Scenario, i: usize) -> MotionSetup {
    let n = scenario.robots.len();
    let target = match &scenario.obstacles[i].motion {
        mrsim_scenario::Motion::Intentional {
            target: Some(t), ..
        } => scenario.robot_index(t).or_else(|| {
            scenario
                .obstacles
                .iter()
                .position(|o| &o.name == t)
                .map(|k| n + k)
        }),
        _ => None,
    };
    MotionSetup {
        seed: scenario.world.seed,
        index: i,
        body: n + i,
        target,
        radius: scenario.obstacles[i].radius,
        dt: scenario.world.dt,
    }
}

/// Records `owner` for collider `c`.
fn set_owner(owners: &mut Vec<Option<Owner>>, c: ColliderHandle, owner: Owner) {
    let i = c.into_raw_parts().0 as usize;
    if owners.len() <= i {
        owners.resize(i + 1, None);
    }
    owners[i] = Some(owner);
}

/// Every body's state before the first refresh: robots, then obstacles,
/// then people, each with its id, kind and radius.
fn initial_states(scenario: &Scenario) -> Vec<BodyState> {
    let robots = scenario.robots.iter().map(|r| (body_kind::ROBOT, r.radius));
    let obstacles = scenario
        .obstacles
        .iter()
        .map(|o| (body_kind::OBSTACLE, o.radius));
    let people = scenario
        .people
        .iter()
        .map(|p| (body_kind::PERSON, p.radius));
    robots
        .chain(obstacles)
        .chain(people)
        .enumerate()
        .map(|(id, (kind, radius))| BodyState {
            id: id as u32,
            kind,
            radius,
            ..Default::default()
        })
        .collect()
}

/// The collider of a body's shape: a ball (a point body's the small
/// `min_radius`), a cuboid for a rectangle, a convex polygon for a polygon
/// (the scenario validated it; should rapier refuse one, the disc that
/// holds it).
fn collider_of(shape: &ShapeSpec, radius: f64, min_radius: f64) -> ColliderBuilder {
    match shape {
        ShapeSpec::Disc => ColliderBuilder::ball(radius.max(min_radius) as f32),
        ShapeSpec::Rectangle { length, width } => {
            ColliderBuilder::cuboid((length / 2.0) as f32, (width / 2.0) as f32)
        }
        ShapeSpec::Polygon { points } => {
            ColliderBuilder::convex_polyline(points.iter().map(|p| v2(*p)).collect())
                .unwrap_or_else(|| ColliderBuilder::ball(radius.max(min_radius) as f32))
        }
    }
}

/// One substep of a car (module documentation): from its state `s` (the
/// centre, heading, speed and steering), the command, its velocity lag
/// and the substep `h`, its next state. Only a car's command drives it;
/// any other brakes it, the wheels held.
pub fn ackermann_substep(car: &Car, cmd: Applied, s: CarState, lag: f64, h: f64) -> CarState {
    let (speed, steering) = match cmd {
        Applied::Ackermann([v, d]) => (v, d),
        Applied::Force(_) | Applied::Velocity(_) | Applied::Unicycle(_) => (0.0, s.steering),
    };
    bicycle_step(car, s, speed, steering, lag, h)
}

/// One substep of the unicycle model (module documentation): from the
/// body's velocity `v`, heading `theta` and turn rate `omega`, the command,
/// the limits of `spec` and the substep `h`, the new velocity, heading and
/// turn rate.
pub fn unicycle_substep(
    spec: &RobotSpec,
    cmd: Applied,
    v: [f64; 2],
    theta: f64,
    omega: f64,
    h: f64,
) -> ([f64; 2], f64, f64) {
    let (s, c) = theta.sin_cos();
    let speed = v[0] * c + v[1] * s;
    let lag = if spec.velocity_lag > 0.0 {
        spec.velocity_lag
    } else {
        h
    };
    // A NaN set-point asks for 0 (the world never lets one through; a last
    // line, as in `clamp_norm`).
    let z = |x: f64| if x.is_nan() { 0.0 } else { x };
    let (accel, omega_cmd) = match cmd {
        Applied::Unicycle([vc, wc]) => ((z(vc) - speed) / lag, z(wc)),
        Applied::Velocity(u) => ((u[0] * c + u[1] * s - speed) / lag, 0.0),
        Applied::Force(f) => (
            (f[0] * c + f[1] * s - spec.damping * speed) / spec.mass,
            0.0,
        ),
        // Not a unicycle's command: brake, and stop turning.
        Applied::Ackermann(_) => (-speed / lag, 0.0),
    };
    let finite = |x: f64| if x.is_nan() { 0.0 } else { x };
    let accel = finite(accel).clamp(-spec.max_accel, spec.max_accel);
    let speed = (speed + accel * h).clamp(-spec.max_speed, spec.max_speed);
    let alpha =
        finite((omega_cmd - omega) / lag).clamp(-spec.max_angular_accel, spec.max_angular_accel);
    let omega = (omega + alpha * h).clamp(-spec.max_angular_speed, spec.max_angular_speed);
    let theta = theta + omega * h;
    ([speed * theta.cos(), speed * theta.sin()], theta, omega)
}

fn v2(p: [f64; 2]) -> Vector {
    Vector::new(p[0] as f32, p[1] as f32)
}

impl World {
    /// Builds the world of a validated scenario, robots at their starts.
    pub fn new(scenario: &Scenario) -> Result<Self, WorldError> {
        let mut phys = PhysicsWorld::new();
        phys.gravity = Vector::ZERO;
        let sub = scenario.world.substeps.max(1);
        phys.integration_parameters.dt = (scenario.world.dt / sub as f64) as f32;
        phys.integration_parameters.length_unit = scenario.length_unit.per_metre() as f32;
        // A point robot (radius 0) still needs a collider: a disc ten times
        // smaller than the touch tolerance, so that a point robot stopped
        // against a body measures a gap well inside the tolerance.
        let min_radius = 1e-4 * scenario.length_unit.per_metre();

        let mut owners = Vec::new();
        let mut robots = Vec::with_capacity(scenario.robots.len());
        for (i, r) in scenario.robots.iter().enumerate() {
            let mut body = RigidBodyBuilder::dynamic()
                .translation(v2(r.start))
                .lock_rotations()
                .linear_damping(0.0)
                .can_sleep(false)
                .ccd_enabled(true);
            if !r.shape.is_disc() {
                body = body.rotation(r.start_heading() as f32);
            }
            let h = phys.insert_body(body);
            let collider = collider_of(&r.shape, r.radius, min_radius)
                .mass(r.mass as f32)
                .friction(0.0);
            let c = phys.insert_collider(collider, Some(h));
            set_owner(&mut owners, c, Owner::Robot(i));
            robots.push(h);
        }

        let mut obstacles = Vec::with_capacity(scenario.obstacles.len());
        let mut motions = Vec::with_capacity(scenario.obstacles.len());
        for (i, o) in scenario.obstacles.iter().enumerate() {
            let motion = MotionState::new(&o.motion, o.start, motion_setup(scenario, i)).map_err(
                |source| WorldError::Motion {
                    name: o.name.clone(),
                    source,
                },
            )?;
            let builder = if motion.is_static() {
                RigidBodyBuilder::fixed()
            } else {
                RigidBodyBuilder::kinematic_position_based()
            };
            let h = phys.insert_body(builder.translation(v2(o.start)).rotation(o.heading as f32));
            let collider = collider_of(&o.shape, o.radius, min_radius);
            let c = phys.insert_collider(collider, Some(h));
            set_owner(&mut owners, c, Owner::Obstacle(i));
            obstacles.push(h);
            motions.push(motion);
        }

        let mut people = Vec::with_capacity(scenario.people.len());
        for (k, p) in scenario.people.iter().enumerate() {
            let h = phys
                .insert_body(RigidBodyBuilder::kinematic_position_based().translation(v2(p.start)));
            let c = phys.insert_collider(ColliderBuilder::ball(p.radius as f32), Some(h));
            set_owner(&mut owners, c, Owner::Person(k));
            people.push(h);
        }

        let walls = scenario.all_walls();
        for (i, w) in walls.iter().enumerate() {
            let h = phys.insert_body(RigidBodyBuilder::fixed());
            let collider = ColliderBuilder::segment(v2(w[0]), v2(w[1]));
            let c = phys.insert_collider(collider, Some(h));
            set_owner(&mut owners, c, Owner::Wall(i));
        }

        let mut world = Self {
            scenario: scenario.clone(),
            phys,
            robots,
            actuators: scenario.robots.iter().map(Actuator::of).collect(),
            obstacles,
            motions,
            people_live: vec![true; people.len()],
            people,
            people_near: Vec::new(),
            near_scratch: Vec::new(),
            robot_top_speed: scenario
                .robots
                .iter()
                .map(|r| {
                    let back = r.ackermann.map_or(0.0, |a| a.max_reverse_speed);
                    r.max_speed.max(back)
                })
                .fold(0.0, f64::max),
            crowd: Crowd::new(scenario),
            bodies: Vec::with_capacity(scenario.robots.len() + scenario.obstacles.len()),
            owners,
            commands: vec![Applied::BRAKE; scenario.robots.len()],
            pending: vec![Default::default(); scenario.robots.len()],
            any_pending: false,
            headings: scenario
                .robots
                .iter()
                .map(RobotSpec::start_heading)
                .collect(),
            shapes: scenario.body_shapes(),
            turn_rates: vec![0.0; scenario.robots.len()],
            wheels: scenario
                .robots
                .iter()
                .map(|r| {
                    car_of(r).map(|car| Wheels {
                        car,
                        speed: 0.0,
                        steering: 0.0,
                        given: [0.0, 0.0],
                    })
                })
                .collect(),
            states: initial_states(scenario),
            touching: Vec::new(),
            touching_next: Vec::new(),
            touch_tolerance: 1e-3 * scenario.length_unit.per_metre(),
            walls,
            tick: 0,
            physics_ns: 0,
        };
        world.refresh_states();
        Ok(world)
    }

    /// Ticks done so far.
    pub fn tick(&self) -> u64 {
        self.tick
    }

    /// Simulated time, s.
    pub fn time(&self) -> f64 {
        self.tick as f64 * self.scenario.world.dt
    }

    /// Every body's state: robots first (ids 0..n), then obstacles, then
    /// people.
    pub fn states(&self) -> &[BodyState] {
        &self.states
    }

    /// Mutable access to the per-body flags (lost, at goal).
    pub fn set_flags(&mut self, body: usize, flags: u32) {
        if let Some(s) = self.states.get_mut(body) {
            s.flags = flags;
        }
    }

    /// Every wall segment, the arena's included.
    pub fn walls(&self) -> &[[[f64; 2]; 2]] {
        &self.walls
    }

    /// Sets the command robot `i` follows from now on.
    pub fn set_command(&mut self, i: usize, cmd: Applied) {
        if let Some(c) = self.commands.get_mut(i) {
            *c = cmd;
        }
    }

    /// Robot `i` follows `cmd` from physics substep `at` on (counted from
    /// the run's start: tick k's substeps are k * substeps, ...); one at or
    /// before the next substep is set now.
    pub fn set_command_at(&mut self, i: usize, at: u64, cmd: Applied) {
        let sub = u64::from(self.scenario.world.substeps.max(1));
        if at <= self.tick * sub {
            self.set_command(i, cmd);
        } else if let Some(q) = self.pending.get_mut(i) {
            q.push_back((at, cmd));
            self.any_pending = true;
        }
    }

    /// Forgets robot `i`'s commands not yet in effect (its agent is lost).
    pub fn clear_pending(&mut self, i: usize) {
        if let Some(q) = self.pending.get_mut(i) {
            q.clear();
        }
    }

    /// Puts in effect every pending command due at substep `at`.
    fn take_due(&mut self, at: u64) {
        let mut any = false;
        for (i, q) in self.pending.iter_mut().enumerate() {
            while let Some(&(when, cmd)) = q.front() {
                if when > at {
                    break;
                }
                self.commands[i] = cmd;
                q.pop_front();
            }
            any |= !q.is_empty();
        }
        self.any_pending = any;
    }

    /// Time the last [`World::step`] spent in rapier's own step (all its
    /// substeps), ns: the floor the world's tick is measured against.
    pub fn physics_ns(&self) -> u64 {
        self.physics_ns
    }

    /// The command robot `i` is following.
    pub fn command(&self, i: usize) -> Applied {
        self.commands.get(i).copied().unwrap_or(Applied::BRAKE)
    }

    /// One tick: `substeps` physics steps. Returns the contacts that started.
    pub fn step(&mut self, contacts: &mut Vec<Contact>) {
        contacts.clear();
        let sub = self.scenario.world.substeps.max(1);
        let h = self.scenario.world.dt / sub as f64;
        // Scripted obstacles choose this tick's acceleration from every
        // body's state at its start (the intentional models need them).
        self.bodies.clear();
        self.bodies.extend(self.states.iter().map(|s| Body {
            position: s.position,
            velocity: s.velocity,
            radius: s.radius,
        }));
        for m in &mut self.motions {
            m.begin_tick(&self.bodies);
        }
        // People choose this tick's velocity from the same states.
        self.crowd.begin_tick(&self.states);
        if !self.crowd.is_empty() {
            self.people_in_reach();
        }
        self.physics_ns = 0;
        for j in 0..sub {
            if self.any_pending {
                self.take_due(self.tick * u64::from(sub) + u64::from(j));
            }
            for (i, (handle, spec)) in self.robots.iter().zip(&self.actuators).enumerate() {
                let Some(body) = self.phys.bodies.get_mut(*handle) else {
                    continue;
                };
                let lv = body.linvel();
                let v = [lv.x as f64, lv.y as f64];
                if let Some(w) = &mut self.wheels[i] {
                    let theta = self.headings[i];
                    // What a contact changed of the velocity given, along
                    // the heading (the wheels do not slip).
                    let (sn, cs) = theta.sin_cos();
                    let dv = [
                        f64::from(lv.x) - f64::from(w.given[0]),
                        f64::from(lv.y) - f64::from(w.given[1]),
                    ];
                    let speed = w.speed + dv[0] * cs + dv[1] * sn;
                    let t = body.translation();
                    let p = [f64::from(t.x), f64::from(t.y)];
                    let now = CarState {
                        position: Vec2::new(p[0], p[1]),
                        heading: theta,
                        speed,
                        steering: w.steering,
                    };
                    let next =
                        ackermann_substep(&w.car, self.commands[i], now, spec.velocity_lag, h);
                    let nv = [(next.position.x - p[0]) / h, (next.position.y - p[1]) / h];
                    let given = v2(nv);
                    body.set_linvel(given, true);
                    body.set_rotation(Rotation::new(next.heading as f32), true);
                    w.given = [given.x, given.y];
                    w.speed = next.speed;
                    w.steering = next.steering;
                    self.headings[i] = next.heading;
                    self.turn_rates[i] = next.speed * next.steering.tan() / w.car.wheelbase;
                    continue;
                }
                if spec.kinematics == Kinematics::Unicycle {
                    let (nv, theta, omega) = unicycle_substep(
                        &self.scenario.robots[i],
                        self.commands[i],
                        v,
                        self.headings[i],
                        self.turn_rates[i],
                        h,
                    );
                    self.headings[i] = theta;
                    self.turn_rates[i] = omega;
                    body.set_linvel(v2(nv), true);
                    // A disc is the same at any angle; another shape's
                    // collider turns with the heading.
                    if !self.shapes[i].is_disc() {
                        body.set_rotation(Rotation::new(theta as f32), true);
                    }
                    continue;
                }
                // The actuator model: acceleration from the command.
                let mut a = match self.commands[i] {
                    // Force: m r'' + b r' = f.
                    Applied::Force(f) => [
                        (f[0] - spec.damping * v[0]) / spec.mass,
                        (f[1] - spec.damping * v[1]) / spec.mass,
                    ],
                    // Velocity: first-order lag of time constant T, or
                    // ideal tracking (T = 0) within the limits.
                    Applied::Velocity(vc) => {
                        let t = if spec.velocity_lag > 0.0 {
                            spec.velocity_lag
                        } else {
                            h
                        };
                        [(vc[0] - v[0]) / t, (vc[1] - v[1]) / t]
                    }
                    // Not a holonomic command: brake.
                    Applied::Unicycle(_) | Applied::Ackermann(_) => {
                        let t = if spec.velocity_lag > 0.0 {
                            spec.velocity_lag
                        } else {
                            h
                        };
                        [-v[0] / t, -v[1] / t]
                    }
                };
                a = clamp_norm(a, spec.max_accel);
                let nv = clamp_norm([v[0] + a[0] * h, v[1] + a[1] * h], spec.max_speed);
                body.set_linvel(v2(nv), true);
            }
            for (k, handle) in self.obstacles.iter().enumerate() {
                let m = &mut self.motions[k];
                if m.is_static() {
                    continue;
                }
                m.advance(h);
                if let Some(body) = self.phys.bodies.get_mut(*handle) {
                    body.set_next_kinematic_translation(v2(m.position));
                }
            }
            if !self.crowd.is_empty() {
                self.crowd.advance(h);
                let people = self.people.iter().zip(&self.crowd.people);
                for ((handle, p), _) in people.zip(&self.people_live).filter(|(_, live)| **live) {
                    if let Some(body) = self.phys.bodies.get_mut(*handle) {
                        body.set_next_kinematic_translation(v2(p.position));
                    }
                }
            }
            let t = std::time::Instant::now();
            self.phys.step();
            self.physics_ns += t.elapsed().as_nanos() as u64;
            self.detect_contacts(contacts);
        }
        self.tick += 1;
        self.refresh_states();
    }

    /// Enables in rapier the bodies of the people who may touch a robot
    /// over this tick and disables the others'. A person touches nothing
    /// else that counts (contacts among people, and of people with walls
    /// and obstacles, are nobody's, and nothing pushes a person), so a
    /// person farther from every robot than both can close in a tick has
    /// no part in the physics: rapier's step then costs the robots'
    /// surroundings, not the whole crowd. The margin is twice the closing
    /// distance (the robots' top speed and the people's fastest this
    /// tick) plus a metre; a body enabled again starts where its person
    /// is.
    fn people_in_reach(&mut self) {
        let dt = self.scenario.world.dt;
        let closing = (self.robot_top_speed + self.crowd.top_speed()) * dt;
        let margin = 2.0 * closing + 1000.0 * self.touch_tolerance;
        let mut near = std::mem::take(&mut self.people_near);
        self.crowd
            .near_robots(&self.states, margin, &mut near, &mut self.near_scratch);
        for (k, (&want, live)) in near.iter().zip(&mut self.people_live).enumerate() {
            if want == *live {
                continue;
            }
            *live = want;
            if let Some(body) = self.phys.bodies.get_mut(self.people[k]) {
                body.set_enabled(want);
                if want {
                    body.set_translation(v2(self.crowd.people[k].position), true);
                }
            }
        }
        self.people_near = near;
    }

    /// A collision is a pair whose surfaces have actually closed (gap at
    /// most 1 mm in the scenario's unit) after being apart (by more than
    /// 1 cm, or no longer a candidate pair). Rapier's own
    /// contact events start within its prediction distance (centimetres in a
    /// cm-scale world), which would count near misses; so rapier only
    /// proposes the candidate pairs and the gap is measured here, after
    /// every substep.
    fn detect_contacts(&mut self, contacts: &mut Vec<Contact>) {
        let mut now = std::mem::take(&mut self.touching_next);
        now.clear();
        for pair in self.phys.narrow_phase.contact_pairs() {
            let (Some(a), Some(b)) = (self.owner(pair.collider1), self.owner(pair.collider2))
            else {
                continue;
            };
            if !matches!(a, Owner::Robot(_)) && !matches!(b, Owner::Robot(_)) {
                continue;
            }
            let gap = self.owner_gap(a, b);
            let was_touching = self.touching.binary_search(&(a, b)).is_ok();
            // Hysteresis: a pair that touched stays in contact until it has
            // separated by ten times the tolerance, so discs held exactly at
            // touching (ORCA in a crowd) count one collision, not one per
            // flicker across the tolerance.
            let limit = if was_touching {
                10.0 * self.touch_tolerance
            } else {
                self.touch_tolerance
            };
            if gap > limit {
                continue;
            }
            now.push((a, b));
            if !was_touching {
                let at = match (self.owner_position(a), self.owner_position(b)) {
                    (Some(p), Some(q)) => [(p[0] + q[0]) / 2.0, (p[1] + q[1]) / 2.0],
                    (Some(p), None) | (None, Some(p)) => p,
                    (None, None) => [0.0, 0.0],
                };
                contacts.push(Contact { a, b, at, gap });
            }
        }
        now.sort_unstable();
        self.touching_next = std::mem::replace(&mut self.touching, now);
    }

    fn owner(&self, c: ColliderHandle) -> Option<Owner> {
        self.owners
            .get(c.into_raw_parts().0 as usize)
            .copied()
            .flatten()
    }

    /// The radius of `o`'s collider (a point body's is the small minimum).
    fn owner_radius(&self, o: Owner) -> f64 {
        let min = 1e-4 * self.scenario.length_unit.per_metre();
        match o {
            Owner::Robot(i) => self.scenario.robots[i].radius.max(min),
            Owner::Obstacle(i) => self.scenario.obstacles[i].radius.max(min),
            Owner::Person(k) => self.scenario.people[k].radius,
            Owner::Wall(_) => 0.0,
        }
    }

    /// `o`'s shape and pose (`None` for a wall).
    fn owner_pose(&self, o: Owner) -> Option<(mrsim_shape::Shape, mrsim_shape::Pose)> {
        let p = self.owner_position(o)?;
        let (id, heading) = match o {
            Owner::Robot(i) => (i, self.headings[i]),
            Owner::Obstacle(i) => (self.robots.len() + i, self.scenario.obstacles[i].heading),
            Owner::Person(k) => (self.robots.len() + self.obstacles.len() + k, 0.0),
            Owner::Wall(_) => return None,
        };
        Some((self.shapes[id], mrsim_shape::Pose::new(p, heading)))
    }

    fn owner_gap(&self, a: Owner, b: Owner) -> f64 {
        if let (Some((sa, pa)), Some((sb, pb))) = (self.owner_pose(a), self.owner_pose(b))
            && !(sa.is_disc() && sb.is_disc())
        {
            return mrsim_shape::gap(&sa, pa, &sb, pb);
        }
        match (a, b) {
            (Owner::Wall(w), o) | (o, Owner::Wall(w)) => {
                if let Some((s, p)) = self.owner_pose(o).filter(|(s, _)| !s.is_disc()) {
                    return mrsim_shape::gap_to_segment(&s, p, self.walls[w]);
                }
            }
            _ => {}
        }
        let r = self.owner_radius(a) + self.owner_radius(b);
        match (self.owner_position(a), self.owner_position(b), a, b) {
            (Some(p), Some(q), _, _) => (p[0] - q[0]).hypot(p[1] - q[1]) - r,
            (Some(p), None, _, Owner::Wall(w)) | (None, Some(p), Owner::Wall(w), _) => {
                crate::clearance::segment_distance(self.walls[w], p) - r
            }
            _ => 0.0,
        }
    }

    fn owner_position(&self, o: Owner) -> Option<[f64; 2]> {
        let h = match o {
            Owner::Robot(i) => self.robots[i],
            Owner::Obstacle(i) => self.obstacles[i],
            Owner::Person(k) => return self.crowd.people.get(k).map(|p| p.position),
            Owner::Wall(_) => return None,
        };
        self.phys.bodies.get(h).map(|b| {
            let t = b.translation();
            [t.x as f64, t.y as f64]
        })
    }

    /// Refreshes the positions and velocities in `states` from the bodies
    /// (each body keeps its id, kind, radius and flags).
    fn refresh_states(&mut self) {
        let n = self.robots.len();
        for (s, h) in self.states.iter_mut().zip(&self.robots) {
            let (p, v) = self
                .phys
                .bodies
                .get(*h)
                .map(|b| (b.translation(), b.linvel()))
                .unwrap_or((Vector::ZERO, Vector::ZERO));
            s.position = [p.x as f64, p.y as f64];
            s.velocity = [v.x as f64, v.y as f64];
        }
        for (s, ((th, w), wheels)) in self
            .states
            .iter_mut()
            .zip(self.headings.iter().zip(&self.turn_rates).zip(&self.wheels))
        {
            s.heading = *th;
            s.angular_velocity = *w;
            if let Some(wh) = wheels {
                s.steering = wh.steering;
                // The centre's velocity at the tick's end, v e + (v
                // tan(delta) / 2) e_perp, and what a contact changed of the
                // velocity given (rapier's is the last substep's chord).
                let c = centre_velocity(&CarState {
                    position: Vec2::zeros(),
                    heading: *th,
                    speed: wh.speed,
                    steering: wh.steering,
                });
                s.velocity = [
                    c.x + s.velocity[0] - f64::from(wh.given[0]),
                    c.y + s.velocity[1] - f64::from(wh.given[1]),
                ];
            }
        }
        for ((s, m), o) in self.states[n..]
            .iter_mut()
            .zip(&self.motions)
            .zip(&self.scenario.obstacles)
        {
            s.position = m.position;
            s.velocity = m.velocity;
            s.heading = o.heading;
        }
        let first = n + self.motions.len();
        for (s, p) in self.states[first..].iter_mut().zip(&self.crowd.people) {
            s.position = p.position;
            s.velocity = p.velocity;
            s.heading = p.heading;
        }
    }
}

#[cfg(test)]
mod clamp_tests {
    use super::clamp_norm;

    #[test]
    fn clamping_keeps_the_direction_even_when_the_length_overflows() {
        assert_eq!(clamp_norm([3.0, 4.0], 10.0), [3.0, 4.0]);
        let c = clamp_norm([3.0, 4.0], 1.0);
        assert!((c[0] - 0.6).abs() < 1e-12 && (c[1] - 0.8).abs() < 1e-12);
        let c = clamp_norm([1e308, 1e308], 2.0);
        assert!((c[0] - 2f64.sqrt()).abs() < 1e-12 && (c[1] - 2f64.sqrt()).abs() < 1e-12);
        let c = clamp_norm([f64::INFINITY, 5.0], 2.0);
        assert_eq!(c, [2.0, 0.0]);
        assert_eq!(clamp_norm([f64::NAN, 1.0], 2.0), [0.0, 0.0]);
    }
}
