//! Dynamic window approach: D. Fox, W. Burgard & S. Thrun, "The Dynamic
//! Window Approach to Collision Avoidance", IEEE Robotics & Automation
//! Magazine 4(1), 1997, pp. 23-33, written for a holonomic disc.
//!
//! The paper searches (v, omega) of a synchro-drive; a holonomic disc
//! commands a velocity vector, so the search space here is the velocity
//! plane and the "curvature" of each candidate is a straight line.
//!
//! 1. **Dynamic window** V_d (paper section 3.1, "dynamic window"): the
//!    velocities reachable within one control period, |v - v_c| <=
//!    max_accel * dt around the current velocity v_c, intersected with the
//!    speed limit V_s (|v| <= max_speed). It is sampled on a `samples` x
//!    `samples` grid over its bounding box (the current velocity is always
//!    a candidate).
//! 2. **Admissible velocities** V_a (section 3.1): the paper admits v when
//!    the robot can still stop before the first obstacle on its curvature,
//!    v <= sqrt(2 dist(v) a_brake). The paper's obstacles stand still;
//!    here every other body moves (at its sensed velocity, held constant),
//!    so we apply the condition in each body's own frame, where it does
//!    stand still: v is admissible when, for every body o, |v - v_o| <=
//!    sqrt(2 dist_o max_accel) with dist_o = |v - v_o| t_o(v), t_o the time
//!    to contact with o (walls: v_o = 0, which is the paper's condition).
//!    Neither reading makes DWA collision-free between moving robots (each
//!    assumes the other keeps its velocity): two robots reaching a
//!    right-angle crossing at the same instant graze (overlap 0.006 with
//!    radius 0.3 in the testkit); staggered by one unit they pass.
//! 3. **Objective** (section 3.2, eq for G(v, omega)):
//!    G(v) = w_heading heading(v) + w_clearance clearance(v) + w_speed speed(v),
//!    maximised over the admissible samples, each term in [0, 1]:
//!    - heading = 1 - theta / pi, theta the angle between v and the goal as
//!      seen from the position reached after one period (the paper
//!      evaluates the heading at the predicted position); 1/2 for v = 0;
//!    - clearance = min(t_c, horizon) / horizon: the paper's dist term,
//!      measured in time so that it covers moving bodies, and saturated at
//!      `horizon` as the paper saturates dist when nothing is on the
//!      curvature;
//!    - speed = 1 - ||v| - v_goal| / max_speed with v_goal = min(max_speed,
//!      sqrt(2 max_accel d_goal), d_goal / dt): the paper's "as fast as
//!      possible" while far from the goal, and a braking profile near it
//!      (the paper leaves stopping at the goal to its global planner; a
//!      point goal needs one).
//!
//!    The paper smooths the weighted sum and normalises each term over the
//!    window; we use the fixed normalisations above instead, which keeps
//!    the weights comparable between ticks.
//!
//! Within `goal_tolerance` of the goal the robot picks the slowest
//! admissible sample (it stops). If no sample is admissible (already
//! boxed in), it picks the one with the longest time to contact.
//!
//! Parameters and defaults: `w_heading` = 2, `w_clearance` = 0.2, `w_speed`
//! = 0.2 (Fox et al.'s alpha, beta, gamma in their RHINO experiments, as the
//! paper reports them, quoted from the published article, IEEE Robotics &
//! Automation Magazine 4(1), 1997); `samples` = 11 per axis and
//! `horizon` = 3 s are our choices (the paper discretises its window
//! without fixing a resolution); `obstacles` = `truth` (below).
//!
//! **On a unicycle robot** (`kinematics = "unicycle"`) the planner searches
//! the paper's own space, (v, omega), and answers [`Command::Unicycle`]
//! (its `unicycle` module): the window is
//! [v_c - a dt, v_c + a dt] x [omega_c - alpha dt, omega_c + alpha dt]
//! within 0 <= v <= max_speed, |omega| <= max_angular_speed (section 3.1,
//! forward motion only as in the paper); each candidate's curvature is the
//! circular arc it drives (eq 8's approximation: v and omega held), checked
//! against every body moving at its sensed velocity in steps of dt / 2 up
//! to `horizon`; admissible when v <= sqrt(2 dist(v, omega) a_max) with
//! dist the arc length to the first contact (section 3.1, V_a); heading is
//! 1 - |angle to the goal from the pose predicted after dt| / pi (section
//! 3.2), clearance as above; speed = 1 - |v - v_goal| / max_speed with
//! v_goal the braking profile above, further capped by omega_max d_goal /
//! (2 |sin alpha|) (the arc from the robot through the goal, alpha the
//! goal's bearing off the heading, needs v / omega at most its radius; a
//! faster robot circles its goal instead of reaching it) and scaled by
//! max(cos alpha, 0), so that a goal more than a right angle off is turned
//! to in place. It says so
//! ([`Planner::native_unicycle`]), so the look-ahead controller that
//! drives the other planners on a unicycle ([`crate::unicycle`]) gives it
//! the robot's own pose and goal tolerance, not the look-ahead point's.
//!
//! **Recovery** (unicycle; the paper has none, ROS's local planners back
//! off and rotate): a robot touching something (its disc within 5 % of its
//! radius of a body, wall or scan return) or standing still facing its goal
//! (within 45 degrees) for 3 s, away from its goal, backs off for up to
//! 1.5 s at half its top speed: backwards with its nose turning away when
//! the nearest obstacle is ahead, forwards when it is behind, not at all
//! (turning in place) when that way is blocked too, for the whole 1.5 s
//! unless that way becomes blocked: the turn as it backs leaves it beside,
//! not in front of, what it touched (two robots face to face each turn
//! their noses right and pass each other on the left). Turning in place is always admissible for a disc,
//! so a robot that cannot advance turns towards its goal and waits for the
//! way to clear; the back-off is what gets two robots that touch apart.
//!
//! **Going round** (unicycle, from the scan; DWA's objective alone keeps a
//! robot facing what blocks the way to its goal, a local minimum, and
//! keeping to half the gap to every return holds it there): a robot that has not
//! moved half its radius for 1.5 s, facing its goal (within 45 degrees),
//! with the nearest obstacle within its radius, ahead and between it and
//! its goal, goes round it for up to 2 s: its heading term aims along the
//! nearest obstacle's edge (its direction turned a right angle) on the side
//! away from it, or on the right when it is within 10 degrees of straight
//! in the way, until it is past (no longer towards the goal) or two radii
//! off. Two robots stopped face to face both go round to their right. (On
//! true states the ties below suffice for two robots head-on, and going
//! round jammed the robots crossing the hospital map's main corridor: 1
//! of 10 arrived, against 10 of 10 without.)
//!
//! **Keeping right** (unicycle, from the scan): robots that meet in a
//! corridor, each swerving its own way or all keeping to the middle line
//! their routes share, stop face to face and those behind them pile up
//! (ten Pioneers crossing the hospital map's 1.85 m main corridor from the
//! scan: 1 of 10 arrived). So a robot keeps right when it meets something,
//! as people and traffic do: when a return that the map does not explain
//! (none of the walls within a quarter of the radius of it: another robot,
//! a person, an obstacle not on the map) lies ahead in the way to its goal
//! (the strip its padded disc sweeps towards the goal, widened by another
//! padded disc, up to max_speed x horizon ahead), the heading term aims at
//! a point one and a half radii to the right of the goal (a third of the
//! distance to the goal at most, so that the robot still arrives), less
//! where the walls there leave its padded disc less room: in a corridor
//! one robot wide, not at all. It keeps right for 3 s after it last met
//! something, so that it does not swing back to the middle between two
//! robots coming the other way. Robots coming the other way that both keep
//! right pass each other left to left, and those going the same way fall
//! into a lane. Otherwise the goal is aimed at as the route gives it. The
//! walls only tell returns apart: what the robot avoids is still the scan.
//! A rectangle or polygon on true states keeps right too (eight AGVs
//! swapping rooms along one corridor all kept to its middle line, met
//! head-on and stood): when another body is ahead in the strip its padded
//! footprint sweeps towards the goal (its half width and padding to
//! either side, widened by as much again), it aims one and a half half
//! widths to the right of the goal, as far as the walls leave its padded
//! half width room beside the whole way there (an AGV in a door does not
//! swerve into its jamb).
//!
//! **Ties** (unicycle): samples scored within 1e-6 of the objective's range
//! of the best are a tie, taken by the right-most turn. Two robots meeting
//! exactly head-on see mirror images of one scene and score each turn as
//! its mirror turn; rounding, different in each robot's frame, would turn
//! one left and the other right, to the same side of the line between
//! them, where they meet again. A back-off's turn follows the same rule
//! (nose right when what it touched is within 10 degrees of dead ahead).
//!
//! **Padding** (`padding`, unicycle only; default a quarter of the
//! radius): the arcs are checked for a disc that much larger, so the robot
//! keeps that distance from everything it can (DWA alone admits any arc it
//! can stop on, however close; a scan of discrete beams can also miss a
//! corner between two of them by up to the beams' spacing there).
//!
//! **Obstacles** (`obstacles`): `truth` (default) avoids the sensed bodies
//! at their velocities and the walls, as above; `scan` avoids only the
//! returns of the robot's laser scan (the `sensor` key; a robot without
//! one is refused), each a still point, as a robot with a real lidar must.
//! On a unicycle each return is checked exactly against the circle the
//! centre drives; on a holonomic robot the returns become still bodies of
//! radius 0. Only returns within max_speed x horizon + radius matter. A
//! return may be another robot coming the other way, which the scan cannot
//! tell, so on a unicycle an arc is admissible only if both could stop in
//! the gap, each after a tick's delay: v^2 / a <= v (t_c - 2 dt), t_c the
//! time to contact with the return standing still. That covers a robot
//! coming along the arc, not one that swerves into it: two robots meeting
//! head-on, each bending its arc away from where the other stands, can
//! bend to the same side and meet (the arcs are checked against still
//! points). So, from the scan, the robot also closes on every return only
//! as fast as it can stop within half the gap to its padded disc after a
//! tick, (v cos phi)^2 / (2 a) + v cos phi dt <= gap / 2, phi the return's
//! bearing off the heading (what is beside it does not slow it): two
//! robots that each keep to their half stop apart whatever the other does
//! (the responsibility shared as ORCA shares it). On true states the
//! others' velocities are known and the arcs are checked against them,
//! and both must be able to stop (below).
//!
//! **Both could stop** (unicycle, true states; module `brake`): Fox et
//! al.'s V_a lets the robot stop before the first obstacle on its arc,
//! the obstacle standing still. Another robot keeps coming while this one
//! stops, and every command is held for a tick: v <= sqrt(2 dist a) with
//! dist taken from the closing motion let two Pioneers meeting head-on at
//! 0.6 m/s each keep their speed until about 0.41 m apart, where the two
//! together need about 0.5 m to stop after a tick, and two TurtleBot3s
//! touched when one turned into the other's path.
//! So, after the paper's test, an arc is admitted only if the robot,
//! driving it for a tick and then braking as hard as it can along the same
//! curve, is at rest before it could touch any other body, each other
//! robot going on for a tick as it moves, straight on and along the turn
//! its velocity's direction shows over successive ticks (per id, bounded
//! by the robot's own turn-rate limit), and then braking as hard as this
//! robot can; a scripted obstacle does not brake. This is passive-friendly
//! motion safety (Macek, Vasquez, Fraichard & Siegwart 2009; Bouraine,
//! Fraichard & Salhi 2012): should a contact come, the robot is at rest
//! and the other had room to stop. A contact after the robot is at rest,
//! or one it does not drive into (the other coming on from behind or the
//! side as it drives away), is not counted: were it, a robot coming on
//! would forbid every arc, driving away included. Turning in place is
//! always admitted. From the scan, the gap rules above do this work.
//!
//! **True footprints** (module `footprint`; a robot whose `shape` is a
//! rectangle or convex polygon, on true states): the arcs of a unicycle,
//! the straight lines of a holonomic robot and the trajectories of a car
//! are checked with the robot's polygon at each sampled pose (every half
//! tick, or a quarter for a car), against the walls' segments and the
//! others' true shapes (their discs or polygons at their headings,
//! moving at their velocities), not with the disc around it: a 0.9 x 0.6
//! AGV, whose circumscribed disc padded is 1.35 m across, drives through
//! a 1.2 m door. The gaps are `mrsim-shape`'s; the samples between two
//! checks are skipped by conservative advancement (no point of the
//! footprint moves faster than its centre plus its turn times its
//! radius). The padding is then a quarter of the inscribed radius (half
//! the shorter side of a rectangle) by default, kept from everything; a
//! robot already nearer than that to something may not come nearer. The
//! paper's V_a and "Both could stop" become one test: driving the sample
//! for a tick and then braking as hard as the robot can (along the same
//! curve) leaves the footprint clear of the walls, of the others going on
//! for a tick and braking (a scripted obstacle going on), and of the
//! others standing where they are; a contact counts only when the robot's
//! own motion brings it nearer. Turning in place is checked too (a
//! rectangle's corners swing), and a back-off that is not clear is tried
//! straight, then turning in place, then not at all. With no sample
//! admissible, a footprint brakes as hard as it can, its turn too (the
//! disc's least bad sample, the one whose contact comes last, was a turn
//! at full rate that swung a corner into a robot already within its
//! padding). Discs keep the tests above exactly. From the scan, a polygon is still its padded
//! circumscribed disc.
//!
//! **On a car** (`kinematics = "ackermann"`; module `ackermann`, which
//! says each case): the window is (speed, steering), speeds within
//! max_accel dt of the present one down to -max_reverse_speed, steering
//! within max_steering_rate dt of the present one within +-max_steering;
//! each sample is held over the horizon (at least the time to stop from
//! top speed) through the bicycle model the world drives
//! ([`crate::ackermann::bicycle_step`]), checked with the car's true
//! footprint as above, and scored as above with the heading taken a second
//! on and a speed target that also keeps the sample's lateral
//! acceleration within max_accel (teb_local_planner's and nav2's car-like
//! practice: the bicycle's own controls, its minimum radius never
//! exceeded). A car cannot turn in place: it recovers by backing with its
//! wheels turned so that its nose swings towards the goal
//! ([`Planner::native_ackermann`]: the car's command is dwa's own).
//!
//! **Walls on true states**: a map's traced outlines hold thousands of
//! wall segments, and every chord of every arc would be checked against
//! every one within reach. A grid of the walls (square cells of the padded
//! diameter, each holding the segments whose bounding box meets it) is
//! built at the first tick (again only if the walls given change); each
//! chord is checked only against the walls within reach in the cells its
//! padded disc's box meets, which are all those it could touch. (The
//! outcome differs from checking every wall within reach in one case:
//! a disc within its radius of a segment's line but beyond its end gets a
//! contact time in the past from that side, which made an arc
//! inadmissible even when the segment was metres away; now only a
//! segment near the chord can do so.) A robot already nearer a wall than
//! its padded radius checks the walls for a disc just under its distance
//! to the nearest: what would take it deeper is inadmissible, driving along
//! the wall is not (with the padded radius, every short segment of a traced
//! outline ahead was already in contact, and the robot stood still for
//! good).

