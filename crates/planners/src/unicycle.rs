//! Holonomic planners on a unicycle (differential-drive) robot: the
//! look-ahead point controller, input/output feedback linearisation of the
//! unicycle about a point off its wheel axis (B. Siciliano, L. Sciavicco,
//! L. Villani & G. Oriolo, "Robotics: Modelling, Planning and Control",
//! Springer 2009, chapter 11, trajectory tracking of a point B at distance
//! b along the sagittal axis; the same construction as J. R. Lawton,
//! R. W. Beard & B. J. Young, IEEE T-RA 19(6), 2003, "hand position").
//!
//! The unicycle x' = v cos theta, y' = v sin theta, theta' = omega cannot
//! move sideways, but the point p = (x, y) + l (cos theta, sin theta) at
//! distance l ahead of its centre can move in any direction:
//!
//! p' = [cos theta, -l sin theta; sin theta, l cos theta] (v, omega),
//!
//! a matrix of determinant l, invertible for l > 0. So a planar velocity u
//! asked of p is obtained exactly by
//!
//! v = cos theta u_x + sin theta u_y,
//! omega = (-sin theta u_x + cos theta u_y) / l.
//!
//! [`LookAhead`] wraps any planner: the planner sees the robot as the
//! point p (its observation's position and velocity are p's, p' = the
//! matrix above times the current (v, omega); its disc, goal and everything
//! else unchanged), so the planner's closed loop runs on a point that
//! moves exactly as asked, and p, not the centre, is brought to the goal:
//! the centre stops within l of it, so l should be below the goal
//! tolerance. A velocity command u is applied to p through the inverse
//! above; a force f becomes the velocity it would give
//! p in one tick under m r'' + b r' = f with the world's acceleration
//! clamp, u = p' + dt clamp((f - b p') / m, max_accel); a
//! unicycle command (a planner that knows the model, such as
//! [`crate::dwa`]) passes unchanged, and on a holonomic robot nothing is
//! converted. The world then enforces the speed, turn-rate and acceleration
//! limits. `l` is the robot's `lookahead` key: small l follows u more
//! tightly but turns harder (omega grows as 1/l).

use crate::{Command, Diagnostic, Kinematics, Observation, Planner, Vec2};

/// A planner made to drive a unicycle robot through its look-ahead point.
pub struct LookAhead {
    inner: Box<dyn Planner>,
    lookahead: f64,
}

impl LookAhead {
    /// Wraps `inner`; `lookahead` (> 0) is the distance l of the controlled
    /// point ahead of the centre.
    pub fn new(inner: Box<dyn Planner>, lookahead: f64) -> Self {
        Self { inner, lookahead }
    }

    /// (v, omega) that move the look-ahead point at `u` from heading
    /// `theta`.
    pub fn unicycle_for(u: Vec2, theta: f64, lookahead: f64) -> (f64, f64) {
        let (s, c) = theta.sin_cos();
        (c * u.x + s * u.y, (-s * u.x + c * u.y) / lookahead)
    }
}

impl Planner for LookAhead {
    fn plan(&mut self, obs: &Observation) -> Command {
        if obs.me.kinematics == Kinematics::Holonomic {
            return self.inner.plan(obs);
        }
        let l = self.lookahead;
        let (s, c) = obs.me.heading.sin_cos();
        let mut seen = *obs;
        seen.me.position += Vec2::new(c, s) * l;
        seen.me.velocity += Vec2::new(-s, c) * (l * obs.me.angular_velocity);
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
        let (v, omega) = Self::unicycle_for(u, me.heading, l);
        Command::Unicycle { v, omega }
    }

    fn diagnostics(&self) -> Vec<Diagnostic> {
        self.inner.diagnostics()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::FRAC_PI_2;

    #[test]
    fn the_inverse_gives_the_look_ahead_point_the_asked_velocity() {
        for &(theta, u) in &[
            (0.3, Vec2::new(1.0, -0.5)),
            (2.5, Vec2::new(-0.2, 0.7)),
            (-1.0, Vec2::new(0.0, 1.0)),
        ] {
            let l = 0.2;
            let (v, w) = LookAhead::unicycle_for(u, theta, l);
            let (s, c) = f64::sin_cos(theta);
            let p_dot = Vec2::new(c * v - l * s * w, s * v + l * c * w);
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
}
