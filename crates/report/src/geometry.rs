//! Where things are drawn: the extent of a run's map, a body's radius, a
//! collision's point.

use crate::records::{Event, EventKind};
use crate::run::RunData;

impl RunData {
    /// `[xmin, xmax, ymin, ymax]` of the smallest box holding the arena,
    /// the walls, every robot's start and goal and every sample, grown by
    /// the largest body radius and 2% of its larger side. Never empty: a
    /// side of zero length becomes one length unit.
    pub fn extent(&self) -> [f64; 4] {
        let mut b = [
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ];
        let mut add = |x: f64, y: f64| {
            if x.is_finite() && y.is_finite() {
                b[0] = b[0].min(x);
                b[1] = b[1].max(x);
                b[2] = b[2].min(y);
                b[3] = b[3].max(y);
            }
        };
        for w in self.scenario.all_walls() {
            add(w[0][0], w[0][1]);
            add(w[1][0], w[1][1]);
        }
        for r in &self.scenario.robots {
            add(r.start[0], r.start[1]);
            add(r.goal[0], r.goal[1]);
        }
        for o in &self.scenario.obstacles {
            add(o.start[0], o.start[1]);
        }
        for body in &self.trajectory.bodies {
            for s in &body.samples {
                add(s.x, s.y);
            }
        }
        if !b[0].is_finite() {
            b = [-1.0, 1.0, -1.0, 1.0];
        }
        let radius = self
            .scenario
            .robots
            .iter()
            .map(|r| r.radius)
            .chain(self.scenario.obstacles.iter().map(|o| o.radius))
            .filter(|r| r.is_finite())
            .fold(0.0, f64::max);
        let pad = radius + 0.02 * (b[1] - b[0]).max(b[3] - b[2]);
        b = [b[0] - pad, b[1] + pad, b[2] - pad, b[3] + pad];
        for k in [0, 2] {
            if b[k + 1] - b[k] <= 0.0 {
                b[k] -= 0.5;
                b[k + 1] += 0.5;
            }
        }
        b
    }

    /// Radius of a body by name, from the scenario (0 if it is not there).
    pub fn radius_of(&self, name: &str) -> f64 {
        self.scenario
            .robots
            .iter()
            .find(|r| r.name == name)
            .map(|r| r.radius)
            .or_else(|| {
                self.scenario
                    .obstacles
                    .iter()
                    .find(|o| o.name == name)
                    .map(|o| o.radius)
            })
            .unwrap_or(0.0)
    }

    /// Where a collision is drawn: its contact point, or else body `a`'s
    /// position at that tick.
    pub fn collision_point(&self, event: &Event) -> Option<[f64; 2]> {
        match &event.kind {
            EventKind::Collision {
                x: Some(x),
                y: Some(y),
                ..
            } => Some([*x, *y]),
            EventKind::Collision { a, .. } => self
                .trajectory
                .body(a)
                .and_then(|t| t.at(event.tick))
                .map(|s| [s.x, s.y]),
            _ => None,
        }
    }
}
