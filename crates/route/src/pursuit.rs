//! Following a car's path: pure pursuit, segment by segment between cusps.
//!
//! R. C. Coulter, "Implementation of the pure pursuit path tracking
//! algorithm", CMU-RI-TR-92-01, 1992: the vehicle steers along the arc
//! through its position, tangent to its heading, that passes through the
//! *goal point*, the path's point a look-ahead distance on; in the
//! vehicle's frame, with the goal point at lateral offset `y` and distance
//! `l`, the arc's curvature is `2 y / l^2` (Coulter's derivation writes it
//! `2 x / l^2`, his x being the lateral offset; the steering of a bicycle
//! of wheelbase `L` is then `atan(2 L y / l^2)`).
//!
//! A path of Hybrid A* or Reeds-Shepp changes gear at its cusps, where a
//! pursuit that looked past them would cut the corner, so [`Pursuit`]
//! follows one *segment* (the run of poses between two cusps, driven in one
//! gear) at a time, as nav2's Regulated Pure Pursuit controller does: the
//! goal point is never beyond the segment's end, and the next segment is
//! taken once the car is within [`Pursuit::new`]'s `at_cusp` of that end
//! (S. Macenski et al., "Regulated Pure Pursuit for Robot Path Tracking",
//! Autonomous Robots 47, 2023).
//! Backwards the car pursues the point behind it, and with the goal point's
//! lateral offset taken in the car's own frame the same formula gives the
//! steering in both gears: the curvature a command applies as `turn rate =
//! signed speed * curvature` (for a bicycle, `tan(steering) / L`).
//!
//! What a planner is given: [`Target`], the goal point with the path's
//! heading there and the gear, the pursuit's curvature, and how far the
//! car has to go to the segment's end (where it must stop, at a cusp or
//! at the goal): the waypoint a disc's planner gets from [`crate::Follower`],
//! with a heading and a gear; or, for a car driven directly, the curvature
//! and the gear give the (speed, steering) command ([`Target::steering`]).

use crate::drive::{CarPath, CarPose, Gear, wrap};
use crate::{P, dist};
use mrsim_shape::Pose;

/// What to steer for: the goal point of the pursuit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Target {
    /// The goal point: the path's point the look-ahead on from the car's
    /// projection, or, past the segment's end, on the line of the end's
    /// heading (module documentation).
    pub point: P,
    /// The path's heading at the goal point (at the segment's end, past
    /// it), rad.
    pub heading: f64,
    /// The gear to drive in (the segment's).
    pub gear: Gear,
    /// The pursuit arc's curvature `2 y / l^2`, `y` the goal point's offset
    /// to the car's left and `l` its distance: a turn rate of `signed speed
    /// * curvature` (1/length; 0 when the goal point is where the car is).
    pub curvature: f64,
    /// Distance along the path from the car's projection to the segment's
    /// end: where the car must stop (a cusp, or the goal).
    pub to_stop: f64,
    /// Is the segment the path's last (its end the goal)?
    pub last: bool,
}

impl Target {
    /// The steering angle of a bicycle of `wheelbase` that drives the
    /// pursuit arc, `atan(wheelbase * curvature)`, within
    /// `[-max_steering, max_steering]`.
    pub fn steering(&self, wheelbase: f64, max_steering: f64) -> f64 {
        (wheelbase * self.curvature)
            .atan()
            .clamp(-max_steering, max_steering)
    }
}

/// Leads a car along a [`CarPath`] by pure pursuit (module documentation).
#[derive(Debug, Clone)]
pub struct Pursuit {
    poses: Vec<CarPose>,
    /// Index ranges of the segments: `(first, last)` pose, inclusive; a
    /// cusp is the last pose of one and the first of the next.
    segments: Vec<(usize, usize)>,
    seg: usize,
    /// Arc length along the path of the car's projection (never less).
    progress: f64,
    lookahead: f64,
    /// How far on the goal point is ([`Pursuit::set_lookahead`]).
    reach: f64,
    at_cusp: f64,
    patience: f64,
    /// Progress at the last time it grew by a quarter of the look-ahead,
    /// and that time.
    mark: (f64, f64),
}

/// The segments of sampled poses: runs of one gear.
fn segments(poses: &[CarPose]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut first = 0;
    for k in 1..poses.len() {
        if k + 1 < poses.len() && poses[k + 1].gear != poses[k].gear {
            out.push((first, k));
            first = k;
        }
    }
    out.push((first, poses.len().saturating_sub(1)));
    out
}

impl Pursuit {
    /// Follows `path` with goal points `lookahead` on (> 0), taking the
    /// next segment within `at_cusp` of a cusp, and counting the car stuck
    /// after `patience` s without advancing by a quarter of the look-ahead.
    pub fn new(path: &CarPath, lookahead: f64, at_cusp: f64, patience: f64) -> Self {
        let step = (lookahead / 8.0).min(path.radius() / 8.0).max(1e-3);
        let poses = path.poses(step);
        Self {
            segments: segments(&poses),
            poses,
            seg: 0,
            progress: 0.0,
            lookahead,
            reach: lookahead,
            at_cusp,
            patience,
            mark: (0.0, f64::NAN),
        }
    }

