//! The bicycle model and the tracking controller, against geometry and
//! against the controller's own bound.

use super::*;
use crate::testkit::{CarLimits, RobotModel, observation};
use std::f64::consts::{FRAC_PI_2, FRAC_PI_3, FRAC_PI_6};

/// ir-sim's car: wheelbase 3, steering to 30 degrees at 60 degrees/s, 4 m/s
/// and 2 m/s² forwards, no reverse.
const LIMITS: CarLimits = CarLimits {
    wheelbase: 3.0,
    max_steering: FRAC_PI_6,
    max_steering_rate: FRAC_PI_3,
    max_reverse_speed: 0.0,
};

const MODEL: RobotModel = RobotModel {
    radius: 2.43,
    mass: 1.0,
    damping: 0.0,
    max_speed: 4.0,
    max_accel: 2.0,
};

fn car(reverse: f64) -> Car {
    Car {
        wheelbase: LIMITS.wheelbase,
        max_steering: LIMITS.max_steering,
        max_steering_rate: LIMITS.max_steering_rate,
        max_reverse_speed: reverse,
        max_speed: MODEL.max_speed,
        max_accel: MODEL.max_accel,
    }
}

fn at(heading: f64, speed: f64, steering: f64) -> CarState {
    CarState {
        position: Vec2::new(1.0, 2.0),
        heading,
        speed,
        steering,
    }
}

#[test]
fn at_full_lock_the_rear_axle_drives_the_minimum_circle_and_the_centre_a_wider_one() {
    // Already at full lock and speed: every substep keeps the rear axle
    // at R = L / tan(30 deg) = 5.196 from the turn's centre, which is R to
    // the left of the rear axle's start; the body's centre stays at
    // sqrt(R^2 + (L/2)^2) from it.
    let c = car(0.0);
    let r = c.min_turning_radius();
    assert!((r - 3.0 / FRAC_PI_6.tan()).abs() < 1e-12);
    let mut s = at(0.3, 2.0, c.max_steering);
    let pivot = s.rear_axle(c.wheelbase) + Vec2::new(-(0.3f64.sin()), 0.3f64.cos()) * r;
    let centre_r = (r * r + 2.25f64).sqrt();
    // A full turn and a bit: 2 pi R / (2 m/s) = 16.3 s.
    for _ in 0..1700 {
        s = bicycle_step(&c, s, 2.0, c.max_steering, 0.0, 0.01);
        let rear = s.rear_axle(c.wheelbase);
        assert!(
            ((rear - pivot).norm() - r).abs() < 1e-9,
            "{}",
            (rear - pivot).norm()
        );
        assert!(((s.position - pivot).norm() - centre_r).abs() < 1e-9);
    }
    assert!(s.heading > 0.3 + 2.0 * PI, "{}", s.heading);
}

#[test]
fn the_bicycle_holds_every_limit_whatever_it_is_asked() {
    let c = car(0.0);
    let h = 0.01;
    // From rest asked for everything: the steering moves 60 deg/s, the
    // speed 2 m/s², each to its limit and no further.
    let mut s = at(0.0, 0.0, 0.0);
    s = bicycle_step(&c, s, 1e9, 1e9, 0.0, h);
    assert!((s.steering - c.max_steering_rate * h).abs() < 1e-15);
    assert!((s.speed - c.max_accel * h).abs() < 1e-15);
    for _ in 0..1000 {
        s = bicycle_step(&c, s, f64::INFINITY, f64::INFINITY, 0.0, h);
    }
    assert_eq!((s.speed, s.steering), (c.max_speed, c.max_steering));
    // Backwards without reverse: down to 0 and not below; NaN steering
    // keeps the wheels, a NaN speed asks 0.
    for _ in 0..1000 {
        s = bicycle_step(&c, s, -1e9, f64::NAN, 0.0, h);
    }
    assert_eq!((s.speed, s.steering), (0.0, c.max_steering));
    s = bicycle_step(&c, at(0.0, 1.0, 0.2), f64::NAN, -1e9, 0.0, h);
    assert!((s.speed - (1.0 - c.max_accel * h)).abs() < 1e-15);
    assert!((s.steering - (0.2 - c.max_steering_rate * h)).abs() < 1e-15);
    // With reverse 1 m/s: to -1 and not beyond.
    let c = car(1.0);
    let mut s = at(0.0, 0.0, 0.0);
    for _ in 0..1000 {
        s = bicycle_step(&c, s, -1e9, 0.0, 0.0, h);
    }
    assert_eq!(s.speed, -1.0);
}

