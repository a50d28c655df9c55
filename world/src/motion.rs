//! Scripted obstacle motion models (Zhu & Loh, "Modeling and Control
//! Strategies for Dynamical Obstacle Avoidance by Mobile Robots", section
//! 2.3.1), moved by the world.
//!
//! The world calls [`MotionState::begin_tick`] once per tick with every
//! body's state at the start of the tick (robots first, then obstacles, the
//! order of the snapshot), then [`MotionState::advance`] once per physics
//! substep. The models' Δt is the tick (the paper's sampling interval): the
//! acceleration is chosen once per tick and held over its substeps, which
//! integrate v += a h (speed capped), p += v h.
//!
//! - `static`, `constant-velocity` (eqs 2.13-2.15), `waypoints` (straight
//!   lines at `speed` through `points`, from the first again after the last
//!   if `loop`).
//! - `random` (eqs 2.16-2.20): a(t) = alpha1 a(t - Δt) + beta1 w(t), w
//!   white noise, per component Gaussian of standard deviation
//!   `accel_sigma`, or uniform on [-√3 σ, √3 σ] (the same standard
//!   deviation). alpha1 = 0, beta1 = 1 (the defaults) is eq 2.16's
//!   a(t) = w(t). Stationary variance per component:
//!   beta1² σ² / (1 - alpha1²) for |alpha1| < 1. Speed capped at `max_speed`.
//! - `intentional` (eqs 2.21-2.23): a(t) = alpha2 a(t - Δt) + beta2 e(t),
//!   where e(t) is the obstacle's control: the acceleration that would
//!   bring its velocity to a desired one within one tick,
//!   e = (v_des - v) / Δt, capped at `max_accel` (as is a). The paper leaves
//!   the control strategy open; ours, per `behavior`:
//!   - `pursue` (hostile): v_des = `max_speed` towards the target's current
//!     position (pure pursuit).
//!   - `avoid` (friendly): away from every other body (or only `target` if
//!     given) whose gap is under the escape distance
//!     D = 2 s × max_speed + max_speed² / (2 max_accel), each pushing with
//!     weight 1 - gap / D; v_des = max_speed × the sum, capped at
//!     max_speed. Nobody that near: v_des = 0 (it settles).
//!   - `goal` (fixed route, disregarding others): through `points`, then to
//!     `goal`, at max_speed, slowing to arrive at the last point
//!     (speed ≤ √(2 max_accel d)). A point counts as passed within
//!     max_speed × Δt.
//!
//!   With the defaults alpha2 = beta2 = 0.5 a constant e is followed with
//!   unit gain (a → e) and one tick's lag.
//!
//! Obstacles are kinematic: walls do not stop them and they do not react to
//! contacts. Each obstacle's noise comes from its own stream of the
//! scenario's seed ([`mrsim_scenario::rng::Rng::stream`]), so runs repeat.

use mrsim_scenario::Motion;
use mrsim_scenario::rng::Rng;

/// Seconds of escape an `avoid` obstacle keeps from others (see the module
/// documentation).
const AVOID_HORIZON: f64 = 2.0;

/// Time constant of a `goal` obstacle's final approach, s: near its goal
/// the desired speed is d / ARRIVE_TIME (a finite gain, so the lagged
/// control of eq 2.23 settles instead of circling the goal).
const ARRIVE_TIME: f64 = 0.5;

/// What a motion model sees of one body at the start of a tick.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Body {
    /// Position.
    pub position: [f64; 2],
    /// Velocity.
    pub velocity: [f64; 2],
    /// Disc radius.
    pub radius: f64,
}

/// What a motion model needs to know besides its parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MotionSetup {
    /// The scenario's seed.
    pub seed: u64,
    /// The obstacle's index among the obstacles (picks its noise stream).
    pub index: usize,
    /// The obstacle's own index among all bodies (robots first).
    pub body: usize,
    /// The body an intentional model pursues or avoids, by index among all
    /// bodies.
    pub target: Option<usize>,
    /// The obstacle's radius.
    pub radius: f64,
    /// The tick, Δt of eqs 2.16-2.23, s.
    pub dt: f64,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Behavior {
    Pursue,
    Avoid,
    Goal,
}

/// The moving state of one scripted obstacle.
#[derive(Debug, Clone)]
pub struct MotionState {
    model: Motion,
    setup: MotionSetup,
    /// Current position.
    pub position: [f64; 2],
    /// Current velocity.
    pub velocity: [f64; 2],
    /// Acceleration held over the current tick (random and intentional).
    pub acceleration: [f64; 2],
    /// Waypoints and route: index of the point being approached.
    next: usize,
    /// Waypoints: done (stays at the last point).
    done: bool,
    /// Intentional: the behavior; goal: the route.
    behavior: Option<Behavior>,
    route: Vec<[f64; 2]>,
    rng: Rng,
}

