//! dwa with the robot's true footprint: the admissibility and clearance
//! tests of Fox, Burgard & Thrun (1997, section 3.1) for a robot that is
//! a rectangle or a convex polygon, checked with its polygon at each
//! sampled pose along the motion, not with the disc around it (module
//! documentation of `dwa`, "True footprints").
//!
//! A motion is a [`Rollout`]: the robot's poses at times k h. Walls and
//! other bodies are checked at the sampled poses only, by the signed
//! surface gap of `mrsim-shape` (polygon against segment, polygon against
//! the other's disc or polygon), and the samples are skipped by
//! conservative advancement (Mirtich 1996): no point of the footprint
//! moves faster than [`Rollout::reach`], so a gap g leaves the next g /
//! (reach h) samples clear. A contact is a gap below the padding (the
//! robot keeps that much from everything), or, when the robot already
//! stands nearer than that, below the gap it has now: what would take it
//! nearer is a contact, moving along or away is not.

use super::brake::braking_distance;
use super::walls::WallGrid;
use crate::{BodyKind, Segment, Sensed, Shape, Vec2};
use mrsim_shape::{Placement, Pose, placed_gap, placed_gap_to_segment};

/// The robot's sampled motion: poses (position, heading) at times k h,
/// k = 0, 1, ...
pub(super) struct Rollout {
    /// The sampling step, s.
    pub(super) h: f64,
    /// Poses, the first the robot's present one.
    pub(super) poses: Vec<(Vec2, f64)>,
    /// A bound on the speed of any point of the footprint between two
    /// samples: the centre's chord plus the turn times the circumscribed
    /// radius, per step.
    pub(super) reach: f64,
}

impl Rollout {
    /// The rollout of `poses` sampled every `h` by a footprint of
    /// circumscribed radius `radius`.
    pub(super) fn new(h: f64, poses: Vec<(Vec2, f64)>, radius: f64) -> Self {
        let reach = poses
            .windows(2)
            .map(|w| ((w[1].0 - w[0].0).norm() + (w[1].1 - w[0].1).abs() * radius) / h)
            .fold(0.0, f64::max);
        Self { h, poses, reach }
    }

    /// The time of sample `k`.
    fn time(&self, k: usize) -> f64 {
        k as f64 * self.h
    }
}

/// How another body is taken to move along a rollout.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Motion {
    /// At its sensed velocity throughout (its heading held).
    Constant,
    /// Standing where it is (it plans too, and may stop).
    Still,
    /// At its velocity for `delay`, then braking at `a` to rest, straight
    /// on; a scripted obstacle does not brake (module documentation of
    /// `dwa`, "Both could stop").
    Braking {
        /// How long it goes on, s.
        delay: f64,
        /// Its deceleration.
        a: f64,
    },
}

/// Where body `o` is at time `t` moving by `motion`.
fn body_at(o: &Sensed, motion: Motion, t: f64) -> Vec2 {
    match motion {
        Motion::Constant => o.position + o.velocity * t,
        Motion::Still => o.position,
        Motion::Braking { delay, a } => {
            let a = if o.kind == BodyKind::Robot { a } else { 0.0 };
            let u = o.velocity.norm();
            if u <= 1e-12 {
                return o.position;
            }
            o.position + o.velocity * (braking_distance(u, a, delay, t) / u)
        }
    }
}

/// The body's speed bound under `motion`.
fn body_speed(o: &Sensed, motion: Motion) -> f64 {
    match motion {
        Motion::Still => 0.0,
        _ => o.velocity.norm(),
    }
}

/// The gap below which a body now `g0` away counts as touched: the
/// padding, or, when nearer already, just under the present gap.
fn threshold(pad: f64, g0: f64) -> f64 {
    if g0 > pad {
        pad
    } else {
        g0 - 1e-9 - 1e-6 * g0.abs()
    }
}