#[test]
fn a_velocity_lag_slows_the_speed_as_for_the_other_drives() {
    // T = 0.5 s: one substep of 0.01 s from rest towards 1 m/s moves 0.02.
    let c = car(0.0);
    let s = bicycle_step(&c, at(0.0, 0.0, 0.0), 1.0, 0.0, 0.5, 0.01);
    assert!((s.speed - 0.02).abs() < 1e-15);
}

#[test]
fn the_law_turns_towards_the_asked_side_and_reverses_only_when_it_may() {
    let s = at(0.0, 0.0, 0.0);
    let fwd = car(0.0);
    let (v, d) = steer(&fwd, &s, Vec2::new(1.0, 1.0), 1.0, 0.1);
    assert!(v > 0.0 && d > 0.0, "{v} {d}");
    let (v, d) = steer(&fwd, &s, Vec2::new(1.0, -1.0), 1.0, 0.1);
    assert!(v > 0.0 && d < 0.0, "{v} {d}");
    // Aligned: straight.
    assert_eq!(steer(&fwd, &s, Vec2::new(2.0, 0.0), 1.0, 0.1), (1.0, 0.0));
    // Behind and a little to the left, no reverse: forwards at full lock
    // left, turning round.
    let (v, d) = steer(&fwd, &s, Vec2::new(-1.0, 0.1), 0.5, 0.1);
    assert!(v > 0.0 && d == fwd.max_steering, "{v} {d}");
    // With reverse: backwards, the heading turned clockwise so that the
    // rear swings left towards u (theta' = v tan(delta) / L < 0).
    let rev = car(1.0);
    let (v, d) = steer(&rev, &s, Vec2::new(-1.0, 0.1), 0.5, 0.1);
    assert!(v < 0.0 && v * d.tan() < 0.0, "{v} {d}");
    // Nothing asked: stop, the wheels where they are.
    assert_eq!(
        steer(&fwd, &at(0.0, 1.0, 0.3), Vec2::zeros(), 1.0, 0.1),
        (0.0, 0.3)
    );
}

/// The largest distance over `horizon` between a disc under the velocity
/// speed u / |u| (within `max_accel`, from the car's centre and velocity)
/// and the car driven by the law at `speed`, with the world's 10 substeps
/// a tick rather than the prediction's 4.
fn error_at_world_rate(c: &Car, s: CarState, u: Vec2, speed: f64, horizon: f64) -> f64 {
    let (dt, sub) = (0.1, 10);
    let h = dt / sub as f64;
    let target = u * (speed / u.norm());
    let (mut p, mut w) = (s.position, centre_velocity(&s));
    let (mut x, mut worst) = (s, 0.0f64);
    for _ in 0..(horizon / dt).round() as usize {
        let (v, d) = steer(c, &x, u, speed, dt);
        for _ in 0..sub {
            x = bicycle_step(c, x, v, d, 0.0, h);
            w += (target - w).cap_magnitude(c.max_accel * h);
            p += w * h;
            worst = worst.max((x.position - p).norm());
        }
    }
    worst
}

#[test]
fn every_speed_it_chooses_is_tracked_within_the_bound() {
    let eps = 0.3;
    for reverse in [0.0, 1.5] {
        let c = car(reverse);
        for k in 0..24 {
            let a = k as f64 * PI / 12.0;
            for &(n, v0, d0) in &[(4.0, 0.0, 0.0), (1.0, 0.0, 0.5), (4.0, 2.0, -0.5)] {
                let s = at(0.0, v0, d0);
                let u = Vec2::new(a.cos(), a.sin()) * n;
                let speed = trackable_speed(&c, s, u, 0.1, eps, 1.0);
                assert!((0.0..=n).contains(&speed), "{speed}");
                if speed > 0.0 {
                    let e = tracking_error(&c, s, u, speed, 0.1, 1.0);
                    assert!(e <= eps, "angle {a}: {e}");
                    // The prediction's 4 substeps against the world's 10.
                    let fine = error_at_world_rate(&c, s, u, speed, 1.0);
                    assert!(fine <= 1.02 * eps, "angle {a}, {n} from {v0}: {fine}");
                }
            }
        }
    }
}