/// Why a motion model cannot be run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MotionError {
    /// A parameter has a value the model does not know.
    #[error("unknown {what} `{value}`")]
    Unknown {
        /// Which parameter.
        what: &'static str,
        /// Its value.
        value: String,
    },
    /// An intentional model lacks what its behavior needs.
    #[error("behavior `{behavior}` needs {what}")]
    Missing {
        /// The behavior.
        behavior: String,
        /// What is missing.
        what: &'static str,
    },
}

fn norm(v: [f64; 2]) -> f64 {
    v[0].hypot(v[1])
}

fn cap(v: [f64; 2], max: f64) -> [f64; 2] {
    let n = norm(v);
    if n > max && n > 0.0 {
        [v[0] * max / n, v[1] * max / n]
    } else {
        v
    }
}

impl MotionState {
    /// Starts `model` at `start`. Fails for parameters the world cannot run
    /// (the scenario crate's validation refuses them first).
    pub fn new(model: &Motion, start: [f64; 2], setup: MotionSetup) -> Result<Self, MotionError> {
        let mut behavior = None;
        let mut route = Vec::new();
        match model {
            Motion::Random { distribution, .. }
                if distribution != "gaussian" && distribution != "uniform" =>
            {
                return Err(MotionError::Unknown {
                    what: "distribution",
                    value: distribution.clone(),
                });
            }
            Motion::Intentional {
                behavior: b,
                goal,
                points,
                ..
            } => {
                let missing = |what| MotionError::Missing {
                    behavior: b.clone(),
                    what,
                };
                behavior = Some(match b.as_str() {
                    "pursue" if setup.target.is_none() => return Err(missing("a target")),
                    "pursue" => Behavior::Pursue,
                    "avoid" => Behavior::Avoid,
                    "goal" => {
                        route = points.clone();
                        route.extend(goal.iter().copied());
                        if route.is_empty() {
                            return Err(missing("a goal or points"));
                        }
                        Behavior::Goal
                    }
                    other => {
                        return Err(MotionError::Unknown {
                            what: "behavior",
                            value: other.to_string(),
                        });
                    }
                });
            }
            _ => {}
        }
        let velocity = match model {
            Motion::ConstantVelocity { velocity } => *velocity,
            _ => [0.0, 0.0],
        };
        Ok(Self {
            model: model.clone(),
            setup,
            position: start,
            velocity,
            acceleration: [0.0, 0.0],
            next: 0,
            done: false,
            behavior,
            route,
            rng: Rng::stream(setup.seed, "obstacle-motion", setup.index as u64),
        })
    }

    /// True if the obstacle never moves.
    pub fn is_static(&self) -> bool {
        matches!(self.model, Motion::Static)
    }

    /// Chooses the acceleration of the tick that starts now, from `bodies`
    /// (every body at the start of the tick, robots first, this obstacle
    /// included at its own index).
    pub fn begin_tick(&mut self, bodies: &[Body]) {
        let dt = self.setup.dt;
        match &self.model {
            // Eq 2.18 (2.16 with alpha1 = 0, beta1 = 1).
            Motion::Random {
                distribution,
                accel_sigma,
                alpha1,
                beta1,
                ..
            } => {
                let uniform = distribution == "uniform";
                let mut w = [0.0; 2];
                for c in &mut w {
                    *c = if uniform {
                        (2.0 * self.rng.unit() - 1.0) * 3f64.sqrt() * accel_sigma
                    } else {
                        self.rng.gaussian() * accel_sigma
                    };
                }
                let a = self.acceleration;
                self.acceleration = [alpha1 * a[0] + beta1 * w[0], alpha1 * a[1] + beta1 * w[1]];
            }
            // Eq 2.23.
            Motion::Intentional {
                max_speed,
                max_accel,
                alpha2,
                beta2,
                ..
            } => {
                let (max_speed, max_accel, alpha2, beta2) =
                    (*max_speed, *max_accel, *alpha2, *beta2);
                let v_des = self.desired_velocity(bodies, max_speed, max_accel);
                let e = cap(
                    [
                        (v_des[0] - self.velocity[0]) / dt,
                        (v_des[1] - self.velocity[1]) / dt,
                    ],
                    max_accel,
                );
                let a = self.acceleration;
                self.acceleration = cap(
                    [alpha2 * a[0] + beta2 * e[0], alpha2 * a[1] + beta2 * e[1]],
                    max_accel,
                );
            }
            _ => {}
        }
    }