mod ackermann;
mod brake;
mod contact;
mod footprint;
mod meeting;
mod planner;
mod unicycle;
mod walls;

pub use planner::{Dwa, Obstacles};

use crate::{BodyKind, Command, Kinematics, Observation, Planner, Sensed, Vec2};
use contact::{scan_points, time_to_disc, time_to_segment};
use footprint::{Footprint, Motion, Rollout};

impl Dwa {
    /// Time to the first contact of the robot moving at `v` (infinite if
    /// none), and whether `v` is admissible: for every body (and wall),
    /// the robot can bring its velocity relative to that body to zero
    /// before contact, |v - v_o| <= sqrt(2 a_max |v - v_o| t_c).
    fn time_to_contact(obs: &Observation, v: Vec2) -> (f64, bool) {
        let me = &obs.me;
        let a_max = me.max_accel;
        let mut t_min = f64::INFINITY;
        let mut admissible = true;
        let mut consider = |t: Option<f64>, closing: Vec2| {
            if let Some(t) = t {
                t_min = t_min.min(t);
                let s = closing.norm();
                if s > 0.0 && s > 2.0 * a_max * t {
                    admissible = false;
                }
            }
        };
        for o in obs.others {
            let rel = v - o.velocity;
            consider(
                time_to_disc(me.position - o.position, rel, me.radius + o.radius),
                rel,
            );
        }
        for w in obs.walls {
            consider(time_to_segment(me.position, v, me.radius, w), v);
        }
        (t_min, admissible)
    }