#[test]
fn a_car_drives_as_fast_as_asked_ahead_and_creeps_while_it_turns() {
    let (c, eps) = (car(0.0), 0.3);
    let s = at(0.0, 0.0, 0.0);
    let speed_at = |deg: f64| {
        let a = deg.to_radians();
        trackable_speed(&c, s, Vec2::new(a.cos(), a.sin()) * 4.0, 0.1, eps, 1.0)
    };
    // Straight ahead from rest the car speeds up as a holonomic robot
    // would (the reference has the same max_accel): all of the 4 m/s; off
    // its heading it is given less, and sideways it creeps (about eps /
    // (sqrt 2 s)).
    let ahead = speed_at(0.0);
    assert_eq!(ahead, 4.0);
    let mut last = ahead;
    for deg in [15.0, 30.0, 60.0, 90.0, 135.0, 180.0] {
        let v = speed_at(deg);
        assert!(v > 0.0 && v <= last + 1e-9, "{deg}: {v} after {last}");
        last = v;
    }
    let side = speed_at(90.0);
    assert!(side < eps && side > eps / 4.0, "{side}");
    // Already at 4 m/s and aligned: all of it.
    let fast = at(0.0, 4.0, 0.0);
    let v = trackable_speed(&c, fast, Vec2::new(4.0, 0.0), 0.1, eps, 1.0);
    assert_eq!(v, 4.0);
}

#[test]
fn a_unicycle_command_becomes_the_steering_of_the_same_turn_rate() {
    // v = 2, omega = 0.5 on L = 3: tan(delta) = 0.75.
    let d = steering_for_turn_rate(2.0, 0.5, 3.0, 0.1);
    assert!((d.tan() - 0.75).abs() < 1e-12);
    assert!((2.0 * d.tan() / 3.0 - 0.5).abs() < 1e-12);
    // Backwards the steering turns the other way for the same omega.
    assert!(steering_for_turn_rate(-2.0, 0.5, 3.0, 0.1) < 0.0);
    // At rest no steering turns the car: the current one is kept.
    assert_eq!(steering_for_turn_rate(0.0, 0.5, 3.0, 0.1), 0.1);
}

/// Records the radius and tolerance it was shown; answers `answer`.
struct Probe {
    answer: Command,
    native: bool,
    seen: std::sync::Arc<std::sync::Mutex<Option<(f64, f64)>>>,
}

impl Planner for Probe {
    fn plan(&mut self, obs: &Observation) -> Command {
        *self.seen.lock().expect("probe") = Some((obs.me.radius, obs.goal_tolerance));
        self.answer
    }
    fn native_ackermann(&self) -> bool {
        self.native
    }
}

fn probe(answer: Command, native: bool) -> (Tracker, impl Fn() -> (f64, f64)) {
    let seen = std::sync::Arc::new(std::sync::Mutex::new(None));
    let p = Probe {
        answer,
        native,
        seen: seen.clone(),
    };
    let read = move || seen.lock().expect("probe").expect("planned");
    (Tracker::new(Box::new(p)), read)
}

fn car_me(heading: f64, speed: f64, steering: f64) -> SelfState {
    MODEL.car(LIMITS, Vec2::new(1.0, 2.0), heading, speed, steering)
}

#[test]
fn a_holonomic_planner_sees_the_car_enlarged_by_the_bound_and_its_velocity_is_tracked() {
    let (mut t, seen) = probe(Command::Velocity(Vec2::new(0.0, 1.0)), false);
    let mut obs = observation(car_me(0.0, 0.0, 0.0), Vec2::zeros(), &[]);
    obs.goal_tolerance = 0.5;
    let cmd = t.plan(&obs);
    let (radius, tol) = seen();
    // epsilon = L / 10 = 0.3.
    assert!((radius - (2.43 + 0.3)).abs() < 1e-12, "{radius}");
    assert_eq!(tol, 0.5);
    // Asked to go left from rest: forwards slowly at full lock left.
    let Command::Ackermann { speed, steering } = cmd else {
        panic!("a car's command, got {cmd:?}");
    };
    assert!(speed > 0.0 && speed < 0.3, "{speed}");
    assert_eq!(steering, FRAC_PI_6);
}