    fn desired_velocity(&mut self, bodies: &[Body], max_speed: f64, max_accel: f64) -> [f64; 2] {
        let p = self.position;
        match self.behavior {
            Some(Behavior::Pursue) => {
                let Some(t) = self.setup.target.and_then(|t| bodies.get(t)) else {
                    return [0.0, 0.0];
                };
                let d = [t.position[0] - p[0], t.position[1] - p[1]];
                let n = norm(d);
                if n < 1e-12 {
                    [0.0, 0.0]
                } else {
                    [d[0] / n * max_speed, d[1] / n * max_speed]
                }
            }
            Some(Behavior::Avoid) => {
                let reach = AVOID_HORIZON * max_speed + max_speed * max_speed / (2.0 * max_accel);
                let mut push = [0.0, 0.0];
                for (j, b) in bodies.iter().enumerate() {
                    if j == self.setup.body || self.setup.target.is_some_and(|t| t != j) {
                        continue;
                    }
                    let d = [p[0] - b.position[0], p[1] - b.position[1]];
                    let n = norm(d);
                    let gap = n - b.radius - self.setup.radius;
                    if gap >= reach {
                        continue;
                    }
                    // Coincident centres: flee along +x (any fixed direction).
                    let u = if n < 1e-12 {
                        [1.0, 0.0]
                    } else {
                        [d[0] / n, d[1] / n]
                    };
                    let w = 1.0 - gap / reach;
                    push[0] += w * u[0];
                    push[1] += w * u[1];
                }
                cap([push[0] * max_speed, push[1] * max_speed], max_speed)
            }
            Some(Behavior::Goal) => {
                let pass = max_speed * self.setup.dt;
                while self.next + 1 < self.route.len() {
                    let q = self.route[self.next];
                    if norm([q[0] - p[0], q[1] - p[1]]) <= pass {
                        self.next += 1;
                    } else {
                        break;
                    }
                }
                let q = self.route[self.next];
                let d = [q[0] - p[0], q[1] - p[1]];
                let n = norm(d);
                if n < 1e-12 {
                    return [0.0, 0.0];
                }
                let last = self.next + 1 == self.route.len();
                let speed = if last {
                    max_speed
                        .min((2.0 * max_accel * n).sqrt())
                        .min(n / ARRIVE_TIME)
                } else {
                    max_speed
                };
                [d[0] / n * speed, d[1] / n * speed]
            }
            None => [0.0, 0.0],
        }
    }

