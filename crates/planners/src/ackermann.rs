//! Holonomic planners on a car-like robot: a tracking controller after J.
//! Alonso-Mora, A. Breitenmoser, P. Beardsley & R. Siegwart, "Reciprocal
//! Collision Avoidance for Multiple Car-Like Robots", IEEE ICRA 2012
//! (B-ORCA): the planner chooses a holonomic velocity for a disc enlarged
//! by the car's tracking error bound epsilon, and the car tracks that
//! velocity, driven only as fast as it can track it within epsilon.
//!
//! **1. The car.** The kinematic bicycle: the rear axle r moves at speed v
//! along the heading theta, the front wheels are steered by delta, and
//!
//! r' = v (cos theta, sin theta),  theta' = v tan(delta) / L
//!
//! (L the wheelbase). The robot's position is the centre of its body, with
//! the wheelbase centred on it: c = r + (L / 2) (cos theta, sin theta).
//! At a constant steering delta the rear axle drives a circle of radius
//! R = L / |tan delta| and the centre one of radius sqrt(R^2 + (L/2)^2);
//! the tightest, at `max_steering`, bounds every path the car can drive.
//! [`bicycle_step`] is one substep of that model with every limit of the
//! car (steering, steering rate, speed forwards and backwards,
//! acceleration, velocity lag); the world moves cars with it
//! (`mrsim_world::physics`), so what this controller predicts is what the
//! world does while nothing touches the car (and its velocity lag is 0:
//! the prediction leaves the lag out).
//!
//! **2. Tracking a holonomic velocity.** A holonomic planner asks the
//! centre to move at u, that is along the holonomic trajectory c0 + u t. A
//! car cannot move sideways, so it follows that line only within some
//! distance, and the paper's construction is to leave that distance to
//! collision avoidance: the planner plans for a disc of radius r + epsilon
//! (the body's circumscribed radius plus the bound), and the car is given
//! only velocities it tracks within epsilon, the paper's set of allowed
//! holonomic velocities (there computed offline, by simulating its
//! tracking controller from each initial angle and steering, into tables;
//! here computed at each control step, by simulating this controller from
//! the car's present speed and steering).
//!
//! The law ([`steer`]): the car drives forwards, or backwards when it may
//! (`max_reverse_speed` > 0) and u points behind it, its rear then turned
//! towards u. Its centre does not move along the heading while it turns:
//! half the wheelbase ahead of the rear axle, it moves at the slip angle
//! beta = atan(tan(delta) / 2) from it ([`slip_angle`]). alpha is the angle
//! from the way the centre moves to u, and the car turns at the rate alpha
//! / T, that is steering delta = atan(L alpha / (T v)) within
//! ±`max_steering`: full lock while far off, straight once aligned. (Taken
//! from the heading instead, alpha would keep a turning car turning when
//! the planner asks its present velocity: its centre's velocity is turned
//! by beta from the heading.) T ([`align_time`]) is the time the steering
//! takes to sweep from straight to full lock, and at least two control
//! periods, so that neither the steering's rate limit nor the held command
//! makes the heading overshoot.
//!
//! The speed ([`trackable_speed`]) is the largest s, at most |u| (and the
//! car's speed limit that way), whose tracking error e(s) is at most
//! epsilon, where e(s) is the largest distance over the horizon between
//! the holonomic trajectory of the velocity s (u / |u|) (the world's disc
//! model under it, from the car's centre and velocity, with the car's
//! `max_accel`) and the car running this law at speed s from its present
//! state, simulated with [`bicycle_step`] ([`tracking_error`]), found by
//! bisection, which keeps only speeds whose error was simulated within
//! epsilon. Asked along its heading the car drives at |u|; asked sideways
//! it creeps, at about epsilon / (sqrt 2 horizon) from rest, while it
//! turns. (The projection |u| cos alpha would stop a car asked to go
//! sideways, and a car at rest cannot turn.) A car moving too fast to stay
//! within epsilon even stopping gets s = 0 and brakes.
//!
//! **The bound.** epsilon is [`DEFAULT_EPSILON_PER_WHEELBASE`] times the
//! wheelbase (a tenth of it) and the horizon [`DEFAULT_HORIZON`] (1 s),
//! or what [`Tracker::with_bound`] is given. It is a simpler bound than
//! the paper's, which holds over the planner's whole horizon: here it is
//! over the horizon of this controller, re-planned every control step from
//! where the car actually is. Over ORCA's own 10 s horizon a car asked to
//! turn could only crawl. The prediction knows nothing of contacts or of
//! the velocity lag (it takes the speed to follow within `max_accel`), so
//! epsilon bounds the model's error, not a collision's.
//!
//! **3. What the planner sees and what passes.** The car's true
//! observation (its centre, velocity, heading, steering) with its radius
//! enlarged by epsilon; the goal tolerance is the world's (the planner
//! sees the centre itself, as the world's goal test does). A velocity is
//! tracked as above; a force becomes the velocity it would give the centre
//! in one tick, u = v + dt clamp((f - b v) / m, max_accel), as the
//! unicycle's look-ahead controller does ([`crate::unicycle`]); a unicycle
//! command (v, omega) becomes speed v with the steering of the same turn
//! rate ([`steering_for_turn_rate`]); a car's own command passes
//! unchanged, and so does everything of a planner that plans cars itself
//! ([`Planner::native_ackermann`]). On a holonomic robot or a unicycle the
//! planner is used as it is.
//!
//! **What it cannot do.** A car cannot stop on a point beside it: a goal
//! within its turning circle is circled until the planner, seeing it pass,
//! asks something else; without reverse a goal straight behind it takes a
//! turn of at least its minimum radius. A holonomic planner knows nothing
//! of a goal heading (`goal_heading_deg`), so a car arrives facing the way
//! it came in.

