//! A car's path: arcs of its minimum turning radius and straight lines,
//! each driven forwards or backwards (crate documentation, "Cars").
//!
//! A [`CarPath`] is a start pose, a radius R and a list of [`Piece`]s; a
//! piece is an arc turning left, an arc turning right, or a straight, and a
//! signed length (negative: driven backwards). This is the form of the
//! paths of L. E. Dubins ("On curves of minimal length with a constraint on
//! average curvature...", Amer. J. Math. 79, 1957) and of J. A. Reeds &
//! L. A. Shepp ("Optimal paths for a car that goes both forwards and
//! backwards", Pacific J. Math. 145(2), 1990), and of every motion
//! primitive of Hybrid A*, so that the path a search returns is exact: its
//! curvature is 0 or 1/R everywhere, never more, and its poses are the
//! closed-form integrals of the pieces (section 8 of Reeds & Shepp, and
//! OMPL's `ReedsSheppStateSpace::interpolate`), not a sum of small steps.

use crate::P;
use mrsim_shape::Pose;

/// Which way a piece steers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Steer {
    /// An arc of radius R turning counter-clockwise when driven forwards.
    Left,
    /// A straight line.
    Straight,
    /// An arc of radius R turning clockwise when driven forwards.
    Right,
}

/// Which way a car drives.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Gear {
    /// Along its heading.
    Forward,
    /// Against its heading.
    Reverse,
}

/// One piece of a car's path: how it steers and how far it goes, signed
/// (negative: backwards, the heading unchanged in meaning: a left arc driven
/// backwards turns the heading clockwise).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Piece {
    /// How it steers.
    pub steer: Steer,
    /// Arc length, in the scenario's units; negative when driven backwards.
    pub length: f64,
}

impl Piece {
    /// Which way it is driven (a piece of no length counts as forwards).
    pub fn gear(&self) -> Gear {
        if self.length < 0.0 {
            Gear::Reverse
        } else {
            Gear::Forward
        }
    }

    /// The pose reached after `s` (signed, the same sign as the length, at
    /// most its size) of this piece from `from`, turning with radius
    /// `radius`.
    pub fn advance(&self, from: Pose, s: f64, radius: f64) -> Pose {
        advance(from, self.steer, s, radius)
    }
}

/// The pose after driving `s` (signed) from `from` steering `steer` at
/// radius `r`: the closed form of the kinematic car's motion,
/// `x' = cos h, y' = sin h, h' = u / r` with `u` in {1, 0, -1}.
pub(crate) fn advance(from: Pose, steer: Steer, s: f64, r: f64) -> Pose {
    let [x, y] = from.position;
    let h = from.heading;
    match steer {
        Steer::Straight => Pose::new([x + s * h.cos(), y + s * h.sin()], h),
        Steer::Left => {
            let v = s / r;
            Pose::new(
                [
                    x + r * ((h + v).sin() - h.sin()),
                    y + r * (h.cos() - (h + v).cos()),
                ],
                h + v,
            )
        }
        Steer::Right => {
            let v = s / r;
            Pose::new(
                [
                    x + r * (h.sin() - (h - v).sin()),
                    y + r * ((h - v).cos() - h.cos()),
                ],
                h - v,
            )
        }
    }
}

/// An angle wrapped into (-pi, pi].
pub fn wrap(a: f64) -> f64 {
    let t = std::f64::consts::TAU;
    let v = a - t * (a / t).round();
    if v <= -std::f64::consts::PI { v + t } else { v }
}

/// One pose of a sampled path: where the car's reference point is, its
/// heading, the gear it arrived in (the first pose: the gear it leaves in)
/// and the arc length driven from the start to it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CarPose {
    /// Position of the reference point (the footprint's origin).
    pub position: P,
    /// Heading, rad, wrapped into (-pi, pi].
    pub heading: f64,
    /// The gear of the motion that reached this pose.
    pub gear: Gear,
    /// Arc length from the path's start (forwards and backwards alike
    /// counted positive).
    pub s: f64,
}

impl CarPose {
    /// As a [`Pose`].
    pub fn pose(&self) -> Pose {
        Pose::new(self.position, self.heading)
    }
}

/// A path a car of minimum turning radius `radius` can drive: a start pose
/// and pieces (module documentation).
#[derive(Debug, Clone, PartialEq)]
pub struct CarPath {
    start: Pose,
    radius: f64,
    pieces: Vec<Piece>,
}

