//! Holonomic planners on a unicycle (differential-drive) robot: the
//! look-ahead point controller, input/output feedback linearisation of the
//! unicycle about a point off its wheel axis (B. Siciliano, L. Sciavicco,
//! L. Villani & G. Oriolo, "Robotics: Modelling, Planning and Control",
//! Springer 2009, section 11.6.2, trajectory tracking via input/output
//! linearisation of a point B at distance b along the sagittal axis; the
//! same construction as J. R. Lawton, R. W. Beard & B. J. Young, IEEE T-RA
//! 19(6), 2003, "hand position").
//!
//! **1. The linearising map.** The unicycle x' = v cos theta,
//! y' = v sin theta, theta' = omega cannot move sideways, but the point
//! p = (x, y) + l (cos theta, sin theta) at distance l ahead of its centre
//! can move in any direction:
//!
//! p' = T(theta) (v, omega),  T = [cos theta, -l sin theta; sin theta, l cos theta],
//!
//! a matrix of determinant l, invertible for l > 0 (Siciliano et al. eq
//! 11.75 with b = l). So a planar velocity u asked of p is obtained
//! exactly by (v, omega) = T^-1 u ([`LookAhead::unicycle_for`]):
//!
//! v = cos theta u_x + sin theta u_y,  omega = (-sin theta u_x + cos theta u_y) / l.
//!
//! [`LookAhead`] wraps any planner: the planner sees the robot as the point
//! p (its observation's position is p, its velocity p' = T (v, omega) of
//! the current forward speed and turn rate, its radius r + l (below);
//! everything else unchanged), so the planner's closed loop runs on a point that moves as
//! asked. A velocity command u is applied to p through T^-1; a force f
//! becomes the velocity it would give p in one tick under m r'' + b r' = f
//! with the acceleration clamp, u = p' + dt clamp((f - b p') / m,
//! max_accel).
//!
//! **2. The goal.** The planner brings p, not the centre, to the goal, and
//! the world counts a robot arrived when its centre is within
//! `goal_tolerance` of the goal. The centre is at distance l from p, so by
//! the triangle inequality |c - g| <= |p - g| + l: the planner is told the
//! tolerance `goal_tolerance - l`, and wherever it deems p arrived the
//! centre is within the world's tolerance ([`LookAhead::tolerance_seen`];
//! with l >= `goal_tolerance` nothing can guarantee this and the planner
//! keeps the world's tolerance; a scenario refuses such a `lookahead` on a unicycle).
//!
//! **The disc.** The planner keeps p clear of everything, but the robot's
//! disc is centred l behind p: a disc of radius r + l about p covers the
//! robot's disc whatever its heading, so the planner is told the radius
//! r + l (the enlarged footprint of ORCA for differential-drive robots:
//! J. Snape, J. van den Berg, S. J. Guy & D. Manocha, "Smooth and
//! collision-free navigation for multiple robots under differential-drive
//! constraints", IROS 2010) and keeping its disc clear keeps the real one
//! clear. The enlarged disc is twice l wider than the robot: a door the
//! robot passes with room to spare can be as narrow as the enlarged disc.
//! The planner is told l ([`Planner::drives_look_ahead`]), so that one
//! that knows where the real disc is can keep it, not the enlarged one,
//! off the walls: [`crate::orca`] does, keeping p nearer a wall when the
//! robot heads towards it, as the centre is then further off than p.
//!
//! **3. The limits.** T^-1 is exact only while (v, omega) is within the
//! robot's limits; the world clamps v to ±`max_speed`, omega to
//! ±`max_angular_speed` and their rates of change, each on its own. A
//! request beyond the turn rate (omega grows as 1/l: with l = 0.05 a
//! sideways 0.1 m/s already asks 2 rad/s) then moves p more along the
//! heading than asked, and the planner sees that in its next observation
//! and corrects. Scaling v and omega by one factor would keep p's direction
//! instead (p' is linear in them), but it turns every saturated request
//! into a near stop-and-turn, since with a small l almost every request
//! with a sideways part is saturated. Measured on the unicycle crossing
//! with every planner, that scaling (against the speed limits alone, or
//! also against what the acceleration limits reach in one tick) made
//! robots slower and no planner's goals more reachable, and gave more
//! contacts (docs/maps.md, "Unicycle robots: every planner"), so the controller leaves
//! the limits to the world. A planner that knows it drives a look-ahead
//! point can keep within them itself: [`crate::orca`] picks only velocities
//! the point reaches within the tick, so that what it plans is what the
//! robot does.
//!
//! **4. Planners that know the model.** A planner that plans (v, omega)
//! itself ([`Planner::native_unicycle`], [`crate::dwa`]) needs none of
//! this: it gets the robot's true observation (centre, heading, world
//! tolerance) and its command passes unchanged. A unicycle command from any
//! other planner also passes unchanged (it was planned for p). On a
//! holonomic robot nothing is converted.
//!
//! `l` is the robot's `lookahead` key: a small l follows u more tightly
//! but turns harder (omega grows as 1/l, so the turn-rate limit binds more
//! often), and the tolerance left to the planner is `goal_tolerance - l`.

