//! A route as a polyline, and following it: progress along it and the
//! waypoint a robot is steered to.

use crate::{P, dist};

/// A route: straight legs from the start to the goal.
#[derive(Debug, Clone, PartialEq)]
pub struct Path {
    pts: Vec<P>,
    /// Arc length at each point.
    cum: Vec<f64>,
}

impl Path {
    /// The polyline through `pts` (at least one point).
    pub fn new(pts: Vec<P>) -> Self {
        let mut cum = Vec::with_capacity(pts.len());
        let mut s = 0.0;
        for (k, p) in pts.iter().enumerate() {
            if k > 0 {
                s += dist(pts[k - 1], *p);
            }
            cum.push(s);
        }
        Self { pts, cum }
    }

    /// Its points, first the start, last the goal.
    pub fn points(&self) -> &[P] {
        &self.pts
    }

    /// Its length.
    pub fn length(&self) -> f64 {
        self.cum.last().copied().unwrap_or(0.0)
    }

    /// The point at arc length `s` (clamped to the path).
    pub fn at(&self, s: f64) -> P {
        let s = s.clamp(0.0, self.length());
        let k = self
            .cum
            .partition_point(|&c| c <= s)
            .clamp(1, self.pts.len().max(2) - 1);
        if self.pts.len() < 2 {
            return self.pts[0];
        }
        let (a, b) = (self.pts[k - 1], self.pts[k]);
        let len = self.cum[k] - self.cum[k - 1];
        if len <= 0.0 {
            return b;
        }
        let t = ((s - self.cum[k - 1]) / len).clamp(0.0, 1.0);
        [a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t]
    }

    /// The path from its start up to arc length `s`, as a polyline.
    pub fn up_to(&self, s: f64) -> Vec<P> {
        let s = s.clamp(0.0, self.length());
        let mut out: Vec<P> = self
            .pts
            .iter()
            .zip(&self.cum)
            .take_while(|&(_, &c)| c < s)
            .map(|(p, _)| *p)
            .collect();
        out.push(self.at(s));
        out
    }

    /// The arc length of the point of the path nearest `p` among those
    /// with arc length in `[lo, hi]`, and its distance from `p`.
    pub fn project(&self, p: P, lo: f64, hi: f64) -> (f64, f64) {
        let mut best = (lo.clamp(0.0, self.length()), f64::INFINITY);
        best.1 = dist(self.at(best.0), p);
        for k in 1..self.pts.len() {
            let (s0, s1) = (self.cum[k - 1], self.cum[k]);
            if s1 < lo || s0 > hi {
                continue;
            }
            let t = crate::along(p, self.pts[k - 1], self.pts[k]);
            let s = (s0 + t * (s1 - s0)).clamp(lo, hi);
            let d = dist(self.at(s), p);
            if d < best.1 {
                best = (s, d);
            }
        }
        best
    }
}

/// Leads a robot along a [`Path`]: its progress (arc length reached, never
/// decreasing), the waypoint `ahead` further on, and whether it has made
/// no progress for `patience` seconds.
#[derive(Debug, Clone)]
pub struct Follower {
    path: Path,
    ahead: f64,
    patience: f64,
    progress: f64,
    /// Progress at the last time it grew by `ahead / 4`, and that time.
    mark: (f64, f64),
}

impl Follower {
    /// Follows `path` with the waypoint `ahead` beyond the progress, and
    /// counts the robot stuck after `patience` s without advancing by a
    /// quarter of `ahead`.
    pub fn new(path: Path, ahead: f64, patience: f64) -> Self {
        Self {
            path,
            ahead,
            patience,
            progress: 0.0,
            mark: (0.0, f64::NAN),
        }
    }

    /// The path followed.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Progress, arc length along the path.
    pub fn progress(&self) -> f64 {
        self.progress
    }

    /// Takes the robot's position at `time` and returns its waypoint: the
    /// path's point `ahead` beyond its progress (the goal at the end). The
    /// progress is the robot's projection onto the path, looked for up to
    /// twice `ahead` beyond the progress so far.
    pub fn waypoint(&mut self, p: P, time: f64) -> P {
        let (s, _) = self
            .path
            .project(p, self.progress, self.progress + 2.0 * self.ahead);
        self.progress = self.progress.max(s);
        if self.mark.1.is_nan() || self.progress >= self.mark.0 + self.ahead / 4.0 {
            self.mark = (self.progress, time);
        }
        self.path.at(self.progress + self.ahead)
    }

    /// The point of the path `s` along it.
    pub fn at(&self, s: f64) -> P {
        self.path.at(s)
    }

    /// Has the robot made no progress for `patience` s (by `time`)? Never
    /// once the waypoint is the goal.
    pub fn stuck(&self, time: f64) -> bool {
        self.progress + self.ahead < self.path.length() && time - self.mark.1 > self.patience
    }

    /// Is the waypoint the path's end (the goal)?
    pub fn at_end(&self) -> bool {
        self.progress + self.ahead >= self.path.length()
    }

    /// Counts the robot as making progress at `time` (it stands by choice,
    /// waiting its turn, and is not stuck).
    pub fn wait(&mut self, time: f64) {
        self.mark = (self.progress, time);
    }

    /// Follows `path` from now on (a replan), progress from its start.
    pub fn replace(&mut self, path: Path, time: f64) {
        self.path = path;
        self.progress = 0.0;
        self.mark = (0.0, time);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn l_path() -> Path {
        Path::new(vec![[0.0, 0.0], [4.0, 0.0], [4.0, 3.0]])
    }

    #[test]
    fn the_waypoint_is_ahead_of_the_projection_and_ends_at_the_goal() {
        let mut f = Follower::new(l_path(), 1.0, 5.0);
        assert_eq!(f.waypoint([1.0, 0.3], 0.0), [2.0, 0.0]);
        let w = f.waypoint([2.5, 0.2], 0.1);
        assert!((w[0] - 3.5).abs() < 1e-12 && w[1] == 0.0, "{w:?}");
        let w = f.waypoint([3.6, 0.2], 0.1);
        assert!(w[0] == 4.0 && (w[1] - 0.6).abs() < 1e-12, "{w:?}");
        // A robot far ahead of its progress is taken up to 2 `ahead` on.
        let w = f.waypoint([4.0, 2.5], 0.2);
        assert!(w[0] == 4.0 && (w[1] - 2.6).abs() < 1e-12, "{w:?}");
        assert_eq!(f.waypoint([4.0, 2.5], 0.3), [4.0, 3.0]);
        assert!((f.path().length() - 7.0).abs() < 1e-12);
        assert_eq!(
            f.path().up_to(5.0),
            vec![[0.0, 0.0], [4.0, 0.0], [4.0, 1.0]]
        );
        assert_eq!(f.path().up_to(0.0), vec![[0.0, 0.0]]);
    }

    #[test]
    fn progress_never_goes_back_and_standing_still_is_noticed() {
        let mut f = Follower::new(l_path(), 1.0, 5.0);
        f.waypoint([2.0, 0.0], 0.0);
        f.waypoint([1.0, 0.0], 1.0);
        assert_eq!(f.progress(), 2.0);
        assert!(!f.stuck(4.0));
        f.waypoint([2.1, 0.0], 5.5);
        assert!(f.stuck(5.5));
        f.waypoint([2.5, 0.0], 6.0);
        assert!(!f.stuck(6.0));
        f.replace(Path::new(vec![[2.5, 0.0], [4.0, 3.0]]), 7.0);
        assert_eq!(f.progress(), 0.0);
        assert!(!f.stuck(11.0) && f.stuck(12.5));
    }
}