impl CarPath {
    /// The path from `start` through `pieces`, turning at `radius`; pieces
    /// of no length are dropped and consecutive pieces that steer and drive
    /// alike are joined.
    pub fn new(start: Pose, radius: f64, pieces: impl IntoIterator<Item = Piece>) -> Self {
        let mut out: Vec<Piece> = Vec::new();
        for p in pieces {
            if p.length.abs() < 1e-12 {
                continue;
            }
            match out.last_mut() {
                Some(q) if q.steer == p.steer && q.gear() == p.gear() => q.length += p.length,
                _ => out.push(p),
            }
        }
        Self {
            start,
            radius,
            pieces: out,
        }
    }

    /// Where it starts.
    pub fn start(&self) -> Pose {
        self.start
    }

    /// The turning radius of its arcs.
    pub fn radius(&self) -> f64 {
        self.radius
    }

    /// Its pieces, in order.
    pub fn pieces(&self) -> &[Piece] {
        &self.pieces
    }

    /// Its length: every piece's, forwards and backwards alike.
    pub fn length(&self) -> f64 {
        self.pieces.iter().map(|p| p.length.abs()).sum()
    }

    /// The pose it ends at (heading wrapped into (-pi, pi]).
    pub fn end(&self) -> Pose {
        let mut q = self.start;
        for p in &self.pieces {
            q = p.advance(q, p.length, self.radius);
        }
        Pose::new(q.position, wrap(q.heading))
    }

    /// How many times it changes between forwards and backwards (its
    /// cusps).
    pub fn gear_changes(&self) -> usize {
        self.pieces
            .windows(2)
            .filter(|w| w[0].gear() != w[1].gear())
            .count()
    }

    /// Its poses at most `step` apart along it: the start, every piece cut
    /// into equal parts no longer than `step`, and the end of every piece
    /// (so a cusp is always a pose). `step` is taken as at least a
    /// millionth of the length, so that a tiny or bad step cannot ask for
    /// unbounded memory.
    pub fn poses(&self, step: f64) -> Vec<CarPose> {
        let step = if step.is_finite() && step > 0.0 {
            step.max(self.length() * 1e-6)
        } else {
            self.length().max(1.0)
        };
        let first = self.pieces.first().map_or(Gear::Forward, Piece::gear);
        let mut out = vec![CarPose {
            position: self.start.position,
            heading: wrap(self.start.heading),
            gear: first,
            s: 0.0,
        }];
        let mut q = self.start;
        let mut s0 = 0.0;
        for p in &self.pieces {
            let n = (p.length.abs() / step).ceil().max(1.0) as usize;
            for k in 1..=n {
                let part = p.length * k as f64 / n as f64;
                let at = p.advance(q, part, self.radius);
                out.push(CarPose {
                    position: at.position,
                    heading: wrap(at.heading),
                    gear: p.gear(),
                    s: s0 + part.abs(),
                });
            }
            q = p.advance(q, p.length, self.radius);
            s0 += p.length.abs();
        }
        out
    }
}

/// The least turning radius of a kinematic bicycle with `wheelbase` and
/// steering at most `max_steering` (rad): R = wheelbase / tan(max_steering),
/// the radius its rear axle's centre turns on (R. Rajamani, "Vehicle
/// Dynamics and Control", 2nd ed., 2012, section 2.2). A point `offset`
/// ahead of the rear axle turns on sqrt(R^2 + offset^2): a path planned for
/// the footprint's centre of a car whose centre is not over its rear axle
/// should be planned with that radius.
pub fn turning_radius(wheelbase: f64, max_steering: f64, offset: f64) -> f64 {
    let r = wheelbase / max_steering.tan();
    r.hypot(offset)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn a_backward_left_arc_turns_the_heading_clockwise() {
        let q = advance(Pose::new([0.0, 0.0], 0.0), Steer::Left, -1.0, 1.0);
        assert!((q.heading + 1.0).abs() < 1e-12);
        assert!(q.position[0] < 0.0 && q.position[1] > 0.0, "{q:?}");
    }

    #[test]
    fn the_turning_radius_is_the_wheelbase_over_the_tangent_of_the_steering() {
        let r = turning_radius(3.0, 35f64.to_radians(), 0.0);
        assert!((r - 4.2845).abs() < 1e-3, "{r}");
        assert!((turning_radius(3.0, PI / 4.0, 4.0) - 5.0).abs() < 1e-12);
    }
}
