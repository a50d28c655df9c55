//! The velocities a unicycle's look-ahead point can reach within one tick,
//! as ORCA half-planes (after J. Alonso-Mora, A. Breitenmoser, M. Rufli,
//! P. Beardsley & R. Siegwart, "Optimal Reciprocal Collision Avoidance for
//! Multiple Non-Holonomic Robots", DARS 2010: ORCA's new velocity is chosen
//! only among those the non-holonomic robot can actually track).
//!
//! A unicycle driven through its look-ahead point p ([`crate::unicycle`])
//! moves p at p' = v h + l omega n (h the unit heading, n = h rotated a
//! quarter turn left). Within one tick dt the world moves v at most
//! `max_accel` dt and omega at most `max_angular_accel` dt from where they
//! are, and keeps them within ±`max_speed` and ±`max_angular_speed`. So the
//! p' it can give is the box
//!
//! v_lo <= p' . h <= v_hi,  l omega_lo <= p' . n <= l omega_hi,
//!
//! axis-aligned in the robot's frame. Plain ORCA picks its velocity from
//! the whole speed disc; asked for one outside the box, the world clamps v
//! and omega each on its own, and p moves mostly along the heading instead
//! of where ORCA found room (a robot at rest facing away from where it must
//! go backs straight out along its heading). Within the box, ORCA's choice
//! is what the robot does in the next tick, so the room ORCA keeps from
//! other robots is kept by the real motion. Without other constraints the
//! box changes nothing: the point of the box closest to the preferred
//! velocity is the componentwise clamp that the world applies anyway.

use super::linear_program::Line;
use crate::{Kinematics, SelfState, Vec2};

/// The half-plane {x : x . e >= c}, as an ORCA line (admissible side on
/// the left of its direction).
fn at_least(e: Vec2, c: f64) -> Line {
    Line {
        point: e * c,
        direction: Vec2::new(e.y, -e.x),
    }
}

/// The four half-planes of the velocities the look-ahead point `lookahead`
/// ahead of the robot can reach within `dt`, for a unicycle `me` observed
/// at that point; `None` for a holonomic robot or without a look-ahead.
pub(super) fn reachable(me: &SelfState, lookahead: f64, dt: f64) -> Option<[Line; 4]> {
    let Kinematics::Unicycle {
        max_angular_speed,
        max_angular_accel,
    } = me.kinematics
    else {
        return None;
    };
    if lookahead <= 0.0 || dt <= 0.0 {
        return None;
    }
    let (sin, cos) = me.heading.sin_cos();
    let h = Vec2::new(cos, sin);
    let n = Vec2::new(-sin, cos);
    let v = me.velocity.dot(&h);
    let dv = me.max_accel * dt;
    let v_lo = (v - dv).clamp(-me.max_speed, me.max_speed);
    let v_hi = (v + dv).clamp(-me.max_speed, me.max_speed);
    let w = me.angular_velocity;
    let dw = max_angular_accel * dt;
    let w_lo = (w - dw).clamp(-max_angular_speed, max_angular_speed);
    let w_hi = (w + dw).clamp(-max_angular_speed, max_angular_speed);
    Some([
        // Braking or reversing: at most max_accel dt slower than now.
        at_least(h, v_lo),
        // Speeding up: at most max_accel dt faster than now.
        at_least(-h, -v_hi),
        // Turning right: p moves sideways at l omega.
        at_least(n, lookahead * w_lo),
        // Turning left.
        at_least(-n, -lookahead * w_hi),
    ])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testkit::RobotModel;

    /// A Pioneer-like robot: 0.6 m/s, 1 m/s², 1.8 rad/s, 3 rad/s².
    const PIONEER: RobotModel = RobotModel {
        max_speed: 0.6,
        max_accel: 1.0,
        ..RobotModel::unit(0.25)
    };

    /// The robot seen at its look-ahead point (0.1 ahead), driving at `v`
    /// and turning at `w`.
    fn unicycle(heading: f64, v: f64, w: f64) -> SelfState {
        let (s, c) = heading.sin_cos();
        let p_dot = Vec2::new(c, s) * v + Vec2::new(-s, c) * (0.1 * w);
        PIONEER.unicycle(Vec2::zeros(), p_dot, heading, w, 1.8, 3.0)
    }

    fn inside(lines: &[Line; 4], x: Vec2) -> bool {
        lines.iter().all(|l| l.violation(x) <= 1e-12)
    }

    #[test]
    fn a_robot_at_rest_reaches_a_tick_of_acceleration_along_its_heading_and_a_tick_of_turn_sideways()
     {
        let heading = 0.6_f64;
        let lines = reachable(&unicycle(heading, 0.0, 0.0), 0.1, 0.1).expect("a unicycle");
        let h = Vec2::new(heading.cos(), heading.sin());
        let n = Vec2::new(-heading.sin(), heading.cos());
        // Corners: v = ±0.1 m/s, l omega = ±0.1 * 0.3 = ±0.03 m/s.
        for &(a, b) in &[(0.1, 0.03), (-0.1, 0.03), (0.1, -0.03), (-0.1, -0.03)] {
            assert!(inside(&lines, h * a + n * b));
            assert!(!inside(&lines, h * (a * 1.01) + n * b));
            assert!(!inside(&lines, h * a + n * (b * 1.01)));
        }
        // Backing out at full speed is out of reach.
        assert!(!inside(&lines, h * -0.6));
    }

    #[test]
    fn the_box_is_centred_on_the_current_motion_and_kept_within_the_limits() {
        let lines = reachable(&unicycle(0.0, 0.55, 1.7), 0.1, 0.1).expect("a unicycle");
        // v in [0.45, 0.6], omega in [1.4, 1.8].
        assert!(inside(&lines, Vec2::new(0.6, 0.18)));
        assert!(inside(&lines, Vec2::new(0.45, 0.14)));
        assert!(!inside(&lines, Vec2::new(0.61, 0.16)));
        assert!(!inside(&lines, Vec2::new(0.5, 0.181)));
        assert!(!inside(&lines, Vec2::new(0.44, 0.16)));
        assert!(!inside(&lines, Vec2::new(0.5, 0.139)));
    }

    #[test]
    fn a_holonomic_robot_or_one_without_a_look_ahead_has_no_box() {
        let mut me = unicycle(0.0, 0.0, 0.0);
        assert!(reachable(&me, 0.0, 0.1).is_none());
        me.kinematics = Kinematics::Holonomic;
        assert!(reachable(&me, 0.1, 0.1).is_none());
    }
}
