//! The metrics of the robots' motion, computed off the tick loop.
//!
//! Path length, top speed, smallest clearance to other bodies and walls,
//! and the designated-path deviation are functions of the bodies' states
//! alone, tick after tick. The recording thread already gets every tick's
//! states, in order, to write trajectory.csv ([`crate::record`]); it feeds
//! them to a [`Tracker`] too, and hands the tracker back when the run
//! ends, so the tick loop neither computes them nor waits for them before
//! it publishes the next tick (BENCHMARKS.md, "In-process", has the
//! profile).
//!
//! What the loop must know at once stays there: goals reached (they flag
//! the robot in the next snapshot and can end the run), contacts (events
//! as they happen) and deadline misses.

use crate::clearance::{ClearanceGrid, clearly_beyond, segment_distance, segment_distance_sq};
use crate::interaction::Interaction;
use crate::path_metrics::PathAccumulator;
use mrsim_proto::BodyState;
use mrsim_scenario::Scenario;

/// One robot's motion metrics so far.
#[derive(Debug, Clone)]
pub struct RobotMotion {
    /// Distance travelled.
    pub path_length: f64,
    /// Largest speed.
    pub max_speed: f64,
    /// Smallest surface distance to any other body but a person, or wall
    /// (infinity if there never was one).
    pub min_clearance: f64,
    /// Designated-path metrics, for a robot with a `path`.
    pub path: Option<PathAccumulator>,
    /// The shortest path from its start to its goal, as SPL counts it:
    /// the straight distance, or its route's length ([`Tracker::along_routes`]).
    pub shortest: f64,
}

impl RobotMotion {
    /// Success weighted by path length (Anderson et al., "On Evaluation of
    /// Embodied Navigation Agents", 2018): 0 without success, else the
    /// shortest path over the longer of it and the path driven.
    pub fn spl(&self, reached_goal: bool) -> f64 {
        if !reached_goal {
            return 0.0;
        }
        let longest = self.path_length.max(self.shortest);
        if longest > 0.0 {
            self.shortest / longest
        } else {
            1.0
        }
    }
}

/// Motion metrics of every robot, fed one tick's states at a time.
#[derive(Debug, Clone)]
pub struct Tracker {
    robots: Vec<RobotMotion>,
    walls: Vec<[[f64; 2]; 2]>,
    /// Robots' positions at the previous tick; `None` before the first.
    prev: Option<Vec<[f64; 2]>>,
    grid: ClearanceGrid,
    clearance: Vec<f64>,
    /// Every body's shape by id, empty when every body is a disc.
    shapes: Vec<mrsim_shape::Shape>,
    interaction: Interaction,
}

impl Tracker {
    /// For the robots of `scenario` (the first bodies of every tick's
    /// states), among `walls`.
    pub fn new(scenario: &Scenario, walls: &[[[f64; 2]; 2]]) -> Self {
        Self {
            robots: scenario
                .robots
                .iter()
                .map(|r| RobotMotion {
                    path_length: 0.0,
                    max_speed: 0.0,
                    min_clearance: f64::INFINITY,
                    path: PathAccumulator::new(&r.path, r.boundary),
                    shortest: (r.goal[0] - r.start[0]).hypot(r.goal[1] - r.start[1]),
                })
                .collect(),
            walls: walls.to_vec(),
            prev: None,
            grid: ClearanceGrid::default(),
            clearance: Vec::new(),
            shapes: if scenario.has_shapes() {
                scenario.body_shapes()
            } else {
                Vec::new()
            },
            interaction: Interaction::new(scenario),
        }
    }

    /// The same, with the shortest path of each robot that `route_length`
    /// gives a length for (by its name) the length of its route.
    pub fn along_routes(
        mut self,
        scenario: &Scenario,
        route_length: impl Fn(&str) -> Option<f64>,
    ) -> Self {
        for (m, r) in self.robots.iter_mut().zip(&scenario.robots) {
            if let Some(l) = route_length(&r.name) {
                m.shortest = l;
            }
        }
        self
    }

    /// Takes in the next tick's states (tick `tick`, simulated time
    /// `time`). The first tick's only says where the robots start: the
    /// metrics count from the first step on.
    pub fn track(&mut self, tick: u64, time: f64, states: &[BodyState]) {
        self.interaction.track(tick, time, states);
        let n = self.robots.len().min(states.len());
        let Some(prev) = &mut self.prev else {
            self.prev = Some(states[..n].iter().map(|s| s.position).collect());
            return;
        };
        // Only a clearance below the smallest one recorded changes anything.
        // People (the last bodies) are not in it: their gaps are the
        // interaction's `person_` ones.
        let people = states
            .iter()
            .rev()
            .take_while(|s| s.kind == mrsim_proto::body_kind::PERSON)
            .count();
        let others = &states[..states.len() - people];
        let shapes = &self.shapes[..self.shapes.len().min(others.len())];
        let robots = &self.robots;
        self.grid.clearances_below(
            others,
            shapes,
            n,
            |i| robots[i].min_clearance,
            &mut self.clearance,
        );
        for (i, (s, p)) in states[..n].iter().zip(prev.iter_mut()).enumerate() {
            let m = &mut self.robots[i];
            // Plain square roots: `hypot`'s overflow guard is a libm call per
            // use, and positions and speeds are nowhere near 1e150.
            let (dx, dy) = (s.position[0] - p[0], s.position[1] - p[1]);
            m.path_length += (dx * dx + dy * dy).sqrt();
            *p = s.position;
            let [vx, vy] = s.velocity;
            m.max_speed = m.max_speed.max((vx * vx + vy * vy).sqrt());
            let mut clear = self.clearance[i];
            for w in &self.walls {
                // Only a wall nearer than the smallest clearance so far can
                // change it: the others are ruled out without a root.
                if clearly_beyond(
                    segment_distance_sq(*w, s.position),
                    clear.min(m.min_clearance) + s.radius,
                ) {
                    continue;
                }
                clear = clear.min(match self.shapes.get(i).filter(|b| !b.is_disc()) {
                    Some(b) => {
                        let pose = mrsim_shape::Pose::new(s.position, s.heading);
                        mrsim_shape::gap_to_segment(b, pose, *w)
                    }
                    None => segment_distance(*w, s.position) - s.radius,
                });
            }
            m.min_clearance = m.min_clearance.min(clear);
            if let Some(path) = &mut m.path {
                path.record(s.position);
            }
        }
    }