    /// [`Dwa::time_to_contact`] for a footprint moving at `v`: the first
    /// contact of the footprint translated at `v` up to `horizon`, and
    /// whether, holding `v` for a tick and then braking along it, it stops
    /// clear of the walls and of the others at their velocities.
    fn footprint_contact(
        f: &mut Footprint,
        obs: &Observation,
        v: Vec2,
        horizon: f64,
    ) -> (f64, bool) {
        let me = &obs.me;
        let dt = if obs.dt > 0.0 { obs.dt } else { 0.1 };
        let h = dt / 2.0;
        let (p, th) = (me.position, me.heading);
        let steps = (horizon / h).ceil() as usize;
        let held: Vec<(Vec2, f64)> = (0..=steps).map(|k| (p + v * (k as f64 * h), th)).collect();
        let t_c = f.contact(&Rollout::new(h, held, me.radius), &[Motion::Constant], true);
        let u = v.norm();
        let a = me.max_accel.max(1e-9);
        let stop = ((dt + u / a) / h).ceil() as usize + 1;
        let dir = if u > 0.0 { v / u } else { Vec2::zeros() };
        let braking: Vec<(Vec2, f64)> = (0..=stop)
            .map(|k| {
                let t = k as f64 * h;
                let tb = (t - dt).clamp(0.0, u / a);
                let s = u * t.min(dt) + u * tb - 0.5 * a * tb * tb;
                (p + dir * s, th)
            })
            .collect();
        let stops = f
            .contact(
                &Rollout::new(h, braking, me.radius),
                &[Motion::Constant],
                true,
            )
            .is_infinite();
        (t_c, stops)
    }