#[test]
fn a_force_is_tracked_as_the_velocity_it_gives_in_one_tick() {
    // At rest heading +x, 10 N on 1 kg clamped to 2 m/s²: u = 0.2 m/s
    // ahead, well within the bound: the car is asked 0.2 m/s, straight.
    let (mut t, _) = probe(Command::Force(Vec2::new(10.0, 0.0)), false);
    let obs = observation(car_me(0.0, 0.0, 0.0), Vec2::zeros(), &[]);
    let cmd = t.plan(&obs);
    assert_eq!(
        cmd,
        Command::Ackermann {
            speed: 0.2,
            steering: 0.0
        },
        "{cmd:?}"
    );
}

#[test]
fn a_car_command_and_a_native_planner_pass_unchanged() {
    let own = Command::Ackermann {
        speed: -0.4,
        steering: 0.2,
    };
    let (mut t, seen) = probe(own, false);
    let obs = observation(car_me(0.5, 1.0, 0.1), Vec2::zeros(), &[]);
    assert_eq!(t.plan(&obs), own);
    assert!((seen().0 - 2.73).abs() < 1e-12);
    // A planner of cars sees the car itself, and any command it gives
    // passes.
    let (mut t, seen) = probe(Command::Velocity(Vec2::new(0.3, 0.0)), true);
    assert_eq!(t.plan(&obs), Command::Velocity(Vec2::new(0.3, 0.0)));
    assert_eq!(seen().0, 2.43);
    // A unicycle command becomes the car's of the same turn rate.
    let (mut t, _) = probe(Command::Unicycle { v: 2.0, omega: 0.5 }, false);
    let Command::Ackermann { speed, steering } = t.plan(&obs) else {
        panic!("a car's command");
    };
    assert_eq!(speed, 2.0);
    assert!((steering.tan() - 0.75).abs() < 1e-12);
}

#[test]
fn a_holonomic_robot_gets_the_planner_command_unconverted() {
    let (mut t, seen) = probe(Command::Velocity(Vec2::new(0.5, 0.1)), false);
    let obs = observation(MODEL.at(Vec2::zeros(), Vec2::zeros()), Vec2::zeros(), &[]);
    assert_eq!(t.plan(&obs), Command::Velocity(Vec2::new(0.5, 0.1)));
    assert_eq!(seen().0, 2.43);
}

#[test]
fn orca_drives_a_car_to_a_goal_it_must_turn_to() {
    // The car at (1, 2) facing +x, its goal 20 m to its left: orca's
    // velocity towards it (2 m/s), tracked, turns the car a quarter round
    // and brings its centre within 0.5 m. The car moves by the bicycle
    // with the world's 10 substeps.
    let goal = Vec2::new(1.0, 22.0);
    let mut params = crate::Params::new();
    params.insert("pref_speed".into(), crate::ParamValue::Number(2.0));
    let orca = crate::build("orca", &params).expect("orca");
    let mut t = Tracker::new(orca);
    let c = car(0.0);
    let mut me = car_me(0.0, 0.0, 0.0);
    let mut cmd = Command::Ackermann {
        speed: 0.0,
        steering: 0.0,
    };
    let mut arrived = None;
    for tick in 0..1200 {
        let mut obs = observation(me, goal, &[]);
        obs.goal_tolerance = 0.5;
        cmd = t.plan(&obs);
        let Command::Ackermann { speed, steering } = cmd else {
            panic!("a car's command, got {cmd:?}");
        };
        let mut s = CarState::of(&me);
        for _ in 0..10 {
            s = bicycle_step(&c, s, speed, steering, 0.0, 0.01);
        }
        me = MODEL.car(LIMITS, s.position, s.heading, s.speed, s.steering);
        if (me.position - goal).norm() <= 0.5 {
            arrived = Some(tick);
            break;
        }
    }
    let Some(tick) = arrived else {
        panic!("not arrived: at {} with {cmd:?}", me.position);
    };
    // It had to turn a quarter: no straight 20 m at 4 m/s (50 ticks).
    assert!(tick > 50, "{tick}");
    assert!(me.heading > FRAC_PI_2 - 1.0, "{}", me.heading);
}
