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
//! the current forward speed and turn rate; its disc and everything else
//! unchanged), so the planner's closed loop runs on a point that moves as
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
//! keeps the world's tolerance, so keep `lookahead` below `goal_tolerance`).
//!
//! **3. Saturation that keeps the direction.** T^-1 is exact only while
//! (v, omega) is within the robot's limits. The world clamps v to
//! ±`max_speed` and omega to ±`max_angular_speed` independently, and a
//! request beyond either (omega grows as 1/l: with l = 0.05 a sideways
//! 0.1 m/s already asks 2 rad/s) would then move p in another direction
//! than the planner asked: clamping omega alone keeps the forward part and
//! drops part of the sideways one, so p swerves less than asked, overshoots
//! and the planner's loop sees a motion it did not ask for. Since p' is
//! linear in (v, omega), scaling both by one factor s in (0, 1] scales p'
//! by s and keeps its direction; [`LookAhead::saturate`] takes the largest
//! such s that keeps (v, omega) within the speed limits and within what the
//! acceleration limits reach in one tick, the box
//! [v_c - max_accel dt, v_c + max_accel dt] x
//! [omega_c - max_angular_accel dt, omega_c + max_angular_accel dt] around
//! the current (v_c, omega_c) (the dynamic window of Fox, Burgard & Thrun,
//! section 3.1). If no s > 0 is reachable (the robot cannot slow its
//! current turn or speed enough in one tick), each of v and omega is
//! clamped to the box, which is the point of the box nearest the request
//! in the metric of p' (|T x|^2 = x_v^2 + l^2 x_omega^2, a weighted sum of
//! squares, whose nearest box point is the coordinate-wise clamp), and what
//! the world would do anyway. Siciliano et al. derive the linearising law
//! without input bounds; the common scaling of (v, omega) is our choice of
//! how to respect them, made so that the linearised closed loop p' = u
//! keeps holding in direction, only slower.
//!
//! **4. Planners that know the model.** A planner that plans (v, omega)
//! itself ([`Planner::native_unicycle`], [`crate::dwa`]) needs none of
//! this: it gets the robot's true observation (centre, heading, world
//! tolerance) and its command passes unchanged. A unicycle command from any
//! other planner also passes unchanged (it was planned for p). On a
//! holonomic robot nothing is converted.
//!
//! `l` is the robot's `lookahead` key: a small l follows u more tightly
//! but turns harder (omega grows as 1/l, so saturation scales p' down more
//! often), and the tolerance left to the planner is `goal_tolerance - l`.

use crate::{Command, Diagnostic, Kinematics, Observation, Planner, Vec2};

/// A planner made to drive a unicycle robot through its look-ahead point.
pub struct LookAhead {
    inner: Box<dyn Planner>,
    lookahead: f64,
}

/// A unicycle's limits as [`LookAhead::saturate`] uses them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limits {
    /// Forward-speed limit, m/s.
    pub max_speed: f64,
    /// Turn-rate limit, rad/s.
    pub max_angular_speed: f64,
    /// Forward-acceleration limit, m/s².
    pub max_accel: f64,
    /// Angular-acceleration limit, rad/s².
    pub max_angular_accel: f64,
}