    /// Every robot's metrics, in scenario order.
    pub fn robots(&self) -> &[RobotMotion] {
        &self.robots
    }

    /// The interaction metrics and encounters.
    pub fn interaction(&self) -> &Interaction {
        &self.interaction
    }

    /// The interaction metrics and encounters, to take the encounters from.
    pub fn interaction_mut(&mut self) -> &mut Interaction {
        &mut self.interaction
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mrsim_proto::body_kind;

    fn disc(x: f64, y: f64, vx: f64) -> BodyState {
        BodyState {
            kind: body_kind::ROBOT,
            position: [x, y],
            velocity: [vx, 0.0],
            radius: 0.5,
            ..Default::default()
        }
    }

    #[test]
    fn spl_measures_the_path_against_the_route_where_a_robot_has_one() {
        // a: 8 m straight to its goal; b: 3 m straight, 5 m along its route.
        let mut t = Tracker::new(&two_robots(), &[])
            .along_routes(&two_robots(), |name| (name == "b").then_some(5.0));
        t.track(0, 0.0, &[disc(1.0, 5.0, 0.0), disc(4.0, 5.0, 0.0)]);
        t.track(1, 0.1, &[disc(11.0, 5.0, 0.0), disc(4.0, 1.0, 0.0)]);
        t.track(2, 0.2, &[disc(11.0, 5.0, 0.0), disc(1.0, 5.0, 0.0)]);
        let [a, b] = t.robots() else {
            panic!("two robots")
        };
        assert_eq!((a.shortest, a.path_length), (8.0, 10.0));
        assert!((a.spl(true) - 0.8).abs() < 1e-12);
        assert_eq!(a.spl(false), 0.0);
        // b drove 4 + 5 = 9 m, its route is 5 m: 5 / 9.
        assert_eq!(b.shortest, 5.0);
        assert!((b.path_length - 9.0).abs() < 1e-12);
        assert!((b.spl(true) - 5.0 / 9.0).abs() < 1e-12);
        // A path shorter than the shortest (a route's detour cut) counts 1.
        let short = RobotMotion {
            path_length: 4.0,
            ..b.clone()
        };
        assert_eq!(short.spl(true), 1.0);
    }

    fn two_robots() -> Scenario {
        let toml = r#"
            name = "t"
            [world]
            arena = { min = [0.0, 0.0], max = [10.0, 10.0] }
            [[robot]]
            name = "a"
            start = [1.0, 5.0]
            goal = [9.0, 5.0]
            radius = 0.5
            [[robot]]
            name = "b"
            start = [4.0, 5.0]
            goal = [1.0, 5.0]
            radius = 0.5
        "#;
        mrsim_scenario::parse(toml, "t.toml")
            .expect("scenario")
            .scenario
    }

    #[test]
    fn the_first_tick_sets_the_start_and_later_ones_add_up() {
        let mut t = Tracker::new(&two_robots(), &[]);
        t.track(0, 0.0, &[disc(1.0, 5.0, 0.0), disc(4.0, 5.0, 0.0)]);
        // Before any step: nothing travelled, nothing measured.
        assert_eq!(t.robots()[0].path_length, 0.0);
        assert!(t.robots()[0].min_clearance.is_infinite());
        t.track(0, 0.0, &[disc(2.0, 5.0, 1.0), disc(4.0, 5.0, 0.0)]);
        t.track(0, 0.0, &[disc(2.5, 5.0, 3.0), disc(4.0, 5.0, 0.0)]);
        let a = &t.robots()[0];
        assert!((a.path_length - 1.5).abs() < 1e-12);
        assert_eq!(a.max_speed, 3.0);
        // Closest at the last tick: centres 1.5 apart, radii 0.5 each.
        assert!((a.min_clearance - 0.5).abs() < 1e-12, "{}", a.min_clearance);
        assert!((t.robots()[1].min_clearance - 0.5).abs() < 1e-12);
    }

    #[test]
    fn a_wall_nearer_than_any_body_sets_the_clearance() {
        let mut t = Tracker::new(&two_robots(), &[[[0.0, 5.7], [10.0, 5.7]]]);
        t.track(0, 0.0, &[disc(1.0, 5.0, 0.0), disc(4.0, 5.0, 0.0)]);
        t.track(0, 0.0, &[disc(1.0, 5.0, 0.0), disc(4.0, 5.0, 0.0)]);
        for r in t.robots() {
            assert!((r.min_clearance - 0.2).abs() < 1e-12, "{}", r.min_clearance);
        }
    }
}