/// The robot's footprint and what it is checked against this tick.
pub(super) struct Footprint<'a> {
    /// The robot's shape (body frame).
    shape: Shape,
    /// Its circumscribed radius.
    radius: f64,
    /// The run's walls and their grid ([`WallGrid::near`] done this tick
    /// for the robot's reach).
    walls: &'a [Segment],
    grid: &'a mut WallGrid,
    buf: Vec<u32>,
    /// Whether any wall is within reach.
    any_walls: bool,
    /// The walls' contact gap.
    wall_threshold: f64,
    /// The sensed bodies and each one's contact gap.
    others: &'a [Sensed],
    other_threshold: Vec<f64>,
}

impl<'a> Footprint<'a> {
    /// The robot of `shape` at `pose`, keeping `pad` from everything,
    /// among `walls` (`grid` prepared and its `near` done for this tick;
    /// `any_walls` whether it found any) and `others`.
    pub(super) fn new(
        shape: Shape,
        pose: (Vec2, f64),
        pad: f64,
        walls: &'a [Segment],
        grid: &'a mut WallGrid,
        any_walls: bool,
        others: &'a [Sensed],
    ) -> Self {
        let mut f = Self {
            shape,
            radius: shape.circumradius(),
            walls,
            grid,
            buf: Vec::new(),
            any_walls,
            wall_threshold: pad,
            others,
            other_threshold: Vec::new(),
        };
        let here = f.place(pose);
        let g0 = f.wall_gap(&here, pose.0, f64::INFINITY);
        f.wall_threshold = threshold(pad, g0);
        f.other_threshold = others
            .iter()
            .map(|o| threshold(pad, placed_gap(&here, &Placement::of(&o.shape, o.pose()))))
            .collect();
        f
    }

    /// The footprint at `pose`.
    fn place(&self, pose: (Vec2, f64)) -> Placement {
        Placement::of(&self.shape, Pose::new([pose.0.x, pose.0.y], pose.1))
    }

    /// The least gap from the placed footprint (centre `c`) to the walls
    /// near it, or `cap` if none is within `cap` of it.
    fn wall_gap(&mut self, at: &Placement, c: Vec2, cap: f64) -> f64 {
        if !self.any_walls {
            return cap;
        }
        let r = Vec2::repeat(self.radius + cap.min(1e6) + 1e-9);
        self.grid.query_near(c - r, c + r, &mut self.buf);
        let mut g = cap;
        for &k in &self.buf {
            let w = &self.walls[k as usize];
            g = g.min(placed_gap_to_segment(at, [[w.a.x, w.a.y], [w.b.x, w.b.y]]));
        }
        g
    }

    /// The time of the first sample of `r` at which the footprint comes
    /// within its contact gap of a wall (infinite if none).
    pub(super) fn wall_contact(&mut self, r: &Rollout) -> f64 {
        if !self.any_walls {
            return f64::INFINITY;
        }
        let step = (r.reach * r.h).max(1e-12);
        // Look this far round each sample: enough to skip a few samples.
        let cap = self.wall_threshold.max(0.0) + 4.0 * step;
        let mut k = 0;
        while k < r.poses.len() {
            let at = self.place(r.poses[k]);
            let g = self.wall_gap(&at, r.poses[k].0, cap);
            if k > 0 && g < self.wall_threshold {
                return r.time(k);
            }
            k += (((g - self.wall_threshold) / step).floor() as usize).max(1);
        }
        f64::INFINITY
    }