impl LookAhead {
    /// Wraps `inner`; `lookahead` (> 0) is the distance l of the controlled
    /// point ahead of the centre.
    pub fn new(inner: Box<dyn Planner>, lookahead: f64) -> Self {
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

    /// The command the robot can follow for the request `asked` = (v, omega)
    /// from the current `current` = (v_c, omega_c) within `limits` over one
    /// tick `dt` (module documentation, 3): `asked` scaled by the largest
    /// s in (0, 1] that keeps it within the speed limits and the one-tick
    /// acceleration box, or, when no s > 0 does, `asked` clamped to the
    /// box.
    pub fn saturate(asked: (f64, f64), current: (f64, f64), limits: Limits, dt: f64) -> (f64, f64) {
        let dt = dt.max(0.0);
        let boxes = [
            (
                asked.0,
                (current.0 - limits.max_accel * dt).max(-limits.max_speed),
                (current.0 + limits.max_accel * dt).min(limits.max_speed),
            ),
            (
                asked.1,
                (current.1 - limits.max_angular_accel * dt).max(-limits.max_angular_speed),
                (current.1 + limits.max_angular_accel * dt).min(limits.max_angular_speed),
            ),
        ];
        // The s with s * x in [lo, hi] for each coordinate form an
        // interval; intersect them with (0, 1].
        let (mut s_lo, mut s_hi) = (0.0f64, 1.0f64);
        for &(x, lo, hi) in &boxes {
            if x > 0.0 {
                s_lo = s_lo.max(lo / x);
                s_hi = s_hi.min(hi / x);
            } else if x < 0.0 {
                s_lo = s_lo.max(hi / x);
                s_hi = s_hi.min(lo / x);
            } else if lo > 0.0 || hi < 0.0 {
                // 0 is outside the box: no multiple of x reaches it.
                s_hi = f64::NEG_INFINITY;
            }
        }
        if s_hi > 0.0 && s_lo <= s_hi {
            (asked.0 * s_hi, asked.1 * s_hi)
        } else {
            let clamp = |(x, lo, hi): (f64, f64, f64)| x.clamp(lo, hi.max(lo));
            (clamp(boxes[0]), clamp(boxes[1]))
        }
    }
}

impl Planner for LookAhead {
    fn plan(&mut self, obs: &Observation) -> Command {
        let Kinematics::Unicycle {
            max_angular_speed,
            max_angular_accel,
        } = obs.me.kinematics
        else {
            return self.inner.plan(obs);
        };
        if self.inner.native_unicycle() {
            return self.inner.plan(obs);
        }
        let l = self.lookahead;
        let (s, c) = obs.me.heading.sin_cos();
        let v_c = obs.me.velocity.dot(&Vec2::new(c, s));
        let w_c = obs.me.angular_velocity;
        let mut seen = *obs;
        seen.me.position += Vec2::new(c, s) * l;
        seen.me.velocity = Vec2::new(c, s) * v_c + Vec2::new(-s, c) * (l * w_c);
        seen.goal_tolerance = Self::tolerance_seen(obs.goal_tolerance, l);
        let me = &seen.me;
        let cmd = self.inner.plan(&seen);
        let u = match cmd {
            Command::Unicycle { .. } => return cmd,
            Command::Velocity(u) => u,
            Command::Force(f) => {
                let m = if me.mass > 0.0 { me.mass } else { 1.0 };
                let mut a = (f - me.velocity * me.damping) / m;
                if a.norm() > me.max_accel {
                    a *= me.max_accel / a.norm();
                }
                me.velocity + a * obs.dt
            }
        };
        let limits = Limits {
            max_speed: me.max_speed,
            max_angular_speed,
            max_accel: me.max_accel,
            max_angular_accel,
        };
        let asked = Self::unicycle_for(u, me.heading, l);
        let (v, omega) = Self::saturate(asked, (v_c, w_c), limits, obs.dt);
        Command::Unicycle { v, omega }
    }

    fn diagnostics(&self) -> Vec<Diagnostic> {
        self.inner.diagnostics()
    }