    /// The sampled dynamic window V_d intersected with V_s.
    fn window(&self, obs: &Observation) -> Vec<Vec2> {
        let me = &obs.me;
        let reach = me.max_accel * obs.dt.max(0.0);
        let vc = me.velocity;
        let mut out = vec![vc];
        let n = self.samples;
        let lo = Vec2::new(
            (vc.x - reach).max(-me.max_speed),
            (vc.y - reach).max(-me.max_speed),
        );
        let hi = Vec2::new(
            (vc.x + reach).min(me.max_speed),
            (vc.y + reach).min(me.max_speed),
        );
        for i in 0..n {
            for j in 0..n {
                let f = |k: usize, a: f64, b: f64| a + (b - a) * k as f64 / (n - 1) as f64;
                let v = Vec2::new(f(i, lo.x, hi.x), f(j, lo.y, hi.y));
                if (v - vc).norm() <= reach * (1.0 + 1e-12)
                    && v.norm() <= me.max_speed * (1.0 + 1e-12)
                {
                    out.push(v);
                }
            }
        }
        out
    }
}

impl Planner for Dwa {
    fn plan(&mut self, obs: &Observation) -> Command {
        if let Some(car) = crate::ackermann::Car::of(&obs.me) {
            return ackermann::plan(self, obs, car);
        }
        if let Kinematics::Unicycle {
            max_angular_speed,
            max_angular_accel,
        } = obs.me.kinematics
        {
            return unicycle::plan(self, obs, max_angular_speed, max_angular_accel);
        }
        if self.obstacles == Obstacles::Scan {
            // The scan's returns as still points, in the world's frame (a
            // holonomic robot's scan is taken with heading 0).
            let points: Vec<Sensed> = scan_points(obs)
                .map(|q| {
                    Sensed::disc(
                        u32::MAX,
                        BodyKind::Obstacle,
                        obs.me.position + q,
                        Vec2::zeros(),
                        0.0,
                    )
                })
                .collect();
            let mut seen = *obs;
            seen.others = &points;
            seen.walls = &[];
            seen.scan = None;
            return self.plan_holonomic(&seen);
        }
        self.plan_holonomic(obs)
    }

