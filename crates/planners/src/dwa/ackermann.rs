//! [`crate::dwa`] on a car (`kinematics = "ackermann"`): Fox, Burgard &
//! Thrun's search (1997, section 3) over the car's own controls, (speed,
//! steering), the way car-like local planners do it (teb_local_planner's
//! car-like mode and nav2's MPPI Ackermann model sample the speed and the
//! turn of the bicycle within its minimum radius; nav2's DWB rolls out
//! each sample over a horizon and scores its trajectory), with the car's
//! true footprint (module documentation of `dwa`, "On a car").
//!
//! 1. **Dynamic window**: speeds within max_accel dt of the present speed,
//!    in [-max_reverse_speed, max_speed]; steering angles within
//!    max_steering_rate dt of the present steering, within +-max_steering;
//!    `samples` of each.
//! 2. **Trajectories**: each sample held over `horizon` through the
//!    bicycle model the world drives the car with
//!    ([`crate::ackermann::bicycle_step`], four substeps a tick), the
//!    paper's curvature being the car's arc.
//! 3. **Admissible**: the car driving the sample for a tick and then
//!    braking as hard as it can (its steering held) comes to rest with its
//!    footprint clear of every wall and of every other body, each other
//!    robot going on for a tick and braking too, a scripted obstacle going
//!    on, and each also standing where it is (the paper's V_a, in the
//!    passive-friendly form of `dwa`'s "Both could stop").
//! 4. **Objective** G = w_heading heading + w_clearance clearance +
//!    w_speed speed: heading 1 - |angle to the goal from the pose a second
//!    on| / pi (the paper's is after a tick, which for a car's samples
//!    differs too little to rank them; nav2's DWB scores its trajectories
//!    along their length); clearance min(t_c, horizon) / horizon, t_c the first
//!    contact of the held trajectory with the walls and the others
//!    (moving at their velocities, and standing); speed 1 - |v - v_goal| /
//!    max_speed with v_goal = min(max_speed, sqrt(2 a d_goal), d_goal / dt,
//!    sqrt(a L / |tan delta|)): a braking profile to the goal and, for the
//!    sample's steering, the speed at which its lateral acceleration is at
//!    most max_accel (a car slows for a tight turn). Reverse samples are
//!    scored only when no forward one is admissible.
//! 5. **Recovery** (a differential drive turns in place; a car backs and
//!    turns): a car that has stood still for 3 s away from its goal, or
//!    finds no admissible forward sample while standing, backs for up to
//!    3 s at half its top speed (at most `max_reverse_speed`) with full
//!    steering away from the side its goal is on, so that its nose swings
//!    towards the goal (nose right when the goal is dead ahead), while that
//!    stays admissible. A car that may not reverse waits instead.
//!
//! Within `goal_tolerance` of the goal the slowest admissible sample is
//! taken (the car stops); when none is admissible the car brakes.

use super::footprint::{Footprint, Motion, Rollout};
use super::planner::Dwa;
use super::unicycle::{rightmost_best, wrap};
use crate::ackermann::{Car, CarState, bicycle_step};
use crate::{Command, Observation};
use std::f64::consts::PI;

/// Substeps per tick of the trajectories.
const SUBSTEPS: f64 = 4.0;
/// Seconds standing still away from the goal before the car backs.
const STILL_FOR: f64 = 3.0;
/// Seconds a back-off lasts at most.
const BACK_OFF_FOR: f64 = 3.0;
/// Seconds along a trajectory at which its heading is scored.
const LOOK_AHEAD: f64 = 1.0;
/// Scores closer than this (relative to the objective's range) are a tie.
const TIE: f64 = 1e-6;

/// The car's states driving (speed, steering) from `s`, every `h`: held
/// for `hold` s, then (when `brake`) the speed asked 0 until at rest;
/// without, held up to `horizon`.
fn trajectory(
    car: &Car,
    s: CarState,
    speed: f64,
    steering: f64,
    h: f64,
    hold: f64,
    brake: bool,
) -> Vec<(crate::Vec2, f64)> {
    let mut x = s;
    let mut out = vec![(x.position, x.heading)];
    let held = (hold / h).round() as usize;
    let stop = (speed.abs().max(s.speed.abs()) / car.max_accel.max(1e-9) / h).ceil() as usize;
    let steps = if brake { held + stop + 2 } else { held };
    for i in 0..steps.min(100_000) {
        let ask = if brake && i >= held { 0.0 } else { speed };
        x = bicycle_step(car, x, ask, steering, 0.0, h);
        out.push((x.position, x.heading));
        if brake && i >= held && x.speed == 0.0 {
            break;
        }
    }
    out
}