    fn native_unicycle(&self) -> bool {
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::FRAC_PI_2;

    const LIMITS: Limits = Limits {
        max_speed: 1.0,
        max_angular_speed: 2.0,
        max_accel: 2.0,
        max_angular_accel: 4.0,
    };

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

    #[test]
    fn a_request_within_the_limits_passes_unscaled() {
        let out = LookAhead::saturate((0.9, 1.0), (0.8, 0.8), LIMITS, 0.1);
        assert_eq!(out, (0.9, 1.0));
    }

    #[test]
    fn a_turn_beyond_the_turn_rate_limit_is_scaled_with_its_speed() {
        // Driving at 0.3 turning at 1.8, asked (0.5, 4): omega is capped at
        // 2, so both halve and p still moves in the asked direction.
        let (theta, l) = (0.7, 0.05);
        let asked = (0.5, 4.0);
        let (v, w) = LookAhead::saturate(asked, (0.3, 1.8), LIMITS, 0.1);
        assert!(
            (v - 0.25).abs() < 1e-12 && (w - 2.0).abs() < 1e-12,
            "{v} {w}"
        );
        let want = point_velocity(asked.0, asked.1, theta, l);
        let got = point_velocity(v, w, theta, l);
        let cross = want.x * got.y - want.y * got.x;
        assert!(cross.abs() < 1e-12 && want.dot(&got) > 0.0);
    }

    #[test]
    fn a_speed_beyond_the_speed_limit_is_scaled_with_its_turn() {
        let (v, w) = LookAhead::saturate((-2.0, 1.0), (-1.0, 0.5), LIMITS, 0.1);
        assert!(
            (v + 1.0).abs() < 1e-12 && (w - 0.5).abs() < 1e-12,
            "{v} {w}"
        );
    }

    #[test]
    fn a_turn_beyond_the_angular_acceleration_is_scaled_to_what_one_tick_reaches() {
        // From rest, omega reaches 0.4 in a tick of 0.1 s: (0.1, 2) -> (0.02, 0.4).
        let (v, w) = LookAhead::saturate((0.1, 2.0), (0.0, 0.0), LIMITS, 0.1);
        assert!(
            (v - 0.02).abs() < 1e-12 && (w - 0.4).abs() < 1e-12,
            "{v} {w}"
        );
    }

    #[test]
    fn a_request_no_scaling_reaches_is_clamped_to_the_reachable_box() {
        // Driving at 1 m/s, asked to turn on the spot: v cannot drop below
        // 0.8 in one tick, so no multiple of (0, 2) is reachable.
        let (v, w) = LookAhead::saturate((0.0, 2.0), (1.0, 0.0), LIMITS, 0.1);
        assert!(
            (v - 0.8).abs() < 1e-12 && (w - 0.4).abs() < 1e-12,
            "{v} {w}"
        );
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

    fn unicycle_me(heading: f64, v: f64, w: f64) -> crate::SelfState {
        crate::SelfState {
            id: 0,
            position: Vec2::new(1.0, 2.0),
            velocity: Vec2::new(heading.cos(), heading.sin()) * v,
            radius: 0.25,
            mass: 1.0,
            damping: 0.0,
            max_speed: LIMITS.max_speed,
            max_accel: LIMITS.max_accel,
            heading,
            angular_velocity: w,
            kinematics: Kinematics::Unicycle {
                max_angular_speed: LIMITS.max_angular_speed,
                max_angular_accel: LIMITS.max_angular_accel,
            },
        }
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
        let mut obs =
            crate::testkit::observation(unicycle_me(FRAC_PI_2, 0.4, 1.0), Vec2::zeros(), &[]);
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
        let obs = crate::testkit::observation(unicycle_me(0.3, 0.4, 1.0), Vec2::zeros(), &[]);
        assert_eq!(la.plan(&obs), answer);
        let (p, v, tol) = seen();
        assert_eq!(
            (p, v, tol),
            (obs.me.position, obs.me.velocity, obs.goal_tolerance)
        );
    }

    #[test]
    fn a_sideways_request_from_rest_turns_as_far_as_one_tick_allows() {
        // Heading +x at rest, asked 1 m/s along +y: T^-1 gives (0, 20);
        // one tick reaches omega = 0.4, so (0, 0.4), p moving along +y.
        let (mut la, _) = probe(Command::Velocity(Vec2::new(0.0, 1.0)), false);
        let obs = crate::testkit::observation(unicycle_me(0.0, 0.0, 0.0), Vec2::zeros(), &[]);
        let Command::Unicycle { v, omega } = la.plan(&obs) else {
            panic!("a unicycle command");
        };
        assert!(
            v.abs() < 1e-12 && (omega - 0.4).abs() < 1e-12,
            "{v} {omega}"
        );
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
}