use crate::{Command, Diagnostic, Kinematics, Observation, Planner, Vec2};

/// A planner made to drive a unicycle robot through its look-ahead point.
pub struct LookAhead {
    inner: Box<dyn Planner>,
    lookahead: f64,
}

impl LookAhead {
    /// Wraps `inner`; `lookahead` (> 0) is the distance l of the controlled
    /// point ahead of the centre.
    pub fn new(mut inner: Box<dyn Planner>, lookahead: f64) -> Self {
        inner.drives_look_ahead(lookahead);
        Self { inner, lookahead }
    }

    /// (v, omega) = T(theta)^-1 u: the forward speed and turn rate that
    /// move the look-ahead point at `u` from heading `theta` (module
    /// documentation, 1).
    pub fn unicycle_for(u: Vec2, theta: f64, lookahead: f64) -> (f64, f64) {
        let (s, c) = theta.sin_cos();
        (c * u.x + s * u.y, (-s * u.x + c * u.y) / lookahead)
    }

    /// The goal tolerance the planner is told: `tolerance - lookahead` when
    /// positive, so that p within it puts the centre within `tolerance`
    /// (module documentation, 2); else `tolerance` unchanged.
    pub fn tolerance_seen(tolerance: f64, lookahead: f64) -> f64 {
        if tolerance > lookahead {
            tolerance - lookahead
        } else {
            tolerance
        }
    }
}

impl Planner for LookAhead {
    fn plan(&mut self, obs: &Observation) -> Command {
        if obs.me.kinematics == Kinematics::Holonomic || self.inner.native_unicycle() {
            return self.inner.plan(obs);
        }
        let l = self.lookahead;
        let (s, c) = obs.me.heading.sin_cos();
        let v_c = obs.me.velocity.dot(&Vec2::new(c, s));
        let w_c = obs.me.angular_velocity;
        let mut seen = *obs;
        seen.me.position += Vec2::new(c, s) * l;
        seen.me.velocity = Vec2::new(c, s) * v_c + Vec2::new(-s, c) * (l * w_c);
        seen.me.radius += l;
        seen.goal_tolerance = Self::tolerance_seen(obs.goal_tolerance, l);
        let me = &seen.me;
        let cmd = self.inner.plan(&seen);
        let u = match cmd {
            // A car's command on a unicycle passes, and the world brakes.
            Command::Unicycle { .. } | Command::Ackermann { .. } => return cmd,
            Command::Velocity(u) => u,
            Command::Force(f) => me.velocity_after(f, obs.dt),
        };
        let (v, omega) = Self::unicycle_for(u, me.heading, l);
        Command::Unicycle { v, omega }
    }

    fn diagnostics(&self) -> Vec<Diagnostic> {
        self.inner.diagnostics()
    }