/// One control step of dwa on a car.
pub(super) fn plan(dwa: &mut Dwa, obs: &Observation, car: Car) -> Command {
    let me = &obs.me;
    let dt = if obs.dt > 0.0 { obs.dt } else { 0.1 };
    let h = dt / SUBSTEPS;
    let s = CarState::of(me);
    let a = car.max_accel;
    let to_goal = obs.goal - me.position;
    let d_goal = to_goal.norm();
    let at_goal = d_goal <= obs.goal_tolerance;
    let alpha = wrap(to_goal.y.atan2(to_goal.x) - me.heading);
    let pad = dwa.padding.unwrap_or(me.shape.inradius() / 4.0);
    let top = car.max_speed.max(car.max_reverse_speed);
    let horizon = dwa.horizon.max(top / a.max(1e-9) + dt);
    let reach = top * horizon + me.radius + pad;
    dwa.walls.prepare(obs.walls, 2.0 * (me.radius + pad));
    let any_walls = !dwa.walls.near(obs.walls, me.position, reach).is_empty();
    let pose = (me.position, me.heading);
    let mut foot = Footprint::new(
        me.shape,
        pose,
        pad,
        obs.walls,
        &mut dwa.walls,
        any_walls,
        obs.others,
    );
    let braking = [Motion::Braking { delay: dt, a }, Motion::Still];
    let moving = [Motion::Constant, Motion::Still];
    let admissible = |foot: &mut Footprint, v: f64, delta: f64| {
        let r = Rollout::new(h, trajectory(&car, s, v, delta, h, dt, true), me.radius);
        foot.contact(&r, &braking, true).is_infinite()
    };

    // Recovery: go on backing, while that stays admissible.
    let rec = &mut dwa.recovery;
    if let Some((until, v, delta)) = rec.backing {
        if !at_goal && obs.time < until && admissible(&mut foot, v, delta) {
            return Command::Ackermann {
                speed: v,
                steering: delta,
            };
        }
        rec.backing = None;
        rec.still_since = f64::NAN;
    }
    let still = s.speed.abs() < 0.05 * car.max_speed;
    if at_goal || !still {
        rec.still_since = f64::NAN;
    } else if rec.still_since.is_nan() {
        rec.still_since = obs.time;
    }
    // Backing: full steering away from the goal's side (the nose swings
    // towards it), nose right when it is dead ahead; straight, or the
    // other way, if that is not admissible.
    let back = -(0.5 * car.max_speed).min(car.max_reverse_speed);
    let start_backing = |foot: &mut Footprint, rec: &mut super::planner::Recovery| {
        if back >= 0.0 {
            return None;
        }
        let side = if alpha.abs() < 10f64.to_radians() {
            1.0
        } else {
            -alpha.signum()
        };
        for delta in [side * car.max_steering, 0.0, -side * car.max_steering] {
            if admissible(foot, back, delta) {
                rec.backing = Some((obs.time + BACK_OFF_FOR, back, delta));
                rec.still_since = f64::NAN;
                return Some(Command::Ackermann {
                    speed: back,
                    steering: delta,
                });
            }
        }
        None
    };
    if !at_goal
        && obs.time - rec.still_since >= STILL_FOR
        && let Some(cmd) = start_backing(&mut foot, rec)
    {
        return cmd;
    }

    // The window.
    let (v_lo, v_hi) = (
        (s.speed - a * dt).max(-car.max_reverse_speed),
        (s.speed + a * dt).min(car.max_speed),
    );
    let turn = car.max_steering_rate * dt;
    let (d_lo, d_hi) = (
        (s.steering - turn).max(-car.max_steering),
        (s.steering + turn).min(car.max_steering),
    );
    let v_goal = car
        .max_speed
        .min((2.0 * a * d_goal).sqrt())
        .min(d_goal / dt);
    let n = dwa.samples;
    let at = |k: usize, lo: f64, hi: f64| lo + (hi - lo) * k as f64 / (n - 1) as f64;
    // The heading is scored at the pose a second on (a tick's turn is
    // too small a difference between a car's samples to rank them).
    let look = (LOOK_AHEAD.max(dt) / h).round() as usize;
    let mut forward: Vec<(f64, f64, f64)> = Vec::with_capacity(n * n);
    let mut reverse: Vec<(f64, f64, f64)> = Vec::new();
    for i in 0..n {
        for j in 0..n {
            let (v, delta) = (at(i, v_lo, v_hi.max(v_lo)), at(j, d_lo, d_hi.max(d_lo)));
            if !admissible(&mut foot, v, delta) {
                continue;
            }
            let score = if at_goal {
                -v.abs()
            } else {
                let held = Rollout::new(
                    h,
                    trajectory(&car, s, v, delta, h, horizon, false),
                    me.radius,
                );
                let t_c = foot.contact(&held, &moving, true);
                let (p, th) = held.poses[look.min(held.poses.len() - 1)];
                let ahead = obs.goal - p;
                let heading = if ahead.norm() <= f64::EPSILON {
                    1.0
                } else {
                    1.0 - wrap(ahead.y.atan2(ahead.x) - th).abs() / PI
                };
                let clearance = t_c.min(horizon) / horizon;
                let lateral = if delta.tan().abs() > 1e-9 {
                    (a * car.wheelbase / delta.tan().abs()).sqrt()
                } else {
                    f64::INFINITY
                };
                let speed = 1.0 - (v - v_goal.min(lateral)).abs() / car.max_speed;
                dwa.w_heading * heading + dwa.w_clearance * clearance + dwa.w_speed * speed
            };
            if v > 0.0 || at_goal {
                forward.push((score, v, delta));
            } else {
                reverse.push((score, v, delta));
            }
        }
    }
    let scale = if at_goal {
        car.max_speed
    } else {
        dwa.w_heading + dwa.w_clearance + dwa.w_speed
    };
    let tie = TIE * scale.max(f64::MIN_POSITIVE);
    let rec = &mut dwa.recovery;
    if let Some((_, v, delta)) = rightmost_best(&forward, tie) {
        return Command::Ackermann {
            speed: v,
            steering: delta,
        };
    }
    // No forward sample is admissible: standing, back and turn.
    if !at_goal
        && still
        && let Some(cmd) = start_backing(&mut foot, rec)
    {
        return cmd;
    }
    if let Some((_, v, delta)) = rightmost_best(&reverse, tie) {
        return Command::Ackermann {
            speed: v,
            steering: delta,
        };
    }
    // Nothing admissible: brake, the wheels where they are.
    Command::Ackermann {
        speed: 0.0,
        steering: s.steering,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testkit::{CarLimits, RobotModel, observation, robot};
    use crate::{Planner, Polygon, Segment, SelfState, Sensed, Shape, Vec2};

    const LIMITS: CarLimits = CarLimits {
        wheelbase: 2.8,
        max_steering: 0.6108652381980153, // 35 degrees
        max_steering_rate: 1.0471975511965976,
        max_reverse_speed: 2.0,
    };
    const MODEL: RobotModel = RobotModel {
        radius: 2.4,
        mass: 1.0,
        damping: 0.0,
        max_speed: 8.0,
        max_accel: 2.5,
    };

    fn car_state(position: Vec2, heading: f64, speed: f64) -> SelfState {
        let body = Shape::Polygon(Polygon::rectangle(4.6, 1.6).unwrap());
        let mut s = MODEL.car(LIMITS, position, heading, speed, 0.0);
        s.shape = body;
        s.radius = body.circumradius();
        s
    }

    fn command(dwa: &mut Dwa, obs: &Observation) -> (f64, f64) {
        match dwa.plan(obs) {
            Command::Ackermann { speed, steering } => (speed, steering),
            c => panic!("dwa answers a car in (speed, steering), not {c:?}"),
        }
    }

    /// Drives the car with dwa towards `goal` among `walls` and `others`
    /// (standing) through the bicycle model, for `ticks`; returns the
    /// states it went through.
    fn drive(
        start: SelfState,
        goal: Vec2,
        walls: &[Segment],
        others: &[Sensed],
        ticks: usize,
    ) -> Vec<SelfState> {
        let car = Car::of(&start).unwrap();
        let mut dwa = Dwa::default();
        let mut me = start;
        let mut out = vec![me];
        for k in 0..ticks {
            let mut obs = observation(me, goal, others);
            obs.walls = walls;
            obs.time = k as f64 * 0.1;
            obs.goal_tolerance = 1.0;
            let (v, delta) = command(&mut dwa, &obs);
            let mut x = CarState::of(&me);
            for _ in 0..10 {
                x = bicycle_step(&car, x, v, delta, 0.0, 0.01);
            }
            let omega = x.speed * x.steering.tan() / car.wheelbase;
            let (sn, cs) = x.heading.sin_cos();
            me.position = x.position;
            me.heading = x.heading;
            me.steering = x.steering;
            me.angular_velocity = omega;
            me.velocity =
                Vec2::new(cs, sn) * x.speed + Vec2::new(-sn, cs) * (car.wheelbase / 2.0 * omega);
            out.push(me);
        }
        out
    }

    #[test]
    fn a_car_commands_speed_and_steering_within_its_window() {
        let me = car_state(Vec2::zeros(), 0.0, 4.0);
        let obs = observation(me, Vec2::new(0.0, 30.0), &[]);
        let (v, delta) = command(&mut Dwa::default(), &obs);
        // The goal is a right angle to the left: steer left as far as a
        // tick allows (60 deg/s: 6 degrees), speed within 0.25 of 4.
        assert!((v - 4.0).abs() <= 0.25 + 1e-9, "{v}");
        assert!(delta > 0.0 && delta <= 0.1047197551196598 + 1e-9, "{delta}");
    }

    #[test]
    fn a_car_brakes_for_a_wall_across_its_road_and_stops_clear_of_it() {
        // At 6 m/s, a wall 12 m ahead of its nose: 7.2 m to stop after
        // 0.6 m of a held tick. Driving on, it stops short of the wall.
        let wall = [Segment {
            a: Vec2::new(14.3, -10.0),
            b: Vec2::new(14.3, 10.0),
        }];
        let states = drive(
            car_state(Vec2::zeros(), 0.0, 6.0),
            Vec2::new(40.0, 0.0),
            &wall,
            &[],
            150,
        );
        let car = Shape::Polygon(Polygon::rectangle(4.6, 1.6).unwrap());
        for s in &states {
            let g = mrsim_shape::gap_to_segment(
                &car,
                mrsim_shape::Pose::new([s.position.x, s.position.y], s.heading),
                [[14.3, -10.0], [14.3, 10.0]],
            );
            assert!(g > 0.0, "touched the wall at {:?}", s.position);
        }
    }

    #[test]
    fn a_car_nosed_up_to_a_wall_backs_and_turns_towards_its_goal() {
        // Standing 0.15 m from a wall straight ahead (within its padding
        // of 0.2), the goal beyond it to the left: no forward sample is
        // admissible, so it backs with its wheels turned right (its nose
        // swings left, towards the goal).
        let wall = [Segment {
            a: Vec2::new(2.45, -10.0),
            b: Vec2::new(2.45, 10.0),
        }];
        let me = car_state(Vec2::zeros(), 0.0, 0.0);
        let mut obs = observation(me, Vec2::new(10.0, 20.0), &[]);
        obs.walls = &wall;
        let (v, delta) = command(&mut Dwa::default(), &obs);
        assert!(v < 0.0 && delta < 0.0, "{v} {delta}");
    }

    #[test]
    fn a_car_waits_for_another_crossing_its_way() {
        // Another car crossing 9 m ahead at 5 m/s: going on for a tick and
        // braking, it stops across the road (y from -2.8 to 1.8, its near
        // side at x = 8.2), where this car, going on at 6 m/s for a tick and
        // braking, would put its nose (0.6 + 7.2 + 2.3 = 10.1): it slows.
        let me = car_state(Vec2::zeros(), 0.0, 6.0);
        let other = [
            robot(1, Vec2::new(9.0, -6.0), Vec2::new(0.0, 5.0), 2.4).shaped(
                Shape::Polygon(Polygon::rectangle(4.6, 1.6).unwrap()),
                PI / 2.0,
            ),
        ];
        let obs = observation(me, Vec2::new(60.0, 0.0), &other);
        let (v, _) = command(&mut Dwa::default(), &obs);
        assert!(v < 6.0, "{v}");
    }
}