use crate::{Command, Diagnostic, Kinematics, Observation, Planner, SelfState, Vec2};
use std::f64::consts::PI;

/// The built-in tracking error bound epsilon, as a fraction of the
/// wheelbase.
pub const DEFAULT_EPSILON_PER_WHEELBASE: f64 = 0.1;

/// The built-in horizon over which the tracking error is bounded, s.
pub const DEFAULT_HORIZON: f64 = 1.0;

/// Substeps per control period of the controller's prediction.
const PREDICTION_SUBSTEPS: u32 = 4;

/// Bisection steps of [`trackable_speed`] (a speed to 1/4096 of the
/// asked one).
const BISECTIONS: u32 = 12;

/// A car's geometry and limits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Car {
    /// Distance between the axles, > 0.
    pub wheelbase: f64,
    /// Steering limit either way, rad, in (0, pi/2).
    pub max_steering: f64,
    /// Steering-rate limit, rad/s, > 0.
    pub max_steering_rate: f64,
    /// Fastest speed backwards, >= 0.
    pub max_reverse_speed: f64,
    /// Fastest speed forwards, > 0.
    pub max_speed: f64,
    /// Largest rate of change of the speed, > 0.
    pub max_accel: f64,
}

impl Car {
    /// The car `me` is, if it is one.
    pub fn of(me: &SelfState) -> Option<Car> {
        match me.kinematics {
            Kinematics::Ackermann {
                wheelbase,
                max_steering,
                max_steering_rate,
                max_reverse_speed,
            } => Some(Car {
                wheelbase,
                max_steering,
                max_steering_rate,
                max_reverse_speed,
                max_speed: me.max_speed,
                max_accel: me.max_accel,
            }),
            _ => None,
        }
    }

    /// The radius of the tightest circle the rear axle drives, L / tan
    /// delta_max.
    pub fn min_turning_radius(&self) -> f64 {
        self.wheelbase / self.max_steering.tan()
    }
}

/// A car's state: the centre of its body, heading, speed and steering.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CarState {
    /// The centre of the body.
    pub position: Vec2,
    /// Heading, rad.
    pub heading: f64,
    /// Speed of the rear axle along the heading (negative: backwards).
    pub speed: f64,
    /// Steering angle, rad.
    pub steering: f64,
}