    /// The time of the first sample of `r` at which the footprint comes
    /// within its contact gap of another body moving by `motion`
    /// (infinite if none); when `driving_into`, a contact counts only if
    /// the robot's own motion since the sample before brought it nearer
    /// (one the other runs into from behind or the side does not).
    pub(super) fn body_contact(&self, r: &Rollout, motion: Motion, driving_into: bool) -> f64 {
        let mut first = f64::INFINITY;
        for (o, &thr) in self.others.iter().zip(&self.other_threshold) {
            let step = ((r.reach + body_speed(o, motion)) * r.h).max(1e-12);
            let place_o = |t: f64| {
                let p = body_at(o, motion, t);
                Placement::of(&o.shape, Pose::new([p.x, p.y], o.heading))
            };
            let mut k = 1;
            while k < r.poses.len() && r.time(k) < first {
                let other = place_o(r.time(k));
                let g = placed_gap(&self.place(r.poses[k]), &other);
                if g < thr && (!driving_into || placed_gap(&self.place(r.poses[k - 1]), &other) > g)
                {
                    first = first.min(r.time(k));
                    break;
                }
                k += (((g - thr) / step).floor() as usize).max(1);
            }
        }
        first
    }

    /// The first contact along `r` with walls, or with the others moving
    /// by any of `motions`.
    pub(super) fn contact(&mut self, r: &Rollout, motions: &[Motion], driving_into: bool) -> f64 {
        let mut t = self.wall_contact(r);
        for &m in motions {
            t = t.min(self.body_contact(r, m, driving_into));
        }
        t
    }

    /// The nearest wall or body from the footprint at `pose`: its true
    /// gap, and the direction towards it from the robot's centre in the
    /// world (a unit vector; zero if nothing is near).
    pub(super) fn nearest(&mut self, pose: (Vec2, f64), reach: f64) -> (f64, Vec2) {
        let here = self.place(pose);
        let mut best = (f64::INFINITY, Vec2::zeros());
        let mut take = |g: f64, d: Vec2| {
            if g < best.0 {
                let n = d.norm();
                best = (g, if n > 0.0 { d / n } else { Vec2::zeros() });
            }
        };
        if self.any_walls {
            let r = Vec2::repeat(self.radius + reach);
            self.grid.query_near(pose.0 - r, pose.0 + r, &mut self.buf);
            for &k in &self.buf {
                let w = &self.walls[k as usize];
                let g = placed_gap_to_segment(&here, [[w.a.x, w.a.y], [w.b.x, w.b.y]]);
                take(g, w.closest_point(pose.0) - pose.0);
            }
        }
        for o in self.others {
            let g = placed_gap(&here, &Placement::of(&o.shape, o.pose()));
            take(g, o.position - pose.0);
        }
        best
    }
}