    fn native_unicycle(&self) -> bool {
        true
    }

    fn native_ackermann(&self) -> bool {
        true
    }

    fn needs_scan(&self) -> bool {
        self.obstacles == Obstacles::Scan
    }
}

impl Dwa {
    /// One step on a holonomic robot (module documentation, 1-3).
    fn plan_holonomic(&mut self, obs: &Observation) -> Command {
        let me = &obs.me;
        let to_goal = obs.goal - me.position;
        let d_goal = to_goal.norm();
        let a_max = me.max_accel;
        let dt = if obs.dt > 0.0 { obs.dt } else { 1.0 };
        let v_goal = me
            .max_speed
            .min((2.0 * a_max * d_goal).sqrt())
            .min(d_goal / dt);
        let at_goal = d_goal <= obs.goal_tolerance;

        let mut best: Option<(f64, Vec2)> = None;
        let mut least_bad = (f64::NEG_INFINITY, me.velocity);
        let window = self.window(obs);
        // A rectangle or polygon: its true footprint, translated (a
        // holonomic robot never turns), against the walls and the others.
        let pad = self.padding.unwrap_or(me.shape.inradius() / 4.0);
        let mut foot = (!me.shape.is_disc()).then(|| {
            let reach = me.max_speed * self.horizon + me.radius + pad;
            self.walls.prepare(obs.walls, 2.0 * (me.radius + pad));
            let any = !self.walls.near(obs.walls, me.position, reach).is_empty();
            Footprint::new(
                me.shape,
                (me.position, me.heading),
                pad,
                obs.walls,
                &mut self.walls,
                any,
                obs.others,
            )
        });
        for v in window {
            let speed = v.norm();
            let (t_c, admissible) = match foot.as_mut() {
                Some(f) => Self::footprint_contact(f, obs, v, self.horizon),
                None => Self::time_to_contact(obs, v),
            };
            if t_c > least_bad.0 {
                least_bad = (t_c, v);
            }
            if !admissible {
                continue;
            }
            let score = if at_goal {
                // Goal reached: stop (slowest admissible velocity).
                -speed
            } else {
                // Heading at the predicted position.
                let ahead = obs.goal - (me.position + v * dt);
                let heading = if speed <= f64::EPSILON || ahead.norm() <= f64::EPSILON {
                    0.5
                } else {
                    let cos = (v.dot(&ahead) / (speed * ahead.norm())).clamp(-1.0, 1.0);
                    1.0 - cos.acos() / std::f64::consts::PI
                };
                let clearance = t_c.min(self.horizon) / self.horizon;
                let speed_term = if me.max_speed > 0.0 {
                    1.0 - (speed - v_goal).abs() / me.max_speed
                } else {
                    0.0
                };
                self.w_heading * heading + self.w_clearance * clearance + self.w_speed * speed_term
            };
            if best.is_none_or(|(s, _)| score > s) {
                best = Some((score, v));
            }
        }
        // No admissible velocity: the one that keeps contact furthest off.
        Command::Velocity(best.map_or(least_bad.1, |(_, v)| v))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Segment;
    use crate::testkit::{RobotModel, Sim, observation, obstacle};

    const ROBOT: RobotModel = RobotModel::unit(0.3);

    /// The robot at the origin moving at `velocity`, its goal 10 along x.
    fn obs<'a>(velocity: Vec2, others: &'a [Sensed], walls: &'a [Segment]) -> Observation<'a> {
        let me = ROBOT.at(Vec2::zeros(), velocity);
        Observation {
            goal_tolerance: 0.1,
            walls,
            ..observation(me, Vec2::new(10.0, 0.0), others)
        }
    }

    #[test]
    fn time_to_contact_of_discs_and_segments_is_exact() {
        // Point at x = -5 moving +x at 1 towards a disc of radius 1: t = 4.
        let t = time_to_disc(Vec2::new(-5.0, 0.0), Vec2::new(1.0, 0.0), 1.0).unwrap();
        assert!((t - 4.0).abs() < 1e-12);
        assert!(time_to_disc(Vec2::new(-5.0, 0.0), Vec2::new(-1.0, 0.0), 1.0).is_none());
        // Disc of radius 0.5 at the origin moving +x at 2 towards the wall
        // x = 3: touches after (3 - 0.5) / 2.
        let wall = Segment {
            a: Vec2::new(3.0, -1.0),
            b: Vec2::new(3.0, 1.0),
        };
        let t = time_to_segment(Vec2::zeros(), Vec2::new(2.0, 0.0), 0.5, &wall).unwrap();
        assert!((t - 1.25).abs() < 1e-12, "{t}");
        // Past the wall's end it reaches the round end only.
        let t = time_to_segment(Vec2::new(0.0, 1.3), Vec2::new(1.0, 0.0), 0.5, &wall).unwrap();
        assert!((t - 2.6).abs() < 1e-12, "{t}");
    }

    #[test]
    fn chosen_velocity_stays_in_the_dynamic_window() {
        let mut dwa = Dwa::default();
        let v0 = Vec2::new(0.0, 0.8);
        let v = dwa.plan(&obs(v0, &[], &[])).vector();
        // Reachable in one tick: |dv| <= 2 * 0.1, and turned towards +x.
        assert!((v - v0).norm() <= 0.2 + 1e-9, "{v:?}");
        assert!(v.norm() <= 1.0 + 1e-9);
        assert!(v.x > 0.1, "{v:?}");
    }

    #[test]
    fn free_robot_heads_for_the_goal_at_full_speed() {
        let mut dwa = Dwa::default();
        let v = dwa.plan(&obs(Vec2::new(1.0, 0.0), &[], &[])).vector();
        assert!((v - Vec2::new(1.0, 0.0)).norm() < 1e-9, "{v:?}");
    }

    #[test]
    fn velocities_that_cannot_stop_before_contact_are_not_admissible() {
        // A still body 0.1 from contact straight ahead: moving at u along
        // x, stopping takes u^2 / 4 and contact comes after 0.1, so only
        // u <= sqrt(0.4) = 0.63 is admissible; free, the robot would take
        // the window's fastest, 0.7.
        let ahead = [obstacle(1, Vec2::new(0.7, 0.0), Vec2::zeros(), 0.3)];
        let mut dwa = Dwa::default();
        let free = dwa.plan(&obs(Vec2::new(0.5, 0.0), &[], &[])).vector();
        assert!((free - Vec2::new(0.7, 0.0)).norm() < 1e-9, "{free:?}");
        let v = dwa.plan(&obs(Vec2::new(0.5, 0.0), &ahead, &[])).vector();
        let (t_c, admissible) = Dwa::time_to_contact(&obs(Vec2::zeros(), &ahead, &[]), v);
        assert!(admissible);
        assert!(v.norm() <= 2.0 * t_c * 2.0 + 1e-12, "{v:?} t_c {t_c}");
        assert!(v.x < 0.64, "{v:?}");
    }

    #[test]
    fn two_robots_crossing_at_right_angles_one_behind_the_other_pass_without_contact() {
        let mut sim = Sim::new(0.1, 10);
        // B starts one unit further back: with both reaching the crossing
        // at the same instant the encounter is mirror-symmetric about the
        // diagonal, which this model resolves by no rule of its own.
        let (ra, rb) = (Vec2::new(-5.0, 0.0), Vec2::new(0.0, -6.0));
        for (start, goal) in [(ra, -ra), (rb, Vec2::new(0.0, 5.0))] {
            sim.add_robot(
                Box::new(Dwa::default()),
                start,
                goal,
                0.3,
                1.0,
                0.0,
                1.0,
                2.0,
            );
        }
        let mut min_gap = f64::INFINITY;
        let mut reached = [false; 2];
        for _ in 0..400 {
            sim.step();
            min_gap = min_gap.min(sim.clearance(0));
            for (k, r) in sim.robots.iter().enumerate() {
                reached[k] |= (r.state.position - r.goal).norm() < 0.2;
            }
        }
        assert!(min_gap > 0.0, "contact: gap {min_gap}");
        assert_eq!(reached, [true, true]);
    }
}