    fn diagnostics_into(&self, out: &mut Vec<Diagnostic>) {
        self.inner.diagnostics_into(out);
    }

    fn native_unicycle(&self) -> bool {
        true
    }

    fn plans_unicycle(&self) -> bool {
        self.inner.plans_unicycle()
    }

    fn needs_scan(&self) -> bool {
        self.inner.needs_scan()
    }
}

/// A unicycle asked to arrive facing a heading (the scenario's
/// `goal_heading_deg`): where the robot's centre is within its goal
/// tolerance of the goal, it stands and turns in place to the heading,
/// the short way round, at the turn rate from which it stops on the
/// heading decelerating at its `max_angular_accel` (at most
/// `max_angular_speed`); elsewhere `inner` plans as ever. The world counts
/// the robot arrived only once its heading is within the tolerance too.
/// On a holonomic robot or a car it changes nothing (a holonomic robot
/// never turns; a car cannot turn in place).
pub struct GoalHeading {
    inner: Box<dyn Planner>,
    heading: f64,
}

impl GoalHeading {
    /// Wraps `inner`, to arrive facing `heading` (rad).
    pub fn new(inner: Box<dyn Planner>, heading: f64) -> Self {
        Self { inner, heading }
    }

    /// The turn rate towards the heading `error` (rad, signed) away: the
    /// rate from which the turn stops there decelerating at `accel`, at
    /// most `top`.
    pub fn turn_rate(error: f64, top: f64, accel: f64) -> f64 {
        error.signum() * (2.0 * accel * error.abs()).sqrt().min(top)
    }
}

impl Planner for GoalHeading {
    fn plan(&mut self, obs: &Observation) -> Command {
        let Kinematics::Unicycle {
            max_angular_speed,
            max_angular_accel,
        } = obs.me.kinematics
        else {
            return self.inner.plan(obs);
        };
        if (obs.me.position - obs.goal).norm() > obs.goal_tolerance {
            return self.inner.plan(obs);
        }
        // At the goal: turn in place, the short way round.
        let error = (self.heading - obs.me.heading + std::f64::consts::PI)
            .rem_euclid(std::f64::consts::TAU)
            - std::f64::consts::PI;
        Command::Unicycle {
            v: 0.0,
            omega: Self::turn_rate(error, max_angular_speed, max_angular_accel),
        }
    }

    fn diagnostics(&self) -> Vec<Diagnostic> {
        self.inner.diagnostics()
    }

    fn diagnostics_into(&self, out: &mut Vec<Diagnostic>) {
        self.inner.diagnostics_into(out);
    }

    fn native_unicycle(&self) -> bool {
        self.inner.native_unicycle()
    }

    fn native_ackermann(&self) -> bool {
        self.inner.native_ackermann()
    }

    fn needs_scan(&self) -> bool {
        self.inner.needs_scan()
    }