impl CarState {
    /// The state of the car `me`: its speed is its velocity's component
    /// along the heading (the centre's velocity is v e + (L/2) theta' e_perp).
    pub fn of(me: &SelfState) -> Self {
        Self {
            position: me.position,
            heading: me.heading,
            speed: me.velocity.dot(&unit(me.heading)),
            steering: me.steering,
        }
    }

    /// The rear axle's position for wheelbase `wheelbase`.
    pub fn rear_axle(&self, wheelbase: f64) -> Vec2 {
        self.position - unit(self.heading) * (wheelbase / 2.0)
    }
}

/// The unit vector of heading `theta`.
fn unit(theta: f64) -> Vec2 {
    let (s, c) = theta.sin_cos();
    Vec2::new(c, s)
}

/// `a` wrapped into [-pi, pi).
fn wrap(a: f64) -> f64 {
    (a + PI).rem_euclid(2.0 * PI) - PI
}

/// sin(x) / x, 1 at 0.
fn sinc(x: f64) -> f64 {
    if x.abs() < 1e-4 {
        1.0 - x * x / 6.0
    } else {
        x.sin() / x
    }
}

/// One substep `h` of the bicycle (module documentation, 1) from `s`
/// towards the set-points `speed` and `steering`, every limit of `car`
/// enforced whatever is asked: the steering moves towards the asked one,
/// clamped to ±`max_steering`, by at most `max_steering_rate` h; the speed
/// towards the asked one by the first-order lag of time constant `lag`
/// (ideal within the limits when 0), its change clamped to `max_accel` h
/// and the result to [-`max_reverse_speed`, `max_speed`]. With the new
/// speed v and steering delta (semi-implicit Euler, as the world's other
/// models) the rear axle moves along the arc of length v h and turn
/// v tan(delta) h / L exactly (by its chord), and the centre is placed
/// L / 2 ahead of it. A NaN speed asks 0, a NaN steering keeps the wheels
/// where they are.
pub fn bicycle_step(
    car: &Car,
    s: CarState,
    speed: f64,
    steering: f64,
    lag: f64,
    h: f64,
) -> CarState {
    let max = car.max_steering;
    let target = if steering.is_nan() {
        s.steering
    } else {
        steering.clamp(-max, max)
    };
    let turn = car.max_steering_rate * h;
    let steering = (s.steering + (target - s.steering).clamp(-turn, turn)).clamp(-max, max);
    let t = if lag > 0.0 { lag } else { h };
    let asked = if speed.is_nan() { 0.0 } else { speed };
    let accel = (asked - s.speed) / t;
    let accel = if accel.is_nan() { 0.0 } else { accel };
    let accel = accel.clamp(-car.max_accel, car.max_accel);
    let speed = (s.speed + accel * h).clamp(-car.max_reverse_speed, car.max_speed);
    let l = car.wheelbase;
    let dtheta = speed * steering.tan() / l * h;
    let rear = s.rear_axle(l) + unit(s.heading + dtheta / 2.0) * (speed * h * sinc(dtheta / 2.0));
    let heading = s.heading + dtheta;
    CarState {
        position: rear + unit(heading) * (l / 2.0),
        heading,
        speed,
        steering,
    }
}

/// The time constant T of the heading's approach to the asked direction:
/// the time the steering takes from straight to full lock, and at least
/// two control periods `dt` (module documentation, 2).
pub fn align_time(car: &Car, dt: f64) -> f64 {
    (car.max_steering / car.max_steering_rate).max(2.0 * dt)
}

/// The angle the centre's velocity makes with the heading at steering
/// `steering`, forwards: beta = atan(tan(delta) / 2) (the centre is half
/// the wheelbase ahead of the rear axle, so it moves at v e + (v tan(delta)
/// / 2) e_perp); backwards the same angle from the opposite of the
/// heading.
pub fn slip_angle(steering: f64) -> f64 {
    (steering.tan() / 2.0).atan()
}