    /// Puts the goal point `reach` on (> 0) from now on, as regulated pure
    /// pursuit scales its look-ahead with the speed (Macenski et al.
    /// 2023); the projection and [`Pursuit::stuck`] keep the look-ahead
    /// the pursuit was made with.
    pub fn set_lookahead(&mut self, reach: f64) {
        if reach.is_finite() && reach > 0.0 {
            self.reach = reach;
        }
    }

    /// The path's sampled poses.
    pub fn poses(&self) -> &[CarPose] {
        &self.poses
    }

    /// Which segment is followed (0-based), of how many.
    pub fn segment(&self) -> (usize, usize) {
        (self.seg, self.segments.len())
    }

    /// Progress: arc length along the path.
    pub fn progress(&self) -> f64 {
        self.progress
    }

    /// The pose at arc length `s` within poses `lo..=hi` (interpolated).
    fn at(&self, s: f64, lo: usize, hi: usize) -> (P, f64) {
        let ps = &self.poses[lo..=hi];
        let k = ps
            .partition_point(|p| p.s <= s)
            .clamp(1, ps.len().max(2) - 1);
        if ps.len() < 2 {
            return (ps[0].position, ps[0].heading);
        }
        let (a, b) = (ps[k - 1], ps[k]);
        let len = b.s - a.s;
        let t = if len > 0.0 {
            ((s - a.s) / len).clamp(0.0, 1.0)
        } else {
            1.0
        };
        (
            [
                a.position[0] + (b.position[0] - a.position[0]) * t,
                a.position[1] + (b.position[1] - a.position[1]) * t,
            ],
            a.heading + wrap(b.heading - a.heading) * t,
        )
    }

    /// The arc length of the point of segment poses `lo..=hi` nearest `p`
    /// with arc length in `[from, to]`.
    fn project(&self, p: P, lo: usize, hi: usize, from: f64, to: f64) -> f64 {
        let mut best = (from, dist(self.at(from, lo, hi).0, p));
        for k in lo + 1..=hi {
            let (a, b) = (self.poses[k - 1], self.poses[k]);
            if b.s < from || a.s > to {
                continue;
            }
            let t = crate::along(p, a.position, b.position);
            let s = (a.s + t * (b.s - a.s)).clamp(from, to);
            let d = dist(self.at(s, lo, hi).0, p);
            if d < best.1 {
                best = (s, d);
            }
        }
        best.0
    }

    /// Takes the car's pose at `time` and returns what to steer for.
    pub fn target(&mut self, pose: Pose, time: f64) -> Target {
        loop {
            let (lo, hi) = self.segments[self.seg];
            let end = self.poses[hi].s;
            let from = self.progress.max(self.poses[lo].s);
            let s = self.project(pose.position, lo, hi, from, from + 2.0 * self.lookahead);
            self.progress = self.progress.max(s);
            let last = self.seg + 1 == self.segments.len();
            let near_end = dist(pose.position, self.poses[hi].position) <= self.at_cusp;
            if !last && (near_end || self.progress >= end) {
                self.seg += 1;
                self.progress = end;
                continue;
            }
            if self.mark.1.is_nan() || self.progress >= self.mark.0 + self.lookahead / 4.0 {
                self.mark = (self.progress, time);
            }
            let want = self.progress + self.reach;
            let (mut point, heading) = self.at(want.min(end), lo, hi);
            if want > end {
                // Beyond the segment's end the goal point runs on along
                // its end heading, the way it is driven (module
                // documentation).
                let gear = self.poses[hi].gear;
                let on = if gear == Gear::Forward { 1.0 } else { -1.0 } * (want - end);
                point = [point[0] + on * heading.cos(), point[1] + on * heading.sin()];
            }
            let (sh, ch) = pose.heading.sin_cos();
            let d = [point[0] - pose.position[0], point[1] - pose.position[1]];
            let y = -sh * d[0] + ch * d[1];
            let l2 = d[0] * d[0] + d[1] * d[1];
            let curvature = if l2 > 1e-18 { 2.0 * y / l2 } else { 0.0 };
            return Target {
                point,
                heading: wrap(heading),
                gear: self.poses[hi].gear,
                curvature,
                to_stop: (end - self.progress).max(0.0),
                last,
            };
        }
    }

    /// Has the car made no progress for `patience` s (by `time`)? Never
    /// on the last segment once the goal is within the look-ahead.
    pub fn stuck(&self, time: f64) -> bool {
        !self.at_end() && time - self.mark.1 > self.patience
    }

    /// Is the goal point the path's end?
    pub fn at_end(&self) -> bool {
        let (_, hi) = self.segments[self.seg];
        self.seg + 1 == self.segments.len() && self.progress + self.lookahead >= self.poses[hi].s
    }

    /// Follows `path` from now on (a replan), from its start.
    pub fn replace(&mut self, path: &CarPath, time: f64) {
        *self = Self::new(path, self.lookahead, self.at_cusp, self.patience);
        self.mark = (0.0, time);
    }
}
