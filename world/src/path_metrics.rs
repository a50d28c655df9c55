//! Designated-path metrics (Yamada et al.): how far a robot with a `path`
//! strays from it, and how many ticks it spends outside its corridor.
//!
//! The distance is [`mrsim_planners::designated_path::distance_to_path`],
//! the very function the `designated-path` planner uses to drop via points
//! out of the boundary, so the metric and the planner agree on what "inside
//! the corridor" means. (The world takes only that pure helper from the
//! planners crate; it never builds or runs a planner.)
//!
//! A tick is a *boundary violation* when the robot's centre is farther than
//! `boundary` from the path: the boundary bounds the centre, as the planner
//! reads it (its via points are centre positions), not the whole disc. A
//! robot with a path but no `boundary` has no corridor, so it has a
//! deviation but no violation count.

use mrsim_planners::Vec2;
use mrsim_planners::designated_path::distance_to_path;

pub use mrsim_runfolder::metrics::PathDeviation;

/// Accumulates one robot's path metrics tick by tick.
#[derive(Debug, Clone, Default)]
pub struct PathAccumulator {
    points: Vec<Vec2>,
    boundary: Option<f64>,
    sum: f64,
    max: f64,
    count: u64,
    violations: u64,
}

impl PathAccumulator {
    /// For a robot whose scenario entry has `path` (empty: no path, `None`)
    /// and `boundary`.
    pub fn new(path: &[[f64; 2]], boundary: Option<f64>) -> Option<Self> {
        (!path.is_empty()).then(|| Self {
            points: path.iter().map(|p| Vec2::new(p[0], p[1])).collect(),
            boundary,
            ..Default::default()
        })
    }

    /// Records the robot's position at one tick.
    pub fn record(&mut self, position: [f64; 2]) {
        let d = distance_to_path(&self.points, Vec2::new(position[0], position[1]));
        if !d.is_finite() {
            return;
        }
        self.sum += d;
        self.max = self.max.max(d);
        self.count += 1;
        if self.boundary.is_some_and(|b| d > b) {
            self.violations += 1;
        }
    }

    /// Mean and largest distance from the path (zeros before any tick).
    pub fn deviation(&self) -> PathDeviation {
        PathDeviation {
            mean: if self.count > 0 {
                self.sum / self.count as f64
            } else {
                0.0
            },
            max: self.max,
        }
    }

    /// Ticks with the centre outside the corridor; `None` without a
    /// boundary.
    pub fn boundary_violations(&self) -> Option<u64> {
        self.boundary.map(|_| self.violations)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_robot_without_a_path_has_no_path_metrics() {
        assert!(PathAccumulator::new(&[], None).is_none());
    }

    #[test]
    fn deviation_is_the_distance_to_the_nearest_segment_and_violations_count_ticks_outside() {
        // An L: (0,0) -> (4,0) -> (4,4), corridor half-width 1.
        let mut acc =
            PathAccumulator::new(&[[0.0, 0.0], [4.0, 0.0], [4.0, 4.0]], Some(1.0)).expect("a path");
        acc.record([1.0, 0.5]); // 0.5 from the first segment
        acc.record([5.5, 2.0]); // 1.5 from the second: outside
        acc.record([4.0, 1.0]); // on the second segment
        acc.record([2.0, -1.0]); // exactly on the boundary: inside
        let d = acc.deviation();
        assert!((d.mean - 3.0 / 4.0).abs() < 1e-12, "mean {}", d.mean);
        assert!((d.max - 1.5).abs() < 1e-12, "max {}", d.max);
        assert_eq!(acc.boundary_violations(), Some(1));
    }

    #[test]
    fn a_path_without_a_boundary_has_a_deviation_but_no_violation_count() {
        let mut acc = PathAccumulator::new(&[[0.0, 0.0], [1.0, 0.0]], None).expect("a path");
        acc.record([0.5, 7.0]);
        assert_eq!(acc.deviation().max, 7.0);
        assert_eq!(acc.boundary_violations(), None);
    }
}