    /// Advances by `h` seconds (one substep).
    pub fn advance(&mut self, h: f64) {
        match &self.model {
            // Static: stays where it started.
            Motion::Static => {}
            // Constant velocity (Zhu & Loh 2.13-2.15): p += v h.
            Motion::ConstantVelocity { velocity } => {
                self.position[0] += velocity[0] * h;
                self.position[1] += velocity[1] * h;
            }
            // Waypoints: straight at `speed` to each point in turn.
            Motion::Waypoints {
                points,
                speed,
                r#loop,
            } => {
                let mut budget = speed * h;
                let start = self.position;
                while budget > 0.0 && !self.done && !points.is_empty() {
                    let target = points[self.next];
                    let d = [target[0] - self.position[0], target[1] - self.position[1]];
                    let dist = d[0].hypot(d[1]);
                    if dist <= budget {
                        self.position = target;
                        budget -= dist;
                        self.next += 1;
                        if self.next == points.len() {
                            if *r#loop {
                                self.next = 0;
                            } else {
                                self.done = true;
                            }
                        }
                        if dist == 0.0 && points.len() == 1 {
                            break;
                        }
                    } else {
                        self.position[0] += d[0] / dist * budget;
                        self.position[1] += d[1] / dist * budget;
                        budget = 0.0;
                    }
                }
                self.velocity = if h > 0.0 {
                    [
                        (self.position[0] - start[0]) / h,
                        (self.position[1] - start[1]) / h,
                    ]
                } else {
                    [0.0, 0.0]
                };
            }
            // Eqs 2.17/2.20 and 2.21-2.22: v += a h (capped), p += v h.
            Motion::Random { max_speed, .. } | Motion::Intentional { max_speed, .. } => {
                let a = self.acceleration;
                self.velocity = cap(
                    [self.velocity[0] + a[0] * h, self.velocity[1] + a[1] * h],
                    *max_speed,
                );
                self.position[0] += self.velocity[0] * h;
                self.position[1] += self.velocity[1] * h;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn setup(body: usize, target: Option<usize>) -> MotionSetup {
        MotionSetup {
            seed: 1,
            index: 0,
            body,
            target,
            radius: 0.2,
            dt: 0.1,
        }
    }

    /// Runs `ticks` ticks of 10 substeps; body 0 is a robot fixed at
    /// `robot`, body 1 the obstacle.
    fn run(m: &mut MotionState, robot: [f64; 2], ticks: usize) {
        for _ in 0..ticks {
            let bodies = [
                Body {
                    position: robot,
                    velocity: [0.0, 0.0],
                    radius: 0.2,
                },
                Body {
                    position: m.position,
                    velocity: m.velocity,
                    radius: 0.2,
                },
            ];
            m.begin_tick(&bodies);
            for _ in 0..10 {
                m.advance(0.01);
            }
        }
    }

    fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
        (a[0] - b[0]).hypot(a[1] - b[1])
    }

    fn random(distribution: &str, alpha1: f64, beta1: f64) -> Motion {
        Motion::Random {
            distribution: distribution.to_string(),
            accel_sigma: 0.7,
            alpha1,
            beta1,
            max_speed: 1e9,
        }
    }

    fn intentional(behavior: &str, target: Option<&str>, goal: Option<[f64; 2]>) -> Motion {
        Motion::Intentional {
            behavior: behavior.to_string(),
            target: target.map(str::to_string),
            goal,
            points: Vec::new(),
            max_speed: 1.0,
            max_accel: 2.0,
            alpha2: 0.5,
            beta2: 0.5,
        }
    }

    #[test]
    fn constant_velocity_keeps_speed() {
        let mut m = MotionState::new(
            &Motion::ConstantVelocity {
                velocity: [1.0, -2.0],
            },
            [0.0, 0.0],
            setup(1, None),
        )
        .unwrap();
        run(&mut m, [5.0, 5.0], 10);
        assert!((m.position[0] - 1.0).abs() < 1e-9 && (m.position[1] + 2.0).abs() < 1e-9);
        assert_eq!(m.velocity, [1.0, -2.0]);
    }

    #[test]
    fn waypoints_turn_corners_and_stop_at_the_end() {
        let model = Motion::Waypoints {
            points: vec![[1.0, 0.0], [1.0, 1.0]],
            speed: 1.0,
            r#loop: false,
        };
        let mut m = MotionState::new(&model, [0.0, 0.0], setup(1, None)).unwrap();
        m.advance(1.5);
        assert!((m.position[0] - 1.0).abs() < 1e-9 && (m.position[1] - 0.5).abs() < 1e-9);
        m.advance(5.0);
        assert_eq!(m.position, [1.0, 1.0]);
        m.advance(1.0);
        assert_eq!(m.velocity, [0.0, 0.0]);
    }

    #[test]
    fn looped_waypoints_go_round_again() {
        let model = Motion::Waypoints {
            points: vec![[1.0, 0.0], [0.0, 0.0]],
            speed: 1.0,
            r#loop: true,
        };
        let mut m = MotionState::new(&model, [0.0, 0.0], setup(1, None)).unwrap();
        m.advance(2.5);
        assert!((m.position[0] - 0.5).abs() < 1e-9, "{:?}", m.position);
        assert!(m.velocity[0] > 0.0);
    }

    /// Sample variance of each component of the acceleration over `n` ticks
    /// after a burn-in, compared with beta² σ² / (1 - alpha²).
    fn check_ar_variance(distribution: &str, alpha1: f64, beta1: f64) {
        let mut m = MotionState::new(
            &random(distribution, alpha1, beta1),
            [0.0, 0.0],
            setup(1, None),
        )
        .unwrap();
        let n = 100_000;
        for _ in 0..200 {
            m.begin_tick(&[]);
        }
        let mut xs = Vec::with_capacity(2 * n);
        for _ in 0..n {
            m.begin_tick(&[]);
            xs.extend(m.acceleration);
        }
        let sigma: f64 = 0.7;
        let expected = beta1 * beta1 * sigma * sigma / (1.0 - alpha1 * alpha1);
        let mean = xs.iter().sum::<f64>() / xs.len() as f64;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (xs.len() - 1) as f64;
        // Standard error of a sample variance of an AR(1) series with
        // coefficient rho: expected * sqrt(2 / N * (1 + rho²) / (1 - rho²))
        // for Gaussian noise (N = 2n samples, the components independent).
        // Uniform noise has a lower kurtosis, so the same bound is looser.
        // Allow 4 standard errors.
        let rho2 = alpha1 * alpha1;
        let se = expected * (2.0 / xs.len() as f64 * (1.0 + rho2) / (1.0 - rho2)).sqrt();
        assert!(
            (var - expected).abs() < 4.0 * se,
            "{distribution} alpha1 {alpha1}: variance {var}, expected {expected} ± {}",
            4.0 * se
        );
    }

    #[test]
    fn ar_noise_has_the_set_variance() {
        check_ar_variance("gaussian", 0.0, 1.0);
        check_ar_variance("gaussian", 0.8, 0.5);
        check_ar_variance("uniform", 0.0, 1.0);
        check_ar_variance("uniform", 0.6, 2.0);
    }

    #[test]
    fn random_motion_respects_its_speed_cap() {
        let model = Motion::Random {
            distribution: "gaussian".to_string(),
            accel_sigma: 5.0,
            alpha1: 0.9,
            beta1: 1.0,
            max_speed: 0.8,
        };
        let mut m = MotionState::new(&model, [0.0, 0.0], setup(1, None)).unwrap();
        let mut fastest: f64 = 0.0;
        for _ in 0..500 {
            run(&mut m, [9.0, 9.0], 1);
            fastest = fastest.max(norm(m.velocity));
        }
        assert!(fastest <= 0.8 + 1e-12 && fastest > 0.7, "{fastest}");
    }

    #[test]
    fn the_same_seed_gives_the_same_random_path_and_another_seed_another() {
        let path = |seed: u64, index: usize| {
            let mut s = setup(1, None);
            s.seed = seed;
            s.index = index;
            let mut m = MotionState::new(&random("gaussian", 0.5, 1.0), [0.0, 0.0], s).unwrap();
            run(&mut m, [9.0, 9.0], 50);
            m.position
        };
        assert_eq!(path(3, 0), path(3, 0));
        assert_ne!(path(3, 0), path(4, 0));
        assert_ne!(path(3, 0), path(3, 1));
    }

    #[test]
    fn pursuit_closes_the_distance_to_its_target() {
        let mut m = MotionState::new(
            &intentional("pursue", Some("r0"), None),
            [4.0, 3.0],
            setup(1, Some(0)),
        )
        .unwrap();
        let before = dist(m.position, [0.0, 0.0]);
        run(&mut m, [0.0, 0.0], 20);
        let after = dist(m.position, [0.0, 0.0]);
        // 2 s at up to 1 m/s with a 2 m/s² limit: at least 1 m closer.
        assert!(after < before - 1.0, "{before} -> {after}");
        assert!(norm(m.velocity) <= 1.0 + 1e-12);
    }

    #[test]
    fn avoidance_increases_the_distance_and_then_settles() {
        let mut m = MotionState::new(
            &intentional("avoid", None, None),
            [0.8, 0.0],
            setup(1, None),
        )
        .unwrap();
        let before = dist(m.position, [0.0, 0.0]);
        run(&mut m, [0.0, 0.0], 30);
        let after = dist(m.position, [0.0, 0.0]);
        assert!(after > before + 1.0, "{before} -> {after}");
        // Moved away along +x, the direction away from the robot.
        assert!(m.position[0] > 1.8 && m.position[1].abs() < 1e-9);
        // The push fades as the gap nears the escape distance, so it comes
        // to rest (here: under 5 % of max_speed within 10 s more).
        run(&mut m, [0.0, 0.0], 100);
        assert!(norm(m.velocity) < 0.05, "{:?}", m.velocity);
    }

    #[test]
    fn a_goal_route_reaches_the_goal_and_stops_there() {
        let model = Motion::Intentional {
            behavior: "goal".to_string(),
            target: None,
            goal: Some([3.0, 0.0]),
            points: vec![[1.5, 1.5]],
            max_speed: 1.0,
            max_accel: 2.0,
            alpha2: 0.5,
            beta2: 0.5,
        };
        let mut m = MotionState::new(&model, [0.0, 0.0], setup(1, None)).unwrap();
        let mut highest: f64 = 0.0;
        // A robot in the way does not matter to a fixed route.
        for _ in 0..100 {
            run(&mut m, [1.0, 1.0], 1);
            highest = highest.max(m.position[1]);
        }
        assert!(highest > 1.3, "went via the route point: {highest}");
        assert!(dist(m.position, [3.0, 0.0]) < 0.05, "{:?}", m.position);
        assert!(norm(m.velocity) < 0.05);
    }

    #[test]
    fn a_pursuit_without_a_target_or_an_unknown_distribution_is_refused() {
        assert!(
            MotionState::new(&intentional("pursue", None, None), [0.0; 2], setup(1, None)).is_err()
        );
        assert!(MotionState::new(&random("cauchy", 0.0, 1.0), [0.0; 2], setup(1, None)).is_err());
    }
}