/// The poses of a unicycle driving (v, omega) from `pose`, sampled every
/// `h`: held for `hold` s (whole samples), then, when `brake` gives the
/// decelerations (a, alpha), both slowed to rest; without, held up to
/// `horizon` s.
pub(super) fn unicycle_poses(
    pose: (Vec2, f64),
    v: f64,
    omega: f64,
    hold: f64,
    brake: Option<(f64, f64)>,
    h: f64,
    horizon: f64,
) -> Vec<(Vec2, f64)> {
    let (mut p, mut th) = pose;
    let mut out = vec![pose];
    let (mut u, mut w) = (v, omega);
    let held = (hold / h).round() as usize;
    let steps = match brake {
        Some((a, alpha)) => {
            let stop = (v.abs() / a.max(1e-9)).max(omega.abs() / alpha.max(1e-9));
            held + (stop / h).ceil() as usize + 1
        }
        None => (horizon / h).ceil() as usize,
    };
    for i in 0..steps.min(100_000) {
        let (u0, w0) = (u, w);
        if let Some((a, alpha)) = brake
            && i >= held
        {
            u = u.signum() * (u.abs() - a * h).max(0.0);
            w = w.signum() * (w.abs() - alpha * h).max(0.0);
        }
        let (um, wm) = (0.5 * (u0 + u), 0.5 * (w0 + w));
        let mid = th + 0.5 * wm * h;
        p += Vec2::new(mid.cos(), mid.sin()) * (um * h);
        th += wm * h;
        out.push((p, th));
        if brake.is_some() && u == 0.0 && w == 0.0 {
            break;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testkit::robot;
    use crate::{Polygon, Shape};

    fn agv() -> Shape {
        Shape::Polygon(Polygon::rectangle(0.9, 0.6).unwrap())
    }

    fn seg(ax: f64, ay: f64, bx: f64, by: f64) -> Segment {
        Segment {
            a: Vec2::new(ax, ay),
            b: Vec2::new(bx, by),
        }
    }

    #[test]
    fn a_rectangle_drives_through_a_door_its_circumscribed_disc_does_not_fit() {
        // A door 1.2 wide in a wall at x = 2 (jambs at y = +-0.6): the
        // 0.9 x 0.6 rectangle (disc 0.54, padded 0.675: 1.35 > 1.2)
        // driving straight along y = 0 keeps 0.3 from each jamb.
        let walls = [seg(2.0, 0.6, 2.0, 5.0), seg(2.0, -0.6, 2.0, -5.0)];
        let mut grid = WallGrid::default();
        grid.prepare(&walls, 1.0);
        let any = !grid.near(&walls, Vec2::zeros(), 10.0).is_empty();
        let mut f = Footprint::new(
            agv(),
            (Vec2::zeros(), 0.0),
            0.075,
            &walls,
            &mut grid,
            any,
            &[],
        );
        let poses = unicycle_poses((Vec2::zeros(), 0.0), 0.8, 0.0, 5.0, None, 0.05, 5.0);
        let r = Rollout::new(0.05, poses, 0.54);
        assert!(f.wall_contact(&r).is_infinite());
        // Off the middle by 0.3, its side is in line with a jamb's end:
        // its front corner comes within the padding of it when its nose
        // is 0.075 short of the wall, after (2 - 0.45 - 0.075) / 0.8 s,
        // at the first sample after that.
        let mut f = Footprint::new(
            agv(),
            (Vec2::new(0.0, 0.3), 0.0),
            0.075,
            &walls,
            &mut grid,
            any,
            &[],
        );
        let poses = unicycle_poses((Vec2::new(0.0, 0.3), 0.0), 0.8, 0.0, 5.0, None, 0.05, 5.0);
        let t = f.wall_contact(&Rollout::new(0.05, poses, 0.54));
        let want = (2.0 - 0.45 - 0.075) / 0.8;
        assert!(t >= want && t <= want + 0.05 + 1e-9, "{t} vs {want}");
    }

    #[test]
    fn a_body_is_met_where_the_rectangles_touch() {
        // Two AGVs side by side, 0.1 apart: the robot turning in place
        // swings its corners into the other (its disc already overlaps);
        // driving straight on passes it.
        let other = [robot(1, Vec2::new(0.0, 0.7), Vec2::zeros(), 0.54).shaped(agv(), 0.0)];
        let walls: [Segment; 0] = [];
        let mut grid = WallGrid::default();
        let f = Footprint::new(
            agv(),
            (Vec2::zeros(), 0.0),
            0.05,
            &walls,
            &mut grid,
            false,
            &other,
        );
        let straight = unicycle_poses((Vec2::zeros(), 0.0), 0.5, 0.0, 3.0, None, 0.05, 3.0);
        let r = Rollout::new(0.05, straight, 0.54);
        assert!(f.body_contact(&r, Motion::Still, true).is_infinite());
        let turn = unicycle_poses((Vec2::zeros(), 0.0), 0.0, 1.0, 3.0, None, 0.05, 3.0);
        let t = f.body_contact(&Rollout::new(0.05, turn, 0.54), Motion::Still, true);
        assert!(t > 0.0 && t < 0.5, "{t}");
    }

    #[test]
    fn braking_poses_come_to_rest_after_the_held_tick() {
        // 0.8 m/s held 0.1 s, then braking at 0.8 m/s^2: 0.08 + 0.4 m.
        let poses = unicycle_poses(
            (Vec2::zeros(), 0.0),
            0.8,
            0.0,
            0.1,
            Some((0.8, 3.0)),
            0.01,
            3.0,
        );
        let end = poses.last().unwrap().0;
        assert!((end.x - 0.48).abs() < 1e-6, "{end:?}");
    }
}