/// Which way the car drives to track `u` from heading `heading` and
/// steering `steering`: +1 forwards, -1 backwards (when it may reverse and
/// u points behind it), and the angle from the way its centre moves (the
/// heading, or its opposite, turned by the [`slip_angle`]) to u, in [-pi,
/// pi).
fn direction(car: &Car, heading: f64, steering: f64, u: Vec2) -> (f64, f64) {
    let alpha = wrap(u.y.atan2(u.x) - heading);
    let (sign, alpha) = if car.max_reverse_speed > 0.0 && alpha.cos() < 0.0 {
        (-1.0, wrap(alpha - PI))
    } else {
        (1.0, alpha)
    };
    (sign, wrap(alpha - slip_angle(steering)))
}

/// The law of the module documentation (2): the (speed, steering) with
/// which the car at `s` tracks the direction of `u` at speed `speed` (a
/// magnitude, >= 0; the sign is the law's). A `u` of length 0 asks the car
/// to stop with its wheels where they are.
pub fn steer(car: &Car, s: &CarState, u: Vec2, speed: f64, dt: f64) -> (f64, f64) {
    if u.norm() <= f64::MIN_POSITIVE {
        return (0.0, s.steering);
    }
    let (sign, alpha) = direction(car, s.heading, s.steering, u);
    let v = sign * speed;
    // theta' = v tan(delta) / L = alpha / T; at rest, the steering that
    // turns the right way once the car moves (full lock, or straight).
    let steering = if alpha == 0.0 {
        0.0
    } else if v == 0.0 {
        (sign * alpha).signum() * car.max_steering
    } else {
        (car.wheelbase * alpha / (align_time(car, dt) * v)).atan()
    };
    (v, steering.clamp(-car.max_steering, car.max_steering))
}

/// The centre's velocity of a car at `s`: v e + (v tan(delta) / 2) e_perp.
pub fn centre_velocity(s: &CarState) -> Vec2 {
    let (sn, cs) = s.heading.sin_cos();
    let lateral = s.speed * s.steering.tan() / 2.0;
    Vec2::new(cs * s.speed - sn * lateral, sn * s.speed + cs * lateral)
}

/// The tracking error of speed `speed` (module documentation, 2): the
/// largest distance, over `horizon`, between the holonomic trajectory of
/// the velocity `speed` (u / |u|) and the car driven from `s` by [`steer`]
/// at that speed, the command recomputed every control period `dt` and
/// held for it, the car moved by [`bicycle_step`] (ideal lag). The
/// holonomic trajectory is the one the world's disc model drives under
/// that velocity with the car's `max_accel`, from the car's centre and
/// its velocity, so that what the acceleration limit costs a holonomic
/// robot too is not counted against the car.
pub fn tracking_error(car: &Car, s: CarState, u: Vec2, speed: f64, dt: f64, horizon: f64) -> f64 {
    let n = u.norm();
    if n <= f64::MIN_POSITIVE {
        return 0.0;
    }
    let target = u * (speed / n);
    let ticks = (horizon / dt).ceil().max(1.0) as u32;
    let h = dt / f64::from(PREDICTION_SUBSTEPS);
    let (mut p, mut w) = (s.position, centre_velocity(&s));
    let mut x = s;
    let mut worst: f64 = 0.0;
    for _ in 0..ticks {
        let (v, delta) = steer(car, &x, u, speed, dt);
        for _ in 0..PREDICTION_SUBSTEPS {
            x = bicycle_step(car, x, v, delta, 0.0, h);
            let mut a = (target - w) / h;
            if a.norm() > car.max_accel {
                a *= car.max_accel / a.norm();
            }
            w += a * h;
            p += w * h;
            worst = worst.max((x.position - p).norm());
        }
    }
    worst
}