    fn drives_look_ahead(&mut self, lookahead: f64) {
        self.inner.drives_look_ahead(lookahead);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testkit::{RobotModel, observation};
    use std::f64::consts::FRAC_PI_2;

    /// p' = T(theta) (v, omega).
    fn point_velocity(v: f64, w: f64, theta: f64, l: f64) -> Vec2 {
        let (s, c) = theta.sin_cos();
        Vec2::new(c * v - l * s * w, s * v + l * c * w)
    }

    #[test]
    fn the_inverse_gives_the_look_ahead_point_the_asked_velocity() {
        for &(theta, u) in &[
            (0.3, Vec2::new(1.0, -0.5)),
            (2.5, Vec2::new(-0.2, 0.7)),
            (-1.0, Vec2::new(0.0, 1.0)),
        ] {
            let l = 0.2;
            let (v, w) = LookAhead::unicycle_for(u, theta, l);
            let p_dot = point_velocity(v, w, theta, l);
            assert!((p_dot - u).norm() < 1e-12, "{p_dot} vs {u}");
        }
    }

    #[test]
    fn a_sideways_velocity_turns_the_robot_without_driving_it() {
        // Heading +x, asked to move +y: v = 0, omega = 1/l.
        let (v, w) = LookAhead::unicycle_for(Vec2::new(0.0, 1.0), 0.0, 0.5);
        assert!(v.abs() < 1e-15 && (w - 2.0).abs() < 1e-15);
        // Heading +y, same request: straight ahead.
        let (v, w) = LookAhead::unicycle_for(Vec2::new(0.0, 1.0), FRAC_PI_2, 0.5);
        assert!((v - 1.0).abs() < 1e-15 && w.abs() < 1e-15);
    }

    /// Records what it was shown; answers `answer`.
    struct Probe {
        answer: Command,
        native: bool,
        seen: std::sync::Arc<std::sync::Mutex<Option<(Vec2, Vec2, f64)>>>,
    }

    impl Planner for Probe {
        fn plan(&mut self, obs: &Observation) -> Command {
            *self.seen.lock().expect("probe") =
                Some((obs.me.position, obs.me.velocity, obs.goal_tolerance));
            self.answer
        }
        fn native_unicycle(&self) -> bool {
            self.native
        }
    }

    const ROBOT: RobotModel = RobotModel::unit(0.25);

    /// The unicycle at (1, 2) with heading `heading`, speed `v` and turn
    /// rate `w`.
    fn unicycle_me(heading: f64, v: f64, w: f64) -> crate::SelfState {
        let velocity = Vec2::new(heading.cos(), heading.sin()) * v;
        ROBOT.unicycle(Vec2::new(1.0, 2.0), velocity, heading, w, 2.0, 4.0)
    }

    fn probe(answer: Command, native: bool) -> (LookAhead, impl Fn() -> (Vec2, Vec2, f64)) {
        let seen = std::sync::Arc::new(std::sync::Mutex::new(None));
        let p = Probe {
            answer,
            native,
            seen: seen.clone(),
        };
        let read = move || seen.lock().expect("probe").expect("planned");
        (LookAhead::new(Box::new(p), 0.05), read)
    }

    #[test]
    fn a_holonomic_planner_sees_the_look_ahead_point_and_a_smaller_tolerance() {
        let (mut la, seen) = probe(Command::Velocity(Vec2::new(0.5, 0.0)), false);
        let mut obs = observation(unicycle_me(FRAC_PI_2, 0.4, 1.0), Vec2::zeros(), &[]);
        obs.goal_tolerance = 0.1;
        la.plan(&obs);
        let (p, v, tol) = seen();
        assert!((p - Vec2::new(1.0, 2.05)).norm() < 1e-12, "{p}");
        // p' = v e + l omega e_perp = (0, 0.4) + 0.05 (-1, 0).
        assert!((v - Vec2::new(-0.05, 0.4)).norm() < 1e-12, "{v}");
        assert!((tol - 0.05).abs() < 1e-12, "{tol}");
    }

    #[test]
    fn a_planner_of_its_own_unicycle_commands_sees_the_robot_itself() {
        let answer = Command::Unicycle {
            v: 0.3,
            omega: -0.2,
        };
        let (mut la, seen) = probe(answer, true);
        let obs = observation(unicycle_me(0.3, 0.4, 1.0), Vec2::zeros(), &[]);
        assert_eq!(la.plan(&obs), answer);
        let (p, v, tol) = seen();
        assert_eq!(
            (p, v, tol),
            (obs.me.position, obs.me.velocity, obs.goal_tolerance)
        );
    }

    #[test]
    fn a_velocity_command_is_applied_to_the_look_ahead_point_unclamped() {
        // Heading +y, asked (0.5, 0): v = 0, omega = -0.5 / 0.05 = -10,
        // beyond the 2 rad/s limit: the world clamps it, not the controller.
        let (mut la, _) = probe(Command::Velocity(Vec2::new(0.5, 0.0)), false);
        let obs = observation(unicycle_me(FRAC_PI_2, 0.0, 0.0), Vec2::zeros(), &[]);
        let Command::Unicycle { v, omega } = la.plan(&obs) else {
            panic!("a unicycle command");
        };
        assert!(
            v.abs() < 1e-12 && (omega + 10.0).abs() < 1e-9,
            "{v} {omega}"
        );
    }

    #[test]
    fn a_force_becomes_the_velocity_it_gives_the_point_in_one_tick() {
        // At rest heading +x, a force of 10 N on 1 kg is clamped to
        // max_accel 2: u = 0.2 m/s along the force, here +x: v = 0.2.
        let (mut la, _) = probe(Command::Force(Vec2::new(10.0, 0.0)), false);
        let obs = observation(unicycle_me(0.0, 0.0, 0.0), Vec2::zeros(), &[]);
        let Command::Unicycle { v, omega } = la.plan(&obs) else {
            panic!("a unicycle command");
        };
        assert!(
            (v - 0.2).abs() < 1e-12 && omega.abs() < 1e-12,
            "{v} {omega}"
        );
    }

    #[test]
    fn a_holonomic_robot_gets_the_planner_command_unconverted() {
        let (mut la, seen) = probe(Command::Velocity(Vec2::new(0.5, 0.1)), false);
        let mut me = unicycle_me(0.0, 0.0, 0.0);
        me.kinematics = Kinematics::Holonomic;
        let obs = observation(me, Vec2::zeros(), &[]);
        assert_eq!(la.plan(&obs), Command::Velocity(Vec2::new(0.5, 0.1)));
        assert_eq!(seen().0, obs.me.position);
    }

    #[test]
    fn the_tolerance_seen_keeps_the_centre_within_the_world_tolerance() {
        let (tol, l) = (0.1, 0.04);
        let seen = LookAhead::tolerance_seen(tol, l);
        assert!((seen - 0.06).abs() < 1e-12);
        // p anywhere on the circle of radius `seen` around the goal, any
        // heading: the centre p - l e is within tol.
        for k in 0..16 {
            let a = k as f64 * 0.4;
            let p = Vec2::new(a.cos(), a.sin()) * seen;
            for j in 0..16 {
                let th = j as f64 * 0.4;
                let centre = p - Vec2::new(th.cos(), th.sin()) * l;
                assert!(centre.norm() <= tol + 1e-12);
            }
        }
        // A look-ahead as long as the tolerance leaves it unchanged.
        assert_eq!(LookAhead::tolerance_seen(0.1, 0.1), 0.1);
    }

    #[test]
    fn a_unicycle_at_its_goal_turns_in_place_the_short_way_to_its_goal_heading() {
        let answer = Command::Unicycle { v: 0.3, omega: 0.0 };
        let (la, _) = probe(answer, false);
        // Facing +x at its goal, asked to face -y (-90 degrees): turns
        // clockwise, standing, at sqrt(2 accel error) capped at 2 rad/s.
        let mut gh = GoalHeading::new(Box::new(la), -FRAC_PI_2);
        let mut obs = observation(unicycle_me(0.0, 0.0, 0.0), Vec2::new(1.0, 2.1), &[]);
        obs.goal_tolerance = 0.2;
        assert_eq!(
            gh.plan(&obs),
            Command::Unicycle {
                v: 0.0,
                omega: -2.0
            }
        );
        // Nearly there: slower, so that it stops on the heading.
        obs.me.heading = -FRAC_PI_2 + 0.02;
        let Command::Unicycle { v, omega } = gh.plan(&obs) else {
            panic!("a unicycle command");
        };
        assert_eq!(v, 0.0);
        assert!(
            (omega + (2.0f64 * 4.0 * 0.02).sqrt()).abs() < 1e-12,
            "{omega}"
        );
        // Away from its goal the planner drives it.
        obs.goal = Vec2::new(5.0, 2.0);
        assert_ne!(
            gh.plan(&obs),
            Command::Unicycle {
                v: 0.0,
                omega: -2.0
            }
        );
        assert!(matches!(gh.plan(&obs), Command::Unicycle { v, .. } if v != 0.0));
    }
}
