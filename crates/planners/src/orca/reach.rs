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
