//! Where things are drawn: the extent of a run's map, a body's radius and
//! shape, the pose it is drawn at, a collision's point.

use crate::records::{Event, EventKind, Sample};
use crate::run::RunData;
use mrsim_shape::{Pose, Shape};
use std::collections::HashMap;

/// How a body is drawn: its shape (a disc, or a polygon in its body frame)
/// and, for an obstacle, the heading it keeps (an obstacle never turns).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyLook {
    /// The scenario's shape (a disc of the body's radius by default).
    pub shape: Shape,
    /// An obstacle's fixed heading, rad; `None` for a robot, which is
    /// drawn at the heading its samples record.
    pub fixed_heading: Option<f64>,
    /// A robot's heading at its start (a unicycle faces its goal; a
    /// holonomic robot 0), for samples that record none.
    pub start_heading: f64,
}

impl BodyLook {
    /// The heading the body is drawn with at `sample`: an obstacle's fixed
    /// one, else the sample's `theta`, else the start heading.
    pub fn heading(&self, sample: Option<&Sample>) -> f64 {
        self.fixed_heading
            .or_else(|| sample.and_then(|s| s.theta))
            .filter(|h| h.is_finite())
            .unwrap_or(self.start_heading)
    }

    /// The body's outline in the world at `position`, turned by `heading`
    /// (counter-clockwise polygon vertices); `None` for a disc.
    pub fn outline(&self, position: [f64; 2], heading: f64) -> Option<Vec<[f64; 2]>> {
        self.shape
            .placed(Pose::new(position, heading))
            .map(|p| p.points().to_vec())
    }

    /// Is the body a disc (drawn as a circle, as it always was)?
    pub fn is_disc(&self) -> bool {
        self.shape.is_disc()
    }
}

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
            .or_else(|| {
                self.scenario
                    .people
                    .iter()
                    .find(|p| p.name == name)
                    .map(|p| p.radius)
            })
            .unwrap_or(0.0)
    }

    /// How each body of the scenario is drawn, by name: robots, then
    /// obstacles (a robot and an obstacle of one name: the robot).
    pub fn looks_by_name(&self) -> HashMap<&str, BodyLook> {
        let mut out = HashMap::new();
        for o in &self.scenario.obstacles {
            out.insert(
                o.name.as_str(),
                BodyLook {
                    shape: o.body_shape(),
                    fixed_heading: Some(o.heading),
                    start_heading: o.heading,
                },
            );
        }
        for r in &self.scenario.robots {
            out.insert(
                r.name.as_str(),
                BodyLook {
                    shape: r.body_shape(),
                    fixed_heading: None,
                    start_heading: r.start_heading(),
                },
            );
        }
        out
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