/// The speed with which the car at `s` tracks `u` (module documentation,
/// 2): the largest s at most |u| (and `max_speed` forwards,
/// `max_reverse_speed` backwards) whose [`tracking_error`] over `horizon`
/// is at most `epsilon`, by bisection (every speed it keeps was simulated
/// within epsilon; 0 when none was).
pub fn trackable_speed(
    car: &Car,
    s: CarState,
    u: Vec2,
    dt: f64,
    epsilon: f64,
    horizon: f64,
) -> f64 {
    let n = u.norm();
    if n <= f64::MIN_POSITIVE {
        return 0.0;
    }
    let (sign, _) = direction(car, s.heading, s.steering, u);
    let cap = n.min(if sign > 0.0 {
        car.max_speed
    } else {
        car.max_reverse_speed
    });
    let within = |speed: f64| tracking_error(car, s, u, speed, dt, horizon) <= epsilon;
    if within(cap) {
        return cap;
    }
    let (mut lo, mut hi) = (0.0, cap);
    for _ in 0..BISECTIONS {
        let mid = 0.5 * (lo + hi);
        if within(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    // Bisection moves `lo` only to speeds found within; 0 itself is
    // checked last (a car moving fast may not stay within even stopping,
    // and then the best it can do is brake).
    lo
}

/// The steering angle at which a car of wheelbase `wheelbase` at speed
/// `speed` turns at `omega` rad/s: atan(L omega / v) (teb_local_planner's
/// car-like conversion); at speed 0 no steering turns the car, and
/// `current`, the steering it has, is kept.
pub fn steering_for_turn_rate(speed: f64, omega: f64, wheelbase: f64, current: f64) -> f64 {
    if speed == 0.0 {
        current
    } else {
        (wheelbase * omega / speed).atan()
    }
}

/// A planner made to drive a car through the tracking controller.
pub struct Tracker {
    inner: Box<dyn Planner>,
    epsilon: Option<f64>,
    horizon: f64,
}

impl Tracker {
    /// Wraps `inner` with the built-in bound: epsilon a tenth of the
    /// wheelbase, over [`DEFAULT_HORIZON`].
    pub fn new(inner: Box<dyn Planner>) -> Self {
        Self {
            inner,
            epsilon: None,
            horizon: DEFAULT_HORIZON,
        }
    }

    /// Wraps `inner` with the tracking error bound `epsilon` (> 0, the
    /// scenario's length unit) over `horizon` (> 0, s).
    pub fn with_bound(inner: Box<dyn Planner>, epsilon: f64, horizon: f64) -> Self {
        Self {
            inner,
            epsilon: Some(epsilon),
            horizon,
        }
    }

    /// The bound epsilon for `car`.
    pub fn epsilon(&self, car: &Car) -> f64 {
        self.epsilon
            .unwrap_or(car.wheelbase * DEFAULT_EPSILON_PER_WHEELBASE)
    }
}

impl Planner for Tracker {
    fn plan(&mut self, obs: &Observation) -> Command {
        let car = match Car::of(&obs.me) {
            Some(car) if !self.inner.native_ackermann() => car,
            _ => return self.inner.plan(obs),
        };
        let epsilon = self.epsilon(&car);
        let mut seen = *obs;
        seen.me.radius += epsilon;
        let me = &obs.me;
        let u = match self.inner.plan(&seen) {
            cmd @ Command::Ackermann { .. } => return cmd,
            Command::Unicycle { v, omega } => {
                return Command::Ackermann {
                    speed: v,
                    steering: steering_for_turn_rate(v, omega, car.wheelbase, me.steering),
                };
            }
            Command::Velocity(u) => u,
            Command::Force(f) => me.velocity_after(f, obs.dt),
        };
        // A planner's NaN or infinity reaches the guard as it was.
        if !(u.x.is_finite() && u.y.is_finite()) {
            return Command::Velocity(u);
        }
        let s = CarState::of(me);
        let speed = trackable_speed(&car, s, u, obs.dt, epsilon, self.horizon);
        let (speed, steering) = steer(&car, &s, u, speed, obs.dt);
        Command::Ackermann { speed, steering }
    }

    fn diagnostics(&self) -> Vec<Diagnostic> {
        self.inner.diagnostics()
    }

    fn diagnostics_into(&self, out: &mut Vec<Diagnostic>) {
        self.inner.diagnostics_into(out);
    }

    fn native_ackermann(&self) -> bool {
        true
    }

    fn plans_ackermann(&self) -> bool {
        self.inner.plans_ackermann()
    }

    fn needs_scan(&self) -> bool {
        self.inner.needs_scan()
    }
}

#[cfg(test)]
mod tests;
